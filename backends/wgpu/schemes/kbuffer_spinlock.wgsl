// kbuffer_spinlock.wgsl: the k-buffer inside a per-pixel spinlock
// (crates/schemes/src/kbuffer/spinlock.rs, Loop::Fixed: the catalog's
// kbuffer-spinlock-fixed; nvpro-samples' spinlock mode). A fragment takes its pixel's lock word
// with atomicCompareExchangeWeak(lock, 0, 1); the holder's path (load the K slots, insert, store
// them back, release the lock) is inside the loop body, so that lanes of one subgroup that failed
// wait at the end of the body while the holder finishes, not at a reconvergence point after the
// loop that the holder would never pass (the naive loop's deadlock under lockstep).
//
// WGSL has no memory fence in a fragment shader (storageBarrier is compute-only) and its atomics
// are relaxed, so the lock orders the slot accesses for no formal memory model: the slots are
// atomics too (each access reaches the device's coherent memory, none is cached in registers
// across the lock), and the capture shows what the hardware did. Words are key << 32 | prim as
// (low, high) u32 pairs, empty = all ones, ascending: the catalog's k-buffer slot layout,
// slots[pixel * K + slot] (the locks, one a pixel, are not dumped).

@group(0) @binding(5) var<storage, read_write> locks: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> slot_words: array<atomic<u32>>;

fn load_slot(i: u32) -> vec2<u32> {
    return vec2<u32>(atomicLoad(&slot_words[2u * i]), atomicLoad(&slot_words[2u * i + 1u]));
}

fn store_slot(i: u32, w: vec2<u32>) {
    atomicStore(&slot_words[2u * i], w.x);
    atomicStore(&slot_words[2u * i + 1u], w.y);
}

@fragment
fn fs_main(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    let f = fragment_of(v, primitive_index);
    if !f.inside {
        return;
    }
    let base = f.pixel * params.slots;
    var done = false;
    while !done {
        if atomicCompareExchangeWeak(&locks[f.pixel], 0u, 1u).exchanged {
            var carried = vec2<u32>(f.prim, f.key);
            for (var i = 0u; i < params.slots; i++) {
                let old = load_slot(base + i);
                if word_before(carried, old) {
                    store_slot(base + i, carried);
                    carried = old;
                }
                if all(carried == EMPTY_WORD) {
                    break;
                }
            }
            atomicStore(&locks[f.pixel], 0u);
            done = true;
        }
    }
}
