//! MDTS with the 64-bit `atomicMin` emulated on 32-bit words
//! (`crates/schemes/src/mdts_emulated64.rs`). Two fragments of one pixel, every
//! interleaving: the unlocked emulation (loads and stores of the halves) tears, leaving in a slot
//! a value neither fragment carried, which loom finds; the emulation inside a per-slot lock keeps
//! exactly the `K` nearest, drops counted, in every interleaving.
//!
//! A walk that failed to take a slot's lock yields before its retry (the shared driver,
//! `run_spinning`), so that loom schedules the holder.

use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim::raster::Fragment;
use fragsim::schemes::mdts::Direction;
use fragsim::schemes::mdts_emulated64::{Emulation, MdtsEmulated64};

use super::{explore, fragments, k_best_error, one_pixel, run_spinning, DISTINCT};

/// Every interleaving of the emulation, one loom thread per fragment of `list`: (interleavings,
/// ones that lost a fragment or miscounted, ones that left a torn value in a slot).
fn model(name: &str, emulation: Emulation, k: u32, list: &[Fragment]) -> (usize, usize, usize) {
    let scheme: &'static MdtsEmulated64 = Box::leak(Box::new(
        MdtsEmulated64::new(one_pixel(), k, emulation, MEMORY_CAP_DEFAULT).unwrap(),
    ));
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let (wrong, torn) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
    let (wrong_in, torn_in) = (Arc::clone(&wrong), Arc::clone(&torn));
    let list = list.to_vec();
    let explored = explore(name, None, move || {
        let (memory, outcomes) = run_spinning(scheme, &list, |_| {}, |_, _| {});
        let kept = scheme.resolve(memory);
        if k_best_error(Direction::Ascending, k, &values, kept.pixel(0), &outcomes).is_some() {
            wrong_in.fetch_add(1, StdOrdering::Relaxed);
        }
        if (0..k as usize)
            .map(|slot| scheme.slot_value(memory, slot))
            .any(|v| v != u64::MAX && !values.contains(&v))
        {
            torn_in.fetch_add(1, StdOrdering::Relaxed);
        }
    });
    let (wrong, torn) = (
        wrong.load(StdOrdering::Relaxed),
        torn.load(StdOrdering::Relaxed),
    );
    eprintln!("loom {name}: {wrong} of {explored} interleavings wrong, {torn} with a torn slot");
    (explored, wrong, torn)
}

/// 2 threads, K = 1 and 2, exhaustive: the locked emulation is never wrong and never torn; the
/// unlocked one leaves a torn value in some interleaving (so the model can fail).
#[test]
fn mdts_emulated64_2_threads_is_exact_where_the_unlocked_halves_tear() {
    let list = fragments(&DISTINCT[..2]);
    for k in [1, 2] {
        let (explored, wrong, torn) = model(
            &format!("mdts_emulated64_2_threads_k{k}"),
            Emulation::Locked,
            k,
            &list,
        );
        assert!(explored > 1, "loom explored one interleaving only");
        assert_eq!(
            (wrong, torn),
            (0, 0),
            "K = {k}: the locked emulation lost or tore"
        );
        #[expect(clippy::shadow_unrelated, reason = "the next model's counts")]
        let (_, wrong, torn) = model(
            &format!("mdts_emulated64_torn_2_threads_k{k}"),
            Emulation::Torn,
            k,
            &list,
        );
        assert!(
            torn > 0 && wrong > 0,
            "K = {k}: the unlocked halves never tore: the model is vacuous"
        );
    }
}
