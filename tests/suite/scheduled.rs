//! The scheduled executor: atomic schemes give the oracle's answer under every policy, width and
//! seed; runs are pure functions of the schedule; traces record every memory operation.

use fragsim::capture::executors::scheduled::{
    run_fragments, run_scheduled, Granularity, Policy, Schedule,
};
use fragsim::capture::{Capture, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::Op;
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::{Direction, Mdts};
use proptest::prelude::*;

fn policy() -> impl Strategy<Value = Policy> {
    prop_oneof![
        Just(Policy::Random),
        Just(Policy::Warps),
        (1_u32..5).prop_map(|depth| Policy::Pct { depth })
    ]
}

fn granularity() -> impl Strategy<Value = Granularity> {
    prop_oneof![Just(Granularity::Fragment), Just(Granularity::Triangle)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// MDTS (all word widths and directions, K below and at the depth complexity) and the
    /// A-buffer equal the oracle under any policy, width and seed.
    #[test]
    fn atomic_schemes_equal_the_oracle_under_every_schedule(
        policy in policy(),
        granularity in granularity(),
        in_flight in prop_oneof![Just(1_usize), Just(32), Just(1024), 2_usize..200],
        seed in any::<u64>(),
        spheres in 1_u32..4,
        k_short in 1_u32..3,
    ) {
        let scene = Scene::procedural(&format!("spheres:{spheres}")).unwrap();
        let view = scene.view(Viewport::new(24, 24).unwrap(), &OrbitCamera::default()).unwrap();
        let oracle = Oracle::build(&view);
        let schedule = Schedule { policy, in_flight, granularity, seed };
        let full = oracle.max_depth_complexity();
        let check = |capture: &Capture| -> Result<(), TestCaseError> {
            let diff = oracle.diff(capture);
            prop_assert!(diff.is_exact(), "{schedule:?}: {diff:?}");
            Ok(())
        };
        for k in [k_short, full] {
            check(&run_scheduled(&view, &Mdts::<u64>::ascending(view.viewport(), k).unwrap(), &schedule, false).run.capture)?;
            let m32 = Mdts::<u32>::new(view.viewport(), k, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
            check(&run_scheduled(&view, &m32, &schedule, false).run.capture)?;
            let desc = Mdts::<u64>::new(view.viewport(), k, Direction::Descending, MEMORY_CAP_DEFAULT).unwrap();
            check(&run_scheduled(&view, &desc, &schedule, false).run.capture)?;
            let probing = Mdts::<u64>::ascending(view.viewport(), k).unwrap().probing();
            check(&run_scheduled(&view, &probing, &schedule, false).run.capture)?;
            check(&run_scheduled(&view, &desc.probing(), &schedule, false).run.capture)?;
        }
        let abuffer = ABuffer::exact(&oracle.depth_complexity(), PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        check(&run_scheduled(&view, &abuffer, &schedule, false).run.capture)?;
        let fixed = ABuffer::fixed(view.viewport(), k_short, PostSort::Bitonic, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_scheduled(&view, &fixed, &schedule, false).run;
        check(&run.capture)?;
        prop_assert_eq!(oracle.diff(&run.capture).overflowed, run.stats.counters.dropped);
    }
}

fn one_pixel(depths: &[f32]) -> Vec<Fragment> {
    depths
        .iter()
        .enumerate()
        .map(|(prim, &d)| Fragment {
            pixel: 0,
            depth_key: depth_key(d).unwrap(),
            prim: u32::try_from(prim).expect("a one-pixel list of a few depths"),
        })
        .collect()
}

#[test]
fn the_same_schedule_replays_the_same_trace_and_another_seed_differs() {
    let fragments = one_pixel(&[0.5, 0.3, 0.9, 0.1, 0.7, 0.2, 0.6, 0.4]);
    let scheme = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), 4).unwrap();
    let schedule = |seed| Schedule {
        policy: Policy::Random,
        in_flight: 8,
        granularity: Granularity::Fragment,
        seed,
    };
    let a = run_fragments(&scheme, &fragments, &schedule(7), true)
        .trace
        .unwrap();
    let b = run_fragments(&scheme, &fragments, &schedule(7), true)
        .trace
        .unwrap();
    assert_eq!(a, b);
    let differs = (8..40).any(|seed| {
        run_fragments(&scheme, &fragments, &schedule(seed), true)
            .trace
            .unwrap()
            != a
    });
    assert!(
        differs,
        "32 seeds all gave the same interleaving of 8 threads"
    );
}

#[test]
fn a_trace_records_every_memory_operation_with_its_values() {
    let fragments = one_pixel(&[0.5, 0.25]);
    let scheme = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), 2).unwrap();
    let schedule = Schedule {
        policy: Policy::Warps,
        in_flight: 2,
        granularity: Granularity::Fragment,
        seed: 0,
    };
    let run = run_fragments(&scheme, &fragments, &schedule, true);
    let trace = run.trace.unwrap();
    assert_eq!(trace.events.len() as u64, run.run.stats.counters.steps);
    // Lane order within the warp: thread 0 (depth 0.5) lands in the empty slot 0, then thread 1
    // (0.25) takes slot 0 and carries 0.5 on to the empty slot 1.
    let ops: Vec<(u32, Op, usize, u64, u64)> = trace
        .events
        .iter()
        .map(|e| (e.thread, e.op, e.word, e.operand, e.returned))
        .collect();
    let (half, quarter) = (fragments[0].packed(), fragments[1].packed());
    assert_eq!(
        ops,
        vec![
            (0, Op::FetchMin, 0, half, u64::MAX),
            (1, Op::FetchMin, 0, quarter, half),
            (1, Op::FetchMin, 1, half, u64::MAX),
        ]
    );
    assert_eq!(trace.pixel(0).events.len(), 3);
    assert!(trace.pixel(1).events.is_empty());
}

#[test]
fn bunny_under_warps_of_triangles_equals_the_oracle() {
    let scene = Scene::default_scene();
    let view = scene
        .view(Viewport::new(128, 128).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let schedule = Schedule {
        policy: Policy::Warps,
        in_flight: 4096,
        granularity: Granularity::Triangle,
        seed: 3,
    };
    let mdts = Mdts::<u64>::ascending(view.viewport(), oracle.max_depth_complexity()).unwrap();
    let run = run_scheduled(&view, &mdts, &schedule, false).run;
    assert!(oracle.diff(&run.capture).is_exact());
    assert_eq!(
        usize::try_from(run.stats.counters.fragments),
        Ok(oracle.fragments())
    );
    assert_eq!(mdts.name(), "mdts");
}
