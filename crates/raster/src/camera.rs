//! The camera: a view-projection matrix, an engine's own or one the orbit camera (one angle
//! sweeps the view around a model) derives from the model's bounds.

use glam::{DMat4, DVec3};

use crate::conventions::DepthRange;

/// A view-projection matrix in f64: model space to clip space, for the clip-space depth range
/// the view's conventions declare (`[0, 1]` unless they say otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Model space to clip space.
    pub view_projection: DMat4,
}

impl Camera {
    /// The camera of a matrix given row by row (`m[row * 4 + column]`, `clip = M · (x, y, z, 1)`),
    /// as an engine's uniform is written down: the bits of every entry are kept.
    #[must_use]
    pub fn from_row_major(m: [f64; 16]) -> Self {
        // glam stores columns: the row-major array read as columns is the transpose.
        Self {
            view_projection: DMat4::from_cols_array(&m).transpose(),
        }
    }

    /// The matrix row by row, the inverse of [`Camera::from_row_major`].
    #[must_use]
    pub fn row_major(&self) -> [f64; 16] {
        self.view_projection.transpose().to_cols_array()
    }
}

/// An eye on a circle around the model's bounding sphere, looking at its centre.
///
/// The eye sits at `angle_degrees` around the vertical (y) axis, raised by `elevation_degrees`,
/// far enough that the bounding sphere fits the vertical field of view. Near and far planes hug
/// the sphere, so every fragment of the model has a depth in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Angle around the vertical axis, in degrees; 0 looks along −z.
    pub angle_degrees: f64,
    /// Angle above the horizontal plane, in degrees.
    pub elevation_degrees: f64,
    /// Vertical field of view, in degrees.
    pub fov_y_degrees: f64,
    /// Eye distance as a multiple of the distance at which the sphere just fits (≥ 1 sees all).
    pub distance_scale: f64,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            angle_degrees: 0.0,
            elevation_degrees: 15.0,
            fov_y_degrees: 40.0,
            distance_scale: 1.1,
        }
    }
}

impl OrbitCamera {
    /// This orbit at another angle.
    #[must_use]
    pub fn at_angle(self, angle_degrees: f64) -> Self {
        Self {
            angle_degrees,
            ..self
        }
    }

    /// The camera for a model with the given bounds and a viewport aspect ratio (width / height).
    #[must_use]
    pub fn camera(&self, bounds: ([f64; 3], [f64; 3]), aspect: f64) -> Camera {
        self.camera_for(bounds, aspect, DepthRange::ZeroToOne)
    }

    /// [`OrbitCamera::camera`] with the projection an engine of `depth_range` builds: D3D's
    /// `perspective_rh` for `[0, 1]`, OpenGL's `perspective_rh_gl` (`gluPerspective`) for
    /// `[−1, 1]`. Both map the same eye-space point to the same window depth in exact arithmetic.
    #[must_use]
    pub fn camera_for(
        &self,
        bounds: ([f64; 3], [f64; 3]),
        aspect: f64,
        depth_range: DepthRange,
    ) -> Camera {
        let frame = self.frame(bounds, aspect);
        let projection = match depth_range {
            DepthRange::ZeroToOne => {
                DMat4::perspective_rh(frame.fov_y, aspect, frame.near, frame.far)
            }
            DepthRange::MinusOneToOne => {
                DMat4::perspective_rh_gl(frame.fov_y, aspect, frame.near, frame.far)
            }
        };
        Camera {
            view_projection: projection * frame.view,
        }
    }

    /// The eye-space distance of a window depth `z ∈ [0, 1]` under [`OrbitCamera::camera`]:
    /// the inverse of the D3D perspective depth mapping, `near · far / (far − z (far − near))`.
    #[must_use]
    pub fn eye_distance(&self, bounds: ([f64; 3], [f64; 3]), aspect: f64, z: f32) -> f64 {
        let Frame { near, far, .. } = self.frame(bounds, aspect);
        near * far / (far - f64::from(z) * (far - near))
    }

    fn frame(&self, bounds: ([f64; 3], [f64; 3]), aspect: f64) -> Frame {
        let (lo, hi) = bounds;
        let lo = DVec3::from(lo);
        let hi = DVec3::from(hi);
        let centre = (lo + hi) * 0.5;
        let radius = ((hi - lo).length() * 0.5).max(1e-6);
        let half_fov = (self.fov_y_degrees.to_radians() * 0.5).clamp(1e-3, 1.5);
        let fit = radius / half_fov.sin().min((half_fov.tan() * aspect).atan().sin());
        let distance = fit * self.distance_scale.max(1e-3);
        // At ±90° the up vector would be parallel to the view direction.
        let pitch = self.elevation_degrees.clamp(-89.0, 89.0).to_radians();
        let yaw = self.angle_degrees.to_radians();
        let direction = DVec3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            yaw.cos() * pitch.cos(),
        );
        let eye = centre + direction * distance;
        // The sphere lies between distance − radius and distance + radius; the margins keep
        // depths strictly inside (0, 1) and the near plane in front of the eye.
        let far = distance + radius * 1.01;
        let near = (distance - radius * 1.01).max(far * 1e-4);
        Frame {
            view: DMat4::look_at_rh(eye, centre, DVec3::Y),
            near,
            far,
            fov_y: half_fov * 2.0,
        }
    }
}

/// What the orbit derives from the model's bounds.
struct Frame {
    view: DMat4,
    near: f64,
    far: f64,
    fov_y: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec4;

    #[test]
    fn a_row_major_matrix_keeps_its_rows_and_bits() {
        let m: [f64; 16] = std::array::from_fn(|i| 0.1 * i as f64 - 0.7);
        let camera = Camera::from_row_major(m);
        // Row 1 times (x, y, z, 1) is clip y.
        let clip = camera.view_projection * DVec4::new(2.0, 3.0, 5.0, 1.0);
        assert_eq!(clip.y, m[4] * 2.0 + m[5] * 3.0 + m[6] * 5.0 + m[7]);
        assert_eq!(camera.row_major().map(f64::to_bits), m.map(f64::to_bits));
    }

    #[test]
    fn the_gl_orbit_gives_the_same_window_depth() {
        let bounds = ([-1.0, -2.0, -0.5], [1.0, 2.0, 0.5]);
        let orbit = OrbitCamera::default().at_angle(25.0);
        let d3d = orbit.camera_for(bounds, 1.0, DepthRange::ZeroToOne);
        let gl = orbit.camera_for(bounds, 1.0, DepthRange::MinusOneToOne);
        assert_ne!(d3d, gl);
        for p in [[0.0, 0.0, 0.0], [0.9, 1.9, 0.4]] {
            let v = DVec4::new(p[0], p[1], p[2], 1.0);
            let (a, b) = (d3d.view_projection * v, gl.view_projection * v);
            assert!((a.z / a.w - (b.z / b.w * 0.5 + 0.5)).abs() < 1e-12);
        }
    }

    #[test]
    fn eye_distance_inverts_the_projection() {
        let bounds = ([-1.0, -2.0, -0.5], [1.0, 2.0, 0.5]);
        let orbit = OrbitCamera::default().at_angle(40.0);
        let camera = orbit.camera(bounds, 1.5);
        for p in [[0.0, 0.0, 0.0], [0.9, 1.9, 0.4], [-1.0, -2.0, -0.5]] {
            let clip = camera.view_projection * DVec4::new(p[0], p[1], p[2], 1.0);
            #[expect(
                clippy::cast_possible_truncation,
                reason = "an f32 depth, as a GPU's pipeline hands it to eye_distance"
            )]
            let z = (clip.z / clip.w) as f32;
            // w is the distance along the view axis: what the inverse mapping must give back.
            let d = orbit.eye_distance(bounds, 1.5, z);
            assert!((d - clip.w).abs() < 1e-5 * clip.w, "{d} vs {}", clip.w);
        }
    }
}
