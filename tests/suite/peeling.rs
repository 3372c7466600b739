//! The peeling baselines and the z-buffer against the oracle: depth peeling and dual depth peeling
//! with packed words are exact fragment for fragment on every executor, with depth-key words they
//! lose exactly the fragments that share a depth with another (the classical merge), their pass
//! counts are the layer counts the papers give, and overflowing storage is counted, not hidden.

use fragsim::capture::executors::scheduled::{
    run_fragments, run_scheduled, Granularity, Policy, Schedule,
};
use fragsim::capture::executors::{run_parallel, run_serial, Run};
use fragsim::capture::{CaptureError, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::Layout;
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::dual_peeling::DualDepthPeeling;
use fragsim::schemes::peeling::DepthPeeling;
use fragsim::schemes::zbuffer::ZBuffer;
use proptest::prelude::*;

/// How many of pixel `p`'s fragments share their depth key with the fragment before them in
/// canonical order: what merging equal depths loses there.
fn equal_depth_duplicates_at(oracle: &Oracle, p: usize) -> u32 {
    let list = oracle.pixel(p);
    let duplicates = list.windows(2).filter(|w| w[0] >> 32 == w[1] >> 32).count();
    u32::try_from(duplicates).expect("a test view's depth complexity")
}

/// What merging equal depths loses over the whole view.
fn equal_depth_duplicates(oracle: &Oracle) -> u64 {
    (0..oracle.pixels())
        .map(|p| u64::from(equal_depth_duplicates_at(oracle, p)))
        .sum()
}

/// The largest number of distinct depth keys at any pixel: the layers of depth-key peeling.
fn max_distinct_depths(oracle: &Oracle) -> u32 {
    (0..oracle.pixels())
        .map(|p| {
            let fragments =
                u32::try_from(oracle.pixel(p).len()).expect("a test view's depth complexity");
            fragments - equal_depth_duplicates_at(oracle, p)
        })
        .max()
        .unwrap_or(0)
}

/// Depth peeling's passes: one per layer, and the one that finds nothing.
fn peeling_passes(layers: u32) -> u32 {
    layers + 1
}

/// Dual depth peeling's passes: one per pair of layers, and the one that finds nothing.
fn dual_passes(layers: u32) -> u32 {
    layers.div_ceil(2) + 1
}

/// Checks one run of a packed-word (`u64`) scheme: exact, every fragment kept, the expected number
/// of passes, and every pass a full geometry pass.
fn assert_exact(oracle: &Oracle, run: &Run, passes: u32) {
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!(diff.overflowed, 0, "nothing overflows");
    assert_eq!(run.stats.passes, passes, "the passes the layers need");
    let counters = run.stats.counters;
    assert_eq!(
        counters.fragments,
        u64::from(passes) * oracle.fragments() as u64,
        "every pass sees every fragment"
    );
    assert_eq!(counters.dropped, 0, "peeling drops nothing");
    assert_eq!(
        counters.stored + counters.discarded,
        counters.fragments,
        "each fragment of a pass is stored or discarded"
    );
}

/// Checks one run of a depth-key (`u32`) scheme: exactly the equal-depth duplicates are lost,
/// nothing else is wrong, and it takes one pass per distinct depth layer (dual: per pair).
fn assert_merges_equal_depths(oracle: &Oracle, run: &Run, passes: u32) {
    let diff = oracle.diff(&run.capture);
    assert_eq!(diff.lost, equal_depth_duplicates(oracle), "{diff:?}");
    assert_eq!(
        (diff.extra, diff.misordered_pixels, diff.overflowed),
        (0, 0, 0),
        "nothing extra, misordered or overflowed: {diff:?}"
    );
    assert_eq!(run.stats.passes, passes, "the passes the layers need");
}

/// `scheme` on `view` with the serial executor and, if asked, the parallel one.
fn runs<S: Scheme>(view: &View<'_>, scheme: &S, parallel: bool) -> Vec<Run> {
    let mut runs = vec![run_serial(view, scheme)];
    if parallel {
        runs.push(run_parallel(view, scheme));
    }
    runs
}

/// Runs every scheme of this file on `view` and checks each against the oracle; returns the
/// scene's maximum depth complexity.
fn check_every_scheme(view: &View<'_>, parallel: bool) -> u32 {
    let oracle = Oracle::build(view);
    let n = oracle.max_depth_complexity();
    let distinct = max_distinct_depths(&oracle);
    let viewport = view.viewport();
    let peel = DepthPeeling::<u64>::with_layers(viewport, n).unwrap();
    for run in runs(view, &peel, parallel) {
        assert_exact(&oracle, &run, peeling_passes(n));
    }
    let dual = DualDepthPeeling::<u64>::with_layers(viewport, n).unwrap();
    for run in runs(view, &dual, parallel) {
        assert_exact(&oracle, &run, dual_passes(n));
    }
    let peel32 = DepthPeeling::<u32>::with_layers(viewport, n).unwrap();
    for run in runs(view, &peel32, parallel) {
        assert_merges_equal_depths(&oracle, &run, peeling_passes(distinct));
    }
    let dual32 = DualDepthPeeling::<u32>::with_layers(viewport, n).unwrap();
    for run in runs(view, &dual32, parallel) {
        assert_merges_equal_depths(&oracle, &run, dual_passes(distinct));
    }
    let zbuffer = ZBuffer::for_viewport(viewport).unwrap();
    for run in runs(view, &zbuffer, parallel) {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(run.stats.passes, 1, "one pass");
        assert_eq!(
            run.stats.counters.steps,
            oracle.fragments() as u64,
            "one step per fragment"
        );
    }
    n
}

fn view_of(scene: &Scene, width: u32, height: u32, angle: f64) -> View<'_> {
    scene
        .view(
            Viewport::new(width, height).unwrap(),
            &OrbitCamera::default().at_angle(angle),
        )
        .unwrap()
}

#[test]
fn every_exact_scheme_equals_the_oracle_on_the_bunny() {
    let scene = Scene::default_scene();
    let n = check_every_scheme(&view_of(&scene, 256, 256, 0.0), true);
    assert!(n >= 4, "the bunny has several layers somewhere, got {n}");
}

#[test]
fn every_exact_scheme_equals_the_oracle_on_nested_spheres_and_soups() {
    for (spec, angle) in [
        ("spheres:4", 0.0),
        ("spheres:7", 40.0),
        ("soup:200:1", 10.0),
        ("soup:120:9", 200.0),
    ] {
        let scene = Scene::procedural(spec).unwrap();
        let n = check_every_scheme(&view_of(&scene, 96, 80, angle), true);
        assert!(n >= 2, "{spec}: at least two layers somewhere, got {n}");
    }
}

fn random_scene() -> impl Strategy<Value = String> {
    prop_oneof![
        (1_u32..5).prop_map(|n| format!("spheres:{n}")),
        (1_u32..300, any::<u64>()).prop_map(|(count, seed)| format!("soup:{count}:{}", seed | 1)),
        (1_u32..9).prop_map(|n| format!("quads:{n}")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Peeling and dual peeling (both word widths) and the z-buffer on random small scenes, views
    /// and viewports: packed words exact, depth keys lose exactly the equal-depth duplicates, pass
    /// counts as derived.
    #[test]
    fn peeling_schemes_match_the_oracle_on_random_scenes(
        spec in random_scene(),
        width in 16_u32..48,
        height in 16_u32..48,
        angle in 0.0_f64..360.0,
        parallel in any::<bool>(),
    ) {
        let scene = Scene::procedural(&spec).unwrap();
        check_every_scheme(&view_of(&scene, width, height, angle), parallel);
    }

    /// Any interleaving of the fragments' steps gives the same capture: each step is one atomic
    /// operation and a pass only needs per-location atomicity.
    #[test]
    fn peeling_is_exact_under_every_schedule(
        policy in prop_oneof![Just(Policy::Random), Just(Policy::Warps), (1_u32..4).prop_map(|depth| Policy::Pct { depth })],
        in_flight in prop_oneof![Just(1_usize), Just(32), 2_usize..300],
        seed in any::<u64>(),
        spheres in 1_u32..4,
    ) {
        let scene = Scene::procedural(&format!("spheres:{spheres}")).unwrap();
        let view = view_of(&scene, 24, 24, 30.0);
        let oracle = Oracle::build(&view);
        let n = oracle.max_depth_complexity();
        let schedule = Schedule { policy, in_flight, granularity: Granularity::Fragment, seed };
        let peel = DepthPeeling::<u64>::with_layers(view.viewport(), n).unwrap();
        let dual = DualDepthPeeling::<u64>::with_layers(view.viewport(), n).unwrap();
        let zbuffer = ZBuffer::for_viewport(view.viewport()).unwrap();
        assert_exact(&oracle, &run_scheduled(&view, &peel, &schedule, false).run, peeling_passes(n));
        assert_exact(&oracle, &run_scheduled(&view, &dual, &schedule, false).run, dual_passes(n));
        let diff = oracle.diff(&run_scheduled(&view, &zbuffer, &schedule, false).run.capture);
        prop_assert!(diff.is_exact(), "{schedule:?}: {diff:?}");
    }
}

fn fragment(prim: u32, depth: f32) -> Fragment {
    Fragment {
        pixel: 0,
        depth_key: depth_key(depth).unwrap(),
        prim,
    }
}

fn key(depth: f32) -> u64 {
    u64::from(depth_key(depth).unwrap()) << 32
}

/// Runs `scheme` on a hand-made fragment list under several interleavings; every one must give
/// the same single-pixel list and pass count, which are returned.
fn run_by_hand<S: Scheme<Input = Fragment>>(scheme: &S, fragments: &[Fragment]) -> (Vec<u64>, u32) {
    let mut result = None;
    for seed in 0..8 {
        let schedule = Schedule {
            policy: Policy::Random,
            in_flight: 1 + usize::try_from(seed % 3).expect("below 3"),
            granularity: Granularity::Fragment,
            seed,
        };
        let run = run_fragments(scheme, fragments, &schedule, false).run;
        let got = (run.capture.pixel(0).to_vec(), run.stats.passes);
        assert_eq!(
            *result.get_or_insert_with(|| got.clone()),
            got,
            "{schedule:?}"
        );
    }
    result.unwrap()
}

#[test]
fn coincident_fragments_merge_with_depth_keys_and_stay_apart_with_packed_words() {
    let one_pixel = Viewport::new(1, 1).unwrap();
    let peel32 = DepthPeeling::<u32>::with_layers(one_pixel, 4).unwrap();
    let dual32 = DualDepthPeeling::<u32>::with_layers(one_pixel, 4).unwrap();
    let peel = DepthPeeling::<u64>::with_layers(one_pixel, 4).unwrap();
    let dual = DualDepthPeeling::<u64>::with_layers(one_pixel, 4).unwrap();
    // Two coincident fragments in front, then one behind; in the reverse arrival order too.
    let front = [fragment(7, 0.25), fragment(3, 0.25), fragment(1, 0.5)];
    let mut reversed = front;
    reversed.reverse();
    for fragments in [front, reversed] {
        // Depth keys: the pair is one layer, peeled away together; two layers, three passes.
        assert_eq!(
            run_by_hand(&peel32, &fragments),
            (vec![key(0.25), key(0.5)], 3)
        );
        assert_eq!(
            run_by_hand(&dual32, &fragments),
            (vec![key(0.25), key(0.5)], 2)
        );
        // Packed words: three layers, in canonical order (the lower primitive id first).
        let all = vec![key(0.25) | 3, key(0.25) | 7, key(0.5) | 1];
        assert_eq!(run_by_hand(&peel, &fragments), (all.clone(), 4));
        assert_eq!(run_by_hand(&dual, &fragments), (all, 3));
    }
    // Dual peeling merges a coincident pair at the far bound as well as at the near one, and a
    // pixel whose fragments all coincide is one layer.
    let back = [fragment(1, 0.25), fragment(7, 0.5), fragment(3, 0.5)];
    assert_eq!(run_by_hand(&dual32, &back), (vec![key(0.25), key(0.5)], 2));
    assert_eq!(
        run_by_hand(&dual, &back).0,
        vec![key(0.25) | 1, key(0.5) | 3, key(0.5) | 7]
    );
    let same = [fragment(2, 0.75), fragment(9, 0.75), fragment(4, 0.75)];
    assert_eq!(run_by_hand(&dual32, &same), (vec![key(0.75)], 2));
    assert_eq!(run_by_hand(&peel32, &same), (vec![key(0.75)], 2));
    assert_eq!(
        run_by_hand(&dual, &same),
        (vec![key(0.75) | 2, key(0.75) | 4, key(0.75) | 9], 3)
    );
}

#[test]
fn duplicated_triangles_are_reported_lost_by_depth_key_peeling_and_kept_by_packed_words() {
    // Four stacked squares, the first square's two triangles listed twice: identical fragments.
    let mut scene = Scene::procedural("quads:4").unwrap();
    let first_square = scene.mesh.triangles[..2].to_vec();
    scene.mesh.triangles.extend(first_square);
    let view = view_of(&scene, 32, 32, 20.0);
    let oracle = Oracle::build(&view);
    let duplicates = equal_depth_duplicates(&oracle);
    let mut covered_by_the_square = 0;
    for prim in 0..2 {
        view.rasterize(prim, &mut |_| covered_by_the_square += 1);
    }
    assert!(covered_by_the_square > 0);
    assert_eq!(duplicates, covered_by_the_square);
    let n = oracle.max_depth_complexity();
    let viewport = view.viewport();
    let peel32 = run_parallel(
        &view,
        &DepthPeeling::<u32>::with_layers(viewport, n).unwrap(),
    );
    let dual32 = run_parallel(
        &view,
        &DualDepthPeeling::<u32>::with_layers(viewport, n).unwrap(),
    );
    for run in [&peel32, &dual32] {
        let diff = oracle.diff(&run.capture);
        assert_eq!(diff.lost, covered_by_the_square, "{diff:?}");
    }
    assert_exact(
        &oracle,
        &run_parallel(
            &view,
            &DepthPeeling::<u64>::with_layers(viewport, n).unwrap(),
        ),
        peeling_passes(n),
    );
    assert_exact(
        &oracle,
        &run_parallel(
            &view,
            &DualDepthPeeling::<u64>::with_layers(viewport, n).unwrap(),
        ),
        dual_passes(n),
    );
}

/// How many of a pixel's layers (nearest first) a scheme keeps at the front and at the back.
type KeptEnds = dyn Fn(usize) -> (usize, usize);

#[test]
fn layers_beyond_storage_are_counted_as_overflow_and_the_kept_ones_are_the_right_ones() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = view_of(&scene, 48, 48, 0.0);
    let oracle = Oracle::build(&view);
    let n = oracle.max_depth_complexity();
    assert_eq!(n, 6);
    let viewport = view.viewport();
    for layers in 1..=n {
        // Depth peeling keeps the nearest `layers`; dual peeling fills its slots from both ends.
        let peel_keeps = move |count: usize| (count.min(layers as usize), 0);
        let dual_keeps = move |count: usize| {
            let front = count.div_ceil(2).min((layers as usize).div_ceil(2));
            let back = (count / 2).min(layers as usize / 2);
            (front, back)
        };
        let peel = DepthPeeling::<u64>::with_layers(viewport, layers).unwrap();
        let dual = DualDepthPeeling::<u64>::with_layers(viewport, layers).unwrap();
        let runs: [(Run, &KeptEnds, u32); 2] = [
            (run_parallel(&view, &peel), &peel_keeps, peeling_passes(n)),
            (run_parallel(&view, &dual), &dual_keeps, dual_passes(n)),
        ];
        for (run, keeps, passes) in runs {
            let diff = oracle.diff(&run.capture);
            assert!(diff.is_exact(), "{layers} layers: {diff:?}");
            // Peeling goes on to the end, so the count of what did not fit is exact.
            assert_eq!(run.stats.passes, passes);
            let mut overflow = 0;
            for p in 0..oracle.pixels() {
                let all = oracle.pixel(p);
                let (front, back) = keeps(all.len());
                let expected: Vec<u64> = all[..front]
                    .iter()
                    .chain(&all[all.len() - back..])
                    .copied()
                    .collect();
                assert_eq!(run.capture.pixel(p), expected, "{layers} layers, pixel {p}");
                overflow += (all.len() - front - back) as u64;
            }
            assert_eq!(diff.overflowed, overflow);
            assert_eq!(overflow > 0, layers < n);
        }
    }
}

/// Builds a scheme within a memory cap: its name and layout.
type Build = Box<dyn Fn(u64) -> Result<(String, Layout), CaptureError>>;

#[test]
fn zero_layers_or_too_much_memory_is_an_error() {
    let viewport = Viewport::new(64, 32).unwrap();
    let bad =
        |result: Result<(), CaptureError>| matches!(result, Err(CaptureError::BadParameter(_)));
    assert!(bad(DepthPeeling::<u64>::with_layers(viewport, 0).map(drop)));
    assert!(bad(DepthPeeling::<u32>::with_layers(viewport, 0).map(drop)));
    assert!(bad(
        DualDepthPeeling::<u64>::with_layers(viewport, 0).map(drop)
    ));
    assert!(bad(
        DualDepthPeeling::<u32>::with_layers(viewport, 0).map(drop)
    ));
    let pixels = viewport.pixels() as u64;
    // Bytes per pixel as documented: working words, output slots, a 4-byte overflow counter.
    let cases: [(u64, Build); 5] = [
        (
            (2 + 5) * 8 + 4,
            Box::new(move |cap| {
                DepthPeeling::<u64>::new(viewport, 5, cap).map(|s| (s.name(), s.layout()))
            }),
        ),
        (
            (2 + 5) * 4 + 4,
            Box::new(move |cap| {
                DepthPeeling::<u32>::new(viewport, 5, cap).map(|s| (s.name(), s.layout()))
            }),
        ),
        (
            (4 + 5) * 8 + 4,
            Box::new(move |cap| {
                DualDepthPeeling::<u64>::new(viewport, 5, cap).map(|s| (s.name(), s.layout()))
            }),
        ),
        (
            (4 + 5) * 4 + 4,
            Box::new(move |cap| {
                DualDepthPeeling::<u32>::new(viewport, 5, cap).map(|s| (s.name(), s.layout()))
            }),
        ),
        (
            8,
            Box::new(move |cap| ZBuffer::new(viewport, cap).map(|s| (s.name(), s.layout()))),
        ),
    ];
    let mut names = Vec::new();
    for (bytes_per_pixel, build) in cases {
        let (name, layout) = build(MEMORY_CAP_DEFAULT).unwrap();
        assert_eq!(layout.bytes(), bytes_per_pixel * pixels, "{name}");
        // The cap refuses at build what is allocated before any fragment (the page tables);
        // the pages are checked as a frame writes them.
        let least = layout.least_bytes();
        assert!(build(least).is_ok(), "{name}");
        match build(least - 1) {
            Err(CaptureError::TooMuchMemory { needed: n, cap, .. }) => {
                assert_eq!((n, cap), (least, least - 1));
            }
            other => panic!("expected TooMuchMemory, got {other:?}"),
        }
        names.push(name);
    }
    assert_eq!(
        names,
        [
            "peeling",
            "peeling32",
            "dual-peeling",
            "dual-peeling32",
            "zbuffer"
        ]
    );
    assert!(DepthPeeling::<u64>::new(viewport, u32::MAX, MEMORY_CAP_DEFAULT).is_err());
}
