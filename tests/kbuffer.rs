//! The k-buffer family and the stencil-routed A-buffer against the oracle: the k-buffer exact up
//! to K serially and visibly wrong under hand-driven interleavings; the multi-pass k-buffer exact
//! serially, with progress but not completeness under hazards; the stencil-routed A-buffer exact up
//! to 8 fragments a pass, counting the rest as overflow.

use fragsim::capture::executor::{run_parallel, run_serial};
use fragsim::capture::kbuffer::KBuffer;
use fragsim::capture::kbuffer_multipass::KBufferMultipass;
use fragsim::capture::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::stencil_routed::StencilRouted;
use fragsim::capture::{CaptureError, Keeps, Scheme, SerialMemory, Step, MEMORY_CAP_DEFAULT};
use fragsim::oracle::Oracle;
use fragsim::raster::{Fragment, OrbitCamera, Scene, SplitMix64, View, Viewport};
use proptest::prelude::*;

/// Looking straight down the z axis at `quads:N`: every pixel the quads cover has N fragments.
fn head_on() -> OrbitCamera {
    OrbitCamera {
        elevation_degrees: 0.0,
        ..OrbitCamera::default()
    }
}

fn viewport(width: u32, height: u32) -> Viewport {
    Viewport::new(width, height).unwrap()
}

/// The view's fragments in submission order.
fn fragments(view: &View<'_>) -> Vec<Fragment> {
    let mut all = Vec::new();
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| all.push(f));
    }
    all
}

/// The fragments of pixel 0 of a 1×1 view of `quads:n` seen head-on, nearest first.
fn one_pixel_quads(scene: &Scene) -> (View<'_>, Vec<Fragment>) {
    let view = scene.view(viewport(1, 1), &head_on()).unwrap();
    let mut list = fragments(&view);
    list.sort_by_key(|f| f.packed());
    (view, list)
}

/// Runs a hand-written interleaving: `script[i]` names the fragment whose walk takes the i-th
/// step. Every walk must be over when the script ends.
fn drive<S: Scheme>(scheme: &S, memory: &SerialMemory, walks: &[Fragment], script: &[usize]) {
    let mut states: Vec<Option<S::State>> = walks.iter().map(|&f| Some(scheme.begin(f))).collect();
    for &w in script {
        let state = states[w]
            .as_mut()
            .expect("the script steps a finished walk");
        if scheme.step(state, memory) != Step::Continue {
            states[w] = None;
        }
    }
    assert!(
        states.iter().all(Option::is_none),
        "the script left a walk unfinished"
    );
}

/// Runs one pass of a multi-pass scheme over `all`, interleaving the walks as `pick` chooses among
/// the unfinished ones, then the between-pass kernel; returns whether another pass is needed.
fn drive_pass<S: Scheme>(
    scheme: &S,
    memory: &SerialMemory,
    pass: u32,
    all: &[Fragment],
    mut pick: impl FnMut(usize) -> usize,
) -> bool {
    let mut states: Vec<S::State> = all
        .iter()
        .filter_map(|&f| scheme.begin_pass(pass, f))
        .collect();
    while !states.is_empty() {
        let i = pick(states.len());
        if scheme.step(&mut states[i], memory) != Step::Continue {
            states.swap_remove(i);
        }
    }
    scheme.end_pass(pass, memory)
}

/// How many fragments pixel `p`'s resolve reports now.
fn captured_now<S: Scheme>(scheme: &S, memory: &SerialMemory, p: usize) -> usize {
    let mut out = Vec::new();
    scheme.resolve_pixel(memory, p, &mut out);
    out.len()
}

// ---------------------------------------------------------------- k-buffer

#[test]
fn serial_kbuffer_equals_the_oracle_up_to_k_on_real_scenes() {
    let bunny = Scene::default_scene();
    let spheres = Scene::procedural("spheres:3").unwrap();
    for (scene, size, angle) in [
        (&bunny, 96, 30.0),
        (&spheres, 32, 0.0),
        (&spheres, 24, 75.0),
    ] {
        let view = scene
            .view(
                viewport(size, size),
                &OrbitCamera::default().at_angle(angle),
            )
            .unwrap();
        let oracle = Oracle::build(&view);
        let d = oracle.max_depth_complexity();
        for k in [1, 3, d] {
            let scheme = KBuffer::with_k(view.viewport(), k).unwrap();
            let run = run_serial(&view, &scheme);
            let diff = oracle.diff(&run.capture);
            assert!(diff.is_exact(), "k = {k}: {diff:?}");
            assert_eq!(diff.overflowed, run.stats.counters.dropped, "k = {k}");
            assert_eq!(run.capture.keeps, Keeps::Nearest(k));
            assert_eq!(run.stats.passes, 1);
        }
    }
}

#[test]
fn interleaved_read_insert_write_loses_a_fragment() {
    let scene = Scene::procedural("quads:2").unwrap();
    let (view, frags) = one_pixel_quads(&scene);
    assert_eq!(frags.len(), 2);
    let scheme = KBuffer::with_k(view.viewport(), 2).unwrap();
    let memory: SerialMemory = scheme.layout().allocate();
    let (near, far) = (0, 1);
    // Both read the empty slots before either writes; the later write-back, [far, empty],
    // overwrites [near, empty].
    drive(
        &scheme,
        &memory,
        &frags,
        &[near, near, far, far, near, near, far, far],
    );
    let capture = scheme.resolve(&memory);
    assert_eq!(capture.pixel(0), &[frags[far].packed()]);
    let diff = Oracle::build(&view).diff(&capture);
    assert_eq!(
        (diff.lost, diff.extra, diff.overflowed),
        (1, 0, 0),
        "{diff:?}"
    );
}

#[test]
fn interleaved_write_backs_duplicate_a_fragment() {
    let scene = Scene::procedural("quads:3").unwrap();
    let (view, frags) = one_pixel_quads(&scene);
    let (near, mid, far) = (0, 1, 2);
    let scheme = KBuffer::with_k(view.viewport(), 2).unwrap();
    let memory: SerialMemory = scheme.layout().allocate();
    // mid alone: [mid, -]. near and far both read [mid, -]: near will write [near, mid], far
    // [mid, far]. near's slot 0, far's slot 0, far's slot 1, near's slot 1: [mid, mid].
    let script = [
        mid, mid, mid, mid, near, near, far, far, near, far, far, near,
    ];
    drive(&scheme, &memory, &frags, &script);
    let capture = scheme.resolve(&memory);
    assert_eq!(
        capture.pixel(0),
        &[frags[mid].packed(), frags[mid].packed()]
    );
    let diff = Oracle::build(&view).diff(&capture);
    // The oracle's nearest two are [near, mid]: near is lost, mid's second copy is extra.
    assert_eq!(
        (diff.lost, diff.extra, diff.overflowed),
        (1, 1, 1),
        "{diff:?}"
    );
}

#[test]
fn a_stale_write_back_leaves_the_slots_out_of_order() {
    let scene = Scene::procedural("quads:3").unwrap();
    let (view, frags) = one_pixel_quads(&scene);
    let (near, mid, far) = (0, 1, 2);
    let scheme = KBuffer::with_k(view.viewport(), 2).unwrap();
    let memory: SerialMemory = scheme.layout().allocate();
    // far reads [-, -]; mid inserts alone: [mid, -]; near reads it. far writes [far, -] over
    // near's slot 0, near's slot 1 is mid: [far, mid].
    let script = [
        far, far, mid, mid, mid, mid, near, near, near, far, far, near,
    ];
    drive(&scheme, &memory, &frags, &script);
    let capture = scheme.resolve(&memory);
    assert_eq!(
        capture.pixel(0),
        &[frags[far].packed(), frags[mid].packed()]
    );
    let diff = Oracle::build(&view).diff(&capture);
    assert_eq!(
        (diff.lost, diff.extra, diff.misordered_pixels),
        (1, 1, 1),
        "{diff:?}"
    );
}

#[test]
fn kbuffer_under_lockstep_warps_loses_fragments_and_the_diff_says_so() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene
        .view(viewport(24, 24), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let schedule = Schedule {
        policy: Policy::Warps,
        in_flight: 1024,
        granularity: Granularity::Fragment,
        seed: 1,
    };
    let kbuffer = KBuffer::with_k(view.viewport(), oracle.max_depth_complexity()).unwrap();
    let diff = oracle.diff(&run_scheduled(&view, &kbuffer, &schedule, false).run.capture);
    assert!(diff.lost > 0 && diff.mismatched_pixels > 0, "{diff:?}");
    // The same schedule cannot hurt the atomic stencil routing.
    let srab = StencilRouted::single_pass(view.viewport()).unwrap();
    let diff = oracle.diff(&run_scheduled(&view, &srab, &schedule, false).run.capture);
    assert!(diff.is_exact(), "{diff:?}");
}

// ---------------------------------------------------------------- multi-pass k-buffer

/// `⌊D / K⌋ + 1`: the last pass finds some pixel's slot K − 1 empty.
fn expected_passes(max_depth_complexity: u32, k: u32) -> u32 {
    max_depth_complexity / k + 1
}

#[test]
fn multipass_kbuffer_is_exact_serially_in_floor_d_over_k_plus_one_passes() {
    let bunny = Scene::default_scene();
    let quads8 = Scene::procedural("quads:8").unwrap();
    let quads9 = Scene::procedural("quads:9").unwrap();
    let bunny_view = bunny
        .view(viewport(96, 96), &OrbitCamera::default())
        .unwrap();
    let quads8_view = quads8.view(viewport(8, 8), &head_on()).unwrap();
    let quads9_view = quads9.view(viewport(8, 8), &head_on()).unwrap();
    for (view, ks) in [
        (&bunny_view, &[1u32, 4, 7][..]),
        (&quads8_view, &[4, 3, 8][..]),
        (&quads9_view, &[4, 9, 10][..]),
    ] {
        let oracle = Oracle::build(view);
        let d = oracle.max_depth_complexity();
        for &k in ks {
            let scheme = KBufferMultipass::new(view.viewport(), k, d, MEMORY_CAP_DEFAULT).unwrap();
            let run = run_serial(view, &scheme);
            let diff = oracle.diff(&run.capture);
            assert!(diff.is_exact(), "k = {k}: {diff:?}");
            assert_eq!(diff.captured as usize, oracle.fragments());
            assert_eq!(run.stats.passes, expected_passes(d, k), "k = {k}, D = {d}");
            assert_eq!(run.stats.counters.dropped, 0);
        }
    }
    // Named cases: 9 layers, K = 4: 4 + 4 + 1. 8 layers, K = 4: 4 + 4, then a pass to learn it.
    assert_eq!(expected_passes(9, 4), 3);
    assert_eq!(expected_passes(8, 4), 3);
}

#[test]
fn multipass_captures_at_least_one_more_fragment_per_incomplete_pixel_each_pass_under_hazards() {
    let spheres = Scene::procedural("spheres:2").unwrap();
    let quads = Scene::procedural("quads:7").unwrap();
    let views = [
        spheres
            .view(viewport(16, 16), &OrbitCamera::default())
            .unwrap(),
        quads.view(viewport(4, 4), &head_on()).unwrap(),
    ];
    for view in &views {
        let oracle = Oracle::build(view);
        let d = oracle.max_depth_complexity();
        let all = fragments(view);
        for (k, seed) in [(2, 1), (3, 2), (2, 3), (4, 4)] {
            let scheme = KBufferMultipass::new(view.viewport(), k, d, MEMORY_CAP_DEFAULT).unwrap();
            let memory: SerialMemory = scheme.layout().allocate();
            let mut rng = SplitMix64::new(seed);
            let pixels = view.viewport().pixels();
            let mut before = vec![0usize; pixels];
            let mut stopped = vec![false; pixels];
            let mut pass = 0;
            loop {
                // Every walk of the pass in flight at once, stepped in random order.
                let more = drive_pass(&scheme, &memory, pass, &all, |n| {
                    (rng.next_u64() % n as u64) as usize
                });
                for p in 0..pixels {
                    let now = captured_now(&scheme, &memory, p);
                    let gained = now - before[p];
                    if pass == 0 && !oracle.pixel(p).is_empty() {
                        assert!(gained >= 1, "pixel {p} captured nothing in the first pass");
                    }
                    // Progress: a pixel gains at least one fragment every pass until it gains
                    // none, which marks it complete; it never gains again.
                    assert!(
                        !(stopped[p] && gained > 0),
                        "pixel {p} resumed in pass {pass}"
                    );
                    stopped[p] |= gained == 0;
                    before[p] = now;
                }
                pass += 1;
                if !more {
                    break;
                }
                assert!(pass <= d + 1, "more than D + 1 = {} passes", d + 1);
            }
            assert!(pass <= d + 1);
        }
    }
}

#[test]
fn multipass_under_lockstep_loses_fragments_for_good_and_the_diff_says_so() {
    let scene = Scene::procedural("quads:6").unwrap();
    let view = scene.view(viewport(4, 4), &head_on()).unwrap();
    let oracle = Oracle::build(&view);
    let all = fragments(&view);
    let scheme = KBufferMultipass::new(view.viewport(), 2, 6, MEMORY_CAP_DEFAULT).unwrap();
    let memory: SerialMemory = scheme.layout().allocate();
    let mut passes = 0;
    // Round-robin lockstep: every walk reads before any writes, so each pixel's last writer
    // leaves [itself, empty]: the pixel looks complete after one pass with one fragment of six.
    let mut turn = 0;
    while drive_pass(&scheme, &memory, passes, &all, |n| {
        turn = (turn + 1) % n;
        turn
    }) {
        passes += 1;
    }
    passes += 1;
    let diff = oracle.diff(&scheme.resolve(&memory));
    assert_eq!(passes, 1);
    let covered = (0..oracle.pixels())
        .filter(|&p| !oracle.pixel(p).is_empty())
        .count() as u64;
    assert!(covered > 0);
    assert_eq!(
        (diff.captured, diff.lost, diff.extra),
        (covered, 5 * covered, 0),
        "{diff:?}"
    );
}

// ---------------------------------------------------------------- stencil-routed A-buffer

#[test]
fn srab_equals_the_oracle_where_depth_complexity_is_at_most_8() {
    let spheres = Scene::procedural("spheres:3").unwrap();
    let quads = Scene::procedural("quads:8").unwrap();
    for view in [
        spheres
            .view(viewport(32, 32), &OrbitCamera::default().at_angle(40.0))
            .unwrap(),
        quads.view(viewport(8, 8), &head_on()).unwrap(),
    ] {
        let oracle = Oracle::build(&view);
        assert!(oracle.max_depth_complexity() <= 8);
        for passes in [1, 2] {
            let srab = StencilRouted::new(view.viewport(), passes, MEMORY_CAP_DEFAULT).unwrap();
            for run in [run_serial(&view, &srab), run_parallel(&view, &srab)] {
                let diff = oracle.diff(&run.capture);
                assert!(diff.is_exact(), "{diff:?}");
                assert_eq!((diff.overflowed, run.stats.passes), (0, 1));
                assert_eq!(diff.captured as usize, oracle.fragments());
            }
        }
    }
}

#[test]
fn srab_reports_exactly_the_ninth_fragment_as_overflow() {
    let scene = Scene::procedural("quads:9").unwrap();
    let view = scene.view(viewport(8, 8), &head_on()).unwrap();
    let oracle = Oracle::build(&view);
    let complexity = oracle.depth_complexity();
    let nine = complexity.iter().filter(|&&n| n == 9).count() as u64;
    assert!(nine > 0 && oracle.max_depth_complexity() == 9);
    let srab = StencilRouted::single_pass(view.viewport()).unwrap();
    for run in [run_serial(&view, &srab), run_parallel(&view, &srab)] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(diff.overflowed, nine);
        assert_eq!(run.stats.counters.dropped, nine);
        assert_eq!(run.stats.passes, 1);
        let Keeps::All { overflow, .. } = &run.capture.keeps else {
            panic!("the stencil-routed A-buffer promises all fragments but the overflow");
        };
        for (p, &n) in complexity.iter().enumerate() {
            assert_eq!(overflow[p], n.saturating_sub(8), "pixel {p}");
            assert_eq!(run.capture.pixel(p).len() as u32, n.min(8), "pixel {p}");
        }
    }
    // A second geometry pass routes the ninth; on the serial executor it is exact.
    let two = StencilRouted::new(view.viewport(), 2, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_serial(&view, &two);
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!((diff.overflowed, run.stats.passes), (0, 2));
    assert_eq!(diff.captured as usize, oracle.fragments());
    assert_eq!(
        (srab.name(), two.name()),
        ("srab".to_string(), "srab-2pass".to_string())
    );
}

#[test]
fn two_pass_srab_duplicates_and_loses_when_the_second_pass_sees_another_order() {
    let scene = Scene::procedural("quads:9").unwrap();
    let (view, frags) = one_pixel_quads(&scene);
    assert_eq!(frags.len(), 9);
    let srab = StencilRouted::new(view.viewport(), 2, MEMORY_CAP_DEFAULT).unwrap();
    let memory: SerialMemory = srab.layout().allocate();
    // Pass 0 in one order, pass 1 in the reverse: the GPU's per-pixel API order would forbid it,
    // unordered threads do not.
    assert!(drive_pass(&srab, &memory, 0, &frags, |_| 0));
    let mut reversed = frags.clone();
    reversed.reverse();
    assert!(!drive_pass(&srab, &memory, 1, &reversed, |_| 0));
    let diff = Oracle::build(&view).diff(&srab.resolve(&memory));
    assert_eq!(
        (diff.lost, diff.extra, diff.overflowed),
        (1, 1, 0),
        "{diff:?}"
    );
}

// ---------------------------------------------------------------- constructors

#[test]
fn constructors_reject_k_zero_no_passes_and_too_much_memory() {
    let v = viewport(64, 64);
    let bad = |e: Result<(), CaptureError>| matches!(e, Err(CaptureError::BadParameter(_)));
    assert!(bad(KBuffer::with_k(v, 0).map(drop)));
    assert!(bad(
        KBufferMultipass::new(v, 0, 4, MEMORY_CAP_DEFAULT).map(drop)
    ));
    assert!(bad(StencilRouted::new(v, 0, MEMORY_CAP_DEFAULT).map(drop)));
    let too_much =
        |e: Result<(), CaptureError>| matches!(e, Err(CaptureError::TooMuchMemory { .. }));
    // 4,096 pixels: 8 slots of 8 bytes are 256 KiB; the output list counts too.
    assert!(KBuffer::new(v, 8, 256 << 10).is_ok());
    assert!(too_much(KBuffer::new(v, 8, (256 << 10) - 1).map(drop)));
    assert!(KBufferMultipass::new(v, 8, 0, 4096 * (64 + 8 + 4)).is_ok());
    assert!(too_much(
        KBufferMultipass::new(v, 8, 1, 4096 * (64 + 8 + 4)).map(drop)
    ));
    assert!(too_much(StencilRouted::new(v, 2, 4096 * 132 - 1).map(drop)));
    assert!(StencilRouted::new(v, 2, 4096 * 132).is_ok());
}

// ---------------------------------------------------------------- random scenes

fn scene_name() -> impl Strategy<Value = String> {
    prop_oneof![
        (1u32..4).prop_map(|n| format!("spheres:{n}")),
        (1u32..120, any::<u64>()).prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        (1u32..20).prop_map(|n| format!("quads:{n}")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Serially, the k-buffer keeps exactly the K nearest, the multi-pass k-buffer every fragment
    /// in ⌊D/K⌋ + 1 passes, and the stencil-routed A-buffer all but the counted overflow.
    #[test]
    fn serial_kbuffers_and_srab_keep_what_they_promise_on_random_scenes(
        name in scene_name(),
        width in 3u32..24,
        height in 3u32..24,
        angle in 0.0f64..360.0,
        k in 1u32..6,
        srab_passes in 1u32..4,
    ) {
        let scene = Scene::procedural(&name).unwrap();
        let view = scene.view(viewport(width, height), &OrbitCamera::default().at_angle(angle)).unwrap();
        let oracle = Oracle::build(&view);
        let d = oracle.max_depth_complexity();

        let kbuffer = KBuffer::with_k(view.viewport(), k).unwrap();
        let run = run_serial(&view, &kbuffer);
        let diff = oracle.diff(&run.capture);
        prop_assert!(diff.is_exact(), "kbuffer: {diff:?}");
        prop_assert_eq!(diff.overflowed, run.stats.counters.dropped);

        let multipass = KBufferMultipass::new(view.viewport(), k, d, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_serial(&view, &multipass);
        let diff = oracle.diff(&run.capture);
        prop_assert!(diff.is_exact(), "multipass: {diff:?}");
        prop_assert_eq!(diff.captured as usize, oracle.fragments());
        prop_assert_eq!(run.stats.passes, expected_passes(d, k));

        let srab = StencilRouted::new(view.viewport(), srab_passes, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_serial(&view, &srab);
        let diff = oracle.diff(&run.capture);
        prop_assert!(diff.is_exact(), "srab: {diff:?}");
        let capacity = 8 * srab_passes;
        let overflow: u64 = oracle.depth_complexity().iter().map(|&n| u64::from(n.saturating_sub(capacity))).sum();
        prop_assert_eq!(diff.overflowed, overflow);
        prop_assert_eq!(run.stats.counters.dropped, overflow);
        prop_assert_eq!(run.stats.passes, srab_passes.min(d.div_ceil(8).max(1)));
    }
}

/// Measurements for `docs/baselines/kbuffer.md`:
/// `cargo test --release --test kbuffer -- --ignored --nocapture`.
#[test]
#[ignore = "measurement for the docs, not a check"]
fn measure_hazards_and_passes_on_the_bunny() {
    let scene = Scene::default_scene();
    let view = scene
        .view(viewport(512, 512), &OrbitCamera::default().at_angle(90.0))
        .unwrap();
    let oracle = Oracle::build(&view);
    let d = oracle.max_depth_complexity();
    let covered = (0..oracle.pixels())
        .filter(|&p| !oracle.pixel(p).is_empty())
        .count();
    println!(
        "bunny 512x512 at 90°: {} fragments, {covered} covered pixels, D = {d}",
        oracle.fragments()
    );
    let report = |label: &str, run: &fragsim::capture::executor::Run| {
        let diff = oracle.diff(&run.capture);
        println!(
            "{label:<32} passes {:>2}  overflowed {:>5}  lost {:>6}  extra {:>5}  misordered px {:>5}  error px {:>5} ({:.2}% of covered)  {:.1} MiB",
            run.stats.passes,
            diff.overflowed,
            diff.lost,
            diff.extra,
            diff.misordered_pixels,
            diff.mismatched_pixels,
            100.0 * diff.mismatched_pixels as f64 / covered as f64,
            run.stats.memory_bytes as f64 / f64::from(1 << 20),
        );
    };
    let warps = Schedule {
        policy: Policy::Warps,
        in_flight: 4096,
        granularity: Granularity::Triangle,
        seed: 1,
    };
    for k in [8, d] {
        let kbuffer = KBuffer::with_k(view.viewport(), k).unwrap();
        report(
            &format!("kbuffer K={k} serial"),
            &run_serial(&view, &kbuffer),
        );
        report(
            &format!("kbuffer K={k} parallel"),
            &run_parallel(&view, &kbuffer),
        );
        report(
            &format!("kbuffer K={k} warps 4096 tri"),
            &run_scheduled(&view, &kbuffer, &warps, false).run,
        );
        let multipass = KBufferMultipass::new(view.viewport(), k, d, MEMORY_CAP_DEFAULT).unwrap();
        report(
            &format!("multipass K={k} serial"),
            &run_serial(&view, &multipass),
        );
        report(
            &format!("multipass K={k} parallel"),
            &run_parallel(&view, &multipass),
        );
        report(
            &format!("multipass K={k} warps 4096 tri"),
            &run_scheduled(&view, &multipass, &warps, false).run,
        );
    }
    for passes in [1, 2] {
        let srab = StencilRouted::new(view.viewport(), passes, MEMORY_CAP_DEFAULT).unwrap();
        report(
            &format!("srab {passes} pass(es) serial"),
            &run_serial(&view, &srab),
        );
        report(
            &format!("srab {passes} pass(es) parallel"),
            &run_parallel(&view, &srab),
        );
        report(
            &format!("srab {passes} pass(es) warps 4096 tri"),
            &run_scheduled(&view, &srab, &warps, false).run,
        );
    }
}
