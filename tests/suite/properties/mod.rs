//! Property tests of the whole system on random scenes, cameras, viewports and `K`: the FreePipe
//! schemes against the serial oracle on the parallel executor, serial against parallel and tiled, fragment
//! counts, crack-free coverage of closed meshes and planar tilings, and the depth-key order.
//!
//! The strategies live in `crates/testkit` (`fragsim_testkit::strategies`) for any suite to reuse. Case counts are
//! sized so the whole file runs in well under a minute in release on two cores. Failures are not
//! persisted to disk: a failing case found here is recorded below as an explicit regression test.

use fragsim::capture::depth_count::{DepthCount, DepthCounts};
use fragsim::capture::executors::{ParallelExecutor, Run};
use fragsim::capture::{Keeps, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::oracle::Oracle;
use fragsim::raster::{CullMode, OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::mdts::{Direction, Mdts, MdtsWord};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use crate::support::strategies::{identity_camera, Concurrency, GeneratedScene, PlanarTiling};

mod coverage;
mod executors;

/// A config with `cases` cases (or `PROPTEST_CASES` when set, for a longer run) and no failure
/// file (this suite records its regressions as tests).
fn config(cases: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    ProptestConfig {
        cases,
        failure_persistence: None,
        // Shrinking rebuilds scenes: bound it so that a failure is reported in reasonable time.
        max_shrink_time: 120_000,
        ..ProptestConfig::default()
    }
}

/// Runs MDTS over words `W` in `direction` with `k` slots under `concurrency` (the parallel
/// executor with small tasks, the scheduled executor) and checks it against the oracle: exactly
/// the promised `K` nearest (farthest) fragments in canonical order, and the fragments beyond `K`
/// are exactly the ones the executor counted as dropped.
fn check_mdts_concurrent<W: MdtsWord>(
    view: &View<'_>,
    oracle: &Oracle,
    k: u32,
    direction: Direction,
    concurrency: &Concurrency,
) -> Result<(), TestCaseError> {
    let plain = Mdts::<W>::new(view.viewport(), k, direction, MEMORY_CAP_DEFAULT).unwrap();
    let beyond: u64 = oracle
        .depth_complexity()
        .iter()
        .map(|&n| u64::from(n.saturating_sub(k)))
        .sum();
    // The probing walk must give the very same lists.
    for scheme in [plain.clone(), plain.probing()] {
        for (how, run) in concurrency.runs(view, &scheme) {
            let diff = oracle.diff(&run.capture);
            let name = scheme.name();
            prop_assert!(diff.is_exact(), "{name} K={k} {how}: {diff:?}");
            prop_assert_eq!(
                run.stats.counters.dropped,
                beyond,
                "{} K={} {}",
                name,
                k,
                how
            );
        }
    }
    Ok(())
}

/// The sum of a fixed A-buffer's per-pixel overflow counts.
fn total_overflow(run: &Run) -> u64 {
    match &run.capture.keeps {
        Keeps::All { overflow, .. } => overflow.iter().map(|&o| u64::from(o)).sum(),
        other => panic!("the A-buffer promises all fragments, got {other:?}"),
    }
}

/// The per-pixel counts of the scheme's own counting pass, run under `concurrency`'s parallel
/// executor (what sizes an exact A-buffer; never the oracle's counts).
fn counted(view: &View<'_>, concurrency: &Concurrency) -> Vec<u32> {
    let count = DepthCount::new(view.viewport());
    DepthCounts::from_run(ParallelExecutor::with_task_size(concurrency.task_size).run(view, &count))
        .counts
}

/// Builds the scene of `spec` and its oracle, and calls `check` with the view.
fn with_view(
    spec: &GeneratedScene,
    viewport: Viewport,
    camera: &OrbitCamera,
    check: impl FnOnce(&View<'_>, &Oracle) -> Result<(), TestCaseError>,
) -> Result<(), TestCaseError> {
    let scene: Scene = spec.scene();
    let view = scene.view(viewport, camera).unwrap();
    let oracle = Oracle::build(&view);
    check(&view, &oracle)
}

/// Fragments per pixel, counted straight from the rasterizer.
fn coverage(view: &View<'_>) -> Vec<u32> {
    let mut counts = vec![0_u32; view.viewport().pixels()];
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| counts[f.pixel as usize] += 1);
    }
    counts
}

/// The pixels (index, count) covered an odd number of times, first few.
fn odd_pixels(counts: &[u32]) -> Vec<(usize, u32)> {
    counts
        .iter()
        .enumerate()
        .filter(|(_, &c)| c % 2 == 1)
        .map(|(p, &c)| (p, c))
        .take(8)
        .collect()
}

/// Checks that the planar tiling covers every pixel centre of its snapped rectangle exactly once
/// and nothing else.
fn check_tiling(viewport: Viewport, tiling: &PlanarTiling) -> Result<(), TestCaseError> {
    let view = View::new(&tiling.mesh, &identity_camera(), viewport, CullMode::None);
    let got = coverage(&view);
    let expected = tiling.expected_coverage(viewport);
    let wrong: Vec<(u32, u32, u32, u32)> = (0..got.len())
        .filter(|&p| got[p] != expected[p])
        .map(|p| {
            let index = u32::try_from(p).expect("a pixel of a test viewport");
            let (x, y) = (index % viewport.width, index / viewport.width);
            (x, y, expected[p], got[p])
        })
        .take(8)
        .collect();
    prop_assert!(
        wrong.is_empty(),
        "(x, y, expected, got) at the first wrong pixels: {:?}",
        wrong
    );
    Ok(())
}
