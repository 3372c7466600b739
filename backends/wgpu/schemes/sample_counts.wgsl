// sample_counts.wgsl: the per-sample counting pass (src/sample_counts.rs): how many fragments
// the GPU's rasterizer produced at each sample of each pixel of a multisampled target.
//
// Reading @builtin(sample_index) makes the pipeline shade per sample (Vulkan: a fragment shader
// that uses SampleId runs with sample shading at minSampleShading 1.0), so each covered sample
// of each primitive is one invocation, which adds 1 at (pixel, sample). The depth-range test is
// made on the depth interpolated at the sample (v.sample_depth), as fragsim drops a sample whose
// depth lies outside [0, 1] (docs/semantics.md, "Multisampling"): position.z is not that depth
// on every GPU (the H200 gives the pixel centre's, which for a sliver triangle beside the
// centre lies far outside [0, 1]).
//
// counts holds three arrays of (pixel, sample) words: the fragments; the covered samples inside
// [0, 1] whose position.z is outside it (the shader-visible depth is not the sample's); and the
// bits of the largest such position.z (an example for the log).

@group(0) @binding(1) var<storage, read_write> counts: array<atomic<u32>>;

@fragment
fn fs_main(
    v: Varyings,
    @builtin(primitive_index) primitive_index: u32,
    @builtin(sample_index) sample: u32,
) {
    let f = fragment_of(v, primitive_index);
    let z = v.sample_depth;
    if z < 0.0 || z > 1.0 {
        return;
    }
    let index = f.pixel * params.samples + sample;
    atomicAdd(&counts[index], 1u);
    if !f.inside {
        let samples = arrayLength(&counts) / 3u;
        atomicAdd(&counts[samples + index], 1u);
        atomicMax(&counts[2u * samples + index], bitcast<u32>(v.position.z));
    }
}
