//! Interleavings of a few fragments on one pixel, replayed step by step: the seeds searched, the
//! replay of an explicit order, the words after every step, and every reordering of a set of walks.
//!
//! Every run here replays an explicit order of threads through
//! [`fragsim_capture::executors::scheduled::run_fragments_in_order`], so what a caller prints is what ran.
//! A step may do several memory operations (a render-target read is `K` loads under the pixel's
//! lock); [`Trace::steps`] groups them.

use fragsim_capture::executors::scheduled::{
    run_fragments_in_order, Granularity, Policy, Schedule, Trace,
};
use fragsim_capture::Scheme;
use fragsim_memory::Op;
use fragsim_raster::{depth_key, Fragment};

/// The most fragments an explanation takes: one thread each, and `Trace::order` numbers threads
/// in `u32`, but the searches grow with the walks' interleavings, so a handful is what reads.
pub const MAX_FRAGMENTS: usize = 64;

/// The fragments on one pixel at `depths`: fragment `i` is primitive `i` and runs on thread `i`.
///
/// # Errors
/// No depth, more than [`MAX_FRAGMENTS`], or a depth outside `[0, 1]`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "primitive ids are positions in at most MAX_FRAGMENTS depths"
)]
pub fn one_pixel(depths: &[f32]) -> Result<Vec<Fragment>, String> {
    if depths.is_empty() || depths.len() > MAX_FRAGMENTS {
        return Err(format!("explain needs 1 to {MAX_FRAGMENTS} depths"));
    }
    depths
        .iter()
        .enumerate()
        .map(|(i, &d)| {
            depth_key(d)
                .map(|depth_key| Fragment {
                    pixel: 0,
                    depth_key,
                    prim: i as u32,
                })
                .ok_or_else(|| format!("depth {d} is outside [0, 1]"))
        })
        .collect()
}

/// The schedule searched at `seed`: uniform random on even seeds, PCT on odd ones, one thread
/// per fragment.
#[must_use]
pub fn schedule(seed: u64, threads: usize) -> Schedule {
    Schedule {
        policy: if seed.is_multiple_of(2) {
            Policy::Random
        } else {
            Policy::Pct { depth: 3 }
        },
        in_flight: threads,
        granularity: Granularity::Fragment,
        seed,
    }
}

/// The trace of `fragments` run in `order` (thread `order[i]` takes step `i`).
#[must_use]
pub fn record<S: Scheme>(scheme: &S, fragments: &[S::Input], order: &[u32]) -> Trace {
    run_fragments_in_order(scheme, fragments, order, true)
        .trace
        .expect("a recorded run has a trace")
}

/// Steps in the trace (a step may record several memory operations).
#[must_use]
pub fn step_count(trace: &Trace) -> usize {
    trace.steps().count()
}

/// Times the running thread changes from one step to the next.
#[must_use]
pub fn switches(trace: &Trace) -> usize {
    trace.order().windows(2).filter(|w| w[0] != w[1]).count()
}

/// The pixel's `k` slot words (the `u64` words; a render target's lock and last writer are `u32`)
/// after each step, replayed from the trace's (operand, returned) pairs, starting from `init`.
#[must_use]
pub fn memory_after(trace: &Trace, k: u32, init: u64) -> Vec<Vec<u64>> {
    let mut words = vec![init; k as usize];
    trace
        .steps()
        .map(|events| {
            for e in events.iter().filter(|e| e.width == 64) {
                words[e.word] = match e.op {
                    Op::Load => e.returned,
                    Op::Store | Op::Swap => e.operand,
                    Op::FetchMin => e.returned.min(e.operand),
                    Op::FetchMax => e.returned.max(e.operand),
                    Op::FetchAdd => e.returned.wrapping_add(e.operand),
                    Op::FetchOr => e.returned | e.operand,
                };
            }
            words.clone()
        })
        .collect()
}

/// The `k` nearest of the fragments' packed words, ascending: what exact slots hold.
#[must_use]
pub fn nearest(fragments: &[Fragment], k: u32) -> Vec<u64> {
    let mut expected: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
    expected.sort_unstable();
    expected.truncate(k as usize);
    expected
}

/// Every distinct reordering of `order` (each thread keeps its number of steps, in its own
/// order), or `None` when there are more than `limit`.
#[must_use]
pub fn interleavings(order: &[u32], limit: u64) -> Option<Vec<Vec<u32>>> {
    let threads = order.iter().max().map_or(0, |&t| t as usize + 1);
    let mut left = vec![0_usize; threads];
    for &t in order {
        left[t as usize] += 1;
    }
    // The multinomial coefficient, stopping once past the limit.
    let mut count: u64 = 1;
    let mut placed: u64 = 0;
    for &n in &left {
        for i in 1..=n as u64 {
            placed += 1;
            count = count.checked_mul(placed)? / i;
            if count > limit {
                return None;
            }
        }
    }
    #[expect(
        clippy::cast_possible_truncation,
        reason = "thread indices are below the fragment count, at most MAX_FRAGMENTS"
    )]
    fn extend(left: &mut [usize], prefix: &mut Vec<u32>, len: usize, out: &mut Vec<Vec<u32>>) {
        if prefix.len() == len {
            out.push(prefix.clone());
            return;
        }
        for t in 0..left.len() {
            if left[t] > 0 {
                left[t] -= 1;
                prefix.push(t as u32);
                extend(left, prefix, len, out);
                prefix.pop();
                left[t] += 1;
            }
        }
    }
    let mut out = Vec::new();
    extend(&mut left, &mut Vec::new(), order.len(), &mut out);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_raster::Viewport;
    use fragsim_schemes::kbuffer::EMPTY;
    use fragsim_schemes::mdts::Mdts;

    #[test]
    fn interleavings_are_the_distinct_reorderings_and_stop_past_the_limit() {
        // Two steps of thread 0 and one of thread 1: 3! / (2! 1!) = 3 orders.
        let all = interleavings(&[0, 1, 0], 100).unwrap();
        assert_eq!(all, vec![vec![0, 0, 1], vec![0, 1, 0], vec![1, 0, 0]]);
        // 4 threads of 3 steps: 12! / (3!)^4 = 369,600 orders, past a limit of 1,000.
        let order: Vec<u32> = (0..4).flat_map(|t| [t; 3]).collect();
        assert!(interleavings(&order, 1_000).is_none());
        assert_eq!(interleavings(&order[..6], 1_000).unwrap().len(), 20);
    }

    #[test]
    fn depths_outside_the_unit_interval_or_too_many_are_refused() {
        assert_eq!(one_pixel(&[0.5, 0.25]).unwrap()[1].prim, 1);
        assert!(one_pixel(&[0.5, -0.1]).unwrap_err().contains("-0.1"));
        assert!(one_pixel(&[]).is_err());
        assert!(one_pixel(&[0.5; MAX_FRAGMENTS + 1]).is_err());
    }

    #[test]
    fn the_replayed_words_end_as_the_schemes_slots() {
        // MDTS leaves the sorted inputs in its slots, whatever the order of its walks.
        let fragments = one_pixel(&[0.3, 0.5, 0.1]).unwrap();
        let scheme = Mdts::<u64>::ascending(Viewport::new(1, 1).unwrap(), 3).unwrap();
        let trace = record(&scheme, &fragments, &schedule_order(&scheme, &fragments));
        let memory = memory_after(&trace, 3, EMPTY);
        assert_eq!(memory.len(), step_count(&trace));
        assert_eq!(memory.last().unwrap(), &nearest(&fragments, 3));
    }

    /// The order seed 1 (PCT) runs.
    fn schedule_order<S: Scheme<Input = Fragment>>(scheme: &S, fragments: &[Fragment]) -> Vec<u32> {
        let run = fragsim_capture::executors::scheduled::run_fragments(
            scheme,
            fragments,
            &schedule(1, fragments.len()),
            true,
        );
        run.trace.unwrap().order()
    }
}
