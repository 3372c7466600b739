//! Per-fragment attributes, computed only when an effect asks for them: depth-only runs (every
//! capture scheme) carry none, and the pipeline's [`Fragment`](crate::Fragment) stays three words.
//!
//! - [`vertex_normals`]: area-weighted vertex normals (the sum of the unnormalised face normals
//!   of the triangles around a vertex, whose lengths are twice their areas), normalised.
//! - [`Attributes`]: the deferred attribute pass of one view. Given a fragment's pixel and
//!   primitive id it recomputes the perspective-correct barycentrics of the pixel centre and
//!   interpolates what the effects need: the model-space position, the normal, and the cosine of
//!   the angle between the normal and the view ray (Schlick's Fresnel term).
//!
//! Perspective-correct barycentrics are computed in homogeneous space (Olano & Greer 1997): the
//! pixel centre's normalised device coordinates `(px, py)` lie on the triangle where
//! `Σ bᵢ (xᵢ − px wᵢ) = 0`, `Σ bᵢ (yᵢ − py wᵢ) = 0` and `Σ bᵢ = 1`, so `b` is the cross product
//! of `(xᵢ − px wᵢ)` and `(yᵢ − py wᵢ)`, normalised to sum 1. No division by a vertex's `w`
//! happens, so a triangle that crosses the near plane (and was clipped into pieces) interpolates
//! exactly as its unclipped plane does. Unlike a GPU, which interpolates from the snapped window
//! positions, the clip-space positions here are not snapped: attributes differ from a GPU's by
//! at most the snapping's 1/512 pixel, and depth (the only thing the schemes order by) is
//! untouched.

use glam::{DMat4, DVec3, DVec4};

use crate::mesh::Mesh;
use crate::pipeline::View;

/// Area-weighted vertex normals of `mesh`, unit length; a vertex that no triangle of non-zero
/// area uses gets `[0, 0, 0]`.
#[must_use]
pub fn vertex_normals(mesh: &Mesh) -> Vec<[f32; 3]> {
    let mut sums = vec![DVec3::ZERO; mesh.positions.len()];
    for tri in &mesh.triangles {
        let [a, b, c] = tri.map(|i| position(mesh, i));
        // |(b − a) × (c − a)| is twice the triangle's area: summing it weights by area.
        let face = (b - a).cross(c - a);
        for &i in tri {
            sums[i as usize] += face;
        }
    }
    sums.into_iter()
        .map(|n| n.normalize_or_zero().as_vec3().to_array())
        .collect()
}

fn position(mesh: &Mesh, index: u32) -> DVec3 {
    DVec3::from(mesh.positions[index as usize].map(f64::from))
}

/// The deferred attribute pass of one view: attributes of a fragment from its pixel and
/// primitive id.
#[derive(Clone, Debug)]
pub struct Attributes<'a> {
    mesh: &'a Mesh,
    normals: Vec<[f32; 3]>,
    view_projection: DMat4,
    eye: DVec3,
    width: f64,
    height: f64,
}

impl<'a> Attributes<'a> {
    /// The attribute pass of `view`, with area-weighted vertex normals ([`vertex_normals`]).
    #[must_use]
    pub fn new(view: &View<'a>) -> Self {
        Self::with_normals(view, vertex_normals(view.mesh()))
    }

    /// The attribute pass of `view` with the given per-vertex normals (one per position; they
    /// need not be unit length).
    ///
    /// # Panics
    /// If there is not one normal per vertex.
    #[must_use]
    pub fn with_normals(view: &View<'a>, normals: Vec<[f32; 3]>) -> Self {
        let mesh = view.mesh();
        assert_eq!(normals.len(), mesh.positions.len(), "one normal per vertex");
        let view_projection = view.view_projection();
        // The eye is the point the projection sends to w = 0 with x = y = 0: the image of the
        // clip-space direction (0, 0, 1, 0) under the inverse.
        let e = view_projection.inverse() * DVec4::new(0.0, 0.0, 1.0, 0.0);
        let viewport = view.viewport();
        Self {
            mesh,
            normals,
            view_projection,
            eye: e.truncate() / e.w,
            width: f64::from(viewport.width),
            height: f64::from(viewport.height),
        }
    }

    /// The eye position in model space.
    #[must_use]
    pub fn eye(&self) -> [f64; 3] {
        self.eye.to_array()
    }

    /// Perspective-correct barycentric weights of the centre of pixel `pixel` (row-major) on
    /// triangle `prim`, summing to 1; `None` for a triangle seen edge-on or an unknown `prim`.
    #[must_use]
    pub fn barycentrics(&self, prim: u32, pixel: u32) -> Option<[f64; 3]> {
        let tri = self.mesh.triangles.get(prim as usize)?;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the width is a viewport's (Viewport::new), at most Viewport::MAX_SIDE, held as f64 from a u32"
        )]
        let width = self.width as u32;
        let (x, y) = (pixel % width, pixel / width);
        // Window to normalised device coordinates: the inverse of the pipeline's rule 4.
        let px = (f64::from(x) + 0.5) / self.width * 2.0 - 1.0;
        let py = 1.0 - (f64::from(y) + 0.5) / self.height * 2.0;
        let clip = tri.map(|i| self.view_projection * position(self.mesh, i).extend(1.0));
        let u = DVec3::new(
            clip[0].x - px * clip[0].w,
            clip[1].x - px * clip[1].w,
            clip[2].x - px * clip[2].w,
        );
        let v = DVec3::new(
            clip[0].y - py * clip[0].w,
            clip[1].y - py * clip[1].w,
            clip[2].y - py * clip[2].w,
        );
        let b = u.cross(v);
        let sum = b.x + b.y + b.z;
        (sum != 0.0 && sum.is_finite()).then(|| (b / sum).to_array())
    }

    /// The model-space point of triangle `prim` seen at the centre of `pixel`.
    #[must_use]
    pub fn point(&self, prim: u32, pixel: u32) -> Option<[f64; 3]> {
        let b = self.barycentrics(prim, pixel)?;
        let tri = self.mesh.triangles[prim as usize];
        Some(interpolate(b, tri.map(|i| position(self.mesh, i))).to_array())
    }

    /// The interpolated unit normal of triangle `prim` at the centre of `pixel`; the face normal
    /// where the vertex normals cancel.
    #[must_use]
    pub fn normal(&self, prim: u32, pixel: u32) -> Option<[f64; 3]> {
        let b = self.barycentrics(prim, pixel)?;
        Some(self.normal_at(prim, b).to_array())
    }

    fn normal_at(&self, prim: u32, b: [f64; 3]) -> DVec3 {
        let tri = self.mesh.triangles[prim as usize];
        let n = interpolate(
            b,
            tri.map(|i| DVec3::from(self.normals[i as usize].map(f64::from))),
        );
        n.try_normalize().unwrap_or_else(|| {
            let [p0, p1, p2] = tri.map(|i| position(self.mesh, i));
            (p1 - p0).cross(p2 - p0).normalize_or_zero()
        })
    }

    /// `|cos θ|` between the interpolated normal of triangle `prim` at the centre of `pixel` and
    /// the ray from that point to the eye (both sides of a surface alike, as the papers'
    /// `abs(dot(I, N))`); `None` as for [`Attributes::barycentrics`].
    #[must_use]
    pub fn cosine(&self, prim: u32, pixel: u32) -> Option<f64> {
        let b = self.barycentrics(prim, pixel)?;
        let tri = self.mesh.triangles[prim as usize];
        let point = interpolate(b, tri.map(|i| position(self.mesh, i)));
        let ray = (self.eye - point).normalize_or_zero();
        Some(self.normal_at(prim, b).dot(ray).abs().min(1.0))
    }
}

fn interpolate(b: [f64; 3], values: [DVec3; 3]) -> DVec3 {
    values[0] * b[0] + values[1] * b[1] + values[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OrbitCamera, Scene, Viewport};

    #[test]
    fn a_flat_square_has_the_axis_as_every_normal() {
        let mesh = crate::scenes::stacked_quads(1);
        for n in vertex_normals(&mesh) {
            assert_eq!(n, [0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn area_weighting_favours_the_larger_face() {
        // Two faces meet at vertex 0: a large one in z = 0 and a small one in x = 0.
        let mesh = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [10.0, 0.0, 0.0],
                [0.0, 10.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [0, 3, 4]],
        };
        let n = vertex_normals(&mesh)[0];
        // Areas 50 and 0.5: the normal is (−0.5, 0, 50) normalised.
        let expected = DVec3::new(-0.5, 0.0, 50.0).normalize();
        assert!(
            (DVec3::from(n.map(f64::from)) - expected).length() < 1e-6,
            "{n:?}"
        );
    }

    #[test]
    fn barycentrics_reproduce_the_rasterized_depth() {
        // The interpolated point, projected, has the depth the rasterizer gave the fragment.
        let scene = Scene::procedural("spheres:2").unwrap();
        let view = scene
            .view(Viewport::new(48, 40).unwrap(), &OrbitCamera::default())
            .unwrap();
        let attributes = Attributes::new(&view);
        let (mut checked, mut close) = (0, 0);
        for prim in (0..view.triangle_count()).step_by(7) {
            view.rasterize(prim, &mut |f| {
                let p = attributes.point(f.prim, f.pixel).unwrap();
                let clip = view.view_projection() * DVec3::from(p).extend(1.0);
                let error = (clip.z / clip.w - f64::from(f.depth())).abs();
                // The rasterizer interpolates from snapped positions (1/256 pixel): on triangles
                // seen nearly edge-on the depth changes fast enough across that to show.
                assert!(error < 1e-3, "{error} at pixel {}", f.pixel);
                close += usize::from(error < 2e-4);
                let b = attributes.barycentrics(f.prim, f.pixel).unwrap();
                assert!(b.iter().all(|&w| w > -1e-2), "{b:?}");
                checked += 1;
            });
        }
        assert!(checked > 50);
        assert!(close * 10 > checked * 9, "{close} of {checked} within 2e-4");
    }
}
