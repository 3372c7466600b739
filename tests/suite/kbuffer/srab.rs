//! The stencil-routed A-buffer: exact up to 8 fragments a pass, the rest counted as overflow;
//! its second pass wrong when it sees another order.

use fragsim::capture::executors::{run_parallel, run_serial};
use fragsim::capture::{Keeps, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::SerialMemory;
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene};
use fragsim::schemes::stencil_routed::StencilRouted;

use super::{drive_pass, head_on, one_pixel_quads, viewport};

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
                assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
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
            assert_eq!(run.capture.pixel(p).len(), n.min(8) as usize, "pixel {p}");
        }
    }
    // A second geometry pass routes the ninth; on the serial executor it is exact.
    let two = StencilRouted::new(view.viewport(), 2, MEMORY_CAP_DEFAULT).unwrap();
    let run = run_serial(&view, &two);
    let diff = oracle.diff(&run.capture);
    assert!(diff.is_exact(), "{diff:?}");
    assert_eq!((diff.overflowed, run.stats.passes), (0, 2));
    assert_eq!(usize::try_from(diff.captured), Ok(oracle.fragments()));
    // One spelling whatever the passes: the catalog's.
    assert_eq!((srab.name(), two.name()), ("srab".into(), "srab".into()));
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
