//! Reusable proptest strategies for fragsim's integration tests.
//!
//! Everything here is small on purpose: viewports of 8 to 64 pixels a side and meshes of at most
//! a few thousand triangles, so that a property runs dozens of cases in a second or two of a
//! release build.
//!
//! | strategy | value |
//! |---|---|
//! | [`viewport`], [`viewport_with_sides`] | a [`Viewport`](fragsim_raster::Viewport) |
//! | [`orbit_camera`], [`orbit_camera_outside`], [`orbit_camera_with_distance`] | an [`OrbitCamera`](fragsim_raster::OrbitCamera) |
//! | [`procedural_scene_name`] | a name for [`Scene::procedural`](fragsim_raster::Scene::procedural) |
//! | [`random_mesh`], [`random_mesh_in_box`] | a triangle soup with near-degenerate and coincident triangles |
//! | [`generated_scene`] | a [`GeneratedScene`]: a procedural name or a random mesh |
//! | [`closed_mesh`] | a watertight mesh (perturbed icosphere or subdivided cube) |
//! | [`planar_tiling`], [`viewport_and_tiling`] | a [`PlanarTiling`]: triangles tiling a rectangle |
//! | [`depth_plane`] | a [`DepthPlane`] to put a tiling on, crossing the near plane |
//! | [`hinge`] | a [`Hinge`]: two triangles sharing an edge that crosses the near plane |
//! | [`k_choice`] | a [`KChoice`]: a `K` (or capacity) relative to the depth complexity |
//! | [`unit_depth`], [`unit_depth_pair`] | depths in `[0, 1]` for the depth-key order |
//! | [`concurrency`] | a [`Concurrency`]: how a run interleaves (task size, schedule) |
//!
//! Scenes are generated as a [`GeneratedScene`] rather than as a [`Scene`](fragsim_raster::Scene) so that a failing case
//! prints a short procedural name rather than thousands of vertices.

mod views;
pub use views::*;
mod scenes;
pub use scenes::*;
mod tilings;
pub use tilings::*;
mod k;
pub use k::*;
mod depths;
pub use depths::*;
mod concurrency;
pub use concurrency::*;
