//! The shipping OIT algorithms against the oracle (`docs/baselines/shipping.md`): each
//! property states the exact condition under which a scheme departs from the oracle and asserts
//! that it departs then and only then.
//!
//! - loop32 (nvpro-samples): exact under `Ties::MergeEqualDepths` on every interleaving; against
//!   the canonical order it differs in a pixel iff a depth key among the pixel's `K` nearest
//!   distinct keys belongs to two or more fragments (serially; on any interleaving it never
//!   differs without one), where FreePipe's MDTS keeps them all.
//! - the layer counter (Bevy 0.15): a pixel of depth complexity `n` loses exactly
//!   `max(0, n − layer_count)` fragments on every interleaving, and differs iff `n > layer_count`.
//! - linked lists: the keep-first resolve differs in a pixel iff the `N` most recent head
//!   exchanges are not the pixel's `N` nearest fragments; keep-nearest is exact when the pool
//!   suffices, and an exhausted pool loses exactly the fragments past it.
//!
//! Streams are hand-written fragments on a few pixels with depth keys drawn from a handful of
//! values, so that ties are common; "serial" is the scheduled executor with one fragment in flight
//! (submission order), the rest are seeded GPU-like interleavings.

use fragsim::capture::executors::scheduled::{run_fragments, Granularity, Policy, Schedule};
use fragsim::capture::executors::Executor;
use fragsim::capture::{Capture, Keeps, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::Op;
use fragsim::oracle::{Oracle, Ties};
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::layer_counter::LayerCounter;
use fragsim::schemes::linked_list::{LinkedList, Resolve};
use fragsim::schemes::loop32::Loop32;
use fragsim::schemes::mdts::Mdts;
use proptest::prelude::*;

use crate::support::run_on;

/// A stream of fragments on `pixels` pixels: primitive ids in submission order, depth keys from
/// six values (so that many fragments share one).
#[derive(Clone, Debug)]
struct Stream {
    pixels: usize,
    fragments: Vec<Fragment>,
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "1 to 3 pixels and at most 20 fragments"
)]
fn stream() -> impl Strategy<Value = Stream> {
    (1_usize..=3).prop_flat_map(|pixels| {
        proptest::collection::vec((0..pixels as u32, 0_u32..6), 0..=20).prop_map(move |list| {
            let fragments = list
                .into_iter()
                .enumerate()
                .map(|(prim, (pixel, depth))| Fragment {
                    pixel,
                    depth_key: depth_key(depth as f32 / 8.0).expect("in [0, 1]"),
                    prim: prim as u32,
                })
                .collect();
            Stream { pixels, fragments }
        })
    })
}

/// Submission order (one fragment in flight) or a seeded interleaving.
fn schedule() -> impl Strategy<Value = Schedule> {
    let policy = prop_oneof![
        Just(Policy::Random),
        Just(Policy::Warps),
        (1_u32..=3).prop_map(|depth| Policy::Pct { depth }),
    ];
    prop_oneof![
        1 => Just(serial()),
        3 => (policy, 2_usize..=16, any::<u64>()).prop_map(|(policy, in_flight, seed)| Schedule {
            policy,
            in_flight,
            granularity: Granularity::Fragment,
            seed,
        }),
    ]
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

fn viewport(pixels: usize) -> Viewport {
    Viewport::new(u32::try_from(pixels).expect("1 to 3 pixels"), 1).expect("1 to 3 pixels")
}

fn capture<S: Scheme<Input = Fragment>>(
    scheme: &S,
    stream: &Stream,
    schedule: &Schedule,
) -> Capture {
    run_fragments(scheme, &stream.fragments, schedule, false)
        .run
        .capture
}

/// Whether a depth key among the `k` nearest distinct keys of `list` (canonical order) belongs
/// to two or more fragments.
fn repeats_within_distinct(list: &[u64], k: u32) -> bool {
    let keys: Vec<u64> = list.iter().map(|e| e >> 32).collect();
    let mut distinct = keys.clone();
    distinct.dedup();
    distinct
        .iter()
        .take(k as usize)
        .any(|d| keys.iter().filter(|&&x| x == *d).count() > 1)
}

/// `capture` judged as if it promised the `k` nearest: what a shipping scheme that keeps `k` of
/// a longer list by arrival (within its capacity, by its own promise) departs from on screen.
fn as_nearest(capture: &Capture, k: u32) -> Capture {
    Capture {
        keeps: Keeps::Nearest(k),
        ..capture.clone()
    }
}

/// The oracle's `k` nearest of pixel `p` (the `Promise::Nearest` list).
fn nearest(oracle: &Oracle, p: usize, k: u32) -> &[u64] {
    let all = oracle.pixel(p);
    &all[..all.len().min(k as usize)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// loop32 keeps the `K` nearest distinct depths on every interleaving; canonically it differs
    /// iff a key among them repeats (serially, where the later primitive's colour store wins), and
    /// never without one; FreePipe's MDTS keeps every duplicate.
    #[test]
    fn loop32_differs_iff_a_kept_depth_repeats(
        stream in stream(),
        k in 1_u32..=5,
        schedule in schedule(),
    ) {
        let oracle = Oracle::from_fragments(stream.pixels, &stream.fragments);
        let scheme = Loop32::new(viewport(stream.pixels), k, MEMORY_CAP_DEFAULT).unwrap();
        let got = capture(&scheme, &stream, &schedule);
        prop_assert!(oracle.diff_with(&got, Ties::MergeEqualDepths).is_exact());
        let mut departing = 0;
        for p in 0..stream.pixels {
            let repeats = repeats_within_distinct(oracle.pixel(p), k);
            let differs = got.pixel(p) != nearest(&oracle, p, k);
            if schedule.in_flight == 1 {
                prop_assert_eq!(differs, repeats, "pixel {}", p);
            } else {
                prop_assert!(!differs || repeats, "pixel {} differs with no repeated depth", p);
            }
            departing += u64::from(differs);
        }
        prop_assert_eq!(oracle.diff(&got).mismatched_pixels, departing);
        let mdts = Mdts::<u64>::ascending(viewport(stream.pixels), k).unwrap();
        prop_assert!(oracle.diff(&capture(&mdts, &stream, &schedule)).is_exact());
    }

    /// The layer counter loses exactly `max(0, n − layer_count)` fragments of a pixel of depth
    /// complexity `n`, on every interleaving, and nothing else: within its capacity it is exact
    /// (the oracle supplies the overflow it cannot count), and against the nearest `layer_count`
    /// the pixel differs only if `n > layer_count`. Serially the kept are the first arrivals.
    #[test]
    fn layer_counter_loses_exactly_the_excess(
        stream in stream(),
        layers in 1_u32..=5,
        schedule in schedule(),
    ) {
        let oracle = Oracle::from_fragments(stream.pixels, &stream.fragments);
        let scheme = LayerCounter::new(viewport(stream.pixels), layers, MEMORY_CAP_DEFAULT).unwrap();
        let got = capture(&scheme, &stream, &schedule);
        let diff = oracle.diff(&got);
        let mut excess = 0;
        let mut over = 0;
        for (p, &n) in oracle.depth_complexity().iter().enumerate() {
            excess += u64::from(n.saturating_sub(layers));
            over += u64::from(n > layers);
            prop_assert_eq!(got.pixel(p).len(), n.min(layers) as usize);
            if schedule.in_flight == 1 {
                let mut first: Vec<u64> = stream
                    .fragments
                    .iter()
                    .filter(|f| f.pixel as usize == p)
                    .take(layers as usize)
                    .map(|f| f.packed())
                    .collect();
                first.sort_unstable();
                prop_assert_eq!(got.pixel(p), first.as_slice());
            }
        }
        prop_assert_eq!(
            (diff.overflowed, diff.lost, diff.extra, diff.misordered_pixels),
            (excess, 0, 0, 0)
        );
        prop_assert!(diff.is_exact(), "{:?}", diff);
        let on_screen = oracle.diff(&as_nearest(&got, layers));
        prop_assert!(on_screen.mismatched_pixels <= over);
    }

    /// Keep-first differs in a pixel iff the `N` most recent head exchanges (read from the trace)
    /// are not its `N` nearest; keep-nearest never differs while the pool suffices.
    #[test]
    fn linked_list_keep_first_differs_iff_recent_are_not_nearest(
        stream in stream(),
        n in 1_u32..=5,
        schedule in schedule(),
    ) {
        let oracle = Oracle::from_fragments(stream.pixels, &stream.fragments);
        let pool = stream.fragments.len().max(1);
        let view = viewport(stream.pixels);
        let first = LinkedList::new(view, pool, n, Resolve::KeepFirst, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_fragments(&first, &stream.fragments, &schedule, true);
        let trace = run.trace.expect("recorded");
        let mut departing = 0;
        for p in 0..stream.pixels {
            let mut recent: Vec<u64> = trace
                .events
                .iter()
                .filter(|e| e.op == Op::Swap && e.pixel as usize == p)
                .map(|e| stream.fragments[usize::try_from(e.fragment).expect("one of 20 fragments")].packed())
                .collect();
            recent.reverse();
            recent.truncate(n as usize);
            recent.sort_unstable();
            let differs = run.run.capture.pixel(p) != nearest(&oracle, p, n);
            prop_assert_eq!(differs, recent.as_slice() != nearest(&oracle, p, n), "pixel {}", p);
            departing += u64::from(differs);
        }
        // Within its capacity keep-first is exact; it departs from the nearest `N`.
        prop_assert!(oracle.diff(&run.run.capture).is_exact());
        prop_assert_eq!(
            oracle.diff(&as_nearest(&run.run.capture, n)).mismatched_pixels,
            departing
        );
        let nearest_first =
            LinkedList::new(view, pool, n, Resolve::KeepNearest, MEMORY_CAP_DEFAULT).unwrap();
        prop_assert!(oracle.diff(&capture(&nearest_first, &stream, &schedule)).is_exact());
    }

    /// A pool of `P` nodes loses exactly the fragments past it, whatever the resolve keeps: with
    /// `N` at least every list's length, keep-nearest loses `max(0, fragments − P)`; serially
    /// those are the last submitted.
    #[test]
    fn linked_list_pool_loses_exactly_the_fragments_past_it(
        stream in stream(),
        pool in 1_usize..=24,
        schedule in schedule(),
    ) {
        let oracle = Oracle::from_fragments(stream.pixels, &stream.fragments);
        let scheme = LinkedList::new(
            viewport(stream.pixels), pool, 32, Resolve::KeepNearest, MEMORY_CAP_DEFAULT,
        ).unwrap();
        let run = run_fragments(&scheme, &stream.fragments, &schedule, false).run;
        let past = stream.fragments.len().saturating_sub(pool) as u64;
        let diff = oracle.diff(&run.capture);
        prop_assert_eq!((diff.lost, diff.extra, run.stats.counters.dropped), (past, 0, past));
        if schedule.in_flight == 1 {
            let kept = Oracle::from_fragments(
                stream.pixels,
                &stream.fragments[..stream.fragments.len().min(pool)],
            );
            prop_assert!(kept.diff(&run.capture).is_exact());
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The smallest departures, by hand, and the schemes on every executor on a real scene.

/// Depth key of `d / 8`.
fn key(d: u32) -> u32 {
    depth_key(d as f32 / 8.0).unwrap()
}

fn one_pixel(depths: &[u32]) -> Stream {
    Stream {
        pixels: 1,
        fragments: depths
            .iter()
            .enumerate()
            .map(|(prim, &d)| Fragment {
                pixel: 0,
                depth_key: key(d),
                prim: u32::try_from(prim).expect("a one-pixel list of a few depths"),
            })
            .collect(),
    }
}

/// Two fragments at one depth: loop32 keeps one of them (the later primitive's colour), MDTS
/// keeps both. The same on a mesh: `docs/baselines/shipping-tie.obj`.
#[test]
fn loop32_merges_two_fragments_at_one_depth() {
    let stream = one_pixel(&[1, 1]);
    let packed = |prim: u32| u64::from(key(1)) << 32 | u64::from(prim);
    let loop32 = Loop32::new(viewport(1), 2, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(capture(&loop32, &stream, &serial()).pixel(0), [packed(1)]);
    let mdts = Mdts::<u64>::ascending(viewport(1), 2).unwrap();
    assert_eq!(
        capture(&mdts, &stream, &serial()).pixel(0),
        [packed(0), packed(1)]
    );
}

/// Three fragments, two layers, the nearest arriving last: the layer counter keeps the two
/// farther and loses the nearest.
#[test]
fn layer_counter_loses_the_nearest_arriving_last() {
    let stream = one_pixel(&[3, 2, 1]);
    let scheme = LayerCounter::new(viewport(1), 2, MEMORY_CAP_DEFAULT).unwrap();
    let got = capture(&scheme, &stream, &serial());
    let oracle = Oracle::from_fragments(1, &stream.fragments);
    assert_eq!(got.pixel(0), &oracle.pixel(0)[1..]);
    let diff = oracle.diff(&got);
    assert_eq!(
        (diff.overflowed, diff.lost),
        (1, 0),
        "within its capacity of 2"
    );
    assert_eq!(
        oracle.diff(&as_nearest(&got, 2)).lost,
        1,
        "the nearest is gone"
    );
}

/// Three fragments, `N` = 2, the nearest arriving first: keep-first resolves the two most recent
/// (the farther) and loses it; keep-nearest keeps it.
#[test]
fn linked_list_keep_first_loses_the_nearest_arriving_first() {
    let stream = one_pixel(&[1, 2, 3]);
    let oracle = Oracle::from_fragments(1, &stream.fragments);
    let list = |resolve| LinkedList::new(viewport(1), 3, 2, resolve, MEMORY_CAP_DEFAULT).unwrap();
    let first = capture(&list(Resolve::KeepFirst), &stream, &serial());
    assert_eq!(first.pixel(0), &oracle.pixel(0)[1..]);
    assert!(oracle.diff(&first).is_exact(), "two of three, within N = 2");
    let on_screen = oracle.diff(&as_nearest(&first, 2));
    assert_eq!((on_screen.lost, on_screen.extra), (1, 1));
    let nearest = capture(&list(Resolve::KeepNearest), &stream, &serial());
    assert_eq!(nearest.pixel(0), &oracle.pixel(0)[..2]);
}

/// Every shipping scheme on the serial, parallel, tiled and scheduled executors on the spheres
/// scene:
/// the departures are those the properties pin down.
#[test]
fn shipping_schemes_on_every_executor() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let viewport = Viewport::new(48, 40).unwrap();
    let view = scene.view(viewport, &OrbitCamera::default()).unwrap();
    let oracle = Oracle::build(&view);
    let counts = oracle.depth_complexity();
    let max = oracle.max_depth_complexity();
    assert!(max >= 4, "the scene needs overlap");
    let fragments = oracle.fragments();
    let schedule = Schedule {
        policy: Policy::Random,
        in_flight: 64,
        granularity: Granularity::Fragment,
        seed: 8,
    };
    let layers = max - 2;
    let counter = LayerCounter::new(viewport, layers, MEMORY_CAP_DEFAULT).unwrap();
    let excess: u64 = counts
        .iter()
        .map(|&n| u64::from(n.saturating_sub(layers)))
        .sum();
    let loop32 = Loop32::new(viewport, max, MEMORY_CAP_DEFAULT).unwrap();
    let nearest = LinkedList::new(
        viewport,
        fragments,
        3,
        Resolve::KeepNearest,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    let first = LinkedList::new(
        viewport,
        fragments,
        max,
        Resolve::KeepFirst,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    let captures = |f: &dyn Fn(Executor) -> Capture| Executor::EVERY.map(f);
    for got in captures(&|e| run_on(e, &view, &counter, &schedule).capture) {
        let diff = oracle.diff(&got);
        assert_eq!((diff.overflowed, diff.lost), (excess, 0));
        assert!(diff.is_exact());
    }
    for got in captures(&|e| run_on(e, &view, &loop32, &schedule).capture) {
        assert!(oracle.diff_with(&got, Ties::MergeEqualDepths).is_exact());
    }
    for got in captures(&|e| run_on(e, &view, &nearest, &schedule).capture) {
        assert!(oracle.diff(&got).is_exact());
    }
    // N = the maximum depth complexity: every list fits, keep-first is exact too.
    for got in captures(&|e| run_on(e, &view, &first, &schedule).capture) {
        assert!(oracle.diff(&got).is_exact());
    }
}

/// `fragsim render` on `args` (no images, JSON): per row, (scheme, executor, overflowed, lost,
/// mismatches).
fn render_rows(args: &[&str]) -> Vec<(String, String, u64, u64, u64)> {
    let output = assert_cmd::Command::cargo_bin("fragsim")
        .unwrap()
        .args(["--no-images", "--json"])
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{args:?}: {stderr}");
    let rows = crate::support::json_lines(&output.stdout);
    rows.iter()
        .map(|r| {
            let number = |key: &str| r[key].as_u64().unwrap();
            (
                r["scheme"].as_str().unwrap().into(),
                r["executor"].as_str().unwrap().into(),
                number("overflowed"),
                number("lost"),
                number("mismatched_pixels"),
            )
        })
        .collect()
}

/// The smallest scenes' commands of `docs/baselines/shipping.md` print what the docs say, on
/// every executor they name.
#[test]
fn smallest_scenes_through_the_command_line() {
    let tie = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/baselines/shipping-tie.obj"
    );
    let one_pixel = ["--width", "1", "--height", "1", "--elevation", "0"];
    let run = |extra: &[&str]| render_rows(&[&one_pixel[..], extra].concat());
    for (scheme, executor, _, lost, mismatches) in run(&[
        "--mesh",
        tie,
        "--view",
        "0",
        "--k",
        "3",
        "--scheme",
        "mdts,loop32",
        "--executor",
        "all",
    ]) {
        let expected = if scheme == "loop32" { 1 } else { 0 };
        assert_eq!(
            (lost, mismatches),
            (expected, expected),
            "{scheme} {executor}"
        );
    }
    let merged = run(&[
        "--mesh",
        tie,
        "--view",
        "0",
        "--k",
        "3",
        "--scheme",
        "loop32",
        "--executor",
        Executor::Scheduled.name(),
        "--ties",
        "merge-equal-depths",
    ]);
    let scheduled = Executor::Scheduled.name().to_string();
    assert_eq!(merged, [("loop32".into(), scheduled, 0, 0, 0)]);
    let counter = run(&[
        "--scene",
        "quads:3",
        "--view",
        "0",
        "--k",
        "2",
        "--scheme",
        "layer-counter",
        "--executor",
        Executor::Serial.name(),
    ]);
    // One fragment past its 2 layers: overflow the scheme cannot count, supplied by the oracle.
    assert_eq!(
        counter,
        [(
            "layer-counter".into(),
            Executor::Serial.name().into(),
            1,
            0,
            0
        )]
    );
    let lists = run(&[
        "--scene",
        "quads:3",
        "--view",
        "180",
        "--k",
        "2",
        "--scheme",
        "linked-list,linked-list-nearest",
        "--executor",
        Executor::Serial.name(),
    ]);
    assert_eq!(
        lists,
        [
            (
                "linked-list".into(),
                Executor::Serial.name().into(),
                1,
                0,
                0
            ),
            (
                "linked-list-nearest".into(),
                Executor::Serial.name().into(),
                1,
                0,
                0
            )
        ]
    );
}
