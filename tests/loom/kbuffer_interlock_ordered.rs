//! The ordered interlock (`crates/capture/src/schemes/kbuffer_interlock_ordered.rs`): a pixel's
//! critical sections under its lock, entered in primitive order. Two fragments of one pixel,
//! submitted in list order, every interleaving of their attempts (a walk that finds an earlier
//! fragment still to come yields before its retry, the shared driver `run_spinning`):
//! - no lost fragment and mutual exclusion, keeping the `K` nearest (`k_best_error`, the checker
//!   that passes MDTS: two sections overlapping would both read the slots before either wrote
//!   them, and one fragment would be lost);
//! - order: keeping the first `K` = 1, the first submitted is kept in every interleaving, and
//!   both sections ran (the pixel's `done` word is 2); the same policy without the order (the
//!   unordered interlock) keeps the second in some interleaving, so the model can fail.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::primitive_order::PrimitiveOrder;
use fragsim::capture::schemes::kbuffer_interlock_ordered::{KBufferInterlockOrdered, Keep};
use fragsim::capture::schemes::mdts::Direction;
use fragsim::capture::{Scheme, WordMemory, MEMORY_CAP_DEFAULT};
use fragsim::raster::Fragment;

use super::{explore, fragments, k_best_error, one_pixel, run_spinning, DISTINCT};

/// Every interleaving of the scheme keeping `keep` in `K` = `k` slots, `ordered` or not, one
/// loom thread per fragment of `list`: (interleavings, wrong ones). Wrong: keeping the nearest,
/// not exactly the `k` nearest with the drops counted; keeping the first, not the first `k`
/// submitted (sorted), or fewer sections run than fragments.
fn model(name: &str, keep: Keep, ordered: bool, k: u32, list: &[Fragment]) -> (usize, usize) {
    let order: &'static PrimitiveOrder = Box::leak(Box::new(PrimitiveOrder::of_fragments(1, list)));
    let scheme: &'static KBufferInterlockOrdered<'static> = Box::leak(Box::new(
        KBufferInterlockOrdered::new(
            one_pixel(),
            k,
            keep,
            ordered.then_some(order),
            MEMORY_CAP_DEFAULT,
        )
        .unwrap(),
    ));
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let mut first: Vec<u64> = values.iter().copied().take(k as usize).collect();
    first.sort_unstable();
    let wrong = Arc::new(AtomicUsize::new(0));
    let wrong_in = Arc::clone(&wrong);
    let list = list.to_vec();
    let explored = explore(name, None, move || {
        let (memory, outcomes) = run_spinning(scheme, &list, |_| {}, |_, _| {});
        let kept = scheme.resolve(memory);
        let bad = match keep {
            Keep::Nearest => {
                k_best_error(Direction::Ascending, k, &values, kept.pixel(0), &outcomes).is_some()
            }
            Keep::First => {
                let done = WordMemory::<u32>::load(memory, 1);
                kept.pixel(0) != first.as_slice() || (ordered && done != list.len() as u32)
            }
        };
        if bad {
            wrong_in.fetch_add(1, StdOrdering::Relaxed);
        }
    });
    let wrong = wrong.load(StdOrdering::Relaxed);
    eprintln!("loom {name}: {wrong} of {explored} interleavings wrong");
    (explored, wrong)
}

/// 2 threads, exhaustive: keeping the nearest, K = 1, 2, 3, nothing lost and the drops
/// counted; keeping the first, K = 1, the first submitted in every interleaving, which the
/// unordered control misses in some.
#[test]
#[ignore = "issue 19, open: loom panics with \"Model exceeded maximum number of branches\" on this \
            model (fresh-clone CI run of 62bbcb4, 2026-12-02): the waiting fragment's retry loop \
            under an unbounded preemption search; the model needs a bound or a yield-aware wait"]
fn kbuffer_interlock_ordered_2_threads_loses_nothing_and_enters_in_primitive_order() {
    let list = fragments(&DISTINCT[..2]);
    for k in [1, 2, 3] {
        let name = format!("kbuffer_interlock_ordered_2_threads_k{k}");
        let (explored, wrong) = model(&name, Keep::Nearest, true, k, &list);
        assert!(explored > 1, "loom explored one interleaving only");
        assert_eq!(wrong, 0, "{name}: an interleaving lost a fragment");
    }
    // The nearer fragment is submitted second, so that keep-first and keep-nearest differ.
    let later_nearer = &list;
    assert!(later_nearer[1] < later_nearer[0]);
    let (explored, wrong) = model(
        "kbuffer_interlock_ordered_first_2_threads_k1",
        Keep::First,
        true,
        1,
        later_nearer,
    );
    assert!(explored > 1, "loom explored one interleaving only");
    assert_eq!(
        wrong, 0,
        "an interleaving kept the fragment submitted second"
    );
    let (_, missed) = model(
        "kbuffer_interlock_unordered_first_2_threads_k1",
        Keep::First,
        false,
        1,
        later_nearer,
    );
    assert!(
        missed > 0,
        "the unordered control kept the first submitted: the model is vacuous"
    );
}
