// mdts.wgsl: the multi-depth test scheme (crates/schemes/src/mdts.rs, FreePipe §4.1.1).
// A fragment walks its pixel's K slots: old = atomicMin(slot, value); an empty old value (all
// ones) means it landed; otherwise it carries max(value, old) on to the next slot, and past slot
// K - 1 the carried value is dropped. Under any interleaving each pixel ends with its K smallest
// values in ascending order (docs/proof.md).
//
// fs_u64: words key << 32 | prim (the fragment kept whole; needs 64-bit atomics with results,
// wgpu's SHADER_INT64_ATOMIC_ALL_OPS). fs_u32: depth keys alone (FreePipe's Table 1).

@group(0) @binding(1) var<storage, read_write> words: array<atomic<u64>>;
@group(0) @binding(3) var<storage, read_write> keys: array<atomic<u32>>;

// The walk of one fragment's u64 word (fs_u64, and per sample fs_u64_samples).
fn insert_u64(f: Fragment) {
    if !f.inside {
        return;
    }
    var value = (u64(f.key) << 32u) | u64(f.prim);
    let base = f.pixel * params.slots;
    for (var i = 0u; i < params.slots; i++) {
        let old = atomicMin(&words[base + i], value);
        if old == 0xFFFFFFFFFFFFFFFFlu {
            break;
        }
        value = max(value, old);
    }
}

// The walk of one fragment's u32 depth key (fs_u32, and per sample fs_u32_samples).
fn insert_u32(f: Fragment) {
    if !f.inside {
        return;
    }
    var value = f.key;
    let base = f.pixel * params.slots;
    for (var i = 0u; i < params.slots; i++) {
        let old = atomicMin(&keys[base + i], value);
        if old == 0xFFFFFFFFu {
            break;
        }
        value = max(value, old);
    }
}

@fragment
fn fs_u64(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    insert_u64(fragment_of(v, primitive_index));
}

@fragment
fn fs_u32(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    insert_u32(fragment_of(v, primitive_index));
}
