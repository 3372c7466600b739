// linked_list_samples.wgsl: per-sample linked lists (linked_list.wgsl, appended to it): a head
// per (pixel, sample) of a multisampled target, heads[pixel * samples + sample], the node pool
// and its counter shared by every list (docs/dump-format.md's per-sample layout). The entry
// point reads @builtin(sample_index), so the pipeline shades per sample, and takes the depth
// interpolated at the sample (sample_fragment_of).

@fragment
fn fs_main_samples(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    append(sample_fragment_of(v, primitive_index, sample));
}
