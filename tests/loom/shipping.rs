//! Shipping OIT schemes (`docs/baselines/shipping.md`).

use fragsim::capture::{Scheme, Step, MEMORY_CAP_DEFAULT};
use fragsim::memory::WordMemory;
use fragsim::schemes::layer_counter::LayerCounter;
use fragsim::schemes::linked_list::{LinkedList, Resolve};
use fragsim::schemes::loop32::Loop32;

use super::{explore, fragments, keyed, one_pixel, run_threads, LoomMemory, Walks, DISTINCT, TIES};

/// Per-pixel linked list (node counter `fetch_add`, head `swap`, two stores), `n` threads on one
/// pixel with a pool of `pool` nodes: in every interleaving exactly `min(n, pool)` walks store
/// (4 steps each) and the rest are dropped (1 step); the list holds each stored fragment exactly
/// once (the keep-nearest resolve with `N` = 4 returns them all, sorted); the counter ends at `n`.
fn linked_list_model(name: &str, n: usize, pool: usize, preemption_bound: Option<usize>) -> usize {
    let scheme = LinkedList::new(
        one_pixel(),
        pool,
        4,
        Resolve::KeepNearest,
        MEMORY_CAP_DEFAULT,
    )
    .expect("a valid pool");
    let scheme: &'static LinkedList = Box::leak(Box::new(scheme));
    let list = fragments(&DISTINCT[..n]);
    let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
    explore(name, preemption_bound, move || {
        let (memory, Walks { outcomes, steps }) = run_threads(scheme, &list);
        let fit = n.min(pool);
        assert_eq!(
            WordMemory::<u32>::load(memory, 1) as usize,
            n,
            "the counter"
        );
        let mut stored: Vec<u64> = Vec::new();
        #[expect(
            clippy::shadow_unrelated,
            reason = "each walk's own step count, of the walks' `steps`"
        )]
        for ((outcome, steps), value) in outcomes.iter().zip(&steps).zip(&values) {
            match outcome {
                Step::Stored => {
                    assert_eq!(*steps, 4, "a stored linked-list walk is four steps");
                    stored.push(*value);
                }
                Step::Dropped => assert_eq!(*steps, 1, "a dropped linked-list walk is one step"),
                other => panic!("a linked-list walk ended {other:?}"),
            }
        }
        assert_eq!(stored.len(), fit, "walks: {outcomes:?}");
        stored.sort_unstable();
        let capture = scheme.resolve(memory);
        assert_eq!(capture.pixel(0), &stored[..], "each stored fragment once");
    })
}

/// Linked list, 2 threads, exhaustive; 3 threads, exhaustive; 4 threads with a pool of 3 (one
/// dropped), preemption bound 2.
#[test]
fn linked_list_2_and_3_threads_4_threads_pool_3_preemption_bound_2() {
    assert!(linked_list_model("linked_list_2_threads", 2, 2, None) >= 2);
    linked_list_model("linked_list_3_threads", 3, 3, None);
    linked_list_model(
        "linked_list_4_threads_pool_3_preemption_bound_2",
        4,
        3,
        Some(2),
    );
}

/// Bevy's layer counter, 3 threads on one pixel, 1 to 3 layers, exhaustive: exactly
/// `max(0, 3 − layers)` walks dropped, the kept fragments distinct and sorted, and the counter
/// clamped back to the layer count when any was dropped.
#[test]
fn layer_counter_3_threads_layers_1_to_3() {
    for layers in 1..=3_u32 {
        let scheme = LayerCounter::new(one_pixel(), layers, MEMORY_CAP_DEFAULT).unwrap();
        let scheme: &'static LayerCounter = Box::leak(Box::new(scheme));
        let list = fragments(&DISTINCT[..3]);
        let values: Vec<u64> = list.iter().map(|f| f.packed()).collect();
        let name = format!("layer_counter_3_threads_layers_{layers}");
        explore(&name, None, move || {
            let (memory, Walks { outcomes, .. }) = run_threads(scheme, &list);
            let fit = 3.min(layers as usize);
            let dropped = outcomes.iter().filter(|&&o| o == Step::Dropped).count();
            assert_eq!(dropped, 3 - fit, "walks: {outcomes:?}");
            let kept = scheme.resolve(memory).pixel(0).to_vec();
            assert_eq!(kept.len(), fit);
            assert!(kept.windows(2).all(|w| w[0] < w[1]), "{kept:x?}");
            assert!(kept.iter().all(|v| values.contains(v)));
            let counter = WordMemory::<u32>::load(memory, 0) as usize;
            assert_eq!(counter, if dropped > 0 { fit } else { 3 }, "the counter");
        });
    }
}

/// loop32's depth pass, 3 threads on keys [10, 10, 30] with K = 2 and 3, then its colour pass
/// (after the join, a kernel boundary): in every interleaving the slots hold the distinct keys
/// [10, 30], each once, and the 10's colour is one of its two primitives. Exhaustive.
#[test]
fn loop32_3_threads_equal_depths_merge_k2_k3() {
    for k in [2, 3] {
        let scheme: &'static Loop32 = Box::leak(Box::new(
            Loop32::new(one_pixel(), k, MEMORY_CAP_DEFAULT).unwrap(),
        ));
        let list = keyed(&TIES[1..]);
        let name = format!("loop32_3_threads_k{k}");
        explore(&name, None, move || {
            let memory: &'static LoomMemory = Box::leak(Box::new(scheme.layout().allocate()));
            let handles: Vec<_> = list
                .iter()
                .map(|&f| loom::thread::spawn(move || scheme.insert(f, memory, &mut 0)))
                .collect();
            for handle in handles {
                handle.join().expect("a walk");
            }
            assert!(scheme.end_pass(0, memory), "a colour pass follows");
            // loom allows 4 spawned threads in all: the colour pass runs on the main thread.
            for &f in &list {
                let state = scheme.begin_pass(1, f).expect("the colour pass");
                scheme.insert_state(state, memory, &mut 0);
            }
            assert!(!scheme.end_pass(1, memory));
            let kept = scheme.resolve(memory).pixel(0).to_vec();
            let keys: Vec<u64> = kept.iter().map(|e| e >> 32).collect();
            assert_eq!(keys, [10, 30], "{kept:x?}");
            assert!([1, 3].contains(&(kept[0] & 0xFFFF_FFFF)), "{kept:x?}");
        });
    }
}
