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
        let view = DMat4::look_at_rh(eye, centre, DVec3::Y);
        // The sphere lies between distance − radius and distance + radius; the margins keep
        // depths strictly inside (0, 1) and the near plane in front of the eye.
        let far = distance + radius * 1.01;
        let near = (distance - radius * 1.01).max(far * 1e-4);
        let projection = DMat4::perspective_rh(half_fov * 2.0, aspect, near, far);
        Camera {
            view_projection: projection * view,
        }
    }
}
