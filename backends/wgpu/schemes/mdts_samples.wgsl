// mdts_samples.wgsl: MDTS per sample (mdts.wgsl, appended to it): K slots per (pixel, sample) of
// a multisampled target, slots[(pixel * samples + sample) * K + i] (docs/dump-format.md's
// per-sample layout). Each entry point reads @builtin(sample_index), so the pipeline shades per
// sample, and takes the depth interpolated at the sample (sample_fragment_of).

@fragment
fn fs_u64_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    insert_u64(sample_fragment_of(v, primitive_index, sample));
}

@fragment
fn fs_u32_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    insert_u32(sample_fragment_of(v, primitive_index, sample));
}
