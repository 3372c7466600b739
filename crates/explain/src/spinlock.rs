//! The spinlocked k-buffer's deadlock under lockstep warps
//! (`fragsim_schemes::kbuffer::spinlock`): the shortest deadlocking schedule, found by a
//! bounded search, and the fixed loop run on the same fragments.
//!
//! The search runs the naive loop on the first `n` fragments of one pixel, `n` = 2, 3, … up to
//! all of them, one lane per fragment in one warp of the scheduled executor's
//! [`Policy::Lockstep`], and stops at the first `n` that deadlocks: fewer fragments cannot (one
//! fragment has nobody to wait for), so the first found has the fewest lanes. Its schedule is
//! printed up to the step after which nothing changes any more (every stuck lane has made its one
//! attempt; the warp then issues only the spinning lanes, whose compare-and-swap reads the lock
//! held forever), so it is the shortest: each of the steps printed is some lane's first attempt
//! at the lock. The fixed loop (`kbuffer-spinlock-fixed`) on the same fragments and schedule runs
//! to the end and keeps the oracle's list.

use std::fmt;

use fragsim_capture::executors::scheduled::{
    run_fragments, Deadlock, Granularity, Policy, Schedule, WARP_LANES,
};
use fragsim_capture::{CaptureError, MEMORY_CAP_DEFAULT};
use fragsim_memory::{Op, TraceEvent};
use fragsim_raster::{Fragment, Viewport};
use fragsim_schemes::kbuffer::spinlock::{KBufferSpinlock, Loop};

/// What `explain --scheme kbuffer-spinlock` reports.
#[derive(Debug, Clone)]
pub struct DeadlockReport {
    /// Slots per pixel.
    pub k: u32,
    /// The fragments of the deadlocking run (the first ones of the input).
    pub fragments: Vec<Fragment>,
    /// The verdict.
    pub deadlock: Deadlock,
    /// The steps up to the last one that changed anything (each stuck lane's first attempt).
    pub schedule: Vec<TraceEvent>,
    /// The fixed loop on the same fragments and schedule: its steps, and whether it kept the
    /// sorted list of every fragment (`K` nearest).
    pub fixed: (u64, bool),
}

/// The shortest deadlock of the naive spinlock over prefixes of `fragments` (one pixel), `K` =
/// `k`; `None` when no prefix deadlocks (fewer than two fragments).
///
/// # Errors
/// `k == 0`.
pub fn shortest_deadlock(
    k: u32,
    fragments: &[Fragment],
) -> Result<Option<DeadlockReport>, CaptureError> {
    let viewport = Viewport::new(1, 1).expect("one pixel");
    let naive = KBufferSpinlock::new(viewport, k, Loop::Naive, MEMORY_CAP_DEFAULT)?;
    let fixed = KBufferSpinlock::new(viewport, k, Loop::Fixed, MEMORY_CAP_DEFAULT)?;
    // One warp: a deadlock needs two lanes of one warp.
    for n in 2..=fragments.len().min(WARP_LANES) {
        let list = &fragments[..n];
        let schedule = lockstep(n);
        let run = run_fragments(&naive, list, &schedule, true);
        let Some(deadlock) = run.deadlock else {
            continue;
        };
        let trace = run.trace.expect("recorded");
        // The stuck lanes' first attempts: the schedule up to the first repeated failure.
        let first_repeat = trace
            .events
            .iter()
            .enumerate()
            .filter(|(_, e)| e.op == Op::Swap && e.returned == 1)
            .scan(Vec::new(), |seen: &mut Vec<u32>, (i, e)| {
                let repeat = seen.contains(&e.thread);
                seen.push(e.thread);
                Some((i, repeat))
            })
            .find(|&(_, repeat)| repeat)
            .map_or(trace.events.len(), |(i, _)| i);
        let fixed_run = run_fragments(&fixed, list, &schedule, false);
        let mut sorted: Vec<u64> = list.iter().map(|f| f.packed()).collect();
        sorted.sort_unstable();
        sorted.truncate(k as usize);
        let kept = fixed_run.deadlock.is_none() && fixed_run.run.capture.pixel(0) == sorted;
        return Ok(Some(DeadlockReport {
            k,
            fragments: list.to_vec(),
            deadlock,
            schedule: trace.events[..first_repeat].to_vec(),
            fixed: (fixed_run.run.stats.counters.steps, kept),
        }));
    }
    Ok(None)
}

/// One lockstep warp of `lanes` lanes, one fragment each.
fn lockstep(lanes: usize) -> Schedule {
    Schedule {
        policy: Policy::Lockstep,
        in_flight: lanes,
        granularity: Granularity::Fragment,
        seed: 0,
    }
}

impl fmt::Display for DeadlockReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "kbuffer-spinlock, K = {}, {} fragments of one pixel in one lockstep warp: deadlock",
            self.k,
            self.fragments.len()
        )?;
        writeln!(
            f,
            "shortest deadlocking schedule ({} steps):",
            self.schedule.len()
        )?;
        for e in &self.schedule {
            let what = match (e.op, e.width, e.returned) {
                (Op::Swap, 32, 0) => "compare-and-swap on the lock: free, taken; leaves the loop and waits at its exit for the warp".to_string(),
                (Op::Swap, 32, _) => "compare-and-swap on the lock: held, spins".to_string(),
                (op, width, returned) => format!("{op:?} on {width}-bit word {}: {returned:#x}", e.word),
            };
            writeln!(
                f,
                "  step {}: lane {} (fragment {}) {what}",
                e.step, e.thread, e.fragment
            )?;
        }
        writeln!(
            f,
            "then the warp issues only its spinning lanes, which never see the lock free: {}",
            self.deadlock
        )?;
        let (steps, kept) = self.fixed;
        write!(
            f,
            "kbuffer-spinlock-fixed (critical section and release inside the loop body), same fragments and warp: terminates in {steps} steps, {}",
            if kept {
                "every fragment kept in order"
            } else {
                "WRONG: the list differs from the sorted input"
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fragment(depth_key: u32, prim: u32) -> Fragment {
        Fragment {
            pixel: 0,
            depth_key,
            prim,
        }
    }

    #[test]
    fn two_fragments_deadlock_in_two_steps_and_the_fixed_loop_keeps_both() {
        let fragments = [fragment(5, 0), fragment(3, 1), fragment(7, 2)];
        let report = shortest_deadlock(3, &fragments).unwrap().unwrap();
        assert_eq!(report.fragments.len(), 2);
        let steps: Vec<(u32, u64)> = report
            .schedule
            .iter()
            .map(|e| (e.thread, e.returned))
            .collect();
        // Lane 0 takes the lock (read 0), lane 1 finds it held (read 1).
        assert_eq!(steps, vec![(0, 0), (1, 1)]);
        assert!(report.fixed.1, "the fixed loop lost a fragment");
        let text = report.to_string();
        assert!(
            text.contains("spins") && text.contains("terminates"),
            "{text}"
        );
    }

    #[test]
    fn one_fragment_cannot_deadlock_and_k_zero_is_refused() {
        assert!(shortest_deadlock(1, &[fragment(5, 0)]).unwrap().is_none());
        assert!(shortest_deadlock(0, &[fragment(5, 0)]).is_err());
    }
}
