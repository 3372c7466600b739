//! The ordered interlock (`crates/schemes/src/kbuffer/interlock_ordered.rs`): a pixel's
//! critical sections under its lock, entered in primitive order. Two fragments of one pixel,
//! submitted in list order, every interleaving of their attempts with at most
//! [`PREEMPTIONS`] preemptions (a walk that finds an earlier fragment still to come yields before
//! its retry, the shared driver `run_spinning`):
//! - no lost fragment and mutual exclusion, keeping the `K` nearest (`k_best_error`, the checker
//!   that passes MDTS: two sections overlapping would both read the slots before either wrote
//!   them, and one fragment would be lost);
//! - order: keeping the first `K` = 1, the first submitted is kept in every interleaving, and
//!   both sections ran (the pixel's `done` word is 2).
//!
//! The same model fails two broken variants (their own tests): the same policy without the order
//! (the unordered interlock) keeps the second in some interleaving, and the ordered interlock
//! handed the wrong order (the ranks reversed: it enters out of order) keeps the second in every
//! one.
//!
//! **Why a preemption bound.** Unbounded, loom explores schedules where the waiting fragment
//! retries forever, each attempt preempted by the other thread's failed lock at the one moment
//! the lock is held: an unfair livelock that the hardware's scheduler never runs, and which
//! made the unbounded model panic ("Model exceeded maximum number of branches", the fresh-clone
//! CI run of 62bbcb4). Every cycle of it costs a preemption (a yield is not one), so a bound
//! cuts it off. The bound still covers what the properties are about: a violation needs the two
//! sections to overlap or the later fragment to enter first, and each is a schedule with at most
//! two preemptions (switch into the other thread inside the section or before the earlier
//! fragment's attempt, and back): a bound of [`PREEMPTIONS`] explores every placement of the
//! other thread's attempt between any two memory operations of a section, and the two broken
//! variants show that it finds what it must.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::primitive_order::PrimitiveOrder;
use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::memory::WordMemory;
use fragsim::raster::Fragment;
use fragsim::schemes::kbuffer::interlock_ordered::{KBufferInterlockOrdered, Keep};
use fragsim::schemes::mdts::Direction;

use super::{explore, fragments, k_best_error, one_pixel, run_spinning, DISTINCT};

/// The preemption bound of every model here (the module's doc says why it suffices): a
/// violation's two preemptions, and four more, so that the waiting fragment's retries are also
/// interleaved with the section in every way two more preemptions allow. Measured
/// (`cargo test --release --test loom -- kbuffer_interlock_ordered --nocapture`, this machine):
/// bound 3, 41 interleavings a model (K = 1, 2, 3); bound 6, 168, each model under 0.2 s.
const PREEMPTIONS: usize = 6;

/// The order the scheme's sections follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Order {
    /// The fragments' submission order (the list's): the ordered interlock.
    Submission,
    /// No order: the unordered interlock.
    None,
    /// The list's order reversed: an ordered interlock that enters out of order (broken).
    Reversed,
}

/// Every interleaving (within [`PREEMPTIONS`]) of the scheme keeping `keep` in `K` = `k` slots,
/// one loom thread per fragment of `list` (submitted in its order), its sections in `order`:
/// (interleavings, wrong ones). Wrong: keeping the nearest, not exactly the `k` nearest with the
/// drops counted; keeping the first, not the first `k` submitted (sorted), or, with an order,
/// fewer sections run than fragments.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a loom model's list has a few fragments"
)]
fn model(name: &str, keep: Keep, order: Order, k: u32, list: &[Fragment]) -> (usize, usize) {
    let ordered = order != Order::None;
    let submitted: Vec<Fragment> = match order {
        Order::Reversed => list.iter().rev().copied().collect(),
        Order::Submission | Order::None => list.to_vec(),
    };
    #[expect(
        clippy::shadow_unrelated,
        reason = "the order as the model's threads share it"
    )]
    let order: &'static PrimitiveOrder =
        Box::leak(Box::new(PrimitiveOrder::of_fragments(1, &submitted)));
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
    let explored = explore(name, Some(PREEMPTIONS), move || {
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

/// 2 threads, every interleaving within the bound: keeping the nearest, K = 1, 2, 3, nothing lost
/// and the drops counted; keeping the first, K = 1, the first submitted in every interleaving.
#[test]
fn kbuffer_interlock_ordered_2_threads_loses_nothing_and_enters_in_primitive_order() {
    let list = fragments(&DISTINCT[..2]);
    for k in [1, 2, 3] {
        let name = format!("kbuffer_interlock_ordered_2_threads_k{k}");
        let (explored, wrong) = model(&name, Keep::Nearest, Order::Submission, k, &list);
        assert!(explored > 1, "loom explored one interleaving only");
        assert_eq!(wrong, 0, "{name}: an interleaving lost a fragment");
    }
    // The nearer fragment is submitted second, so that keep-first and keep-nearest differ.
    assert!(list[1] < list[0]);
    let (explored, wrong) = model(
        "kbuffer_interlock_ordered_first_2_threads_k1",
        Keep::First,
        Order::Submission,
        1,
        &list,
    );
    assert!(explored > 1, "loom explored one interleaving only");
    assert_eq!(
        wrong, 0,
        "an interleaving kept the fragment submitted second"
    );
}

/// The broken variants, through the same model: without the order (the unordered interlock)
/// the fragment submitted second is kept in some interleaving; with the order reversed (entering
/// out of order) in every one, so the model of the test above can fail both ways.
#[test]
fn kbuffer_interlock_ordered_model_catches_sections_entered_out_of_order() {
    let list = fragments(&DISTINCT[..2]);
    let (explored, missed) = model(
        "kbuffer_interlock_unordered_first_2_threads_k1",
        Keep::First,
        Order::None,
        1,
        &list,
    );
    assert!(
        missed > 0 && missed < explored,
        "the unordered control kept the first submitted in {} of {explored} interleavings: the \
         model is vacuous",
        explored - missed
    );
    #[expect(clippy::shadow_unrelated, reason = "the next model's counts")]
    let (explored, missed) = model(
        "kbuffer_interlock_reversed_first_2_threads_k1",
        Keep::First,
        Order::Reversed,
        1,
        &list,
    );
    assert!(explored > 1, "loom explored one interleaving only");
    assert_eq!(
        missed, explored,
        "the reversed order kept the first submitted in some interleaving"
    );
}
