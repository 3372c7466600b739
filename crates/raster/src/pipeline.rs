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

use glam::{DMat4, DVec4};
use rayon::prelude::*;

use crate::camera::Camera;
use crate::fragment::{depth_key, Fragment};
use crate::mesh::Mesh;

/// Fractional bits of the fixed-point vertex grid (Vulkan's common `subPixelPrecisionBits`).
pub const SUBPIXEL_BITS: u32 = 8;
const ONE: i64 = 1 << SUBPIXEL_BITS;
const HALF: i64 = ONE / 2;

/// How far outside the viewport, in pixels, vertices may lie before they are clipped.
///
/// With viewports of at most [`Viewport::MAX_SIDE`] pixels, snapped coordinates stay below
/// 2^24 in magnitude and the edge functions below 2^49: far from i64 overflow.
pub const GUARD_BAND_PIXELS: f64 = 16384.0;

/// The size of the render target in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Viewport {
    /// The largest side accepted (the guard band's fixed-point bound is sized for it).
    pub const MAX_SIDE: u32 = 16384;

    /// A viewport of `width × height` pixels.
    ///
    /// # Errors
    /// A zero or larger than [`Viewport::MAX_SIDE`] side, named in the message.
    pub fn new(width: u32, height: u32) -> Result<Self, String> {
        for (name, side) in [("width", width), ("height", height)] {
            if side == 0 || side > Self::MAX_SIDE {
                return Err(format!(
                    "viewport {name} must be between 1 and {}, got {side}",
                    Self::MAX_SIDE
                ));
            }
        }
        Ok(Self { width, height })
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Every pixel of the viewport.
    #[must_use]
    pub fn rect(self) -> PixelRect {
        PixelRect {
            x: (0, self.width - 1),
            y: (0, self.height - 1),
        }
    }
}

/// A rectangle of whole pixels, bounds inclusive: the pixels a scan may visit (a screen tile, or
/// the pixels whose centres a triangle's bounding box holds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First and last column.
    pub x: (u32, u32),
    /// First and last row.
    pub y: (u32, u32),
}

impl PixelRect {
    /// The smallest rectangle holding both.
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        Self {
            x: (self.x.0.min(other.x.0), self.x.1.max(other.x.1)),
            y: (self.y.0.min(other.y.0), self.y.1.max(other.y.1)),
        }
    }

    /// The pixel centres that a bounding box `[lo, hi]` (x and y in 1/256 pixel) holds inside
    /// this rectangle; `None` when there is none.
    #[inline]
    fn centres_within(self, lo: [i64; 2], hi: [i64; 2]) -> Option<Self> {
        let x = pixel_span(lo[0], hi[0], self.x)?;
        let y = pixel_span(lo[1], hi[1], self.y)?;
        Some(Self { x, y })
    }
}

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
    /// Per vertex: bit `i` set when the vertex is outside plane `i` of [`View::planes`]; bit 5:
    /// beyond far; bit 6: not in front of the eye (`w ≤ 0` or NaN).
    outcodes: Vec<u8>,
    /// Per vertex: the snapped window position, x and y in 1/256 pixel, y down; meaningful only
    /// when the vertex's outcode has no clip bit set. Inside the guard band they fit an `i32`
    /// (|x| < 2^23). Kept apart from the depth: the triangle loop over a large mesh is bound by
    /// fetching its vertices, and most triangles of a dense mesh are rejected by their bounding
    /// box alone, before the depth is needed.
    window_xy: Vec<[i32; 2]>,
    /// Per vertex: the window depth `z / w`, under the same condition.
    window_z: Vec<f64>,
    viewport: Viewport,
    cull: CullMode,
    guard: [f64; 2],
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
    /// Transforms every vertex of `mesh` once.
    #[must_use]
    pub fn new(mesh: &'mesh Mesh, camera: &Camera, viewport: Viewport, cull: CullMode) -> Self {
        let guard = [
            1.0 + 2.0 * GUARD_BAND_PIXELS / f64::from(viewport.width),
            1.0 + 2.0 * GUARD_BAND_PIXELS / f64::from(viewport.height),
        ];
        let mut view = Self {
            mesh,
            view_projection: camera.view_projection,
            outcodes: Vec::new(),
            window_xy: Vec::new(),
            window_z: Vec::new(),
            viewport,
            cull,
            guard,
        };
        view.set_camera(camera);
        view
    }

    /// Runs the vertex stage again for another camera, reusing this view's buffers (a frame loop
    /// allocates nothing).
    pub fn set_camera(&mut self, camera: &Camera) {
        self.view_projection = camera.view_projection;
        let count = self.mesh.positions.len();
        self.outcodes.resize(count, 0);
        self.window_xy.resize(count, [0, 0]);
        self.window_z.resize(count, 0.0);
        let stage = VertexStage {
            view_projection: self.view_projection,
            planes: self.planes(),
        };
        // Every vertex is independent: chunks of the arrays go to the pool side by side.
        self.mesh
            .positions
            .par_chunks(VERTICES_PER_TASK)
            .zip(self.outcodes.par_chunks_mut(VERTICES_PER_TASK))
            .zip(self.window_xy.par_chunks_mut(VERTICES_PER_TASK))
            .zip(self.window_z.par_chunks_mut(VERTICES_PER_TASK))
            .for_each(|(((positions, outcodes), window_xy), window_z)| {
                let outputs = outcodes.iter_mut().zip(window_xy).zip(window_z);
                for (p, ((outcode, xy), z)) in positions.iter().zip(outputs) {
                    let clip = stage.clip(*p);
                    *outcode = stage.outcode(clip);
                    if *outcode & CLIP_BITS == 0 {
                        let ([x, y], depth) = snap(self.viewport, clip);
                        // Inside the guard band: lossless (see `window_xy`).
                        *xy = [x as i32, y as i32];
                        *z = depth;
                    }
                }
            });
    }

    /// The vertex stage's snapped position and depth of vertex `index` (no clip bit set).
    fn snapped(&self, index: u32) -> Snapped {
        let [x, y] = self.window_xy[index as usize];
        ([x.into(), y.into()], self.window_z[index as usize])
    }

    /// The clip-space position of vertex `index`, exactly as the vertex stage computed it.
    fn clip_position(&self, index: u32) -> DVec4 {
        transform(self.view_projection, self.mesh.positions[index as usize])
    }

    /// The viewport.
    #[must_use]
    pub fn viewport(&self) -> Viewport {
        self.viewport
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

    /// Number of triangles (primitive ids are `0..triangle_count()`).
    #[must_use]
    pub fn triangle_count(&self) -> u32 {
        self.mesh.triangles.len() as u32
    }

    /// Rasterizes triangle `prim`, calling `emit` for each fragment in scan order (rows top to
    /// bottom, pixels left to right, fan pieces in order).
    pub fn rasterize(&self, prim: u32, emit: &mut impl FnMut(Fragment)) {
        self.rasterize_in(prim, self.viewport.rect(), emit);
    }

    /// [`View::rasterize`] restricted to the pixels of `rect` (a screen tile): exactly the
    /// fragments of the whole triangle that fall in `rect`, in the same order.
    pub fn rasterize_in(&self, prim: u32, rect: PixelRect, emit: &mut impl FnMut(Fragment)) {
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcodes[i as usize]);
        if ca & cb & cc != 0 || (ca | cb | cc) & CLIP_BITS != 0 {
            self.screen_triangles(prim, &mut |tri| self.scan_in(&tri, rect, emit));
            return;
        }
        // The common case, inlined: no clipping, and most triangles of a dense mesh cover no
        // pixel centre, which their bounding box tells before any edge function is set up.
        if (ca | cb | cc) & NOT_IN_FRONT_BIT != 0 {
            return;
        }
        let [lo, hi] = bounding_box(indices.map(|i| self.window_xy[i as usize]));
        if rect.centres_within(lo, hi).is_none() {
            return;
        }
        let snapped = indices.map(|i| self.snapped(i));
        self.orient(prim, snapped, &mut |tri| self.scan_in(&tri, rect, emit));
    }

    /// The pixels whose centres the bounding boxes of triangle `prim`'s pieces hold: every
    /// fragment of the triangle lies inside. `None` when the triangle is rejected or its boxes
    /// hold no pixel centre, as for most triangles of a dense mesh (culling and zero area are
    /// left to the scan).
    #[must_use]
    pub fn pixel_bounds(&self, prim: u32) -> Option<PixelRect> {
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcodes[i as usize]);
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
        let [lo, hi] = bounding_box(indices.map(|i| self.window_xy[i as usize]));
        full.centres_within(lo, hi)
    }

    /// Calls `visit` with the snapped, clipped, oriented pieces of triangle `prim` (none when it
    /// is rejected, culled or degenerate).
    pub fn screen_triangles(&self, prim: u32, visit: &mut impl FnMut(ScreenTriangle)) {
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcodes[i as usize]);
        // Trivial reject: all three vertices outside one plane.
        if ca & cb & cc != 0 {
            return;
        }
        if (ca | cb | cc) & CLIP_BITS == 0 {
            if (ca | cb | cc) & NOT_IN_FRONT_BIT == 0 {
                let snapped = indices.map(|i| self.snapped(i));
                self.orient(prim, snapped, visit);
            }
            return;
        }
        let polygon = self.clip(indices.map(|i| self.clip_position(i)));
        if polygon.len() < 3 {
            return;
        }
        for i in 1..polygon.len() - 1 {
            let piece = [polygon[0], polygon[i], polygon[i + 1]];
            if piece.iter().any(|v| !in_front(*v)) {
                continue;
            }
            self.orient(prim, piece.map(|v| snap(self.viewport, v)), visit);
        }
    }

    /// Clips a triangle in homogeneous space against the near plane and the guard band (rule 3);
    /// fewer than 3 vertices when nothing is left.
    fn clip(&self, triangle: [DVec4; 3]) -> Vec<DVec4> {
        let mut polygon = triangle.to_vec();
        for plane in self.planes() {
            polygon = clip_polygon(&polygon, plane);
            if polygon.len() < 3 {
                return polygon;
            }
        }
        // An intersection between vertices far apart (|x| near 1e38, say) cancels catastrophically
        // and may land far outside the band it was clipped to; clamping restores the bound that
        // keeps fixed-point coordinates and edge functions from overflowing (rule 3). It moves
        // nothing that the clipping left inside.
        let [gx, gy] = self.guard;
        for v in &mut polygon {
            v.x = v.x.max(-gx * v.w).min(gx * v.w);
            v.y = v.y.max(-gy * v.w).min(gy * v.w);
        }
        polygon
    }

    /// The clipping planes as `p · v ≥ 0`: near (`z ≥ 0`) then the four guard-band planes.
    fn planes(&self) -> [DVec4; 5] {
        let [gx, gy] = self.guard;
        [
            DVec4::new(0.0, 0.0, 1.0, 0.0),
            DVec4::new(1.0, 0.0, 0.0, gx),
            DVec4::new(-1.0, 0.0, 0.0, gx),
            DVec4::new(0.0, 1.0, 0.0, gy),
            DVec4::new(0.0, -1.0, 0.0, gy),
        ]
    }

    /// Culls or orients a snapped triangle and hands it to `visit`.
    fn orient(&self, prim: u32, snapped: [Snapped; 3], visit: &mut impl FnMut(ScreenTriangle)) {
        let [(pa, za), (mut pb, mut zb), (mut pc, mut zc)] = snapped;
        let area = edge(pa, pb, pc);
        if area == 0 {
            return;
        }
        // In a y-down window a negative area is counter-clockwise as the viewer sees it: a front
        // face under the OpenGL/OBJ convention.
        let front = area < 0;
        match self.cull {
            CullMode::Back if !front => return,
            CullMode::Front if front => return,
            _ => {}
        }
        if area < 0 {
            std::mem::swap(&mut pb, &mut pc);
            std::mem::swap(&mut zb, &mut zc);
        }
        visit(ScreenTriangle {
            prim,
            xy: [pa, pb, pc],
            z: [za, zb, zc],
        });
    }

    /// Scans an oriented snapped triangle: every covered pixel centre emits a fragment.
    pub fn scan(&self, tri: &ScreenTriangle, emit: &mut impl FnMut(Fragment)) {
        self.scan_in(tri, self.viewport.rect(), emit);
    }

    /// [`View::scan`] restricted to the pixels of `rect`.
    pub fn scan_in(&self, tri: &ScreenTriangle, rect: PixelRect, emit: &mut impl FnMut(Fragment)) {
        let [a, b, c] = tri.xy;
        let area = edge(a, b, c);
        debug_assert!(area > 0);
        let [lo, hi] = bounding_box(tri.xy);
        let Some(PixelRect {
            x: (x0, x1),
            y: (y0, y1),
        }) = rect.centres_within(lo, hi)
        else {
            return;
        };
        let [x0, x1, y0, y1] = [x0, x1, y0, y1].map(i64::from);
        // Edge i is opposite vertex i, so its value is the barycentric weight of vertex i.
        let edges = [(b, c), (c, a), (a, b)];
        let bias = edges.map(|(p, q)| if is_top_left(p, q) { 0 } else { -1 });
        let step_x = edges.map(|(p, q)| -(q[1] - p[1]) * ONE);
        let step_y = edges.map(|(p, q)| (q[0] - p[0]) * ONE);
        let start = [x0 * ONE + HALF, y0 * ONE + HALF];
        let mut row = edges.map(|(p, q)| edge(p, q, start));
        let area_f = area as f64;
        let width = i64::from(self.viewport.width);
        for y in y0..=y1 {
            let mut e = row;
            for x in x0..=x1 {
                if (0..3).all(|k| e[k] + bias[k] >= 0) {
                    let z =
                        (e[0] as f64 * tri.z[0] + e[1] as f64 * tri.z[1] + e[2] as f64 * tri.z[2])
                            / area_f;
                    if let Some(depth_key) = depth_key(z as f32) {
                        emit(Fragment {
                            pixel: (y * width + x) as u32,
                            depth_key,
                            prim: tri.prim,
                        });
                    }
                }
                for k in 0..3 {
                    e[k] += step_x[k];
                }
            }
            for k in 0..3 {
                row[k] += step_y[k];
            }
        }
    }
}

/// The bounding box of three window positions: its lowest and highest corner.
#[inline]
fn bounding_box<T: Copy + Ord + Into<i64>>([a, b, c]: [[T; 2]; 3]) -> [[i64; 2]; 2] {
    let axis = |i: usize| {
        (
            a[i].min(b[i]).min(c[i]).into(),
            a[i].max(b[i]).max(c[i]).into(),
        )
    };
    let ((x_lo, x_hi), (y_lo, y_hi)) = (axis(0), axis(1));
    [[x_lo, y_lo], [x_hi, y_hi]]
}

/// The first and last pixel whose centre lies in `[lo, hi]` (1/256 pixel) and in the pixel range
/// `[first, last]`; `None` when there is none.
#[inline]
fn pixel_span(lo: i64, hi: i64, (first, last): (u32, u32)) -> Option<(u32, u32)> {
    let from = (lo - HALF + ONE - 1).div_euclid(ONE).max(first.into());
    let to = (hi - HALF).div_euclid(ONE).min(last.into());
    // Both lie in [first, last] when they are ordered, so the conversions are lossless.
    (from <= to).then_some((from as u32, to as u32))
}

/// What the vertex stage needs, copied out of the view so that it can fill the view's buffers.
struct VertexStage {
    view_projection: DMat4,
    planes: [DVec4; 5],
}

impl VertexStage {
    fn clip(&self, position: [f32; 3]) -> DVec4 {
        transform(self.view_projection, position)
    }

    /// The outcode of [`View::planes`] and the far plane, each plane written out rather than as a
    /// dot product with mostly zero coefficients: for finite coordinates (always: positions are
    /// finite f32 and the matrix finite f64) the zero terms add only signed zeros, so each sum is
    /// rounded exactly as the dot product's and every comparison decides the same.
    fn outcode(&self, clip: DVec4) -> u8 {
        let [_, right, _, bottom, _] = self.planes;
        let (gx, gy) = (right.w, bottom.w);
        let DVec4 { x, y, z, w } = clip;
        let mut outcode = u8::from(z < 0.0)
            | u8::from(x + gx * w < 0.0) << 1
            | u8::from(-x + gx * w < 0.0) << 2
            | u8::from(y + gy * w < 0.0) << 3
            | u8::from(-y + gy * w < 0.0) << 4;
        if -z + w < 0.0 {
            outcode |= FAR_BIT;
        }
        if !in_front(clip) {
            outcode |= NOT_IN_FRONT_BIT;
        }
        outcode
    }
}

/// Rule 1: model space to clip space, in f64.
fn transform(view_projection: DMat4, p: [f32; 3]) -> DVec4 {
    view_projection * DVec4::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0)
}

/// Whether a clip-space vertex has `w > 0` (false for NaN).
fn in_front(clip: DVec4) -> bool {
    clip.w > 0.0
}

/// Rule 4: projects a clip-space vertex to the window and snaps x and y to the fixed-point grid.
fn snap(viewport: Viewport, v: DVec4) -> Snapped {
    let (w, h) = (f64::from(viewport.width), f64::from(viewport.height));
    let x = (v.x / v.w * 0.5 + 0.5) * w;
    let y = (0.5 - v.y / v.w * 0.5) * h;
    (
        [
            round_half_away(x * ONE as f64),
            round_half_away(y * ONE as f64),
        ],
        v.z / v.w,
    )
}

/// `value.round() as i64` (half away from zero, saturating, NaN to 0) without a libm call:
/// baseline x86-64 has no rounding instruction, only the truncating conversion. The fraction
/// `value − trunc(value)` is exact for every f64, so the comparison with one half decides exactly
/// as `round` does.
fn round_half_away(value: f64) -> i64 {
    let truncated = value as i64;
    let fraction = value - truncated as f64;
    if fraction >= 0.5 {
        truncated.saturating_add(1)
    } else if fraction <= -0.5 {
        truncated.saturating_sub(1)
    } else {
        truncated
    }
}

/// Twice the signed area of `(a, b, p)`: positive when `p` is on the interior side of `a → b` for
/// a positively oriented triangle in the y-down window.
fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top edge: horizontal with the interior below; left edge: the interior to its right. For a
/// positively oriented triangle that is `dy < 0`, or `dy == 0 && dx > 0`.
fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx > 0)
}

/// Sutherland–Hodgman against one plane `p · v ≥ 0`.
fn clip_polygon(polygon: &[DVec4], plane: DVec4) -> Vec<DVec4> {
    let mut out = Vec::with_capacity(polygon.len() + 1);
    for (i, &current) in polygon.iter().enumerate() {
        let next = polygon[(i + 1) % polygon.len()];
        let (dc, dn) = (plane.dot(current), plane.dot(next));
        if dc >= 0.0 {
            out.push(current);
        }
        if (dc >= 0.0) != (dn >= 0.0) {
            // From the inside end toward the outside end, whichever way this polygon walks the
            // edge: two triangles sharing the edge then compute the very same f64 point, snap it
            // to the same grid point, and the shared clipped edge stays watertight.
            let (inside, d_in, outside, d_out) = if dc >= 0.0 {
                (current, dc, next, dn)
            } else {
                (next, dn, current, dc)
            };
            let t = d_in / (d_in - d_out);
            out.push(inside + (outside - inside) * t);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view_of(mesh: &Mesh, side: u32) -> View<'_> {
        // Identity projection: model x, y in [-1, 1] map straight to the window, z is depth.
        let camera = Camera {
            view_projection: DMat4::IDENTITY,
        };
        View::new(
            mesh,
            &camera,
            Viewport::new(side, side).unwrap(),
            CullMode::None,
        )
    }

    fn coverage(view: &View<'_>) -> Vec<u32> {
        let mut counts = vec![0; view.viewport().pixels()];
        for prim in 0..view.triangle_count() {
            view.rasterize(prim, &mut |f| counts[f.pixel as usize] += 1);
        }
        counts
    }

    #[test]
    fn two_triangles_sharing_a_diagonal_cover_each_centre_once() {
        // A full-screen quad split along the diagonal, which passes through pixel centres.
        let mesh = Mesh {
            positions: vec![
                [-1.0, -1.0, 0.5],
                [1.0, -1.0, 0.5],
                [1.0, 1.0, 0.5],
                [-1.0, 1.0, 0.5],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        assert!(coverage(&view_of(&mesh, 8)).iter().all(|&c| c == 1));
    }

    #[test]
    fn depth_is_interpolated_and_keyed() {
        let mesh = Mesh {
            positions: vec![[-1.0, -1.0, 0.25], [3.0, -1.0, 0.25], [-1.0, 3.0, 0.25]],
            triangles: vec![[0, 1, 2]],
        };
        let view = view_of(&mesh, 4);
        let mut keys = Vec::new();
        view.rasterize(0, &mut |f| keys.push(f.depth_key));
        assert_eq!(keys.len(), 16);
        assert!(keys.iter().all(|&k| k == 0.25f32.to_bits()));
    }

    #[test]
    fn fragments_beyond_far_are_dropped() {
        let mesh = Mesh {
            positions: vec![[-1.0, -1.0, 1.5], [3.0, -1.0, 1.5], [-1.0, 3.0, 1.5]],
            triangles: vec![[0, 1, 2]],
        };
        assert!(coverage(&view_of(&mesh, 4)).iter().all(|&c| c == 0));
    }

    #[test]
    fn a_clipped_vertex_lost_to_cancellation_is_clamped_into_the_guard_band() {
        // Found by the rasterize fuzz target: clipping the edge from x = 1.9e38 to x = −2.55e38
        // against x ≥ −513 w cancelled to x ≈ −3.8e22, which snapped to i64::MIN and overflowed
        // the edge function (a panic with overflow checks, garbage without).
        let mesh = Mesh {
            positions: vec![
                [-2.552_080_4e38, -2.046_936_3, 0.012],
                [1.900_796_2e38, 0.0, 0.004],
            ],
            triangles: vec![[0, 1, 1]],
        };
        let view = view_of(&mesh, 64);
        let [a, b] = [0, 1].map(|i| view.clip_position(i));
        let polygon = view.clip([a, b, b]);
        assert!(polygon.len() >= 3);
        let [gx, gy] = view.guard;
        for v in &polygon {
            assert!(v.x.abs() <= gx * v.w && v.y.abs() <= gy * v.w, "{v:?}");
        }
        assert!(coverage(&view).iter().all(|&c| c == 0));
    }

    #[test]
    fn the_written_out_outcode_equals_the_plane_dot_products() {
        let mesh = Mesh {
            positions: vec![],
            triangles: vec![],
        };
        let view = view_of(&mesh, 37);
        let stage = VertexStage {
            view_projection: DMat4::IDENTITY,
            planes: view.planes(),
        };
        let by_dot_products = |clip: DVec4| {
            let mut code = stage
                .planes
                .iter()
                .enumerate()
                .fold(0u8, |code, (i, plane)| {
                    code | (u8::from(plane.dot(clip) < 0.0) << i)
                });
            if DVec4::new(0.0, 0.0, -1.0, 1.0).dot(clip) < 0.0 {
                code |= FAR_BIT;
            }
            if !in_front(clip) {
                code |= NOT_IN_FRONT_BIT;
            }
            code
        };
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let specials = [0.0, -0.0, 1.0, -1.0, 1e-300, 3.4e38, -3.4e38, 1e300];
        for _ in 0..200_000 {
            let mut coordinate = || {
                let bits = next();
                match bits % 4 {
                    0 => specials[(bits >> 8) as usize % specials.len()],
                    1 => (bits >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0,
                    _ => f64::from_bits(bits).clamp(-1e300, 1e300),
                }
            };
            let clip = DVec4::new(coordinate(), coordinate(), coordinate(), coordinate());
            if clip.is_finite() {
                assert_eq!(stage.outcode(clip), by_dot_products(clip), "{clip:?}");
            }
        }
    }

    #[test]
    fn rounding_without_libm_equals_f64_round() {
        let mut values = vec![
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.499_999_999_999_999_94,
            -0.499_999_999_999_999_94,
            4_503_599_627_370_495.5,
            4_503_599_627_370_497.0,
            1e30,
            -1e30,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
        ];
        // Halves and their neighbours over the snapped range, and a deterministic spread.
        for i in -3000i32..3000 {
            let half = f64::from(i) + 0.5;
            values.extend([half, half.next_up(), half.next_down()]);
        }
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            values.push(f64::from_bits(x));
        }
        for v in values {
            assert_eq!(round_half_away(v), v.round() as i64, "{v:e}");
        }
    }

    /// Views of a triangle soup seen from far (tiny triangles), near (clipped ones) and inside
    /// (w ≤ 0), on a viewport of odd sides.
    fn soup_views(mesh: &Mesh) -> impl Iterator<Item = (f64, View<'_>)> {
        [40.0, 1.0, 0.3, 0.01].into_iter().map(|distance_scale| {
            let orbit = crate::OrbitCamera {
                distance_scale,
                ..crate::OrbitCamera::default()
            };
            let camera = orbit.camera(mesh.bounds(), 1.0);
            let viewport = Viewport::new(97, 61).unwrap();
            (
                distance_scale,
                View::new(mesh, &camera, viewport, CullMode::None),
            )
        })
    }

    #[test]
    fn the_inlined_fast_path_emits_what_the_general_path_emits() {
        // `rasterize` skips `screen_triangles` for unclipped triangles; both must agree.
        let mesh = crate::scenes::triangle_soup(3000, 7);
        for (distance_scale, view) in soup_views(&mesh) {
            let mut fragments = 0;
            for prim in 0..view.triangle_count() {
                let (mut fast, mut general) = (Vec::new(), Vec::new());
                view.rasterize(prim, &mut |f| fast.push(f));
                view.screen_triangles(prim, &mut |t| view.scan(&t, &mut |f| general.push(f)));
                assert_eq!(
                    fast, general,
                    "triangle {prim} at distance {distance_scale}"
                );
                fragments += fast.len();
            }
            assert!(fragments > 0, "distance {distance_scale} drew nothing");
        }
    }

    #[test]
    fn tiles_split_a_triangle_s_fragments_exactly_and_its_bounds_hold_them() {
        // Tiles of 13 × 8 pixels, misaligned with the 97 × 61 viewport's sides on purpose.
        let mesh = crate::scenes::triangle_soup(3000, 11);
        for (distance_scale, view) in soup_views(&mesh) {
            let Viewport { width, height } = view.viewport();
            let tiles: Vec<PixelRect> = (0..height.div_ceil(8))
                .flat_map(|row| {
                    (0..width.div_ceil(13)).map(move |column| PixelRect {
                        x: (column * 13, (column * 13 + 12).min(width - 1)),
                        y: (row * 8, (row * 8 + 7).min(height - 1)),
                    })
                })
                .collect();
            for prim in 0..view.triangle_count() {
                let mut whole = Vec::new();
                view.rasterize(prim, &mut |f| whole.push(f));
                let bounds = view.pixel_bounds(prim);
                let inside = |rect: &PixelRect, pixel: u32| {
                    let (x, y) = (pixel % width, pixel / width);
                    (rect.x.0..=rect.x.1).contains(&x) && (rect.y.0..=rect.y.1).contains(&y)
                };
                match bounds {
                    None => assert!(whole.is_empty(), "triangle {prim} at {distance_scale}"),
                    Some(rect) => assert!(whole.iter().all(|f| inside(&rect, f.pixel))),
                }
                for tile in &tiles {
                    let mut part = Vec::new();
                    view.rasterize_in(prim, *tile, &mut |f| part.push(f));
                    let expected: Vec<Fragment> = whole
                        .iter()
                        .copied()
                        .filter(|f| inside(tile, f.pixel))
                        .collect();
                    assert_eq!(part, expected, "triangle {prim} at {distance_scale}");
                }
            }
        }
    }

    #[test]
    fn a_triangle_crossing_the_near_plane_is_clipped_not_lost() {
        let mesh = Mesh {
            positions: vec![[-1.0, -1.0, -0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
            triangles: vec![[0, 1, 2]],
        };
        let counts = coverage(&view_of(&mesh, 8));
        let covered = counts.iter().filter(|&&c| c == 1).count();
        assert!(covered > 0 && covered < 64, "{covered}");
        assert!(counts.iter().all(|&c| c <= 1));
    }
}
