// abuffer_samples.wgsl: the A-buffer per sample (abuffer.wgsl, appended to it), a list per
// (pixel, sample) of a multisampled target: docs/dump-format.md's per-sample layout, the
// single-sample one over the sample-expanded framebuffer (counters[pixels * samples], slots
// [pixels * samples, capacity] or offsets[pixels * samples + 1]). Each entry point reads
// @builtin(sample_index), so the pipeline shades per sample: one invocation per covered sample,
// its fragment's depth the varying interpolated at the sample (sample_fragment_of). The compute
// passes (prefix sum, sort) are abuffer.wgsl's, over list_count() lists.

@fragment
fn fs_main_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    insert_fixed(sample_fragment_of(v, primitive_index, sample));
}

@fragment
fn fs_count_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    count_fragment(sample_fragment_of(v, primitive_index, sample));
}

@fragment
fn fs_exact_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    insert_exact(sample_fragment_of(v, primitive_index, sample));
}
