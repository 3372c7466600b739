// kbuffer.wgsl: the non-atomic k-buffer (crates/schemes/src/kbuffer/mod.rs, Bavoil et al.
// 2007): a fragment reads its pixel's K sorted slots and writes back the ones its insertion
// shifts, with plain loads and stores. Two fragments of one pixel that interleave their reads
// and writes lose one of them: the race this shader exists to show on real hardware. Words are
// key << 32 | prim as (low, high) u32 pairs, empty = all ones, ascending: the catalog's k-buffer
// slot layout, slots[pixel * K + slot] (the render-target machine's lock and ticket words, which
// the CPU model keeps beside them, are bound by the host at binding 5 and never touched here).

@group(0) @binding(6) var<storage, read_write> slots: array<vec2<u32>>;

@fragment
fn fs_main(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    let f = fragment_of(v, primitive_index);
    if !f.inside {
        return;
    }
    var carried = vec2<u32>(f.prim, f.key);
    let base = f.pixel * params.slots;
    for (var i = 0u; i < params.slots; i++) {
        let old = slots[base + i];
        if word_before(carried, old) {
            slots[base + i] = carried;
            carried = old;
        }
        if all(carried == EMPTY_WORD) {
            break;
        }
    }
}
