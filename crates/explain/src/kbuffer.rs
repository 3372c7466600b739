//! The k-buffer's read–modify–write hazard on one pixel: the damage a run leaves (fragments lost
//! or duplicated against the `K` nearest inputs), the search of the scheduled executor's seeds
//! for a damaging run, and the shrinker that makes it the shortest, plainest interleaving.
//!
//! Why: `fragsim explain` prints the interleaving, and a loss reads only when it is small. The
//! shortest losing interleaving is 4 steps on render targets and `4 K` with separate stores
//! (`fragsim_schemes::kbuffer` says why); the shrinker reaches them from what a seed found by
//! dropping fragments, then moving steps, each change kept only while the damage still shows.

use std::collections::BTreeMap;

use fragsim_capture::executors::scheduled::{run_fragments, Trace};
use fragsim_raster::Fragment;
use fragsim_schemes::kbuffer::{KBuffer, EMPTY};

use crate::interleaving::{
    interleavings, memory_after, nearest, record, schedule, step_count, switches,
};

/// Interleavings of the shrunk walks tried one by one when there are at most this many.
pub const EXHAUSTIVE_LIMIT: u64 = 200_000;

/// What a k-buffer's slots got wrong against the `K` nearest inputs.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Damage {
    /// Packed words of the `K` nearest inputs missing from the slots, ascending.
    pub lost: Vec<u64>,
    /// Packed words held in two slots or more, ascending.
    pub duplicated: Vec<u64>,
}

impl Damage {
    /// Whether the slots are the `K` nearest inputs, each once.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lost.is_empty() && self.duplicated.is_empty()
    }
}

/// What `slots` (a pixel's `k` slot words, [`EMPTY`] for an empty one) got wrong against the
/// `k` nearest of `fragments`.
#[must_use]
pub fn damage(fragments: &[Fragment], k: u32, slots: &[u64]) -> Damage {
    let mut counts: BTreeMap<u64, i64> = BTreeMap::new();
    for &v in slots.iter().filter(|&&v| v != EMPTY) {
        *counts.entry(v).or_default() += 1;
    }
    Damage {
        lost: nearest(fragments, k)
            .into_iter()
            .filter(|v| !counts.contains_key(v))
            .collect(),
        duplicated: counts
            .iter()
            .filter(|&(_, &c)| c > 1)
            .map(|(&v, _)| v)
            .collect(),
    }
}

/// The trace of `fragments` run in `order` on the k-buffer and its damage, if it shows any.
#[must_use]
pub fn hazard(
    scheme: &KBuffer,
    k: u32,
    fragments: &[Fragment],
    order: &[u32],
) -> Option<(Trace, Damage)> {
    let trace = record(scheme, fragments, order);
    let last = memory_after(&trace, k, EMPTY).pop().unwrap_or_default();
    let damage = damage(fragments, k, &last);
    (!damage.is_empty()).then_some((trace, damage))
}

/// The first of `seeds` seeds of the scheduled executor ([`schedule`]) whose run damages the
/// slots, with the replay of its order.
#[must_use]
pub fn search(
    scheme: &KBuffer,
    k: u32,
    fragments: &[Fragment],
    seeds: u64,
) -> Option<(u64, Trace)> {
    (0..seeds).find_map(|seed| {
        let run = run_fragments(scheme, fragments, &schedule(seed, fragments.len()), true);
        let order = run.trace.expect("a recorded run has a trace").order();
        hazard(scheme, k, fragments, &order).map(|(trace, _)| (seed, trace))
    })
}

/// What shrinking minimises, in order: steps; render-target write-backs dropped because a later
/// reader's had committed (the same loss reads more plainly as the later one's stale read
/// erasing the earlier write-back, in commit order); context switches.
fn rank(trace: &Trace) -> (usize, usize, usize) {
    let dropped = trace
        .steps()
        .filter(|events| events.len() > 1 && events.iter().all(|e| e.width == 32))
        .count();
    (step_count(trace), dropped, switches(trace))
}

/// Shrinks a damaging run of `fragments` in `order`: drops fragments while the damage still
/// shows, then, among the interleavings of what is left (all of them when there are at most
/// [`EXHAUSTIVE_LIMIT`], else one step moved earlier at a time), keeps the damaging one with the
/// fewest steps, then write-backs dropped behind a later reader's, then switches. Returns the fragments left (thread `t` carries the `t`-th of
/// them, which keeps its primitive id) and the order; a run without damage comes back as it is.
#[must_use]
pub fn shrink(
    scheme: &KBuffer,
    k: u32,
    mut fragments: Vec<Fragment>,
    mut order: Vec<u32>,
) -> (Vec<Fragment>, Vec<u32>) {
    let mut changed = true;
    while changed {
        changed = false;
        for drop in (0..fragments.len()).rev() {
            if fragments.len() <= 1 {
                break;
            }
            let mut fewer = fragments.clone();
            // The fragments keep their primitive ids (the user's numbering, which the report
            // prints); only the threads, which are positions in the list, close up.
            fewer.remove(drop);
            #[expect(
                clippy::cast_possible_truncation,
                reason = "drop is a position in at most MAX_FRAGMENTS fragments (crate::interleaving)"
            )]
            let drop = drop as u32;
            let remapped: Vec<u32> = order
                .iter()
                .filter(|&&t| t != drop)
                .map(|&t| if t > drop { t - 1 } else { t })
                .collect();
            if let Some((trace, _)) = hazard(scheme, k, &fewer, &remapped) {
                fragments = fewer;
                order = trace.order();
                changed = true;
                break;
            }
        }
    }
    // Few enough interleavings of these walks: try them all. Else move one step earlier
    // wherever the hazard survives it and the rank improves.
    if let Some(all) = interleavings(&order, EXHAUSTIVE_LIMIT) {
        if let Some(best) = all
            .iter()
            .filter_map(|candidate| hazard(scheme, k, &fragments, candidate))
            .map(|(trace, _)| trace)
            .min_by_key(|trace| (rank(trace), trace.order()))
        {
            order = best.order();
        }
        return (fragments, order);
    }
    let mut best = record(scheme, &fragments, &order);
    #[expect(
        clippy::shadow_unrelated,
        reason = "the second phase's own flag, as the first phase's `changed` above"
    )]
    let mut changed = true;
    while changed {
        changed = false;
        'search: for j in 1..order.len() {
            for i in 0..j {
                if order[i] == order[j] {
                    continue;
                }
                let mut candidate = order.clone();
                let moved = candidate.remove(j);
                candidate.insert(i, moved);
                if let Some((trace, _)) = hazard(scheme, k, &fragments, &candidate) {
                    if rank(&trace) < rank(&best) {
                        order = trace.order();
                        best = trace;
                        changed = true;
                        break 'search;
                    }
                }
            }
        }
    }
    (fragments, order)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interleaving::one_pixel;
    use fragsim_raster::Viewport;
    use fragsim_schemes::kbuffer::WriteBack;

    fn kbuffer(k: u32, machine: WriteBack) -> KBuffer {
        let viewport = Viewport::new(1, 1).unwrap();
        KBuffer::with_write_back(viewport, k, machine, fragsim_capture::MEMORY_CAP_DEFAULT).unwrap()
    }

    #[test]
    #[expect(clippy::shadow_unrelated, reason = "each `d` is its own case's damage")]
    fn damage_names_the_missing_and_the_doubled() {
        let fragments = one_pixel(&[0.3, 0.5, 0.1]).unwrap();
        let [a, b, c] = [0, 1, 2].map(|i| fragments[i].packed());
        // Exact slots: nearest first.
        assert!(damage(&fragments, 3, &[c, a, b]).is_empty());
        // 0.3 overwritten by a copy of 0.1.
        let d = damage(&fragments, 3, &[c, c, b]);
        assert_eq!((d.lost, d.duplicated), (vec![a], vec![c]));
        // With K = 2 the farthest is not owed; an empty slot loses the one it should hold.
        let d = damage(&fragments, 2, &[c, EMPTY]);
        assert_eq!((d.lost, d.duplicated), (vec![a], vec![]));
    }

    #[test]
    fn serialised_walks_show_no_hazard_and_interleaved_ones_do() {
        let fragments = one_pixel(&[0.3, 0.5, 0.1]).unwrap();
        for machine in [WriteBack::RenderTarget, WriteBack::SeparateStores] {
            let scheme = kbuffer(3, machine);
            // One thread in flight: each walk runs alone, nothing is lost.
            let alone = fragsim_capture::executors::scheduled::Schedule {
                in_flight: 1,
                ..schedule(0, fragments.len())
            };
            let run = run_fragments(&scheme, &fragments, &alone, true);
            let serial = run.trace.unwrap().order();
            assert!(hazard(&scheme, 3, &fragments, &serial).is_none());
            assert!(search(&scheme, 3, &fragments, 200).is_some(), "{machine:?}");
        }
    }

    #[test]
    fn shrinking_reaches_the_shortest_loss_on_render_targets() {
        let fragments = one_pixel(&[0.3, 0.5, 0.1, 0.2, 0.7]).unwrap();
        let scheme = kbuffer(5, WriteBack::RenderTarget);
        let (_, found) = search(&scheme, 5, &fragments, 200).expect("a seed loses");
        let (fewer, order) = shrink(&scheme, 5, fragments.clone(), found.order());
        let (trace, damage) = hazard(&scheme, 5, &fewer, &order).expect("still damaging");
        // Two walks of a read and a write-back, the second read stale: 4 steps, one loss.
        assert_eq!((fewer.len(), step_count(&trace)), (2, 4));
        assert_eq!(damage.lost.len(), 1);
        assert!(step_count(&trace) <= step_count(&found));
        // What is left is a subset of the inputs, numbered as they were.
        assert!(fewer.iter().all(|f| fragments.contains(f)), "{fewer:?}");
    }
}
