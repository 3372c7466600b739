//! The orbit camera: one angle sweeps the view around a model.

use glam::{DMat4, DVec3};

/// A view-projection matrix in f64 with D3D/Vulkan clip conventions (depth in `[0, 1]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Model space to clip space.
    pub view_projection: DMat4,
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
        let frame = self.frame(bounds, aspect);
        let projection = DMat4::perspective_rh(frame.fov_y, aspect, frame.near, frame.far);
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
    fn eye_distance_inverts_the_projection() {
        let bounds = ([-1.0, -2.0, -0.5], [1.0, 2.0, 0.5]);
        let orbit = OrbitCamera::default().at_angle(40.0);
        let camera = orbit.camera(bounds, 1.5);
        for p in [[0.0, 0.0, 0.0], [0.9, 1.9, 0.4], [-1.0, -2.0, -0.5]] {
            let clip = camera.view_projection * DVec4::new(p[0], p[1], p[2], 1.0);
            let z = (clip.z / clip.w) as f32;
            // w is the distance along the view axis: what the inverse mapping must give back.
            let d = orbit.eye_distance(bounds, 1.5, z);
            assert!((d - clip.w).abs() < 1e-5 * clip.w, "{d} vs {}", clip.w);
        }
    }
}
