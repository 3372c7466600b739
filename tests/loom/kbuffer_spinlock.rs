//! The spinlocked k-buffer (`crates/schemes/src/kbuffer/spinlock.rs`), both loop shapes:
//! the lock held across the critical section's `2 K` steps. Two fragments of one pixel, every
//! interleaving (loom's threads are independently scheduled, as since Volta): mutual exclusion
//! (never two walks between their lock and their release) and no fragment lost; the same
//! critical section without the lock (the k-buffer on separate stores) is the control that loses
//! one.
//!
//! A walk that failed to take the lock yields (`loom::thread::yield_now`) before its retry, as a
//! spinning GPU thread gives way to the holder under independent thread scheduling (the shared
//! driver, `run_spinning`); without it loom would explore a spin without end. `LoomMemory::try_lock` is an acquire compare-exchange
//! and `unlock` a release store, so loom checks that the slots' `Relaxed` loads see the previous
//! holder's stores.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::raster::Fragment;
use fragsim::schemes::kbuffer::spinlock::{KBufferSpinlock, Lock, Loop, SpinInsert};
use fragsim::schemes::kbuffer::{KBuffer, WriteBack};
use fragsim::schemes::mdts::Direction;
use loom::sync::atomic::{AtomicU32, Ordering::SeqCst};

use super::{explore, fragments, k_best_error, one_pixel, run_spinning, run_threads, DISTINCT};

/// Every interleaving of the spinlocked k-buffer with loop `shape`, one loom thread per fragment
/// of `list`: panics if two walks are ever inside the critical section together; returns
/// (interleavings, ones that lost or miscounted a fragment).
fn spinlock_model(name: &str, shape: Loop, k: u32, list: &[Fragment]) -> (usize, usize) {
    let scheme: &'static KBufferSpinlock = Box::leak(Box::new(
        KBufferSpinlock::new(one_pixel(), k, shape, MEMORY_CAP_DEFAULT).unwrap(),
    ));
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let wrong = Arc::new(AtomicUsize::new(0));
    let wrong_in = Arc::clone(&wrong);
    let list = list.to_vec();
    let explored = explore(name, None, move || {
        // Walks between their lock and their release, counted by the walks themselves.
        let inside: &'static AtomicU32 = Box::leak(Box::new(AtomicU32::new(0)));
        let (memory, outcomes) = run_spinning(
            scheme,
            &list,
            move |walk: &SpinInsert| {
                if let Lock::Release { .. } = walk.lock {
                    // Counted out before the release step frees the lock, so that the next
                    // holder cannot count itself in while this one still counts.
                    inside.fetch_sub(1, SeqCst);
                }
            },
            move |was: &SpinInsert, walk: &SpinInsert| {
                if let (Lock::Acquire { .. }, Lock::Held { .. }) = (was.lock, walk.lock) {
                    assert_eq!(inside.fetch_add(1, SeqCst), 0, "two walks hold the lock");
                }
            },
        );
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
    });
    let wrong = wrong.load(StdOrdering::Relaxed);
    eprintln!("loom {name}: {wrong} of {explored} interleavings lose a fragment");
    (explored, wrong)
}

/// 2 threads, K = 2 and K = 1, exhaustive, both loops: mutual exclusion and nothing lost (K = 1:
/// the nearer kept, one walk `Dropped`); the control, the same loads and stores without the lock,
/// loses a fragment in some interleaving.
#[test]
fn kbuffer_spinlock_2_threads_excludes_and_loses_nothing_where_the_unlocked_section_loses() {
    let list = fragments(&DISTINCT[..2]);
    for k in [2, 1] {
        for shape in [Loop::Naive, Loop::Fixed] {
            let name = format!("{}_2_threads_k{k}", shape.scheme_name().replace('-', "_"));
            let (explored, wrong) = spinlock_model(&name, shape, k, &list);
            assert!(explored > 1, "loom explored one interleaving only");
            assert_eq!(wrong, 0, "{name}: an interleaving lost a fragment");
        }
    }
    let unlocked: &'static KBuffer = Box::leak(Box::new(
        KBuffer::with_write_back(
            one_pixel(),
            2,
            WriteBack::SeparateStores,
            MEMORY_CAP_DEFAULT,
        )
        .unwrap(),
    ));
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let lost = Arc::new(AtomicUsize::new(0));
    let lost_in = Arc::clone(&lost);
    explore("kbuffer_spinlock_control_2_threads_k2", None, move || {
        let (memory, walks) = run_threads(unlocked, &list);
        let kept = unlocked.resolve(memory);
        if k_best_error(
            Direction::Ascending,
            2,
            &values,
            kept.pixel(0),
            &walks.outcomes,
        )
        .is_some()
        {
            lost_in.fetch_add(1, StdOrdering::Relaxed);
        }
    });
    assert!(
        lost.load(StdOrdering::Relaxed) > 0,
        "the control lost nothing: the model is vacuous"
    );
}
