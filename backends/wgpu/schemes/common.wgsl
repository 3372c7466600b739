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
}

@group(0) @binding(0) var<uniform> params: Params;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) prim: u32,
}

// Replay: fragsim's snapped screen triangles, already in clip space with w = 1.
@vertex
fn vs_replay(@location(0) clip: vec4<f32>, @location(1) prim: u32) -> Varyings {
    return Varyings(clip, prim);
}

// Engine: the mesh's model-space vertex times the view-projection matrix, in f32.
@vertex
fn vs_engine(@location(0) model: vec3<f32>) -> Varyings {
    return Varyings(params.view_projection * vec4<f32>(model, 1.0), 0u);
}

struct Fragment {
    pixel: u32,
    key: u32,
    prim: u32,
    inside: bool,
}

fn fragment_of(v: Varyings, primitive_index: u32) -> Fragment {
    let x = u32(v.position.x);
    let y = u32(v.position.y);
    let z = v.position.z;
    var key = bitcast<u32>(z);
    if key == 0x80000000u {
        key = 0u;
    }
    var prim = primitive_index;
    if params.replay == 1u {
        prim = v.prim;
    }
    return Fragment(y * params.width + x, key, prim, z >= 0.0 && z <= 1.0);
}
