//! The interlocked k-buffer (`crates/schemes/src/kbuffer/interlock.rs`): the k-buffer's
//! read–insert–write-back as one critical section under the pixel lock. Two fragments of one
//! pixel, every interleaving: none is lost, and the walks count what fell off; the plain
//! k-buffer (render targets), run through the same model, is the control that loses one.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::raster::Fragment;
use fragsim::schemes::kbuffer::interlock::KBufferInterlock;
use fragsim::schemes::kbuffer::KBuffer;
use fragsim::schemes::mdts::Direction;

use super::{explore, fragments, k_best_error, one_pixel, run_threads, Walks, DISTINCT};

/// Every interleaving of `scheme` (keeping the `K` = `k` nearest), one loom thread per fragment
/// of `list`, checked by the checker that passes MDTS (`k_best_error`: exactly the `k` nearest
/// kept, one `Dropped` walk per fragment beyond them). Returns (interleavings, wrong ones, the
/// most steps a walk took).
fn model<S: Scheme<Input = Fragment> + 'static>(
    name: &str,
    scheme: S,
    k: u32,
    list: &[Fragment],
) -> (usize, usize, u64) {
    let scheme: &'static S = Box::leak(Box::new(scheme));
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let wrong = Arc::new(AtomicUsize::new(0));
    let longest = Arc::new(AtomicUsize::new(0));
    let (wrong_in, longest_in) = (Arc::clone(&wrong), Arc::clone(&longest));
    let list = list.to_vec();
    let explored = explore(name, None, move || {
        let (memory, Walks { outcomes, steps }) = run_threads(scheme, &list);
        let capture = scheme.resolve(memory);
        if k_best_error(
            Direction::Ascending,
            k,
            &values,
            capture.pixel(0),
            &outcomes,
        )
        .is_some()
        {
            wrong_in.fetch_add(1, StdOrdering::Relaxed);
        }
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a loom model's step counts are small"
        )]
        let most = steps.iter().copied().max().unwrap_or(0) as usize;
        longest_in.fetch_max(most, StdOrdering::Relaxed);
    });
    let wrong = wrong.load(StdOrdering::Relaxed);
    eprintln!("loom {name}: {wrong} of {explored} interleavings lose a fragment");
    (explored, wrong, longest.load(StdOrdering::Relaxed) as u64)
}

/// 2 threads, K = 3, exhaustive: the interlocked k-buffer keeps both fragments in every
/// interleaving, each walk one step; the plain k-buffer on render targets, same fragments, same
/// K, loses one in some interleaving (read A, read B, write A, write B), so the model can fail.
#[test]
fn kbuffer_interlock_2_threads_k3_loses_no_fragment_where_the_kbuffer_loses_one() {
    const K: u32 = 3;
    let list = fragments(&DISTINCT[..2]);
    let interlock = KBufferInterlock::new(one_pixel(), K, MEMORY_CAP_DEFAULT).unwrap();
    let (explored, wrong, longest) = model("kbuffer_interlock_2_threads_k3", interlock, K, &list);
    assert!(explored > 1, "loom explored one interleaving only");
    assert_eq!(
        wrong, 0,
        "an interleaving lost a fragment under the interlock"
    );
    assert_eq!(longest, 1, "a critical section is one step");

    let plain = KBuffer::new(one_pixel(), K, MEMORY_CAP_DEFAULT).unwrap();
    let (_, lost, _) = model("kbuffer_control_2_threads_k3", plain, K, &list);
    assert!(lost > 0, "the control lost nothing: the model is vacuous");
}

/// 2 threads, K = 1, exhaustive: one fragment must fall off or be evicted; in every interleaving
/// the nearer one is kept and exactly one walk ends `Dropped`, as on the serial executor.
#[test]
fn kbuffer_interlock_2_threads_k1_keeps_the_nearer_and_counts_one_drop() {
    const K: u32 = 1;
    let list = fragments(&DISTINCT[..2]);
    let interlock = KBufferInterlock::new(one_pixel(), K, MEMORY_CAP_DEFAULT).unwrap();
    let (_, wrong, _) = model("kbuffer_interlock_2_threads_k1", interlock, K, &list);
    assert_eq!(
        wrong, 0,
        "an interleaving kept the wrong fragment or miscounted the drop"
    );

    let plain = KBuffer::new(one_pixel(), K, MEMORY_CAP_DEFAULT).unwrap();
    let (_, lost, _) = model("kbuffer_control_2_threads_k1", plain, K, &list);
    assert!(lost > 0, "the control lost nothing: the model is vacuous");
}
