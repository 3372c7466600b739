//! Rules 1 to 4: the vertex stage (transform in f64, outcodes), homogeneous clipping against the
//! near plane and the guard band, and snapping to the fixed-point grid.

use glam::{DMat4, DVec4};
use rayon::prelude::*;

use super::{
    Snapped, View, Viewport, CLIP_BITS, FAR_BIT, NOT_IN_FRONT_BIT, ONE, VERTICES_PER_TASK,
};
use crate::camera::Camera;

impl View<'_> {
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

    /// Clips a triangle in homogeneous space against the near plane and the guard band (rule 3);
    /// fewer than 3 vertices when nothing is left.
    pub(super) fn clip(&self, triangle: [DVec4; 3]) -> Vec<DVec4> {
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
    pub(super) fn planes(&self) -> [DVec4; 5] {
        let [gx, gy] = self.guard;
        [
            DVec4::new(0.0, 0.0, 1.0, 0.0),
            DVec4::new(1.0, 0.0, 0.0, gx),
            DVec4::new(-1.0, 0.0, 0.0, gx),
            DVec4::new(0.0, 1.0, 0.0, gy),
            DVec4::new(0.0, -1.0, 0.0, gy),
        ]
    }
}

/// What the vertex stage needs, copied out of the view so that it can fill the view's buffers.
pub(super) struct VertexStage {
    pub(super) view_projection: DMat4,
    pub(super) planes: [DVec4; 5],
}

impl VertexStage {
    pub(super) fn clip(&self, position: [f32; 3]) -> DVec4 {
        transform(self.view_projection, position)
    }

    /// The outcode of [`View::planes`] and the far plane, each plane written out rather than as a
    /// dot product with mostly zero coefficients: for finite coordinates (always: positions are
    /// finite f32 and the matrix finite f64) the zero terms add only signed zeros, so each sum is
    /// rounded exactly as the dot product's and every comparison decides the same.
    pub(super) fn outcode(&self, clip: DVec4) -> u8 {
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
pub(super) fn transform(view_projection: DMat4, p: [f32; 3]) -> DVec4 {
    view_projection * DVec4::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0)
}

/// Whether a clip-space vertex has `w > 0` (false for NaN).
pub(super) fn in_front(clip: DVec4) -> bool {
    clip.w > 0.0
}

/// Rule 4: projects a clip-space vertex to the window and snaps x and y to the fixed-point grid.
pub(super) fn snap(viewport: Viewport, v: DVec4) -> Snapped {
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
pub(super) fn round_half_away(value: f64) -> i64 {
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
