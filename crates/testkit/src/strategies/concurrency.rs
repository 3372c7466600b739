//! Strategies for concurrency: how a run interleaves (task size, schedule).

use fragsim_capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::executors::{ParallelExecutor, Run};
use fragsim_capture::Scheme;
use fragsim_raster::View;
use proptest::prelude::*;

/// How a property's concurrent runs interleave: the parallel executor with a small task size
/// (1 to 8 triangles a rayon task, so that even a scene of a dozen triangles runs on every
/// thread), and the scheduled executor under a random policy, width, granularity and seed (a
/// replayable interleaving, so that a failure shrinks and reproduces).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Concurrency {
    /// Triangles per rayon task of the parallel executor.
    pub task_size: usize,
    /// The scheduled executor's interleaving.
    pub schedule: Schedule,
}

impl Concurrency {
    /// `scheme`'s runs under this concurrency: the parallel executor's and the scheduled one's,
    /// each labelled for failure messages.
    pub fn runs<S: Scheme>(&self, view: &View<'_>, scheme: &S) -> [(String, Run); 2] {
        [
            (
                format!("parallel, {} triangles a task", self.task_size),
                ParallelExecutor::with_task_size(self.task_size).run(view, scheme),
            ),
            (
                format!("scheduled {:?}", self.schedule),
                run_scheduled(view, scheme, &self.schedule, false).run,
            ),
        ]
    }
}

/// A scheduling policy: random, lockstep warps, or PCT of depth 1 to 3.
pub fn policy() -> impl Strategy<Value = Policy> {
    prop_oneof![
        Just(Policy::Random),
        Just(Policy::Warps),
        (1_u32..=3).prop_map(|depth| Policy::Pct { depth }),
    ]
}

/// A [`Concurrency`]: task sizes 1 to 8, and a [`schedule`]. Shrinks towards one triangle a task
/// and two fragments in flight under the random policy.
pub fn concurrency() -> impl Strategy<Value = Concurrency> {
    (1_usize..=8, schedule()).prop_map(|(task_size, schedule)| Concurrency {
        task_size,
        schedule,
    })
}

/// A [`Schedule`] of the scheduled executor: any [`policy`], 2 to 64 threads in flight, either
/// granularity, any seed: a replayable interleaving, so a failure under it reproduces. Shrinks
/// towards two fragments in flight under the random policy, one fragment a step, seed 0.
pub fn schedule() -> impl Strategy<Value = Schedule> {
    (
        policy(),
        2_usize..=64,
        prop_oneof![Just(Granularity::Fragment), Just(Granularity::Triangle)],
        any::<u64>(),
    )
        .prop_map(|(policy, in_flight, granularity, seed)| Schedule {
            policy,
            in_flight,
            granularity,
            seed,
        })
}
