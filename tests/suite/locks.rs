//! The lock-based k-buffers (`docs/baselines/kbuffer-spinlock.md`) against the oracle:
//! exact on every executor and every independent-scheduling policy; under lockstep warps the naive
//! spinlock deadlocks then and only then when two fragments of one pixel share the warp, and the
//! fixed loop never does.
//!
//! Streams are hand-written fragments on a few pixels (as `shipping.rs`'s), run by the scheduled
//! executor with every fragment in flight at once in one warp (so which fragments contend is
//! known); the real-scene test runs each catalog entry on every executor through the catalog.

use fragsim::capture::executors::scheduled::{
    run_fragments, Granularity, Policy, Schedule, WARP_LANES,
};
use fragsim::capture::executors::Executor;
use fragsim::capture::{Guarantee, MEMORY_CAP_DEFAULT};
use fragsim::catalog::{Count, SchemeName, SchemeRunner, Sizing};
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Fragment, OrbitCamera, Scene, Viewport};
use fragsim::schemes::kbuffer::spinlock::{KBufferSpinlock, Loop};
use fragsim::schemes::mdts_emulated64::{Emulation, MdtsEmulated64};
use proptest::prelude::*;

/// Fragments on `pixels` pixels, primitive ids in submission order, depth keys from six values;
/// at most one warp's worth.
#[expect(
    clippy::cast_possible_truncation,
    reason = "1 to 3 pixels and at most one warp's fragments"
)]
fn stream() -> impl Strategy<Value = (usize, Vec<Fragment>)> {
    (1_usize..=3).prop_flat_map(|pixels| {
        proptest::collection::vec((0..pixels as u32, 0_u32..6), 0..=WARP_LANES).prop_map(
            move |list| {
                let fragments = list
                    .into_iter()
                    .enumerate()
                    .map(|(prim, (pixel, depth))| Fragment {
                        pixel,
                        depth_key: depth_key(depth as f32 / 8.0).expect("in [0, 1]"),
                        prim: prim as u32,
                    })
                    .collect();
                (pixels, fragments)
            },
        )
    })
}

fn independent_policy() -> impl Strategy<Value = Policy> {
    prop_oneof![
        Just(Policy::Random),
        Just(Policy::Warps),
        (1_u32..=3).prop_map(|depth| Policy::Pct { depth }),
    ]
}

/// Every fragment in flight at once: one warp, since streams hold at most 32.
fn all_in_flight(policy: Policy, fragments: &[Fragment], seed: u64) -> Schedule {
    Schedule {
        policy,
        in_flight: fragments.len().max(1),
        granularity: Granularity::Fragment,
        seed,
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Both loops, under independent scheduling (random, warps, PCT): the `K` nearest of every
    /// pixel, exactly, and never a deadlock.
    #[test]
    fn both_loops_are_exact_under_independent_scheduling(
        (pixels, fragments) in stream(),
        k in 1_u32..=5,
        policy in independent_policy(),
        seed in any::<u64>(),
    ) {
        let oracle = Oracle::from_fragments(pixels, &fragments);
        let viewport = Viewport::new(u32::try_from(pixels).expect("1 to 3 pixels"), 1).unwrap();
        for shape in [Loop::Naive, Loop::Fixed] {
            let scheme = KBufferSpinlock::new(viewport, k, shape, MEMORY_CAP_DEFAULT).unwrap();
            let run = run_fragments(&scheme, &fragments, &all_in_flight(policy, &fragments, seed), false);
            prop_assert!(run.deadlock.is_none(), "{shape:?}: {}", run.deadlock.unwrap());
            prop_assert!(oracle.diff(&run.run.capture).is_exact(), "{shape:?}");
        }
    }

    /// The 64-bit emulations: locked, exact under every policy (lockstep too: its loop has the
    /// fixed shape); unlocked, exact with one fragment in flight (no hazard can happen), and under
    /// concurrency where no two fragments share a pixel.
    #[test]
    fn the_locked_64_bit_emulation_is_exact_everywhere_and_the_torn_one_without_hazards(
        (pixels, fragments) in stream(),
        k in 1_u32..=5,
        policy in prop_oneof![independent_policy(), Just(Policy::Lockstep)],
        seed in any::<u64>(),
    ) {
        let oracle = Oracle::from_fragments(pixels, &fragments);
        let viewport = Viewport::new(u32::try_from(pixels).expect("1 to 3 pixels"), 1).unwrap();
        let concurrent = all_in_flight(policy, &fragments, seed);
        let locked = MdtsEmulated64::new(viewport, k, Emulation::Locked, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_fragments(&locked, &fragments, &concurrent, false);
        prop_assert!(run.deadlock.is_none());
        prop_assert!(oracle.diff(&run.run.capture).is_exact());
        let torn = MdtsEmulated64::new(viewport, k, Emulation::Torn, MEMORY_CAP_DEFAULT).unwrap();
        let one_at_a_time = Schedule { in_flight: 1, ..concurrent };
        let torn_alone = run_fragments(&torn, &fragments, &one_at_a_time, false);
        prop_assert!(oracle.diff(&torn_alone.run.capture).is_exact());
        if oracle.depth_complexity().iter().all(|&n| n <= 1) {
            let torn_together = run_fragments(&torn, &fragments, &concurrent, false);
            prop_assert!(oracle.diff(&torn_together.run.capture).is_exact());
        }
    }

    /// Lockstep, one warp: the naive loop deadlocks iff a pixel has two fragments (the first
    /// lane of each pixel takes its lock and waits at the loop's exit; the others spin), and is
    /// exact otherwise; the fixed loop is exact on every stream.
    #[test]
    fn under_lockstep_the_naive_loop_deadlocks_iff_a_pixel_is_contended(
        (pixels, fragments) in stream(),
        k in 1_u32..=5,
    ) {
        let oracle = Oracle::from_fragments(pixels, &fragments);
        let viewport = Viewport::new(u32::try_from(pixels).expect("1 to 3 pixels"), 1).unwrap();
        let schedule = all_in_flight(Policy::Lockstep, &fragments, 0);
        let contended = oracle.depth_complexity().iter().any(|&n| n >= 2);
        let naive = KBufferSpinlock::new(viewport, k, Loop::Naive, MEMORY_CAP_DEFAULT).unwrap();
        let run = run_fragments(&naive, &fragments, &schedule, false);
        prop_assert_eq!(run.deadlock.is_some(), contended);
        if let Some(deadlock) = &run.deadlock {
            // Nothing progressed: every pixel's fragments are stuck, its first lane holding the
            // lock at the loop's exit and the others spinning on it.
            for (p, &n) in oracle.depth_complexity().iter().enumerate() {
                let on_p = || deadlock.lanes.iter().filter(|l| l.pixel as usize == p);
                prop_assert_eq!(on_p().count(), n as usize);
                prop_assert_eq!(on_p().filter(|l| l.simt.spinning).count(), n.saturating_sub(1) as usize);
                prop_assert!(on_p().all(|l| l.simt.spinning != l.simt.reconverging));
            }
        } else {
            prop_assert!(oracle.diff(&run.run.capture).is_exact());
        }
        let fixed = KBufferSpinlock::new(viewport, k, Loop::Fixed, MEMORY_CAP_DEFAULT).unwrap();
        let fixed_run = run_fragments(&fixed, &fragments, &schedule, false);
        prop_assert!(fixed_run.deadlock.is_none());
        prop_assert!(oracle.diff(&fixed_run.run.capture).is_exact());
    }
}

/// The catalog's lock-based entries on a real scene, every executor (the parallel one with real
/// threads spinning on real locks), `K` below and above the depth complexity: each keeps its
/// guarantee, and the guarantee is exactness.
#[test]
fn the_lock_based_entries_are_exact_on_every_executor() {
    let scene = Scene::procedural("spheres:6").unwrap();
    let view = scene
        .view(Viewport::new(48, 48).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let mut runner = SchemeRunner::default();
    let names = [
        "kbuffer-interlock",
        "kbuffer-spinlock",
        "kbuffer-spinlock-fixed",
        "mdts-emulated64",
    ];
    for name in names {
        let scheme = SchemeName::from_name(name).unwrap();
        for k in [3, 16] {
            let sizing = Sizing {
                k: Count::Fixed(k),
                capacity: Count::Fixed(k),
                memory_cap: MEMORY_CAP_DEFAULT,
            };
            for executor in Executor::EVERY {
                let run = runner.run(scheme, executor, &view, &sizing).unwrap();
                assert_eq!(run.guarantee, Guarantee::Exact, "{name}");
                assert!(
                    oracle.diff(&run.run.capture).is_exact(),
                    "{name}, K = {k}, {executor}"
                );
            }
        }
    }
}

/// `fragsim explain --scheme kbuffer-spinlock` prints the two-step deadlock (lane 0 takes the
/// lock, lane 1 finds it held) and the fixed loop terminating; with one fragment it shows nothing
/// and exits 1.
#[test]
fn explain_prints_the_shortest_deadlocking_schedule() {
    let run = |depths: &str| {
        let output = assert_cmd::Command::cargo_bin("fragsim")
            .unwrap()
            .args([
                "explain",
                "--scheme",
                "kbuffer-spinlock",
                "--depths",
                depths,
            ])
            .output()
            .unwrap();
        (
            output.status.success(),
            String::from_utf8(output.stdout).unwrap(),
        )
    };
    let (shown, text) = run("0.3,0.5,0.1");
    assert!(shown, "{text}");
    assert!(text.contains("2 fragments of one pixel"), "{text}");
    assert!(text.contains("(2 steps)"), "{text}");
    assert!(
        text.contains("step 0: lane 0 (fragment 0) compare-and-swap on the lock: free"),
        "{text}"
    );
    assert!(
        text.contains("step 1: lane 1 (fragment 1) compare-and-swap on the lock: held"),
        "{text}"
    );
    assert!(text.contains("every fragment kept in order"), "{text}");
    let (one_shown, one_text) = run("0.3");
    assert!(!one_shown, "{one_text}");
    assert!(one_text.contains("cannot deadlock"), "{one_text}");
}
