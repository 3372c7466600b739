//! The scheduled executor: replayable GPU-like interleavings, with traces.
//!
//! Real threads on a 2-core CPU almost never interleave two fragments of one pixel, and when they
//! do nobody can replay it; loom explores everything but only for a handful of fragments. This
//! executor runs a whole scene on one thread under a simulated GPU scheduler:
//!
//! - `W` logical threads are in flight at once ([`Schedule::in_flight`]); a thread carries one
//!   fragment's walk ([`Granularity::Fragment`]) or, as FreePipe's one CUDA thread per triangle,
//!   every fragment of one triangle in scan order ([`Granularity::Triangle`]). When a thread
//!   finishes, the next fragment or triangle of the stream takes its place.
//! - Which thread's next step (one memory operation) runs is chosen by the [`Policy`]: uniformly
//!   at random; round-robin over lockstep warps of 32 (a warp issues one step for each of its active
//!   lanes, in lane order, so conflicting atomics on one word serialise in lane order and of plain
//!   stores to one word the last lane wins); or PCT (Burckhardt et al., ASPLOS 2010: random thread
//!   priorities, the highest-priority thread runs, with `depth − 1` random priority change points).
//! - Under [`Policy::Lockstep`] a warp's lanes execute one instruction together, as on GPUs before
//!   Volta: a lane standing at a reconvergence point ([`Simt::reconverging`]) waits there until
//!   every other active lane of its warp does too, so a lane that took a spinlock and left the
//!   spin loop waits for lanes still spinning on that lock, which never get it (below).
//! - **Deadlock detection.** A step that fails to take a lock and will retry it is a spin
//!   ([`Simt::spinning`]); a run in which [`DEADLOCK_SPINS_PER_THREAD`] × `W` consecutive steps
//!   are spins stops and reports a [`Deadlock`] (the lanes stuck, where, and the schedule to replay
//!   it) instead of hanging. Under the warps, lockstep and PCT policies a lock's holder that can
//!   run does so within `W` steps (PCT lowers a spinning thread's priority, as a yield), so the
//!   bound is never reached by a run that can progress; under the random policy the holder is
//!   chosen with probability at least 1 / `W` at each step, so a run that can progress reaches the
//!   bound with probability below (1 − 1/`W`)^(64 `W`) < e^−64.
//! - Everything is a pure function of (scene, scheme, policy, `W`, seed): the same [`Schedule`]
//!   replays the same interleaving, step for step.
//! - Every memory operation can be recorded as a [`TraceEvent`](fragsim_memory::TraceEvent); a trace can be filtered to one
//!   pixel ([`Trace::pixel`]); an explicit interleaving of a fragment list can be replayed
//!   ([`run_fragments_in_order`]: `fragsim explain` shrinks interleavings with it).
//!
//! Unlike a GPU, steps run one at a time: the schedule is a total order of memory operations. That
//! is the model the schemes' proofs use (per-location atomicity); a GPU's lockstep warp is modelled
//! by its lane order.
//!
//! This file holds the run loop; the policies and their chooser are in `scheduled/policy.rs`, the
//! trace in `scheduled/trace.rs`, the memory that records it in `fragsim_memory`'s `recording.rs`.

use std::collections::VecDeque;
use std::time::Instant;

use fragsim_memory::{RecordingMemory, SerialMemory};
use fragsim_raster::View;

use super::frame::{self, Counters, Run};
use crate::scheme::{Scheme, Simt, Step};
use crate::walk_input::{inputs_of, WalkInput};
use policy::Chooser;
pub use policy::{Granularity, Policy, Schedule, WARP_LANES};
pub use trace::Trace;

mod policy;
mod trace;

/// The deadlock bound: a run stops with a [`Deadlock`] after this many consecutive spins per
/// thread in flight (module doc: why no run that can progress reaches it).
pub const DEADLOCK_SPINS_PER_THREAD: u64 = 64;

/// A lane stuck when a [`Deadlock`] was detected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StuckLane {
    /// The logical thread (lane `thread % 32` of warp `thread / 32`).
    pub thread: u32,
    /// Index of its fragment in the pass's stream.
    pub fragment: u64,
    /// The fragment's pixel.
    pub pixel: u32,
    /// What the walk reported ([`Scheme::simt`]).
    pub simt: Simt,
}

/// The verdict of a run that stopped making progress: [`DEADLOCK_SPINS_PER_THREAD`] × `W`
/// consecutive steps were spins.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Deadlock {
    /// The schedule that deadlocked: replaying it deadlocks again.
    pub schedule: Schedule,
    /// The geometry pass.
    pub pass: u32,
    /// The step (of the whole run) at which the bound was reached.
    pub step: u64,
    /// The bound: consecutive spins.
    pub spins: u64,
    /// Every lane still active, in thread order.
    pub lanes: Vec<StuckLane>,
}

impl std::fmt::Display for Deadlock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "deadlock: {} consecutive spins (the bound: {} per thread in flight, {} threads) at step {} of pass {}, {:?} policy, seed {}",
            self.spins,
            DEADLOCK_SPINS_PER_THREAD,
            self.schedule.in_flight,
            self.step,
            self.pass,
            self.schedule.policy,
            self.schedule.seed
        )?;
        for lane in &self.lanes {
            let what = match (lane.simt.spinning, lane.simt.reconverging) {
                (true, _) => "spins on a lock it never gets",
                (false, true) => "waits at a reconvergence point for its warp",
                (false, false) => "is runnable",
            };
            write!(
                f,
                "; warp {} lane {} (fragment {}, pixel {}) {what}",
                lane.thread as usize / WARP_LANES,
                lane.thread as usize % WARP_LANES,
                lane.fragment,
                lane.pixel
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for Deadlock {}

/// A scheduled run: the usual result plus the trace, if one was asked for, and the memory the
/// run left, for a caller that reads the words themselves.
#[derive(Clone, Debug)]
pub struct ScheduledRun {
    /// Capture and statistics.
    pub run: Run,
    /// The memory operations, when recording.
    pub trace: Option<Trace>,
    /// The words after the last pass (the post pass reads them, never writes them).
    pub memory: SerialMemory,
    /// Where the run stopped making progress, if it did: then the walks still active were
    /// abandoned and the capture holds only what the others stored.
    pub deadlock: Option<Deadlock>,
}

impl ScheduledRun {
    /// The run, or its deadlock as the error.
    ///
    /// # Errors
    /// The [`Deadlock`] the run stopped on.
    pub fn checked(self) -> Result<Self, Deadlock> {
        match self.deadlock {
            Some(deadlock) => Err(deadlock),
            None => Ok(self),
        }
    }
}

/// One logical thread: its current walk and the fragments still queued for it.
struct Thread<S, I> {
    walk: Option<(S, I, u64)>,
    queue: VecDeque<(I, u64)>,
    priority: u64,
}

/// Runs `scheme` over `view` under `schedule` on one thread; records a trace when `record`.
///
/// # Panics
/// If `schedule.in_flight` is 0.
pub fn run_scheduled<S: Scheme>(
    view: &View<'_>,
    scheme: &S,
    schedule: &Schedule,
    record: bool,
) -> ScheduledRun {
    let fragments_of = |index: u32| {
        let mut list = Vec::new();
        view.rasterize(view.submitted(index), &mut |f| list.push(f));
        inputs_of(scheme, list)
    };
    run_stream(
        scheme,
        view.triangle_count(),
        fragments_of,
        schedule,
        None,
        record,
    )
}

/// Runs `scheme` on a hand-written fragment list (one "triangle" per fragment) under `schedule`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "fragment indices are u32 in traces (TraceEvent); a scheduled run walks a small frame's stream, far below 2^32 fragments"
)]
pub fn run_fragments<S: Scheme>(
    scheme: &S,
    fragments: &[S::Input],
    schedule: &Schedule,
    record: bool,
) -> ScheduledRun {
    run_stream(
        scheme,
        fragments.len() as u32,
        |i| vec![fragments[i as usize]],
        schedule,
        None,
        record,
    )
}

/// Replays an explicit interleaving of a hand-written fragment list: thread `t` carries
/// `fragments[t]` (one thread per fragment), and step `i` runs thread `order[i]`. Entries naming a
/// thread that has finished are skipped; when `order` runs out, the remaining steps run the
/// lowest-numbered unfinished thread first. So every `order` is a valid schedule, and
/// `order` = the thread of each step of a recorded trace replays that trace exactly (a step that
/// does several memory operations, as a render-target k-buffer's read, records several events with
/// one `step` index: [`Trace::order`]).
#[expect(
    clippy::cast_possible_truncation,
    reason = "fragment indices are u32 in traces (TraceEvent); a scheduled run walks a small frame's stream, far below 2^32 fragments"
)]
pub fn run_fragments_in_order<S: Scheme>(
    scheme: &S,
    fragments: &[S::Input],
    order: &[u32],
    record: bool,
) -> ScheduledRun {
    let schedule = Schedule {
        policy: Policy::Random,
        in_flight: fragments.len().max(1),
        granularity: Granularity::Fragment,
        seed: 0,
    };
    run_stream(
        scheme,
        fragments.len() as u32,
        |i| vec![fragments[i as usize]],
        &schedule,
        Some(order),
        record,
    )
}

fn run_stream<S: Scheme>(
    scheme: &S,
    triangles: u32,
    fragments_of: impl Fn(u32) -> Vec<S::Input>,
    schedule: &Schedule,
    order: Option<&[u32]>,
    record: bool,
) -> ScheduledRun {
    assert!(
        schedule.in_flight > 0,
        "the scheduled executor needs at least one thread in flight"
    );
    let start = Instant::now();
    let mut memory: RecordingMemory = scheme.layout().allocate();
    if record {
        memory.record();
    }
    let mut chooser = Chooser::new(schedule, 4 * u64::from(triangles).max(1));
    chooser.order = order.map(|order| (order.to_vec(), 0));
    // Step indices run on across passes: PCT's change points and the trace number the whole run.
    let mut steps_before = 0;
    let mut deadlock = None;
    let geometry_pass = |pass| {
        if deadlock.is_some() {
            // The walks of a deadlocked pass were abandoned: no later pass runs a step.
            return Counters::default();
        }
        let (counters, stuck) = run_pass(
            scheme,
            &memory,
            pass,
            triangles,
            &fragments_of,
            schedule,
            &mut chooser,
            steps_before,
        );
        steps_before += counters.steps;
        deadlock = stuck;
        counters
    };
    let run = frame::run(scheme, &memory, start, 1, geometry_pass, |memory| {
        scheme.resolve(memory.serial())
    });
    let (memory, events) = memory.into_parts();
    ScheduledRun {
        run,
        trace: events.map(|events| Trace { events }),
        memory,
        deadlock,
    }
}

#[expect(
    clippy::too_many_arguments,
    reason = "one pass of the executor's loop, split out for reading"
)]
fn run_pass<S: Scheme>(
    scheme: &S,
    memory: &RecordingMemory,
    pass: u32,
    triangles: u32,
    fragments_of: &impl Fn(u32) -> Vec<S::Input>,
    schedule: &Schedule,
    chooser: &mut Chooser,
    first_step: u64,
) -> (Counters, Option<Deadlock>) {
    let mut counters = Counters::default();
    let mut next_triangle = 0_u32;
    let mut next_fragment_index = 0_u64;
    let mut pending: VecDeque<(S::Input, u64)> = VecDeque::new();
    // Hands a thread its next unit of work: a fragment, or a whole triangle's fragments.
    let mut refill = |queue: &mut VecDeque<(S::Input, u64)>| -> bool {
        loop {
            match schedule.granularity {
                Granularity::Fragment => {
                    if let Some(item) = pending.pop_front() {
                        queue.push_back(item);
                        return true;
                    }
                }
                Granularity::Triangle => {}
            }
            if next_triangle == triangles {
                return false;
            }
            let list = fragments_of(next_triangle);
            next_triangle += 1;
            let target = match schedule.granularity {
                Granularity::Fragment => &mut pending,
                Granularity::Triangle => &mut *queue,
            };
            for f in list {
                target.push_back((f, next_fragment_index));
                next_fragment_index += 1;
            }
            if schedule.granularity == Granularity::Triangle && !queue.is_empty() {
                return true;
            }
        }
    };
    let mut threads: Vec<Thread<S::State, S::Input>> = Vec::with_capacity(schedule.in_flight);
    let mut active: Vec<usize> = Vec::with_capacity(schedule.in_flight);
    for t in 0..schedule.in_flight {
        let priority = chooser.fresh_priority();
        threads.push(Thread {
            walk: None,
            queue: VecDeque::new(),
            priority,
        });
        if start_next_walk(scheme, pass, &mut threads[t], &mut refill) {
            active.push(t);
        }
    }
    let mut step = first_step;
    let bound = DEADLOCK_SPINS_PER_THREAD * schedule.in_flight as u64;
    let mut spins = 0;
    while !active.is_empty() {
        let t = chooser.choose(&mut threads, &active, step, |s| scheme.simt(s).reconverging);
        let thread = &mut threads[t];
        let (state, fragment, index) = thread.walk.as_mut().expect("chosen threads are active");
        #[expect(
            clippy::cast_possible_truncation,
            reason = "thread indices are u32 in traces; a schedule has a warp's few threads"
        )]
        memory.set_context(step, t as u32, *index, fragment.pixel(), pass);
        step += 1;
        counters.steps += 1;
        let outcome = scheme.step(state, memory);
        if outcome == Step::Continue && scheme.simt(state).spinning {
            spins += 1;
            chooser.spun(thread);
            if spins >= bound {
                #[expect(
                    clippy::cast_possible_truncation,
                    clippy::shadow_unrelated,
                    reason = "the stuck lanes name every thread as the chosen one is named above; thread indices are u32 in traces, and a schedule has a warp's few threads"
                )]
                let lanes = threads
                    .iter()
                    .enumerate()
                    .filter_map(|(t, thread)| {
                        thread
                            .walk
                            .as_ref()
                            .map(|(state, fragment, index)| StuckLane {
                                thread: t as u32,
                                fragment: *index,
                                pixel: fragment.pixel(),
                                simt: scheme.simt(state),
                            })
                    })
                    .collect();
                let deadlock = Deadlock {
                    schedule: *schedule,
                    pass,
                    // `step` already counts the spin just run.
                    step: step - 1,
                    spins,
                    lanes,
                };
                return (counters, Some(deadlock));
            }
        } else {
            spins = 0;
        }
        if outcome != Step::Continue {
            counters.record(outcome);
            thread.walk = None;
            if !start_next_walk(scheme, pass, thread, &mut refill) {
                // swap_remove is deterministic, so the choice stays a pure function of the seed.
                let position = active
                    .iter()
                    .position(|&a| a == t)
                    .expect("active thread is listed");
                active.swap_remove(position);
            } else if schedule.granularity == Granularity::Fragment {
                thread.priority = chooser.fresh_priority();
            }
        }
    }
    (counters, None)
}

/// Starts the thread's next walk that the pass does not ignore; false when it has no more work.
fn start_next_walk<S: Scheme>(
    scheme: &S,
    pass: u32,
    thread: &mut Thread<S::State, S::Input>,
    refill: &mut impl FnMut(&mut VecDeque<(S::Input, u64)>) -> bool,
) -> bool {
    loop {
        if thread.queue.is_empty() && !refill(&mut thread.queue) {
            return false;
        }
        let (fragment, index) = thread.queue.pop_front().expect("refilled");
        if let Some(state) = scheme.begin_pass(pass, fragment) {
            thread.walk = Some((state, fragment, index));
            return true;
        }
    }
}
