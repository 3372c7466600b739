//! What the three schemes share: losses on random soups are exactly the bucket overflows, captures
//! do not depend on the schedule, memory is the documented accounting, and bad parameters are errors.

use fragsim::capture::executors::run_serial;
use fragsim::capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::{CaptureError, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::bucket::{Adp, Bdp, Bdp2, Buckets, ADP_SUBINTERVALS};
use proptest::prelude::*;

use super::{honest, predicted_loss};

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// On random triangle soups, every scheme loses exactly what its buckets cannot hold: all but
    /// the min and max (BDP pairs), the two smallest and two largest (BDP2), the largest (BDP
    /// singles, ADP per 1/1024 subinterval) of each bucket's distinct values.
    #[test]
    fn losses_are_exactly_the_bucket_overflows_on_random_soups(
        count in 50_u32..600,
        seed in any::<u64>(),
        side in 8_u32..40,
        angle in 0.0_f64..360.0,
    ) {
        let scene = Scene::procedural(&format!("soup:{count}:{seed}")).unwrap();
        let view = scene
            .view(Viewport::new(side, side).unwrap(), &OrbitCamera::default().at_angle(angle))
            .unwrap();
        let oracle = Oracle::build(&view);
        let vp = view.viewport();
        let depth = oracle.max_depth_complexity().max(1);
        let cases = [
            (run_serial(&view, &Bdp::<u32>::pairs(vp).unwrap()), 16, 2, true),
            (run_serial(&view, &Bdp::<u64>::singles(vp).unwrap()), 32, 1, false),
            (run_serial(&view, &Bdp2::<u32>::paper(vp).unwrap()), 16, 4, true),
            (run_serial(&view, &Adp::<u64>::for_depth(vp, depth).unwrap()), ADP_SUBINTERVALS, 1, false),
            (run_serial(&view, &Adp::<u32>::for_depth(vp, depth).unwrap()), ADP_SUBINTERVALS, 1, true),
        ];
        for (run, buckets, keeps, key_only) in cases {
            let diff = honest(&oracle, &run, "soup");
            prop_assert_eq!(diff.lost, predicted_loss(&oracle, buckets, keeps, key_only).0);
            prop_assert_eq!(diff.overflowed, 0);
        }
    }
}

#[test]
fn captures_do_not_depend_on_the_schedule() {
    // A random triangle soup: uneven layers, collisions in every scheme.
    let scene = Scene::procedural("soup:600:7").unwrap();
    let view = scene
        .view(Viewport::new(24, 24).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let schedules = [
        (Policy::Random, 97, Granularity::Fragment, 1),
        (Policy::Warps, 64, Granularity::Triangle, 2),
        (Policy::Pct { depth: 3 }, 300, Granularity::Fragment, 3),
    ]
    .map(|(policy, in_flight, granularity, seed)| Schedule {
        policy,
        in_flight,
        granularity,
        seed,
    });
    fn check<S: Scheme>(view: &View<'_>, scheme: &S, schedules: &[Schedule]) {
        let reference = run_serial(view, scheme).capture;
        for schedule in schedules {
            let run = run_scheduled(view, scheme, schedule, false).run;
            assert_eq!(
                run.capture,
                reference,
                "{} under {schedule:?}",
                scheme.name()
            );
        }
    }
    let vp = view.viewport();
    check(&view, &Bdp::<u32>::pairs(vp).unwrap(), &schedules);
    check(&view, &Bdp::<u64>::singles(vp).unwrap(), &schedules);
    check(&view, &Bdp2::<u32>::paper(vp).unwrap(), &schedules);
    let adp = Adp::<u32>::for_depth(vp, oracle.max_depth_complexity()).unwrap();
    check(&view, &adp, &schedules);
    for capture in [
        run_serial(&view, &Bdp2::<u32>::paper(vp).unwrap()).capture,
        run_serial(&view, &adp).capture,
    ] {
        let diff = oracle.diff(&capture);
        assert!(
            diff.lost > 0,
            "the scene must collide for the check to mean anything"
        );
    }
}

#[test]
fn memory_per_pixel_is_the_documented_accounting() {
    let vp = Viewport::new(512, 512).unwrap();
    let per_pixel = |bytes: u64| bytes / vp.pixels() as u64;
    assert_eq!(
        per_pixel(Bdp::<u32>::pairs(vp).unwrap().layout().bytes()),
        136
    );
    assert_eq!(
        per_pixel(Bdp::<u32>::singles(vp).unwrap().layout().bytes()),
        136
    );
    assert_eq!(
        per_pixel(Bdp::<u64>::pairs(vp).unwrap().layout().bytes()),
        264
    );
    assert_eq!(
        per_pixel(Bdp2::<u32>::paper(vp).unwrap().layout().bytes()),
        264
    );
    assert_eq!(
        per_pixel(Adp::<u32>::for_depth(vp, 20).unwrap().layout().bytes()),
        300
    );
    assert_eq!(
        per_pixel(Adp::<u32>::for_depth(vp, 64).unwrap().layout().bytes()),
        8 + 128 + 132 + 256
    );
}

#[test]
fn bad_parameters_and_too_much_memory_are_errors() {
    let vp = Viewport::new(64, 64).unwrap();
    for result in [
        Bdp::<u32>::new(vp, Buckets::Pairs(0), MEMORY_CAP_DEFAULT).map(|_| ()),
        Bdp::<u32>::new(vp, Buckets::Singles(0), MEMORY_CAP_DEFAULT).map(|_| ()),
        Bdp2::<u32>::new(vp, 0, MEMORY_CAP_DEFAULT).map(|_| ()),
        Adp::<u32>::new(vp, 0, MEMORY_CAP_DEFAULT).map(|_| ()),
    ] {
        assert!(
            matches!(result, Err(CaptureError::BadParameter(_))),
            "{result:?}"
        );
    }
    let big = Viewport::new(16384, 16384).unwrap();
    for result in [
        Bdp::<u64>::new(big, Buckets::Pairs(u32::MAX), MEMORY_CAP_DEFAULT).map(|_| ()),
        Bdp2::<u32>::new(vp, 16, 1000).map(|_| ()),
        Adp::<u64>::new(big, 1 << 20, MEMORY_CAP_DEFAULT).map(|_| ()),
    ] {
        assert!(
            matches!(result, Err(CaptureError::TooMuchMemory { .. })),
            "{result:?}"
        );
    }
}
