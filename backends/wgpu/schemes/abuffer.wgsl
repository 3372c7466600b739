// abuffer.wgsl: the A-buffer (crates/schemes/src/abuffer.rs), FreePipe's fixed storage
// and the exact storage of a counting pass, each followed by the post pass's per-pixel sort.
//
// Fixed (fs_main, then cs_sort_fixed): one atomicAdd per fragment on its pixel's counter hands
// out a slot; a slot below the capacity gets the fragment word key << 32 | prim, stored as two
// u32 (low word first: the dump's little-endian u64). The counter keeps counting past the
// capacity, so overflow is visible.
//
// Exact (fs_count, cs_prefix, then fs_exact, cs_sort_exact): the counting pass adds one per
// fragment to its pixel's counter; the prefix pass turns the counts into offsets[pixels + 1]
// (offsets[pixels]: the total, which the host reads back to size the slots) and zeroes the
// counters; the fill pass takes slots as the fixed one does, in offsets[p]..offsets[p + 1].
//
// The sort (one invocation per pixel) is the Rust post pass's insertion sort, in place: the dump
// then holds each pixel's list in canonical order and says so ("sorted": true).
//
// A "pixel" here is a list: one per pixel, or one per (pixel, sample) in a per-sample capture
// (abuffer_samples.wgsl's entry points, list_count() lists).

@group(0) @binding(1) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> slots: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> offsets: array<u32>;

// Stores the fragment in slot `taken` of the `room` slots from `first`, if there is one.
fn store_fragment(f: Fragment, taken: u32, first: u32, room: u32) {
    var limit = room;
    if plant == PLANT_OFF_BY_ONE_CAPACITY && limit > 0u {
        // The planted off-by-one: the last slot is never written, while the counter counts on.
        limit = limit - 1u;
    }
    if taken < limit {
        slots[first + taken] = vec2<u32>(f.prim, f.key);
    }
}

// The fixed A-buffer's insertion of one fragment (fs_main, and per sample fs_main_samples).
fn insert_fixed(f: Fragment) {
    if !f.inside {
        return;
    }
    let taken = atomicAdd(&counters[f.pixel], 1u);
    store_fragment(f, taken, f.pixel * params.slots, params.slots);
}

// The exact A-buffer's counting pass for one fragment.
fn count_fragment(f: Fragment) {
    if f.inside {
        atomicAdd(&counters[f.pixel], 1u);
    }
}

// The exact A-buffer's fill pass for one fragment.
fn insert_exact(f: Fragment) {
    if !f.inside {
        return;
    }
    let taken = atomicAdd(&counters[f.pixel], 1u);
    let first = offsets[f.pixel];
    store_fragment(f, taken, first, offsets[f.pixel + 1u] - first);
}

@fragment
fn fs_main(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    insert_fixed(fragment_of(v, primitive_index));
}

@fragment
fn fs_count(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    count_fragment(fragment_of(v, primitive_index));
}

@fragment
fn fs_exact(v: Varyings, @builtin(primitive_index) primitive_index: u32) {
    insert_exact(fragment_of(v, primitive_index));
}

const SCAN_THREADS: u32 = 256u;
var<workgroup> partial: array<u32, SCAN_THREADS>;

// One workgroup: each thread sums a contiguous chunk of the counts, thread 0 scans the 256 sums,
// then each thread writes its chunk's exclusive prefix sums and zeroes its counters.
@compute @workgroup_size(256)
fn cs_prefix(@builtin(local_invocation_index) t: u32) {
    let pixels = list_count();
    let chunk = (pixels + SCAN_THREADS - 1u) / SCAN_THREADS;
    let begin = min(t * chunk, pixels);
    let end = min(begin + chunk, pixels);
    var sum = 0u;
    for (var p = begin; p < end; p++) {
        sum += atomicLoad(&counters[p]);
    }
    partial[t] = sum;
    workgroupBarrier();
    if t == 0u {
        var running = 0u;
        for (var i = 0u; i < SCAN_THREADS; i++) {
            let s = partial[i];
            partial[i] = running;
            running += s;
        }
        offsets[pixels] = running;
    }
    workgroupBarrier();
    var running = partial[t];
    for (var p = begin; p < end; p++) {
        offsets[p] = running;
        running += atomicLoad(&counters[p]);
        atomicStore(&counters[p], 0u);
    }
}

// Insertion sort of slots[first .. first + n] by the canonical order.
fn sort_slots(first: u32, n: u32) {
    if plant == PLANT_UNSORTED {
        return;
    }
    for (var i = 1u; i < n; i++) {
        let w = slots[first + i];
        var j = i;
        while j > 0u && word_before(w, slots[first + j - 1u]) {
            slots[first + j] = slots[first + j - 1u];
            j--;
        }
        slots[first + j] = w;
    }
}

// The pixel of a sort invocation: dispatches are two-dimensional past 65535 workgroups.
fn sort_pixel(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.y * groups.x * 64u + id.x;
}

@compute @workgroup_size(64)
fn cs_sort_fixed(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let p = sort_pixel(id, groups);
    if p < list_count() {
        sort_slots(p * params.slots, min(atomicLoad(&counters[p]), params.slots));
    }
}

@compute @workgroup_size(64)
fn cs_sort_exact(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let p = sort_pixel(id, groups);
    if p < list_count() {
        let first = offsets[p];
        sort_slots(first, min(atomicLoad(&counters[p]), offsets[p + 1u] - first));
    }
}
