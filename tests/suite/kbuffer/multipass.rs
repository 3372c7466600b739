//! The multi-pass k-buffer: exact serially with its output predicted pass by pass, and exact
//! under interleavings in at least the serial passes, paying for hazards with passes.

use fragsim::capture::executors::run_serial;
use fragsim::capture::executors::scheduled::run_scheduled;
use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::SerialMemory;
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, SplitMix64, View};
use fragsim::schemes::kbuffer::multipass::KBufferMultipass;
use fragsim::schemes::kbuffer::WriteBack;

use super::{
    bunny_256_scheduled, captured_now, drive_pass, fragments, head_on, viewport, MACHINES,
};

/// What the test predicts from the oracle's per-pixel counts alone: a pixel of `n` fragments is
/// complete after `⌈n / K⌉` passes (at least 1), and after `j` passes its output holds all `n`
/// when `n ≤ j K`, else the `(j − 1) K` nearest (the last pass's `K` wait for the next pass's
/// count to confirm them).
fn output_after_passes(n: u32, k: u32, j: u32) -> u32 {
    if n <= j * k {
        n
    } else {
        (j - 1) * k
    }
}

/// The serial pass count predicted from per-pixel counts: the largest `⌈n / K⌉`, at least 1.
pub(super) fn serial_passes(oracle: &Oracle, k: u32) -> u32 {
    oracle
        .depth_complexity()
        .iter()
        .map(|&n| n.div_ceil(k))
        .max()
        .unwrap_or(0)
        .max(1)
}

fn multipass(view: &View<'_>, k: u32, layers: u32, write_back: WriteBack) -> KBufferMultipass {
    KBufferMultipass::with_write_back(view.viewport(), k, layers, write_back, MEMORY_CAP_DEFAULT)
        .unwrap()
}

#[test]
fn multipass_kbuffer_is_exact_serially_with_the_output_predicted_pass_by_pass() {
    let bunny = Scene::default_scene();
    let quads8 = Scene::procedural("quads:8").unwrap();
    let quads9 = Scene::procedural("quads:9").unwrap();
    let bunny_view = bunny
        .view(viewport(96, 96), &OrbitCamera::default())
        .unwrap();
    let quads8_view = quads8.view(viewport(8, 8), &head_on()).unwrap();
    let quads9_view = quads9.view(viewport(8, 8), &head_on()).unwrap();
    for (view, ks) in [
        (&bunny_view, &[1_u32, 4, 7][..]),
        (&quads8_view, &[4, 3, 8][..]),
        (&quads9_view, &[4, 9, 10][..]),
    ] {
        let oracle = Oracle::build(view);
        let counts = oracle.depth_complexity();
        let d = oracle.max_depth_complexity();
        let all = fragments(view);
        for &k in ks {
            for write_back in MACHINES {
                let scheme = multipass(view, k, d, write_back);
                let run = run_serial(view, &scheme);
                let diff = oracle.diff(&run.capture);
                assert!(diff.is_exact(), "k = {k}: {diff:?}");
                assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
                assert_eq!(run.stats.passes, serial_passes(&oracle, k), "k = {k}");
                assert_eq!(run.stats.counters.dropped, 0);
                // Pass by pass, in submission order, each pixel's output as predicted.
                let memory: SerialMemory = scheme.layout().allocate();
                let mut pass = 0;
                loop {
                    let more = drive_pass(&scheme, &memory, pass, &all, |_| 0);
                    pass += 1;
                    for (p, &n) in counts.iter().enumerate() {
                        assert_eq!(
                            u32::try_from(captured_now(&scheme, &memory, p))
                                .expect("at most k fragments"),
                            output_after_passes(n, k, pass),
                            "pixel {p} of {n} fragments after {pass} passes, K = {k}"
                        );
                    }
                    if !more {
                        break;
                    }
                }
                assert_eq!(pass, run.stats.passes);
            }
        }
    }
}

#[test]
fn multipass_under_random_interleavings_is_exact_in_at_least_the_serial_passes() {
    let spheres = Scene::procedural("spheres:2").unwrap();
    let quads = Scene::procedural("quads:7").unwrap();
    let views = [
        spheres
            .view(viewport(16, 16), &OrbitCamera::default())
            .unwrap(),
        quads.view(viewport(4, 4), &head_on()).unwrap(),
    ];
    let mut extra_passes = 0;
    for view in &views {
        let oracle = Oracle::build(view);
        let d = oracle.max_depth_complexity();
        let all = fragments(view);
        for (k, seed) in [(2, 1), (3, 2), (2, 3), (4, 4)] {
            for write_back in MACHINES {
                let scheme = multipass(view, k, d, write_back);
                let memory: SerialMemory = scheme.layout().allocate();
                let mut rng = SplitMix64::new(seed);
                let pixels = view.viewport().pixels();
                let mut before = vec![0_usize; pixels];
                let mut pass = 0;
                loop {
                    // Every walk of the pass in flight at once, stepped in random order.
                    let more = drive_pass(&scheme, &memory, pass, &all, |n| {
                        usize::try_from(rng.next_u64() % n as u64).expect("below n")
                    });
                    pass += 1;
                    for (p, seen) in before.iter_mut().enumerate() {
                        // The output only grows: nothing output is ever taken back.
                        let now = captured_now(&scheme, &memory, p);
                        assert!(now >= *seen, "pixel {p} shrank in pass {pass}");
                        *seen = now;
                    }
                    if !more {
                        break;
                    }
                    assert!(
                        pass <= 2 * d + 1,
                        "more than 2 D + 1 = {} passes",
                        2 * d + 1
                    );
                }
                let diff = oracle.diff(&scheme.resolve(&memory));
                assert!(diff.is_exact(), "k = {k}, {write_back:?}: {diff:?}");
                let serial = serial_passes(&oracle, k);
                assert!(
                    pass >= serial,
                    "{pass} passes, fewer than serially ({serial})"
                );
                extra_passes += pass - serial;
            }
        }
    }
    // The interleavings do hit hazards: some run pays for them with passes.
    assert!(extra_passes > 0);
}

#[test]
fn multipass_under_lockstep_pays_for_the_hazards_with_passes_and_loses_nothing() {
    let scene = Scene::procedural("quads:6").unwrap();
    let view = scene.view(viewport(4, 4), &head_on()).unwrap();
    let oracle = Oracle::build(&view);
    let all = fragments(&view);
    for write_back in MACHINES {
        let scheme = multipass(&view, 2, 6, write_back);
        let memory: SerialMemory = scheme.layout().allocate();
        // Round-robin lockstep: every walk reads before any writes, so each pass captures one
        // fragment per pixel and the counts reject the rest.
        let mut turn = 0;
        let mut passes = 0;
        while drive_pass(&scheme, &memory, passes, &all, |n| {
            turn = (turn + 1) % n;
            turn
        }) {
            passes += 1;
        }
        passes += 1;
        let diff = oracle.diff(&scheme.resolve(&memory));
        assert!(diff.is_exact(), "{write_back:?}: {diff:?}");
        assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
        let serial = serial_passes(&oracle, 2);
        assert_eq!(serial, 3);
        assert!(passes > serial, "{write_back:?}: {passes} passes");
    }
}

#[test]
fn multipass_on_the_bunny_under_the_scheduled_executor_loses_nothing_in_at_least_the_serial_passes()
{
    let (scene, schedule) = bunny_256_scheduled();
    let view = scene
        .view(viewport(256, 256), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let d = oracle.max_depth_complexity();
    for k in [2, 4, 8] {
        let serial = serial_passes(&oracle, k);
        for write_back in MACHINES {
            let scheme = multipass(&view, k, d, write_back);
            assert_eq!(run_serial(&view, &scheme).stats.passes, serial);
            let run = run_scheduled(&view, &scheme, &schedule, false).run;
            let diff = oracle.diff(&run.capture);
            eprintln!(
                "K = {k}, {write_back:?}: {} passes (serially {serial}), {diff:?}",
                run.stats.passes
            );
            assert!(diff.is_exact(), "K = {k}, {write_back:?}: {diff:?}");
            assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
            assert!(run.stats.passes >= serial, "K = {k}, {write_back:?}");
            assert!(run.stats.passes <= 2 * d + 1, "K = {k}, {write_back:?}");
        }
    }
}
