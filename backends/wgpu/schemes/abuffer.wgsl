// abuffer.wgsl: FreePipe's fixed-capacity A-buffer (crates/capture/src/schemes/abuffer.rs).
// One atomicAdd per fragment on its pixel's counter hands out a slot; a slot below the capacity
// gets the fragment word key << 32 | prim, stored as two u32 (low word first: the dump's
// little-endian u64). The counter keeps counting past the capacity, so overflow is visible.

@group(0) @binding(1) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> slots: array<vec2<u32>>;

@fragment
fn fs_main(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    let f = fragment_of(v, primitive_index);
    if !f.inside {
        return;
    }
    let i = atomicAdd(&counters[f.pixel], 1u);
    if i < params.slots {
        slots[f.pixel * params.slots + i] = vec2<u32>(f.prim, f.key);
    }
}
