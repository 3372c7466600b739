//! The acceptance check of the core: on the embedded default scene, both schemes on both
//! executors equal the serial oracle fragment for fragment.

use fragsim::capture::abuffer::{ABuffer, PostSort};
use fragsim::capture::executor::{run_parallel, run_serial};
use fragsim::capture::mdts::{Direction, Mdts};
use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, Viewport};

#[test]
fn bunny_both_schemes_both_executors_equal_the_oracle() {
    let scene = Scene::default_scene();
    let view = scene
        .view(
            Viewport::new(256, 256).unwrap(),
            &OrbitCamera::default().at_angle(30.0),
        )
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    assert!(k >= 4, "the bunny has several layers somewhere, got {k}");
    let mdts = Mdts::<u64>::ascending(view.viewport(), k).unwrap();
    let abuffer = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Bitonic,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    for run in [run_serial(&view, &mdts), run_parallel(&view, &mdts)] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(run.stats.counters.fragments as usize, oracle.fragments());
        assert_eq!(diff.captured as usize, oracle.fragments());
    }
    for run in [run_serial(&view, &abuffer), run_parallel(&view, &abuffer)] {
        let diff = oracle.diff(&run.capture);
        assert!(diff.is_exact(), "{diff:?}");
        assert_eq!(diff.captured as usize, oracle.fragments());
    }
    // With fewer slots than layers MDTS keeps exactly the nearest K, and says how many it dropped.
    let shallow =
        Mdts::<u32>::new(view.viewport(), 2, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_parallel(&view, &shallow);
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!(diff.overflowed, run.stats.counters.dropped);
    assert!(diff.overflowed > 0);
    let descending = Mdts::<u64>::new(
        view.viewport(),
        3,
        Direction::Descending,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    let diff = oracle.diff(&run_parallel(&view, &descending).capture);
    assert!(diff.is_exact(), "{diff:?}");
}
