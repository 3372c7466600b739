//! MDTS's invariant checked after every step of an interleaving (`docs/proof.md`): each slot
//! only ever decreases, and the multiset of slot values plus the values carried in flight (plus
//! those carried past the last slot) equals the inputs. Also the densest interleaving among the
//! scheduled executor's seeds, the one that tests the invariant hardest.
//!
//! Why: `fragsim explain --scheme mdts` prints the interleaving with the invariant beside every
//! step, so the proof's induction can be followed on a run that actually happened.

use fragsim_capture::executors::scheduled::{run_fragments, Trace};
use fragsim_raster::Fragment;
use fragsim_schemes::kbuffer::EMPTY;
use fragsim_schemes::mdts::Mdts;

use crate::interleaving::{record, schedule, switches};

/// The invariant's state after one step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Checked {
    /// Whether the invariant holds after the step.
    pub holds: bool,
    /// Values carried by the threads in flight, by thread.
    pub carried: Vec<u64>,
    /// Values carried past the last slot so far (dropped: farther than the `K` nearest).
    pub dropped: Vec<u64>,
}

/// Checks the invariant after each step of `trace` (one memory operation per MDTS step);
/// `memory` holds the pixel's `k` slots after each step
/// ([`memory_after`](crate::interleaving::memory_after)).
#[must_use]
pub fn invariant(
    fragments: &[Fragment],
    k: u32,
    trace: &Trace,
    memory: &[Vec<u64>],
) -> Vec<Checked> {
    let mut inputs: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    inputs.sort_unstable();
    let mut carried: Vec<Option<u64>> = inputs.iter().map(|_| None).collect();
    for f in fragments {
        carried[f.prim as usize] = Some(f.packed());
    }
    let mut dropped: Vec<u64> = Vec::new();
    let mut before = vec![EMPTY; k as usize];
    trace
        .events
        .iter()
        .zip(memory)
        .map(|(e, after)| {
            let t = e.thread as usize;
            let decreased = after.iter().zip(&before).all(|(a, b)| a <= b);
            carried[t] = (e.returned != EMPTY).then(|| e.returned.max(e.operand));
            if e.word + 1 == k as usize {
                dropped.extend(carried[t].take());
            }
            let mut seen: Vec<u64> = after.iter().copied().filter(|&v| v != EMPTY).collect();
            seen.extend(carried.iter().flatten());
            seen.extend(&dropped);
            seen.sort_unstable();
            before.clone_from(after);
            Checked {
                holds: decreased && seen == inputs,
                carried: carried.iter().flatten().copied().collect(),
                dropped: dropped.clone(),
            }
        })
        .collect()
}

/// The run with the most context switches among seeds `0..seeds` (at least seed 0; the lowest
/// seed among equals), replayed from its order so that it is a replayable interleaving.
#[must_use]
pub fn densest(scheme: &Mdts<u64>, fragments: &[Fragment], seeds: u64) -> (u64, Trace) {
    let threads = fragments.len();
    let (seed, trace) = (0..seeds.max(1))
        .map(|seed| {
            let run = run_fragments(scheme, fragments, &schedule(seed, threads), true);
            (seed, run.trace.expect("a recorded run has a trace"))
        })
        .max_by_key(|(seed, trace)| (switches(trace), std::cmp::Reverse(*seed)))
        .expect("at least one seed");
    (seed, record(scheme, fragments, &trace.order()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interleaving::{memory_after, one_pixel};
    use fragsim_raster::Viewport;

    #[test]
    fn the_invariant_holds_at_every_step_and_fails_on_a_forged_slot() {
        let fragments = one_pixel(&[0.3, 0.5, 0.1, 0.2]).unwrap();
        for k in [2, 4] {
            let scheme = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), k).unwrap();
            let (_, trace) = densest(&scheme, &fragments, 50);
            assert!(switches(&trace) > 0);
            let mut memory = memory_after(&trace, k, EMPTY);
            let checks = invariant(&fragments, k, &trace, &memory);
            assert_eq!(checks.len(), trace.events.len());
            assert!(checks.iter().all(|c| c.holds), "K = {k}");
            // Every input ends in a slot or dropped, none in flight.
            let last = checks.last().unwrap();
            assert!(last.carried.is_empty());
            assert_eq!(last.dropped.len(), fragments.len() - k as usize);
            // A slot that grows (a value appearing from nowhere) breaks it from that step on.
            let step = memory.len() / 2;
            memory[step][0] = EMPTY - 1;
            let forged = invariant(&fragments, k, &trace, &memory);
            assert!(!forged[step].holds);
        }
    }
}
