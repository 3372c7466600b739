//! The exact rasterizer of fragsim: scenes, the orbit camera and the pipeline that turns triangles
//! into a deterministic stream of [`Fragment`]s.
//!
//! Every rule a GPU backend must match bit for bit is written down in `docs/semantics.md` and
//! implemented here once, under fragsim's reference [`Conventions`] (and, with
//! [`View::with_conventions`], under an implementation's declared ones): f64 vertex transform, homogeneous near-plane and guard-band clipping,
//! snapping to 8 fractional bits, exact integer edge functions with the top-left fill rule, depth
//! interpolated in f64 from the integer barycentrics and rounded once to f32, and the
//! order-preserving depth key.
//!
//! ```
//! use fragsim_raster::{Scene, Viewport, OrbitCamera};
//! let scene = Scene::procedural("spheres:2").unwrap();
//! let view = scene.view(Viewport::new(64, 64).unwrap(), &OrbitCamera::default()).unwrap();
//! let mut fragments = 0;
//! for prim in 0..view.triangle_count() {
//!     view.rasterize(prim, &mut |_fragment| fragments += 1);
//! }
//! assert!(fragments > 0);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod attributes;
mod camera;
pub mod conventions;
pub mod files;
mod fragment;
mod mesh;
mod pipeline;
mod ply;
mod rng;
pub mod samples;
pub mod scene_spec;
mod scenes;
mod viewport;

pub use camera::{Camera, OrbitCamera};
pub use conventions::{
    Conventions, ConventionsError, DepthRange, EdgeTies, F32RangeError, VertexPrecision,
    WindowOrigin,
};
pub use fragment::{depth_from_key, depth_key, Fragment, EMPTY_KEY};
pub use mesh::{Mesh, MeshError, UpAxis, UpAxisError, MESH_BYTES_LIMIT};
pub use pipeline::{
    edge_function, fill_thresholds, ClipOrigin, ClipTrace, Clipped, CullMode, ScreenTriangle,
    TriangleSetup, View, GUARD_BAND_PIXELS,
};
pub use rng::SplitMix64;
pub use samples::{SampleError, SamplePattern};
pub use scene_spec::{mesh_hash, SceneSpec, SceneSpecError, ViewProjection};
pub use scenes::{Scene, SceneError, SceneSize, DEFAULT_SCENE_NAME};
pub use viewport::{PixelRect, Viewport, ViewportError, SUBPIXEL_BITS};
