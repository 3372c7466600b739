//! Order independence as a property: a shuffled submission order (`--shuffle SEED`,
//! `View::shuffled`) rasterizes the same fragments in another order, and every scheme that
//! promises order independence captures bit-identical lists under it; the schemes that depend on
//! order (keep-first linked list, layer counter without tail, loop32 with equal depths, and
//! keep-first under the ordered interlock, which is deterministic but follows draw order) are
//! shown so by the smallest scene on which two submission orders disagree, found by searching
//! scenes smallest first and pinned.
//!
//! Which schemes promise it is read from what they promise, not listed: a scheme owed exactness
//! where pixels are serialised ([`Guarantee::owes_exactness`]) keeps a set the fragments alone
//! determine when it keeps the `K` nearest (or farthest), or all of a pixel's fragments within a
//! capacity the scene does not exceed; a scheme that merges equal depths does only on scenes
//! without them.

use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::executors::Executor;
use fragsim::capture::primitive_order::PrimitiveOrder;
use fragsim::capture::{inputs_of, Capture, Guarantee, Keeps, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::catalog::{
    Build, Count, SchemeName, SchemeRunner, SchemeVisitor, Sizing, Storage, CATALOG,
};
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, Viewport};
use proptest::prelude::*;

/// Whether a capture under `guarantee`, keeping `keeps`, of a scene of maximum depth complexity
/// `deepest` (`ties`: some pixel has two fragments at one depth key) is owed the same lists in
/// every submission order on an executor that serialises pixels.
fn promises_order_independence(
    guarantee: Guarantee,
    keeps: &Keeps,
    deepest: u32,
    ties: bool,
) -> bool {
    if !guarantee.owes_exactness(true) || (guarantee.merges_equal_depths() && ties) {
        return false;
    }
    match keeps {
        Keeps::Nearest(_) | Keeps::Farthest(_) => true,
        Keeps::All { capacity, .. } => capacity.overflow(deepest as usize) == 0,
    }
}

fn has_ties(oracle: &Oracle) -> bool {
    (0..oracle.pixels()).any(|p| oracle.pixel(p).windows(2).any(|w| w[0] >> 32 == w[1] >> 32))
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 6,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Every catalog scheme, sized short (`K` and capacity below the depth complexity) and to
    /// the scene: where it promises order independence, the serial executor (and the scheduled
    /// one, for schemes exact under any interleaving) gives bit-identical lists for the view
    /// and for the view shuffled by `seed`.
    #[test]
    fn every_scheme_promising_order_independence_captures_the_same_lists_in_any_order(
        spheres in 1_u32..=4,
        seed in any::<u64>(),
        k in 1_u32..=3,
    ) {
        let scene = Scene::procedural(&format!("spheres:{spheres}")).unwrap();
        let view = scene
            .view(Viewport::new(12, 12).unwrap(), &OrbitCamera::default())
            .unwrap();
        let shuffled = view.clone().shuffled(seed);
        let oracle = Oracle::build(&view);
        let (deepest, ties) = (oracle.max_depth_complexity(), has_ties(&oracle));
        let mut runner = SchemeRunner::default();
        let mut checked = 0;
        for entry in CATALOG {
            for count in [Count::Fixed(k), Count::Auto] {
                // A linked list's node pool is shared by the screen: which fragments a full pool
                // loses depends on the arrival order. Its pool holds every fragment here.
                let capacity = if entry.storage == Storage::KAndPool { Count::Auto } else { count };
                let sizing = Sizing { k: count, capacity, memory_cap: MEMORY_CAP_DEFAULT };
                for executor in [Executor::Serial, Executor::Scheduled] {
                    let mut run =
                        |scene_view| runner.run(entry.scheme, executor, scene_view, &sizing).unwrap();
                    let a = run(&view);
                    let owed = promises_order_independence(
                        a.guarantee, &a.run.capture.keeps, deepest, ties,
                    ) && (executor == Executor::Serial || a.guarantee.owes_exactness(false));
                    if owed {
                        let b = run(&shuffled);
                        prop_assert!(
                            a.run.capture.lists == b.run.capture.lists,
                            "{} ({:?}) on the {} executor: the lists change with the order",
                            entry.name, count, executor
                        );
                        checked += 1;
                    }
                }
            }
        }
        prop_assert!(checked > CATALOG.len(), "only {checked} runs promised order independence");
    }
}

/// A view of one seed's shuffle that the order-dependent schemes capture differently from the
/// view in primitive id order (so the executors do submit in the shuffled order).
#[test]
fn the_order_dependent_schemes_capture_a_shuffled_view_differently() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default())
        .unwrap();
    let shuffled = view.clone().shuffled(1);
    let sizing = Sizing {
        k: Count::Fixed(1),
        capacity: Count::Auto,
        memory_cap: MEMORY_CAP_DEFAULT,
    };
    let mut runner = SchemeRunner::default();
    for name in [
        "layer-counter",
        "linked-list",
        "kbuffer-interlock-ordered-first",
    ] {
        let scheme = SchemeName::from_name(name).unwrap();
        let mut run = |scene_view| {
            runner
                .run(scheme, Executor::Serial, scene_view, &sizing)
                .unwrap()
                .run
                .capture
                .lists
        };
        assert!(
            run(&view) != run(&shuffled),
            "{name}: the shuffle changed nothing"
        );
    }
}

/// One fragment in flight: the stream's submission order.
fn serial() -> Schedule {
    Schedule {
        policy: Policy::Random,
        in_flight: 1,
        granularity: Granularity::Fragment,
        seed: 0,
    }
}

/// The visitor running a built scheme serially on a stream.
struct Serially<'a>(&'a [Fragment]);

impl SchemeVisitor for Serially<'_> {
    type Output = Capture;
    fn visit<S: Scheme>(self, scheme: &S, _: Option<u32>) -> Capture {
        let inputs = inputs_of(scheme, self.0.iter().copied());
        run_fragments(scheme, &inputs, &serial(), false).run.capture
    }
}

/// Scheme `name` with `K` = 1 and a capacity of 2, run serially on `stream` (one pixel), its
/// primitive order the stream's; a linked list's pool holds the stream (an exhausted pool loses
/// whichever fragment comes last, an order dependence of its own).
#[expect(
    clippy::cast_possible_truncation,
    reason = "a stream has at most three fragments"
)]
fn captured(name: &str, stream: &[Fragment]) -> Vec<u64> {
    let order = PrimitiveOrder::of_fragments(1, stream);
    let counts = [stream.len() as u32];
    let build = Build {
        counts: Some(&counts),
        order: Some(&order),
        pool: stream.len().max(1),
        ..Build::fixed(
            Viewport::new(1, 1).unwrap(),
            1,
            2,
            stream.len().max(1) as u32,
            MEMORY_CAP_DEFAULT,
        )
    };
    let capture = SchemeName::from_name(name)
        .unwrap()
        .build(&build, Serially(stream))
        .unwrap();
    capture.pixel(0).to_vec()
}

/// Every order of `0..n`.
fn permutations(n: usize) -> Vec<Vec<usize>> {
    if n == 0 {
        return vec![Vec::new()];
    }
    let mut all = Vec::new();
    for shorter in permutations(n - 1) {
        for at in 0..n {
            let mut p = shorter.clone();
            p.insert(at, n - 1);
            all.push(p);
        }
    }
    all
}

/// Two submission orders of one scene that `name` captures differently.
#[derive(Debug)]
struct Disagreement {
    first: Vec<Fragment>,
    second: Vec<Fragment>,
    kept_first: Vec<u64>,
    kept_second: Vec<u64>,
}

/// The smallest scene (fewest fragments, all on one pixel, depths from two values; with
/// `distinct`, no two equal) with two submission orders that `name` captures differently,
/// searching scenes of up to 3 fragments, smallest first.
fn smallest_disagreement(name: &str, distinct: bool) -> Option<Disagreement> {
    let depths = [0.25_f32, 0.5];
    for n in 1..=3_usize {
        for bits in 0..1_u32 << n {
            let pick = |i: usize| ((bits >> i) & 1) as usize;
            if distinct && (0..n).any(|i| (0..i).any(|j| pick(i) == pick(j))) {
                continue;
            }
            let stream: Vec<Fragment> = (0..n)
                .map(|i| Fragment {
                    pixel: 0,
                    depth_key: depth_key(depths[pick(i)]).unwrap(),
                    prim: u32::try_from(i).expect("at most three fragments"),
                })
                .collect();
            let kept_first = captured(name, &stream);
            for order in permutations(n) {
                let second: Vec<Fragment> = order.iter().map(|&i| stream[i]).collect();
                let kept_second = captured(name, &second);
                if kept_second != kept_first {
                    return Some(Disagreement {
                        first: stream,
                        second,
                        kept_first,
                        kept_second,
                    });
                }
            }
        }
    }
    None
}

/// The order-dependent schemes, `K` = 1: the smallest disagreeing scene is two fragments of one
/// pixel at one depth, in its two orders; the layer counter and keep-first under the ordered
/// interlock keep the first submitted, the keep-first linked list (most recent first) and
/// loop32 (the last colour store wins) the last. loop32 needs the equal depths: with distinct
/// ones no scene of up to 3 fragments disagrees.
#[test]
fn the_order_dependent_schemes_disagree_on_two_fragments_of_one_pixel() {
    for (name, keeps_first) in [
        ("layer-counter", true),
        ("kbuffer-interlock-ordered-first", true),
        ("linked-list", false),
        ("loop32", false),
    ] {
        let found = smallest_disagreement(name, false)
            .unwrap_or_else(|| panic!("{name}: no scene of up to 3 fragments disagrees"));
        assert_eq!(found.first.len(), 2, "{name}: {found:?}");
        assert_eq!(
            found.first[0].depth_key, found.first[1].depth_key,
            "{name}: {found:?}"
        );
        assert_eq!(
            found.second,
            [found.first[1], found.first[0]],
            "{name}: {found:?}"
        );
        let kept =
            |order: &[Fragment]| vec![if keeps_first { order[0] } else { order[1] }.packed()];
        assert_eq!(found.kept_first, kept(&found.first), "{name}: {found:?}");
        assert_eq!(found.kept_second, kept(&found.second), "{name}: {found:?}");
    }
    assert!(
        smallest_disagreement("loop32", true).is_none(),
        "loop32 depends on order without equal depths"
    );
}

/// The controls: schemes promising order independence have no disagreeing scene of up to 3
/// fragments, equal depths included (so the search can find none where none is owed).
#[test]
fn the_order_independent_schemes_have_no_disagreeing_small_scene() {
    for name in [
        "mdts",
        "kbuffer-interlock",
        "kbuffer-interlock-ordered",
        "linked-list-nearest",
    ] {
        let found = smallest_disagreement(name, false);
        assert!(found.is_none(), "{name}: {found:?}");
    }
}
