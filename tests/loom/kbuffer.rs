//! The negative controls: the library's k-buffer, whose read–insert–write is not atomic, on both
//! of its machines.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering as StdOrdering};
use std::sync::Arc;

use fragsim::capture::{Scheme, Step, MEMORY_CAP_DEFAULT};
use fragsim::memory::SerialMemory;
use fragsim::raster::Fragment;
use fragsim::schemes::kbuffer::{KBuffer, WriteBack};
use fragsim::schemes::mdts::Direction;

use super::{
    check_k_best, explore, fragments, k_best_error, one_pixel, run_threads, Walks, DISTINCT,
};

/// The k-buffer with `K` slots on one pixel on `write_back`, leaked for loom's threads.
fn leaked_kbuffer(k: u32, write_back: WriteBack) -> &'static KBuffer {
    Box::leak(Box::new(
        KBuffer::with_write_back(one_pixel(), k, write_back, MEMORY_CAP_DEFAULT)
            .expect("a few slots fit"),
    ))
}

/// Whether `kept` is strictly increasing and made of `values` only: what render-target
/// write-backs leave in every interleaving (no duplicate, no disorder, no torn value).
fn sorted_distinct_subset(kept: &[u64], values: &[u64]) -> bool {
    kept.windows(2).all(|w| w[0] < w[1]) && kept.iter().all(|v| values.contains(v))
}

/// Every interleaving of the k-buffer on `write_back`, one loom thread per fragment of `list`
/// (with at most `preemption_bound` preemptions when given): returns (interleavings, wrong ones,
/// torn ones: a duplicate, disorder or a value not inserted). Checks first that the walks run one
/// after the other, in primitive order, give exactly the `K` nearest.
fn kbuffer_model(
    name: &str,
    k: u32,
    write_back: WriteBack,
    list: &[Fragment],
    preemption_bound: Option<usize>,
) -> (usize, usize, usize) {
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let scheme = leaked_kbuffer(k, write_back);
    let serial: SerialMemory = scheme.layout().allocate();
    let mut in_order = list.to_vec();
    in_order.sort_by_key(|f| f.prim);
    let outcomes: Vec<Step> = in_order
        .iter()
        .map(|&f| scheme.insert(f, &serial, &mut 0))
        .collect();
    let sorted_values: Vec<u64> = in_order.iter().map(|f| f.packed()).collect();
    check_k_best(
        Direction::Ascending,
        k,
        &sorted_values,
        scheme.resolve(&serial).pixel(0),
        &outcomes,
    );

    let wrong = Arc::new(AtomicUsize::new(0));
    let torn = Arc::new(AtomicUsize::new(0));
    let (wrong_in, torn_in) = (Arc::clone(&wrong), Arc::clone(&torn));
    let list_in = list.to_vec();
    let explored = explore(name, preemption_bound, move || {
        #[expect(clippy::shadow_unrelated, reason = "each explored run's own outcomes")]
        let (memory, Walks { outcomes, .. }) = run_threads(scheme, &list_in);
        let capture = scheme.resolve(memory);
        let kept = capture.pixel(0);
        if k_best_error(Direction::Ascending, k, &values, kept, &outcomes).is_some() {
            wrong_in.fetch_add(1, StdOrdering::Relaxed);
        }
        if !sorted_distinct_subset(kept, &values) {
            torn_in.fetch_add(1, StdOrdering::Relaxed);
        }
    });
    let (wrong, torn) = (
        wrong.load(StdOrdering::Relaxed),
        torn.load(StdOrdering::Relaxed),
    );
    eprintln!(
        "loom {name}: {wrong} of {explored} interleavings lose or duplicate a fragment, {torn} tear a write-back"
    );
    (explored, wrong, torn)
}

/// The negative control (2 threads, K = 3, exhaustive): the library's k-buffer with separate
/// stores (`crates/schemes/src/kbuffer/mod.rs`: `K` loads, an insertion in registers, `K` stores, one
/// memory operation per step) is correct when its two walks run one after the other, but loom
/// finds interleavings that lose a fragment, and the very checker that passes MDTS
/// (`check_k_best`) panics on them.
#[test]
fn negative_control_rmw_kbuffer_separate_stores_2_threads_k3_loses_a_fragment() {
    const K: u32 = 3;
    let list = fragments(&DISTINCT[..2]);
    let (explored, wrong, _) = kbuffer_model(
        "negative_control_rmw_kbuffer_stores_count",
        K,
        WriteBack::SeparateStores,
        &list,
        None,
    );
    assert!(
        wrong > 0,
        "loom found no interleaving that loses a fragment: the harness is vacuous"
    );
    assert!(wrong < explored, "the serial orders at least are correct");

    // The same model with the checker's panic left to loom: `loom::model` fails.
    let scheme = leaked_kbuffer(K, WriteBack::SeparateStores);
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    let failed = catch_unwind(AssertUnwindSafe(|| {
        explore(
            "negative_control_rmw_kbuffer_stores_panics",
            None,
            move || {
                let (memory, Walks { outcomes, .. }) = run_threads(scheme, &list);
                let capture = scheme.resolve(memory);
                check_k_best(
                    Direction::Ascending,
                    K,
                    &values,
                    capture.pixel(0),
                    &outcomes,
                );
            },
        )
    }));
    let message = failed.expect_err("loom must reject the non-atomic k-buffer");
    let text = message
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| message.downcast_ref::<&str>().copied())
        .unwrap_or("");
    assert!(
        text.contains("lost or duplicated"),
        "unexpected failure: {text}"
    );
}

/// Render-target write-backs (2 threads, K = 3, exhaustive): the pixel lock really makes a read
/// and a write-back one step each under loom's memory model, so no interleaving tears a
/// write-back (every list sorted, distinct, made of inserted values), yet stale reads lose a
/// fragment in some interleavings and none in others. (Three threads:
/// `tests/suite/kbuffer/single.rs` drives all 90 step interleavings; under loom a preemption
/// bound stops a waiting thread from yielding to the lock's holder, and the unbounded model is
/// too large for the suite.)
#[test]
fn kbuffer_render_target_2_threads_k3_only_loses() {
    let list = fragments(&DISTINCT[..2]);
    let (explored, wrong, torn) = kbuffer_model(
        "kbuffer_render_target_2_threads",
        3,
        WriteBack::RenderTarget,
        &list,
        None,
    );
    assert_eq!(torn, 0, "a render-target write-back tore");
    assert!(wrong > 0, "no stale read lost a fragment");
    assert!(wrong < explored, "every interleaving lost");
}

/// Separate stores tear (3 threads, K = 3, at most 1 preemption): some interleaving leaves a
/// duplicate or the slots out of order, which render targets never do.
#[test]
fn kbuffer_separate_stores_3_threads_k3_preemption_bound_1_tears_a_write_back() {
    let list = fragments(&DISTINCT[..3]);
    let (_, wrong, torn) = kbuffer_model(
        "kbuffer_separate_stores_3_threads",
        3,
        WriteBack::SeparateStores,
        &list,
        Some(1),
    );
    assert!(
        wrong > 0 && torn > 0,
        "separate stores never tore a write-back"
    );
}
