//! Rules 1 to 4: the vertex stage (transform, outcodes), homogeneous clipping against the near
//! plane and the guard band, and snapping to the fixed-point grid, each under the view's
//! [`Conventions`] (`docs/semantics.md`, "Conventions"): the arithmetic of the transform, divide
//! and viewport mapping (f64 or f32), the near plane and window depth of the depth range, the
//! window's y direction and the snapping grid.

use std::ops::{Add, Div, Mul, Sub};

use glam::{DMat4, DVec4};
use rayon::prelude::*;

use super::{
    Snapped, View, Viewport, CLIP_BITS, FAR_BIT, HALF, NOT_IN_FRONT_BIT, ONE, SUBPIXEL_BITS,
    VERTICES_PER_TASK,
};
use crate::camera::Camera;
use crate::conventions::DepthRange::{self, MinusOneToOne, ZeroToOne};
use crate::conventions::VertexPrecision::{self, F32, F64};
use crate::conventions::WindowOrigin::{LowerLeft, UpperLeft};
use crate::conventions::{Conventions, F32RangeError};

impl View<'_> {
    /// Runs the vertex stage again for another camera, reusing this view's buffers (a frame loop
    /// allocates nothing).
    pub fn set_camera(&mut self, camera: &Camera) {
        self.view_projection = camera.view_projection;
        let count = self.mesh.positions.len();
        self.cells.resize(count, NO_CELLS);
        self.window.resize(count, WindowVertex::default());
        self.window_z.resize(count, 0.0);
        let stage = self.stage();
        let AxisPositions { x, y, z } = &self.axes;
        // Every vertex is independent: chunks of the arrays go to the pool side by side.
        x.par_chunks(VERTICES_PER_TASK)
            .zip(y.par_chunks(VERTICES_PER_TASK))
            .zip(z.par_chunks(VERTICES_PER_TASK))
            .zip(self.cells.par_chunks_mut(VERTICES_PER_TASK))
            .zip(self.window.par_chunks_mut(VERTICES_PER_TASK))
            .zip(self.window_z.par_chunks_mut(VERTICES_PER_TASK))
            .for_each(|(((((x, y), z), cells), window), window_z)| {
                let c = stage.conventions;
                let chunk = ([x, y, z], cells, window, window_z);
                match (c.vertex_precision, c.window_origin, c.depth_range) {
                    (F64, UpperLeft, ZeroToOne) => stage.project::<false, false, false>(chunk),
                    (F64, UpperLeft, MinusOneToOne) => stage.project::<false, false, true>(chunk),
                    (F64, LowerLeft, ZeroToOne) => stage.project::<false, true, false>(chunk),
                    (F64, LowerLeft, MinusOneToOne) => stage.project::<false, true, true>(chunk),
                    (F32, UpperLeft, ZeroToOne) => stage.project::<true, false, false>(chunk),
                    (F32, UpperLeft, MinusOneToOne) => stage.project::<true, false, true>(chunk),
                    (F32, LowerLeft, ZeroToOne) => stage.project::<true, true, false>(chunk),
                    (F32, LowerLeft, MinusOneToOne) => stage.project::<true, true, true>(chunk),
                }
            });
    }

    /// Clips a triangle in homogeneous space against the near plane and the guard band (rule 3);
    /// fewer than 3 vertices when nothing is left.
    pub(super) fn clip(&self, triangle: [DVec4; 3]) -> Vec<DVec4> {
        let trace = ClipTrace::of(triangle, &self.planes());
        self.clamped(&trace)
    }

    /// The polygon `trace` leaves, as the pipeline uses it: each vertex clamped to the guard band.
    ///
    /// An intersection between vertices far apart (|x| near 1e38, say) cancels catastrophically
    /// and may land far outside the band it was clipped to; clamping restores the bound that
    /// keeps fixed-point coordinates and edge functions from overflowing (rule 3). It moves
    /// nothing that the clipping left inside.
    fn clamped(&self, trace: &ClipTrace) -> Vec<DVec4> {
        if trace.polygon.len() < 3 {
            return trace.polygon.iter().map(|&i| trace.points[i]).collect();
        }
        let [gx, gy] = self.guard;
        trace
            .polygon
            .iter()
            .map(|&i| {
                let mut v = trace.points[i];
                v.x = v.x.max(-gx * v.w).min(gx * v.w);
                v.y = v.y.max(-gy * v.w).min(gy * v.w);
                v
            })
            .collect()
    }

    /// Triangle `prim` as the pipeline clips it (rule 3), every step recorded, with the polygon's
    /// vertices as the pipeline uses them (clamped, in clip space) and their snapped window
    /// positions and depths (rule 4): what a precision analysis of a clipped triangle starts
    /// from. `None` when the triangle takes no clipping (no vertex outside the near plane or the
    /// guard band) or is rejected whole by one plane.
    #[must_use]
    pub fn clipped(&self, prim: u32) -> Option<Clipped> {
        let indices = self.mesh.triangles[prim as usize];
        let [ca, cb, cc] = indices.map(|i| self.outcode(i));
        if ca & cb & cc != 0 || (ca | cb | cc) & CLIP_BITS == 0 {
            return None;
        }
        let trace = ClipTrace::of(indices.map(|i| self.clip_position(i)), &self.planes());
        let polygon = self.clamped(&trace);
        let stage = self.stage();
        let snapped = polygon.iter().map(|&v| stage.snap(v)).collect();
        Some(Clipped {
            trace,
            polygon,
            snapped,
        })
    }

    /// The clipping planes as `p · v ≥ 0`, in the order the pipeline clips against them: near
    /// (`z ≥ 0`, or `z ≥ −w` for [`DepthRange::MinusOneToOne`]) then the four guard-band planes.
    #[must_use]
    pub fn clip_planes(&self) -> [DVec4; 5] {
        self.planes()
    }

    /// Refuses a view whose f32 vertex stage would leave f32's normal range: a nonzero product of
    /// a matrix entry and a position coordinate (or a nonzero translation entry) below
    /// `f32::MIN_POSITIVE` or above `f32::MAX` in magnitude. A GPU may flush a subnormal to zero
    /// (Vulkan allows it) and an overflow is infinite, so neither fragsim's f32 stage nor the
    /// bounds of `docs/semantics.md` §10 say what such an implementation computes, whatever
    /// precision the matrix was declared in.
    ///
    /// # Errors
    /// The first such entry, by its row-major index, with the vertex and the product.
    #[expect(
        clippy::needless_range_loop,
        reason = "row and column index the column-major matrix and name the row-major entry"
    )]
    pub fn check_f32_range(&self) -> Result<(), F32RangeError> {
        let normal = |x: f64| {
            x == 0.0 || (f64::from(f32::MIN_POSITIVE)..=f64::from(f32::MAX)).contains(&x.abs())
        };
        let m = self.view_projection.to_cols_array_2d();
        let out_of_range =
            |row: usize, column: usize, vertex: Option<usize>, product: f64| F32RangeError {
                index: row * 4 + column,
                entry: m[column][row],
                vertex: vertex.map(|v| (v, ["x", "y", "z"][column])),
                product,
            };
        for row in 0..4 {
            if !normal(m[3][row]) {
                return Err(out_of_range(row, 3, None, m[3][row]));
            }
            for column in 0..3 {
                let entry = m[column][row];
                if entry == 0.0 {
                    continue;
                }
                let bad = self.mesh.positions.iter().enumerate().find_map(|(v, p)| {
                    let product = entry * f64::from(p[column]);
                    (!normal(product)).then_some((v, product))
                });
                if let Some((v, product)) = bad {
                    return Err(out_of_range(row, column, Some(v), product));
                }
            }
        }
        Ok(())
    }

    /// The vertex stage of this view's camera, viewport and conventions.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the f32 vertex stage's matrix: a GPU's single-precision entries"
    )]
    pub(super) fn stage(&self) -> VertexStage {
        VertexStage {
            view_projection: self.view_projection,
            view_projection_f32: self.view_projection.to_cols_array().map(|e| e as f32),
            planes: self.planes(),
            viewport: self.viewport,
            conventions: self.conventions,
        }
    }

    /// The clipping planes as `p · v ≥ 0`: near (`z ≥ 0`, or `z ≥ −w` for
    /// [`DepthRange::MinusOneToOne`]) then the four guard-band planes.
    pub(super) fn planes(&self) -> [DVec4; 5] {
        let [gx, gy] = self.guard;
        let near_w = match self.conventions.depth_range {
            DepthRange::ZeroToOne => 0.0,
            DepthRange::MinusOneToOne => 1.0,
        };
        [
            DVec4::new(0.0, 0.0, 1.0, near_w),
            DVec4::new(1.0, 0.0, 0.0, gx),
            DVec4::new(-1.0, 0.0, 0.0, gx),
            DVec4::new(0.0, 1.0, 0.0, gy),
            DVec4::new(0.0, -1.0, 0.0, gy),
        ]
    }
}

/// Per vertex and axis, the interval between pixel-centre lines that the snapped coordinate lies
/// strictly inside, as `2 · floor((c − ½ pixel) / pixel)`, made odd where the coordinate lies on
/// a centre line or the vertex has no meaningful window position (it needs clipping or is not in
/// front of the eye). A triangle whose three vertices have one even cell on an axis lies strictly
/// between two centre lines there, so its bounding box holds no pixel centre: the triangle
/// setup's first reject, three loads and a few comparisons.
pub(super) type CentreCells = [i32; 2];

/// The [`CentreCells`] of a vertex that can never be rejected by them.
const NO_CELLS: CentreCells = [1, 1];

/// The [`CentreCells`] of a snapped position inside the guard band (|c| < 2^24); any other
/// position gives some value without overflowing, which no triangle reads.
#[inline]
#[expect(
    clippy::cast_possible_truncation,
    reason = "HALF and ONE are 128 and 256 (1/256 pixel), well within i32"
)]
fn centre_cells(xy: [i32; 2]) -> CentreCells {
    let cell = |c: i32| {
        let from_centre = c.wrapping_sub(HALF as i32);
        let on_line = from_centre & (ONE as i32 - 1) == 0;
        // `2 · floor(…) + on_line`, written with shifts so that no value can overflow.
        (from_centre >> SUBPIXEL_BITS) << 1 | i32::from(on_line)
    };
    [cell(xy[0]), cell(xy[1])]
}

/// The mesh's positions as one array per axis: the vertex stage's loop reads them a few vertices
/// per instruction (SIMD lanes), which interleaved `[x, y, z]` triples would prevent. Built once
/// per view; the mesh a view borrows cannot change.
#[derive(Clone, Debug, Default)]
pub(super) struct AxisPositions {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl AxisPositions {
    /// The axes of `positions`.
    pub(super) fn of(positions: &[[f32; 3]]) -> Self {
        Self {
            x: positions.iter().map(|p| p[0]).collect(),
            y: positions.iter().map(|p| p[1]).collect(),
            z: positions.iter().map(|p| p[2]).collect(),
        }
    }
}

/// What the vertex stage leaves for the triangle setup of every triangle that uses a vertex.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct WindowVertex {
    /// The snapped window position, x and y in 1/256 pixel, y down; meaningful only when the
    /// outcode has no clip bit set. Inside the guard band they fit an `i32` (|x| < 2^23).
    pub(super) xy: [i32; 2],
    /// Bit `i` set when the vertex is outside plane `i` of [`View::planes`]; bit 5: beyond far;
    /// bit 6: not in front of the eye (`w ≤ 0` or NaN).
    pub(super) outcode: u8,
}

impl WindowVertex {
    /// The snapped window position, widened.
    #[inline]
    pub(super) fn position(self) -> [i64; 2] {
        [self.xy[0].into(), self.xy[1].into()]
    }
}

/// Vertices the vertex stage computes into local arrays before it copies them out.
const LANE_BLOCK: usize = 64;

/// What the vertex stage needs, copied out of the view so that it can fill the view's buffers.
pub(super) struct VertexStage {
    pub(super) view_projection: DMat4,
    /// The matrix's entries rounded to f32 once, column-major, for an f32 vertex stage.
    pub(super) view_projection_f32: [f32; 16],
    pub(super) planes: [DVec4; 5],
    pub(super) viewport: Viewport,
    pub(super) conventions: Conventions,
}

/// One chunk of the vertex stage: the positions (x, y and z apart), and the outputs for them.
type VertexChunk<'a> = (
    [&'a [f32]; 3],
    &'a mut [CentreCells],
    &'a mut [WindowVertex],
    &'a mut [f64],
);

impl VertexStage {
    /// Rules 1–4 for a chunk of vertices under conventions fixed at compile time (an f32 vertex
    /// stage, a lower-left window origin, a `[−1, 1]` depth range), so that the loop has no match
    /// per vertex; the arithmetic is [`VertexStage::clip`]'s and [`snap`]'s, expression for
    /// expression.
    ///
    /// The loop has no branch, so that the compiler runs it on several vertices at once (SIMD
    /// lanes): every vertex is projected and snapped, and what a clipped vertex gets (a
    /// position, a depth) is never read, as [`WindowVertex`] says. Rounding and the centre cells
    /// work in `i32`, which holds every coordinate inside the guard band, because baseline
    /// x86-64 converts f64 lanes to `i32` but not to `i64`.
    fn project<const F32_STAGE: bool, const LOWER_LEFT: bool, const MINUS_ONE_TO_ONE: bool>(
        &self,
        ([x, y, z], cells, window, window_z): VertexChunk<'_>,
    ) {
        // A block's results go to local arrays first: the compiler then knows that no store
        // can change what a later vertex reads, which it cannot prove of the outputs.
        let mut block_cells = [NO_CELLS; LANE_BLOCK];
        let mut block_xy = [[0; 2]; LANE_BLOCK];
        let mut block_outcode = [0; LANE_BLOCK];
        let mut block_z = [0.0; LANE_BLOCK];
        let mut start = 0;
        while start < cells.len() {
            let end = (start + LANE_BLOCK).min(cells.len());
            let lanes = end - start;
            let (x, y, z) = (&x[start..end], &y[start..end], &z[start..end]);
            for i in 0..lanes {
                let position = [x[i], y[i], z[i]];
                let clip = if F32_STAGE {
                    transform_f32(&self.view_projection_f32, position)
                } else {
                    transform(self.view_projection, position)
                };
                let outcode = self.outcode(clip);
                let (xy, depth) = snap_fixed::<F32_STAGE, LOWER_LEFT, MINUS_ONE_TO_ONE>(
                    self.viewport,
                    self.conventions.subpixel_bits,
                    clip,
                );
                let placed = outcode & u64::from(CLIP_BITS | NOT_IN_FRONT_BIT) == 0;
                block_cells[i] = if placed { centre_cells(xy) } else { NO_CELLS };
                block_xy[i] = xy;
                block_outcode[i] = outcode;
                block_z[i] = depth;
            }
            cells[start..end].copy_from_slice(&block_cells[..lanes]);
            let results = block_xy.iter().zip(block_outcode);
            for (vertex, (&xy, outcode)) in window[start..end].iter_mut().zip(results) {
                // Seven bits: lossless.
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "outcodes have seven bits (one per clip plane)"
                )]
                let outcode = outcode as u8;
                *vertex = WindowVertex { xy, outcode };
            }
            window_z[start..end].copy_from_slice(&block_z[..lanes]);
            start = end;
        }
    }

    /// Rule 1: model space to clip space in the conventions' precision.
    pub(super) fn clip(&self, position: [f32; 3]) -> DVec4 {
        match self.conventions.vertex_precision {
            VertexPrecision::F64 => transform(self.view_projection, position),
            VertexPrecision::F32 => transform_f32(&self.view_projection_f32, position),
        }
    }

    /// Rule 4: projects a clip-space vertex to the window and snaps x and y to the grid.
    pub(super) fn snap(&self, v: DVec4) -> Snapped {
        snap(self.viewport, self.conventions, v)
    }

    /// The outcode of [`View::planes`] and the far plane (the bits of [`WindowVertex::outcode`]),
    /// each plane written out rather than as a dot product with mostly zero coefficients: for
    /// finite coordinates (always: positions are finite f32 and the matrix finite f64) the zero
    /// terms add only signed zeros, so each sum is rounded exactly as the dot product's and every
    /// comparison decides the same. In 64 bits: on SIMD lanes of f64 a comparison gives a 64-bit
    /// mask, which narrowing comparison by comparison would cost several instructions each.
    #[inline]
    pub(super) fn outcode(&self, clip: DVec4) -> u64 {
        let [near, right, _, bottom, _] = self.planes;
        let (gx, gy) = (right.w, bottom.w);
        let DVec4 { x, y, z, w } = clip;
        let bit = |outside: bool, bit: u8| u64::from(outside) << bit.trailing_zeros();
        bit(z + near.w * w < 0.0, 1)
            | bit(x + gx * w < 0.0, 1 << 1)
            | bit(-x + gx * w < 0.0, 1 << 2)
            | bit(y + gy * w < 0.0, 1 << 3)
            | bit(-y + gy * w < 0.0, 1 << 4)
            | bit(-z + w < 0.0, FAR_BIT)
            | bit(!in_front(clip), NOT_IN_FRONT_BIT)
    }
}

/// Rule 1: model space to clip space, in f64: glam's `DMat4 * DVec4`, each row
/// `((m0·x + m1·y) + m2·z) + m3·1` left to right, written out (the product by 1 is exact).
#[inline]
pub(super) fn transform(view_projection: DMat4, [x, y, z]: [f32; 3]) -> DVec4 {
    let (x, y, z) = (f64::from(x), f64::from(y), f64::from(z));
    let [c0, c1, c2, c3] = view_projection.to_cols_array_2d();
    let row = |r: usize| c0[r] * x + c1[r] * y + c2[r] * z + c3[r];
    DVec4::new(row(0), row(1), row(2), row(3))
}

/// Rule 1 as a vertex shader computes `M * vec4(p, 1)` in f32, from the matrix's entries rounded
/// to f32 once (column-major: entry (row r, column c) at c * 4 + r): every row
/// `((m0·x + m1·y) + m2·z) + m3` with each product and sum rounded to f32 (no fused
/// multiply-add: Rust never contracts, and `docs/semantics.md` says what a GPU's FMA changes).
/// The result is exact in f64.
#[inline]
pub(super) fn transform_f32(m: &[f32; 16], [x, y, z]: [f32; 3]) -> DVec4 {
    let row = |r: usize| f64::from(m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r]);
    DVec4::new(row(0), row(1), row(2), row(3))
}

/// Whether a clip-space vertex has `w > 0` (false for NaN).
#[inline]
pub(super) fn in_front(clip: DVec4) -> bool {
    clip.w > 0.0
}

/// Rule 4: projects a clip-space vertex to the window (divide, viewport mapping and window
/// depth in the conventions' precision; a clipped f32 vertex is rounded to f32 first) and snaps x
/// and y to the conventions' grid, expressed in 1/256 pixel with y down whatever the origin.
pub(super) fn snap(viewport: Viewport, conventions: Conventions, v: DVec4) -> Snapped {
    let bits = conventions.subpixel_bits;
    let ([x, y], depth) = match (
        conventions.vertex_precision,
        conventions.window_origin,
        conventions.depth_range,
    ) {
        (F64, UpperLeft, ZeroToOne) => snap_fixed::<false, false, false>(viewport, bits, v),
        (F64, UpperLeft, MinusOneToOne) => snap_fixed::<false, false, true>(viewport, bits, v),
        (F64, LowerLeft, ZeroToOne) => snap_fixed::<false, true, false>(viewport, bits, v),
        (F64, LowerLeft, MinusOneToOne) => snap_fixed::<false, true, true>(viewport, bits, v),
        (F32, UpperLeft, ZeroToOne) => snap_fixed::<true, false, false>(viewport, bits, v),
        (F32, UpperLeft, MinusOneToOne) => snap_fixed::<true, false, true>(viewport, bits, v),
        (F32, LowerLeft, ZeroToOne) => snap_fixed::<true, true, false>(viewport, bits, v),
        (F32, LowerLeft, MinusOneToOne) => snap_fixed::<true, true, true>(viewport, bits, v),
    };
    ([x.into(), y.into()], depth)
}

/// [`snap`] under conventions fixed at compile time (see [`VertexStage::project`]), on the grid
/// of `bits` subpixel bits, in `i32`: exact for a vertex inside the guard band (|x|, |y| < 2^24
/// in 1/256 pixel), some value without overflow for any other, which no triangle reads.
#[inline]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the f32 stage narrows the position and the viewport's size to f32 as a GPU does"
)]
fn snap_fixed<const F32_STAGE: bool, const LOWER_LEFT: bool, const MINUS_ONE_TO_ONE: bool>(
    viewport: Viewport,
    bits: u32,
    v: DVec4,
) -> ([i32; 2], f64) {
    let size = [viewport.width, viewport.height];
    let ([x, y], depth) = if F32_STAGE {
        window::<f32, LOWER_LEFT, MINUS_ONE_TO_ONE>(
            v.to_array().map(|c| c as f32),
            size.map(|s| s as f32),
        )
    } else {
        window::<f64, LOWER_LEFT, MINUS_ONE_TO_ONE>([v.x, v.y, v.z, v.w], size.map(f64::from))
    };
    let grid = |value: f64| {
        // Round on the coarser grid, then express the grid point in 1/256 pixel (a multiple of
        // 2^(8 − bits)), so that the scan is the same for every grid.
        round_half_away(value * f64::from(1_u32 << bits)).wrapping_shl(SUBPIXEL_BITS - bits)
    };
    let y = if LOWER_LEFT {
        // Snapped in the API's own y-up window, then flipped into fragsim's rows: row r of the
        // window is fragsim's row height − 1 − r, and the flip is exact on the grid.
        ((viewport.height as i32) << SUBPIXEL_BITS).wrapping_sub(grid(y))
    } else {
        grid(y)
    };
    ([grid(x), y], depth)
}

/// The arithmetic the window mapping needs, for f64 and f32 alike.
trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    const HALF: Self;
    fn wide(self) -> f64;
}

impl Real for f64 {
    const HALF: Self = 0.5;
    fn wide(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const HALF: Self = 0.5;
    fn wide(self) -> f64 {
        f64::from(self)
    }
}

/// The perspective divide and the viewport mapping in `T`'s arithmetic: window x and y (y in the
/// API's own direction, down for an upper-left origin, up for a lower-left one) in pixels and
/// the window depth (of a `[0, 1]` or a `[−1, 1]` clip depth range). For f64 under the reference
/// conventions these are exactly fragsim's reference expressions.
#[inline]
fn window<T: Real, const LOWER_LEFT: bool, const MINUS_ONE_TO_ONE: bool>(
    [x, y, z, w]: [T; 4],
    [width, height]: [T; 2],
) -> ([f64; 2], f64) {
    let half = T::HALF;
    let window_x = (x / w * half + half) * width;
    let window_y = if LOWER_LEFT {
        (y / w * half + half) * height
    } else {
        (half - y / w * half) * height
    };
    let depth = if MINUS_ONE_TO_ONE {
        // glDepthRange(0, 1): `(f − n)/2 · z_ndc + (n + f)/2`.
        z / w * half + half
    } else {
        z / w
    };
    ([window_x.wide(), window_y.wide()], depth.wide())
}

/// The largest magnitude [`round_half_away`] rounds exactly: 2^30, far beyond the guard band's
/// 2^24 and leaving room for the rounding's step of one inside `i32`.
pub(super) const ROUNDING_BOUND: f64 = (1_u32 << 30) as f64;

/// `value.round() as i32` (half away from zero) for `|value| ≤` [`ROUNDING_BOUND`]; a value
/// beyond is first clamped to it, and NaN to its negative. No libm call, no conversion
/// instruction and no branch: baseline x86-64 has no rounding instruction, its conversions of
/// SIMD lanes of f64 to integers saturate only through scalar code, and the vertex stage's loop
/// must run on SIMD lanes.
///
/// Adding `1.5 · 2^52` to a number below 2^51 in magnitude rounds it to an integer, to nearest
/// with ties to even (IEEE addition), and leaves that integer in the low bits of the sum, two's
/// complement; the difference between the value and that integer is exact, and is ±½ exactly at
/// a tie, where rounding half away from zero differs from rounding to even by one when to even
/// went toward zero.
#[inline]
#[allow(
    clippy::manual_clamp,
    reason = "`f64::clamp` keeps NaN, which the sum below would carry into the integer's bits"
)]
pub(super) fn round_half_away(value: f64) -> i32 {
    const SHIFT: f64 = (3_u64 << 51) as f64;
    // `max` and `min` return the number when one side is NaN (`f64::clamp` keeps NaN).
    let value = value.max(-ROUNDING_BOUND).min(ROUNDING_BOUND);
    let shifted = value + SHIFT;
    let to_even = shifted - SHIFT;
    let tie = value - to_even;
    // The integer's low 32 bits, all it has (|value| ≤ 2^30).
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the integer's low 32 bits, all it has (|value| ≤ 2^30)"
    )]
    let rounded = shifted.to_bits() as i32;
    // At a tie, to even went toward zero where the value's sign and the tie's agree.
    rounded + i32::from(tie == 0.5 && value > 0.0) - i32::from(tie == -0.5 && value < 0.0)
}

/// How a vertex of a clipped polygon was made (rule 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClipOrigin {
    /// Corner `k` (0, 1 or 2) of the triangle, as the vertex stage transformed it.
    Corner(usize),
    /// Where the segment from point `inside` to point `outside` of the trace (indices into
    /// [`ClipTrace::points`]) crosses plane `plane` ([`View::clip_planes`]), computed from the
    /// inside end: `inside + (outside − inside) · t` with `t = d_in / (d_in − d_out)`.
    Crossing {
        /// The end inside the plane.
        inside: usize,
        /// The end outside it.
        outside: usize,
        /// The plane, by index.
        plane: usize,
    },
}

/// Sutherland–Hodgman on one triangle, every step recorded: the points made and how, and the
/// polygon left.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClipTrace {
    /// Every point made, in clip space, before the pipeline's clamp ([`Clipped::polygon`]).
    pub points: Vec<DVec4>,
    /// How each point was made.
    pub origins: Vec<ClipOrigin>,
    /// The polygon left, as indices into `points`, in order; fewer than 3: nothing is left.
    pub polygon: Vec<usize>,
}

impl ClipTrace {
    /// Clips `triangle` against `planes` in order (`p · v ≥ 0` inside), stopping when fewer than
    /// 3 vertices are left.
    fn of(triangle: [DVec4; 3], planes: &[DVec4]) -> Self {
        let mut trace = Self {
            points: triangle.to_vec(),
            origins: (0..3).map(ClipOrigin::Corner).collect(),
            polygon: vec![0, 1, 2],
        };
        for (index, &plane) in planes.iter().enumerate() {
            trace.polygon = trace.clip_against(index, plane);
            if trace.polygon.len() < 3 {
                break;
            }
        }
        trace
    }

    /// Sutherland–Hodgman against plane `index`, `plane · v ≥ 0`: the new polygon, the crossings
    /// added to the points.
    fn clip_against(&mut self, index: usize, plane: DVec4) -> Vec<usize> {
        let polygon = std::mem::take(&mut self.polygon);
        let mut out = Vec::with_capacity(polygon.len() + 1);
        for (i, &current) in polygon.iter().enumerate() {
            let next = polygon[(i + 1) % polygon.len()];
            let (dc, dn) = (
                plane.dot(self.points[current]),
                plane.dot(self.points[next]),
            );
            if dc >= 0.0 {
                out.push(current);
            }
            if (dc >= 0.0) != (dn >= 0.0) {
                // From the inside end toward the outside end, whichever way this polygon walks the
                // edge: two triangles sharing the edge then compute the very same f64 point, snap
                // it to the same grid point, and the shared clipped edge stays watertight.
                let (inside, d_in, outside, d_out) = if dc >= 0.0 {
                    (current, dc, next, dn)
                } else {
                    (next, dn, current, dc)
                };
                let (a, b) = (self.points[inside], self.points[outside]);
                let t = d_in / (d_in - d_out);
                out.push(self.points.len());
                self.points.push(a + (b - a) * t);
                self.origins.push(ClipOrigin::Crossing {
                    inside,
                    outside,
                    plane: index,
                });
            }
        }
        out
    }
}

/// A triangle as the pipeline clips it ([`View::clipped`]); its pieces are the fan
/// `(polygon[0], polygon[i], polygon[i + 1])` of those whose three vertices have `w > 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct Clipped {
    /// The clipping, step by step.
    pub trace: ClipTrace,
    /// The polygon's vertices as the pipeline uses them: `trace.polygon`'s points clamped to the
    /// guard band.
    pub polygon: Vec<DVec4>,
    /// Their snapped window positions (1/256 pixel, y down) and window depths.
    pub snapped: Vec<([i64; 2], f64)>,
}
