//! The scheduled executor's policies: how the next step is chosen ([`Policy`]: random, warps,
//! lockstep warps, PCT), what a thread carries ([`Granularity`]), the [`Schedule`] that replays a
//! run, and the chooser that applies them step by step, PCT's priorities and change points
//! included.

use std::collections::VecDeque;

use fragsim_raster::SplitMix64;

use super::Thread;
#[cfg(doc)]
use crate::scheme::Simt;

/// Lanes of a warp in [`Policy::Warps`] and [`Policy::Lockstep`].
pub const WARP_LANES: usize = 32;

/// How the next step is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Policy {
    /// Any in-flight thread, uniformly at random.
    Random,
    /// Warps of [`WARP_LANES`] threads in round-robin; a warp issues one step per active lane, in
    /// lane order.
    Warps,
    /// Lockstep warps (SIMT before Volta's independent thread scheduling): as [`Policy::Warps`],
    /// but a warp issues its step only for its active lanes not standing at a reconvergence point
    /// ([`Simt::reconverging`]), or for all of them when every one stands at one.
    Lockstep,
    /// Probabilistic concurrency testing with `depth − 1` priority change points.
    Pct {
        /// PCT's bug depth `d` (≥ 1).
        depth: u32,
    },
}

/// What one logical thread carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Granularity {
    /// One fragment per thread.
    #[default]
    Fragment,
    /// One triangle per thread, its fragments in scan order (FreePipe's model).
    Triangle,
}

/// A complete description of an interleaving: replaying it gives the same run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Schedule {
    /// The scheduling policy.
    pub policy: Policy,
    /// Threads in flight (`W` ≥ 1).
    pub in_flight: usize,
    /// What a thread carries.
    pub granularity: Granularity,
    /// The seed of every random choice.
    pub seed: u64,
}
/// Chooses the next thread to step.
pub(super) struct Chooser {
    policy: Policy,
    rng: SplitMix64,
    /// Warps: the warp being issued and the next lane to issue in it.
    warp: usize,
    lane: usize,
    /// Lockstep: the lanes of the current issue still to step.
    issue: VecDeque<usize>,
    /// PCT: steps at which the running thread's priority drops, and the next low priority.
    change_points: Vec<u64>,
    next_low: u64,
    /// Replay: the threads to step, in order, and the next entry to use.
    pub(super) order: Option<(Vec<u32>, usize)>,
}

impl Chooser {
    pub(super) fn new(schedule: &Schedule, expected_steps: u64) -> Self {
        let mut rng = SplitMix64::new(schedule.seed);
        let change_points = match schedule.policy {
            Policy::Pct { depth } => {
                let mut points: Vec<u64> = (1..depth.max(1))
                    .map(|_| rng.next_u64() % expected_steps.max(1))
                    .collect();
                points.sort_unstable();
                points
            }
            _ => Vec::new(),
        };
        Self {
            policy: schedule.policy,
            rng,
            warp: 0,
            lane: 0,
            issue: VecDeque::new(),
            change_points,
            next_low: u64::from(u32::MAX),
            order: None,
        }
    }

    pub(super) fn fresh_priority(&mut self) -> u64 {
        // High priorities live above 2^32, lowered ones below, so a lowered thread yields to all.
        (1 << 32) + (self.rng.next_u64() >> 32)
    }

    /// Lowers a thread's priority below every other's (PCT only): what a thread that spun does,
    /// so that the lock's holder runs.
    pub(super) fn spun<S, I>(&mut self, thread: &mut Thread<S, I>) {
        if let Policy::Pct { .. } = self.policy {
            thread.priority = self.next_low;
            self.next_low = self.next_low.saturating_sub(1);
        }
    }

    /// The next thread to step among `threads`, of which those with `walk.is_some()` are active;
    /// `reconverging` says whether a walk stands at a reconvergence point.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the remainder is below active.len(), a usize"
    )]
    pub(super) fn choose<S, I>(
        &mut self,
        threads: &mut [Thread<S, I>],
        active: &[usize],
        step: u64,
        reconverging: impl Fn(&S) -> bool,
    ) -> usize {
        if let Some((order, next)) = &mut self.order {
            // Entries naming a finished thread are skipped, so every order is a valid schedule
            // (what shrinking needs); past the end, the lowest-numbered thread runs.
            while let Some(&t) = order.get(*next) {
                *next += 1;
                if active.contains(&(t as usize)) {
                    return t as usize;
                }
            }
            return *active
                .iter()
                .min()
                .expect("choose is called with an active thread");
        }
        match self.policy {
            Policy::Random => active[(self.rng.next_u64() % active.len() as u64) as usize],
            Policy::Warps => {
                let warps = threads.len().div_ceil(WARP_LANES);
                loop {
                    let base = self.warp * WARP_LANES;
                    while self.lane < WARP_LANES && base + self.lane < threads.len() {
                        let t = base + self.lane;
                        self.lane += 1;
                        if threads[t].walk.is_some() {
                            return t;
                        }
                    }
                    self.warp = (self.warp + 1) % warps;
                    self.lane = 0;
                }
            }
            Policy::Lockstep => {
                let warps = threads.len().div_ceil(WARP_LANES);
                while self.issue.is_empty() {
                    let lanes =
                        self.warp * WARP_LANES..((self.warp + 1) * WARP_LANES).min(threads.len());
                    self.warp = (self.warp + 1) % warps;
                    let walks = |t: &usize| threads[*t].walk.as_ref().map(|(s, _, _)| s);
                    let running: VecDeque<usize> = lanes
                        .clone()
                        .filter(|t| walks(t).is_some_and(|s| !reconverging(s)))
                        .collect();
                    // Every active lane at the reconvergence point: the warp reconverges.
                    self.issue = if running.is_empty() {
                        lanes.filter(|t| walks(t).is_some()).collect()
                    } else {
                        running
                    };
                }
                self.issue.pop_front().expect("the issue is not empty")
            }
            Policy::Pct { .. } => {
                let best = *active
                    .iter()
                    .max_by_key(|&&t| (threads[t].priority, std::cmp::Reverse(t)))
                    .unwrap_or(&0);
                while self.change_points.first().is_some_and(|&p| p <= step) {
                    self.change_points.remove(0);
                    threads[best].priority = self.next_low;
                    self.next_low -= 1;
                }
                best
            }
        }
    }
}
