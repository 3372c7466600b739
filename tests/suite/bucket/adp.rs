//! ADP: exact when layers are farther apart than a subinterval, merging closer ones, and counting
//! storage below the depth complexity as overflow.

use fragsim::capture::executors::run_parallel;
use fragsim::oracle::Oracle;
use fragsim::raster::{Mesh, Scene};
use fragsim::schemes::bucket::{Adp, ADP_SUBINTERVALS};

use super::{both, honest, predicted_loss, view_of};

/// Four head-on quads at z = 1, 0.5 + `gap`, 0.5 and 0: the middle two are `gap` apart.
fn close_pair_scene(gap: f32) -> Scene {
    let mut mesh = Mesh::default();
    for (q, z) in [1.0, 0.5 + gap, 0.5, 0.0].into_iter().enumerate() {
        let base = 4 * u32::try_from(q).expect("four quads");
        mesh.positions.extend([
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ]);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }
    Scene {
        name: format!("close pair {gap}"),
        mesh,
    }
}

#[test]
fn adp_is_exact_when_layers_are_farther_apart_than_a_subinterval() {
    for quads in [16_u32, 40, 64] {
        let scene = Scene::procedural(&format!("quads:{quads}")).unwrap();
        let view = view_of(&scene, 32);
        let oracle = Oracle::build(&view);
        assert_eq!(predicted_loss(&oracle, ADP_SUBINTERVALS, 1, false).1, 1);
        let adp = Adp::<u64>::for_depth(view.viewport(), oracle.max_depth_complexity()).unwrap();
        for run in both(&view, &adp) {
            let diff = oracle.diff(&run.capture);
            assert!(diff.is_exact(), "quads:{quads}: {diff:?}");
            assert_eq!(diff.overflowed, 0);
            // Range, histogram, then one routing pass per batch of 32 layers.
            assert_eq!(run.stats.passes, 2 + quads.div_ceil(32), "quads:{quads}");
        }
    }
    // Layers 0.001 apart in model space (about 1/1011 of the widest pixel range in depth: just
    // over one of its 1024 subintervals) are still told apart.
    let scene = close_pair_scene(1e-3);
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    assert_eq!(predicted_loss(&oracle, ADP_SUBINTERVALS, 1, false), (0, 1));
    let adp = Adp::<u64>::for_depth(view.viewport(), 4).unwrap();
    assert!(oracle.diff(&both(&view, &adp)[1].capture).is_exact());
}

#[test]
fn adp_merges_two_layers_closer_than_a_subinterval_keeping_the_farther() {
    let scene = close_pair_scene(1e-5);
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    let (predicted, most) = predicted_loss(&oracle, ADP_SUBINTERVALS, 1, false);
    // Every pixel that sees both middle quads sees them in one subinterval.
    let both_middle = (0..oracle.pixels())
        .filter(|&p| {
            let quads: Vec<u64> = oracle
                .pixel(p)
                .iter()
                .map(|e| (e & 0xFFFF_FFFF) / 2)
                .collect();
            quads.contains(&1) && quads.contains(&2)
        })
        .count() as u64;
    assert!(both_middle > 0);
    assert_eq!((predicted, most), (both_middle, 2));
    let adp = Adp::<u64>::for_depth(view.viewport(), 4).unwrap();
    for run in both(&view, &adp) {
        let diff = honest(&oracle, &run, "adp");
        assert_eq!(diff.lost, predicted);
        assert_eq!(diff.overflowed, 0);
        // The nearer of the pair (quad 1, triangles 2 and 3) is the one lost: MAX keeps the
        // farther depth (quad 2, triangles 4 and 5).
        for mismatch in &diff.first_mismatches {
            let prims =
                |list: &[u64]| -> Vec<u64> { list.iter().map(|e| e & 0xFFFF_FFFF).collect() };
            let missing: Vec<u64> = prims(&mismatch.expected)
                .into_iter()
                .filter(|p| !prims(&mismatch.got).contains(p))
                .collect();
            assert!(
                missing.len() == 1 && (missing[0] == 2 || missing[0] == 3),
                "{mismatch:?}"
            );
        }
    }
}

#[test]
fn adp_storage_below_the_depth_complexity_is_counted_as_overflow_not_hidden() {
    let scene = Scene::procedural("quads:40").unwrap();
    let view = view_of(&scene, 32);
    let oracle = Oracle::build(&view);
    let expected_overflow: u64 = oracle
        .depth_complexity()
        .iter()
        .map(|&n| u64::from(n.saturating_sub(10)))
        .sum();
    let adp = Adp::<u32>::for_depth(view.viewport(), 10).unwrap();
    for run in both(&view, &adp) {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(diff.overflowed, expected_overflow);
        assert!(expected_overflow > 0);
        assert_eq!(run.stats.passes, 3, "10 buckets: one batch");
    }
    // 33 buckets: the second batch holds one layer, the rest overflows.
    let adp33 = Adp::<u32>::for_depth(view.viewport(), 33).unwrap();
    let run = run_parallel(&view, &adp33);
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!(run.stats.passes, 4);
    assert_eq!(
        diff.overflowed,
        oracle
            .depth_complexity()
            .iter()
            .map(|&n| u64::from(n.saturating_sub(33)))
            .sum::<u64>()
    );
}
