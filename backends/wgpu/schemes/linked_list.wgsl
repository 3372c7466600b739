// linked_list.wgsl: per-pixel linked lists (crates/schemes/src/linked_list.rs; Yang et
// al. 2010, Vulkan-Samples' oit_linked_lists, nvpro-samples' linked list). A fragment takes node
// n = atomicAdd(counter, 1) + 1 of the pool (node 0 ends a list, as fragsim and nvpro number
// them); past the pool it is discarded, the counter counting on. Otherwise it swaps itself in as
// its pixel's head, old = atomicExchange(heads[p], n), and writes its node: the fragment word
// (prim, key) and next = old. Each list holds its pixel's fragments most recent first.
//
// The resolve (keep the first K nodes, or the K nearest) is the dump's scheme name
// (linked-list, linked-list-nearest): compare runs the Rust scheme's own resolve on these words.

@group(0) @binding(1) var<storage, read_write> heads: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read_write> next_: array<u32>;
@group(0) @binding(4) var<storage, read_write> nodes: array<vec2<u32>>;

// The append of one fragment (fs_main, and per sample fs_main_samples: a list per (pixel,
// sample), the pool shared by all).
fn append(f: Fragment) {
    if !f.inside {
        return;
    }
    let n = atomicAdd(&counter[0], 1u) + 1u;
    if n > params.pool {
        return;
    }
    var old = atomicExchange(&heads[f.pixel], n);
    if plant == PLANT_LOST_NODE && planted(f.pixel, f.prim) {
        // The planted bug: the exchange's old value is dropped, so the rest of the list is lost.
        old = 0u;
    }
    nodes[n - 1u] = vec2<u32>(f.prim, f.key);
    next_[n - 1u] = old;
}

@fragment
fn fs_main(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    append(fragment_of(v, primitive_index));
}
