// common.wgsl: what every scheme shader of fragsim-wgpu shares (prepended to each scheme file):
// the parameters, the two vertex stages and the fragment every scheme stores.
//
// Mirrors fragsim's fragment (crates/raster/src/fragment.rs) and its depth key
// (docs/semantics.md §6): the pixel is the one whose centre the GPU sampled, the key is the f32
// window depth's bit pattern with -0.0 stored as +0.0, and a fragment outside [0, 1] is dropped.
enable primitive_index;

struct Params {
    // Model to clip space, f32, column-major (engine mode only).
    view_projection: mat4x4<f32>,
    width: u32,
    height: u32,
    // K (MDTS, k-buffer) or the capacity (A-buffer): slots per pixel.
    slots: u32,
    // 1: replay mode, the primitive id comes from the vertex (pieces of a clipped triangle share
    // it); 0: engine mode, the primitive id is the draw's primitive_index.
    replay: u32,
    // Linked lists: nodes in the pool.
    pool: u32,
    // Samples per pixel of the target: 1, or N for the counting pass (sample_counts.wgsl) and a
    // per-sample capture (the *_samples.wgsl entry points), whose lists are (pixel, sample).
    samples: u32,
    // Uniform structs are 16-byte multiples.
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: Params;

// The planted bug this pipeline was built with (fragsim-wgpu's `--plant`; 0: the correct
// shader). A pipeline-overridable constant, so each plant is its own specialised shader and the
// correct one carries no branch on it at run time.
override plant: u32 = 0u;
// A planted fragment is dropped before any store.
const PLANT_DROPPED: u32 = 1u;
// A planted fragment is stored with primitive id prim ^ 1.
const PLANT_WRONG_ID: u32 = 2u;
// The A-buffer stores one slot fewer than its capacity (abuffer.wgsl).
const PLANT_OFF_BY_ONE_CAPACITY: u32 = 3u;
// The A-buffer's sort pass returns at once (abuffer.wgsl).
const PLANT_UNSORTED: u32 = 4u;
// A planted fragment's head exchange drops the old head (linked_list.wgsl).
const PLANT_LOST_NODE: u32 = 5u;
// A planted sample's fragment carries the depth at the pixel centre instead of the sample's
// (sample_fragment_of): what position.z gives under sample shading on the H200.
const PLANT_CENTRE_DEPTH: u32 = 6u;

// The lists the storage holds: one per pixel, or one per (pixel, sample) of a multisampled
// target (the sample-expanded framebuffer, list pixel * samples + sample).
fn list_count() -> u32 {
    return params.width * params.height * params.samples;
}

// Whether the fragment of (pixel, prim) is one the planted bugs hit: one in 256, by a hash, so
// that every scene of a few thousand fragments has some and no pixel is singled out.
fn planted(pixel: u32, prim: u32) -> bool {
    var h = (pixel * 0x9E3779B1u) ^ (prim * 0x85EBCA77u);
    h = (h ^ (h >> 15u)) * 0x2C1B3C6Du;
    h = h ^ (h >> 12u);
    return (h >> 24u) == 0u;
}

// The canonical order of fragment words key << 32 | prim held as (low, high) = (prim, key).
fn word_before(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.y < b.y || (a.y == b.y && a.x < b.x);
}

// The empty slot: all ones.
const EMPTY_WORD: vec2<u32> = vec2<u32>(0xFFFFFFFFu, 0xFFFFFFFFu);

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) prim: u32,
    // The window depth interpolated at the sample (screen-linear, as window depth is): what a
    // per-sample depth test sees. Under sample shading position.z need not be it: the H200's is
    // the depth at the pixel centre (docs/semantics.md, "Multisampling"). At one sample a pixel
    // the sample is the centre.
    @location(1) @interpolate(linear, sample) sample_depth: f32,
    // The same depth interpolated at the pixel centre, for the centre-depth plant only.
    @location(2) @interpolate(linear, center) centre_depth: f32,
}

// Replay: fragsim's snapped screen triangles, already in clip space with w = 1.
@vertex
fn vs_replay(@location(0) clip: vec4<f32>, @location(1) prim: u32) -> Varyings {
    return Varyings(clip, prim, clip.z, clip.z);
}

// Engine: the mesh's model-space vertex times the view-projection matrix, in f32.
@vertex
fn vs_engine(@location(0) model: vec3<f32>) -> Varyings {
    let clip = params.view_projection * vec4<f32>(model, 1.0);
    let depth = clip.z / clip.w;
    return Varyings(clip, 0u, depth, depth);
}

struct Fragment {
    // The list the fragment goes to: its pixel, or its (pixel, sample) in a per-sample capture.
    pixel: u32,
    key: u32,
    prim: u32,
    inside: bool,
}

// The fragment of the pixel whose centre the GPU sampled, its depth position.z.
fn fragment_of(v: Varyings, primitive_index: u32) -> Fragment {
    let pixel = u32(v.position.y) * params.width + u32(v.position.x);
    return fragment_at(pixel, v.position.z, v, primitive_index);
}

// The fragment of sample `sample` in a per-sample capture (an entry point that reads
// @builtin(sample_index) runs once per covered sample, position.xy at the sample, inside its
// pixel). Its depth is the varying interpolated at the sample, fragsim's per-sample depth
// (docs/semantics.md §11): position.z need not be the sample's under sample shading.
fn sample_fragment_of(v: Varyings, primitive_index: u32, sample: u32) -> Fragment {
    let pixel = u32(v.position.y) * params.width + u32(v.position.x);
    let list = pixel * params.samples + sample;
    var z = v.sample_depth;
    if plant == PLANT_CENTRE_DEPTH && planted(list, fragment_prim(v, primitive_index)) {
        z = v.centre_depth;
    }
    return fragment_at(list, z, v, primitive_index);
}

// The primitive id: the vertex's in replay mode, the draw's primitive_index in engine mode.
fn fragment_prim(v: Varyings, primitive_index: u32) -> u32 {
    if params.replay == 1u {
        return v.prim;
    }
    return primitive_index;
}

// The fragment of list `list` at window depth z: its key, its primitive id, whether z lies in
// [0, 1], and the dropped and wrong-id plants.
fn fragment_at(list: u32, z: f32, v: Varyings, primitive_index: u32) -> Fragment {
    var key = bitcast<u32>(z);
    if key == 0x80000000u {
        key = 0u;
    }
    var prim = fragment_prim(v, primitive_index);
    var inside = z >= 0.0 && z <= 1.0;
    if plant == PLANT_DROPPED && planted(list, prim) {
        inside = false;
    }
    if plant == PLANT_WRONG_ID && planted(list, prim) {
        prim = prim ^ 1u;
    }
    return Fragment(list, key, prim, inside);
}
