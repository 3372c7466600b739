// sample_counts.wgsl: the per-sample counting pass (src/sample_counts.rs): how many fragments
// the GPU's rasterizer produced at each sample of each pixel of a multisampled target.
//
// Reading @builtin(sample_index) makes the pipeline shade per sample (Vulkan: a fragment shader
// that uses SampleId runs with sample shading at minSampleShading 1.0), so each covered sample
// of each primitive is one invocation, which adds 1 at (pixel, sample). Its position is the
// sample's, so the depth-range test of fragment_of is made at the sample, as fragsim drops a
// sample whose depth lies outside [0, 1] (docs/semantics.md, "Multisampling").
//
// counts holds three arrays of (pixel, sample) words: the fragments; the invocations the
// depth-range test dropped (the rasterizer covered the sample, the depth interpolated there
// left [0, 1]); and the bits of the largest such depth (an example for the diagnosis).

@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

@fragment
fn fs_main(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    let f = fragment_of(v, primitive_index);
    let index = f.pixel * params.samples + sample;
    if !f.inside {
        let samples = arrayLength(&counts) / 3u;
        atomicAdd(&counts[samples + index], 1u);
        atomicMax(&counts[2u * samples + index], bitcast<u32>(v.position.z));
        return;
    }
    atomicAdd(&counts[index], 1u);
}
