//! The pipeline: vertex stage, clipping, snapping and the exact scan.
//!
//! The rules, in the order they apply (`docs/semantics.md` states them for backend authors):
//! 1. Vertices are transformed once, in f64: `clip = view_projection * (x, y, z, 1)`.
//! 2. A triangle whose vertices all lie outside one frustum plane (left, right, top, bottom,
//!    near or far) is rejected whole.
//! 3. A triangle with a vertex in front of the near plane (`z < 0`) or outside the guard band is
//!    clipped in homogeneous space (Sutherland–Hodgman) against `z ≥ 0` and the guard-band
//!    planes; the polygon is split into a fan `(v0, vi, vi+1)`; every piece keeps the primitive id.
//!    Unlike FreePipe, which clips only the screen bounding box, this keeps triangles that cross
//!    `w = 0` correct.
//! 4. Each vertex is projected (`x/w`, `y/w`, `z/w`), mapped to the window (y down) and its x and y
//!    snapped to [`SUBPIXEL_BITS`] fractional bits by rounding half away from zero.
//! 5. The doubled signed area of the snapped triangle decides facing (exact, in i64); zero-area
//!    triangles produce nothing; back faces are culled or, by default, reoriented.
//! 6. Pixel `(i, j)` is sampled at its centre; it is covered when all three edge functions are
//!    positive, or zero on a top or left edge (the top-left rule): a centre on an edge shared by two
//!    triangles is covered exactly once.
//! 7. Depth is interpolated linearly in screen space from the exact integer barycentrics, in f64,
//!    rounded once to f32; depths outside `[0, 1]` are dropped.
//!
//! These are the rules under [`Conventions::REFERENCE`]; [`View::with_conventions`] varies them
//! as `docs/semantics.md` §9 says: the arithmetic of rules 1 and 4 (f32), the near plane of rules
//! 2–3 and the window depth (`[−1, 1]`), the snapping grid of rule 4 (subpixel bits), and the
//! window's y direction with the owner of rule 6's shared edges (lower-left origin).
//!
//! The stages live in submodules, in the order a triangle meets them: `vertex` (rules 1–4:
//! transform, outcodes, clipping, snapping), `setup` (the early reject of triangles whose box holds
//! no pixel centre, and each survivor set up once for the scan), `scan` (rules 6–7: the covered
//! centres of each row from the edge functions, depth), `sample_scan` (rules 6–7 at each sample of
//! a multisampled view, `docs/semantics.md` §11); the render target and its grid are `crate::viewport`; this file holds the view that ties them together and rule 5 (facing).

use glam::{DMat4, DVec4};

use crate::camera::Camera;
use crate::conventions::{Conventions, ConventionsError, VertexPrecision};
use crate::fragment::Fragment;
use crate::mesh::Mesh;
use crate::viewport::{PixelRect, Viewport, HALF, ONE, SUBPIXEL_BITS};

#[cfg(test)]
mod conventions_tests;
mod edges;
mod sample_scan;
mod scan;
#[cfg(test)]
mod scan_tests;
mod setup;
mod submission;
#[cfg(test)]
mod tests;
mod vertex;

use edges::{bounding_box, edge};
pub use edges::{edge as edge_function, fill_thresholds};
use sample_scan::Sampling;
pub use setup::TriangleSetup;
use vertex::{in_front, AxisPositions, CentreCells, WindowVertex};
pub use vertex::{ClipOrigin, ClipTrace, Clipped};

/// How far outside the viewport, in pixels, vertices may lie before they are clipped.
///
/// With viewports of at most [`Viewport::MAX_SIDE`] pixels, snapped coordinates stay below
/// 2^24 in magnitude and the edge functions below 2^49: far from i64 overflow.
pub const GUARD_BAND_PIXELS: f64 = 16384.0;

/// Which triangles are discarded by facing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CullMode {
    /// Keep every triangle; back faces are reoriented (multi-fragment effects need all layers).
    #[default]
    None,
    /// Discard triangles that are clockwise as the viewer sees them.
    Back,
    /// Discard triangles that are counter-clockwise as the viewer sees them.
    Front,
}

/// A triangle after snapping: fixed-point window coordinates and f64 window depth, oriented so
/// that its doubled signed area is positive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenTriangle {
    /// Primitive id.
    pub prim: u32,
    /// x, y in 1/256 pixel, y down.
    pub xy: [[i64; 2]; 3],
    /// Window depth `z / w` of each vertex.
    pub z: [f64; 3],
}

/// A mesh seen through a camera on a viewport: vertices transformed, ready to rasterize any
/// triangle by primitive id. Immutable and `Sync`, so threads rasterize triangles independently.
#[derive(Clone, Debug)]
pub struct View<'mesh> {
    mesh: &'mesh Mesh,
    view_projection: DMat4,
    /// The mesh's positions, an array per axis: what the vertex stage reads.
    axes: AxisPositions,
    /// Per vertex: which interval between pixel-centre lines it lies in on each axis
    /// ([`CentreCells`]), all the triangle setup reads of a triangle it rejects early.
    cells: Vec<CentreCells>,
    /// Per vertex: its outcode and snapped window position ([`WindowVertex`]), what the triangle
    /// setup reads next. Kept apart from the depth: the triangle loop over a large
    /// mesh is bound by fetching its vertices, and most triangles of a dense mesh are rejected by
    /// their bounding box alone, before the depth is needed.
    window: Vec<WindowVertex>,
    /// Per vertex: the window depth `z / w`; meaningful only when the vertex's outcode has no
    /// clip bit set.
    window_z: Vec<f64>,
    viewport: Viewport,
    cull: CullMode,
    guard: [f64; 2],
    conventions: Conventions,
    /// The submission order (`submission[i]`: the primitive submitted `i`-th); empty: primitive
    /// id order ([`View::shuffled`]).
    submission: Vec<u32>,
    /// The sample pattern and expanded framebuffer of a view that rasterizes per sample
    /// ([`View::with_samples`]); `None`: one sample at each pixel centre, through the
    /// single-sample scan.
    sampling: Option<Sampling>,
}

/// A snapped window position (1/256 pixel, y down) and the window depth `z / w`.
type Snapped = ([i64; 2], f64);

/// Outcode bits of the planes that force clipping (near and the guard band).
const CLIP_BITS: u8 = 0b1_1111;
/// Outcode bit of the far plane (rejects, never clips: fragments beyond it are dropped one by one).
const FAR_BIT: u8 = 1 << 5;
/// Outcode bit of a vertex with `w ≤ 0` (or NaN) that no plane clips: possible only with a
/// projection whose near plane does not bound `w` away from 0; its triangles are dropped.
const NOT_IN_FRONT_BIT: u8 = 1 << 6;

/// Vertices per rayon work item of the vertex stage.
const VERTICES_PER_TASK: usize = 4096;

impl<'mesh> View<'mesh> {
    /// Transforms every vertex of `mesh` once, under fragsim's reference conventions
    /// ([`Conventions::REFERENCE`]).
    #[must_use]
    pub fn new(mesh: &'mesh Mesh, camera: &Camera, viewport: Viewport, cull: CullMode) -> Self {
        Self::build(mesh, camera, viewport, cull, Conventions::REFERENCE)
    }

    /// Transforms every vertex of `mesh` once under `conventions` (`docs/semantics.md`,
    /// "Conventions"): what an implementation that declares them rasterizes. Conventions of more
    /// than one sample a pixel give a view rasterizing per sample at the standard pattern
    /// ([`View::with_samples`]), whose [`View::viewport`] is the sample-expanded framebuffer.
    ///
    /// # Errors
    /// Conventions fragsim cannot rasterize under ([`Conventions::check`]), or a
    /// sample-expanded framebuffer too wide.
    pub fn with_conventions(
        mesh: &'mesh Mesh,
        camera: &Camera,
        viewport: Viewport,
        cull: CullMode,
        conventions: Conventions,
    ) -> Result<Self, ConventionsError> {
        conventions.check()?;
        let view = Self::build(mesh, camera, viewport, cull, conventions);
        if conventions.vertex_precision == VertexPrecision::F32 {
            view.check_f32_range()?;
        }
        match conventions.pattern()? {
            Some(pattern) => Ok(view.with_samples(pattern)?),
            None => Ok(view),
        }
    }

    fn build(
        mesh: &'mesh Mesh,
        camera: &Camera,
        viewport: Viewport,
        cull: CullMode,
        conventions: Conventions,
    ) -> Self {
        let guard = [
            1.0 + 2.0 * GUARD_BAND_PIXELS / f64::from(viewport.width),
            1.0 + 2.0 * GUARD_BAND_PIXELS / f64::from(viewport.height),
        ];
        let mut view = Self {
            mesh,
            view_projection: camera.view_projection,
            axes: AxisPositions::of(&mesh.positions),
            cells: Vec::new(),
            window: Vec::new(),
            window_z: Vec::new(),
            viewport,
            cull,
            guard,
            conventions,
            submission: Vec::new(),
            sampling: None,
        };
        view.set_camera(camera);
        view
    }

    /// The vertex stage's snapped position and depth of vertex `index` (no clip bit set).
    #[inline]
    fn snapped(&self, index: u32) -> Snapped {
        (
            self.window[index as usize].position(),
            self.window_z[index as usize],
        )
    }

    /// The outcode of vertex `index`.
    #[inline]
    fn outcode(&self, index: u32) -> u8 {
        self.window[index as usize].outcode
    }

    /// The clip-space position of vertex `index`, exactly as the vertex stage computed it.
    fn clip_position(&self, index: u32) -> DVec4 {
        self.stage().clip(self.mesh.positions[index as usize])
    }

    /// The conventions this view rasterizes under.
    #[must_use]
    pub fn conventions(&self) -> Conventions {
        self.conventions
    }

    /// The framebuffer fragments index: the viewport, or the sample-expanded framebuffer of a
    /// view that rasterizes per sample ([`View::with_samples`]; [`View::pixel_viewport`] is then
    /// the render target in pixels).
    #[must_use]
    #[inline]
    pub fn viewport(&self) -> Viewport {
        self.sampling.map_or(self.viewport, Sampling::framebuffer)
    }

    /// The model-to-clip-space matrix of the current camera.
    #[must_use]
    pub fn view_projection(&self) -> DMat4 {
        self.view_projection
    }

    /// The mesh.
    #[must_use]
    pub fn mesh(&self) -> &'mesh Mesh {
        self.mesh
    }

    /// Number of triangles (primitive ids are `0..triangle_count()`; the executors submit them in
    /// [`View::submitted`] order).
    #[must_use]
    #[inline]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "primitive ids are u32, as a GPU's: mesh files are at most MESH_BYTES_LIMIT (4 GiB), at least 8 bytes a face, and the built-in scenes have at most 10 million triangles"
    )]
    pub fn triangle_count(&self) -> u32 {
        self.mesh.triangles.len() as u32
    }

    /// Rasterizes triangle `prim`, calling `emit` for each fragment in scan order (rows top to
    /// bottom, pixels left to right, fan pieces in order).
    pub fn rasterize(&self, prim: u32, emit: &mut impl FnMut(Fragment)) {
        self.rasterize_in(prim, self.viewport().rect(), emit);
    }

    /// [`View::rasterize`] restricted to the pixels of `rect` (a screen tile): exactly the
    /// fragments of the whole triangle that fall in `rect`, in the same order.
    pub fn rasterize_in(&self, prim: u32, rect: PixelRect, emit: &mut impl FnMut(Fragment)) {
        if let Some(sampling) = self.sampling {
            return self.rasterize_samples_in(prim, sampling, rect, emit);
        }
        self.set_up_in(prim, rect, &mut |setup| self.scan_set_up(&setup, emit));
    }

    /// The pixels whose centres the bounding boxes of triangle `prim`'s pieces hold: every
    /// fragment of the triangle lies inside. `None` when the triangle is rejected or its boxes
    /// hold no pixel centre, as for most triangles of a dense mesh (culling and zero area are
    /// left to the scan).
    #[must_use]
    pub fn pixel_bounds(&self, prim: u32) -> Option<PixelRect> {
        if let Some(sampling) = self.sampling {
            return self.sample_bounds(prim, sampling);
        }
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcode(i));
        let full = self.viewport.rect();
        if ca & cb & cc != 0 || (ca | cb | cc) & CLIP_BITS != 0 {
            let mut bounds: Option<PixelRect> = None;
            self.screen_triangles(prim, &mut |tri| {
                let [lo, hi] = bounding_box(tri.xy);
                if let Some(piece) = full.centres_within(lo, hi) {
                    bounds = Some(bounds.map_or(piece, |b| b.union(piece)));
                }
            });
            return bounds;
        }
        if (ca | cb | cc) & NOT_IN_FRONT_BIT != 0 {
            return None;
        }
        let [lo, hi] = bounding_box(indices.map(|i| self.window[i as usize].position()));
        full.centres_within(lo, hi)
    }

    /// Calls `visit` with the snapped, clipped, oriented pieces of triangle `prim` (none when it
    /// is rejected, culled or degenerate).
    pub fn screen_triangles(&self, prim: u32, visit: &mut impl FnMut(ScreenTriangle)) {
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcode(i));
        // Trivial reject: all three vertices outside one plane.
        if ca & cb & cc != 0 {
            return;
        }
        if (ca | cb | cc) & CLIP_BITS == 0 {
            if (ca | cb | cc) & NOT_IN_FRONT_BIT == 0 {
                let snapped = indices.map(|i| self.snapped(i));
                if let Some((tri, _)) = self.oriented(prim, snapped) {
                    visit(tri);
                }
            }
            return;
        }
        let polygon = self.clip(indices.map(|i| self.clip_position(i)));
        if polygon.len() < 3 {
            return;
        }
        let stage = self.stage();
        for i in 1..polygon.len() - 1 {
            let piece = [polygon[0], polygon[i], polygon[i + 1]];
            if piece.iter().any(|v| !in_front(*v)) {
                continue;
            }
            if let Some((tri, _)) = self.oriented(prim, piece.map(|v| stage.snap(v))) {
                visit(tri);
            }
        }
    }

    /// Rule 5: the snapped triangle culled, or oriented so that its doubled signed area is
    /// positive, with that area; `None` when it is culled or has zero area.
    #[inline]
    fn oriented(&self, prim: u32, snapped: [Snapped; 3]) -> Option<(ScreenTriangle, i64)> {
        let [(pa, za), (mut pb, mut zb), (mut pc, mut zc)] = snapped;
        let area = edge(pa, pb, pc);
        if area == 0 {
            return None;
        }
        // In a y-down window a negative area is counter-clockwise as the viewer sees it: a front
        // face under the OpenGL/OBJ convention.
        let front = area < 0;
        match self.cull {
            CullMode::Back if !front => return None,
            CullMode::Front if front => return None,
            _ => {}
        }
        if front {
            std::mem::swap(&mut pb, &mut pc);
            std::mem::swap(&mut zb, &mut zc);
        }
        let triangle = ScreenTriangle {
            prim,
            xy: [pa, pb, pc],
            z: [za, zb, zc],
        };
        Some((triangle, area.abs()))
    }

    /// The clip-space position of vertex `index` as the vertex stage computed it (rule 1): what a
    /// precision analysis of the stage starts from.
    #[must_use]
    pub fn vertex_clip(&self, index: u32) -> DVec4 {
        self.clip_position(index)
    }

    /// The snapped window position (1/256 pixel) and window depth of vertex `index`, or `None`
    /// when the vertex lies outside the near plane or the guard band (its triangles are clipped)
    /// or not in front of the eye.
    #[must_use]
    pub fn vertex_window(&self, index: u32) -> Option<([i64; 2], f64)> {
        let outcode = self.outcode(index);
        (outcode & (CLIP_BITS | NOT_IN_FRONT_BIT) == 0).then(|| self.snapped(index))
    }
}
