//! Viewports and orbit cameras.

use std::ops::{Range, RangeInclusive};

use fragsim_raster::{Camera, OrbitCamera, Viewport};
use proptest::prelude::*;
use proptest::sample::select;

// Viewports

/// A viewport with each side drawn independently from `8..=64` (square and non-square).
pub fn viewport() -> impl Strategy<Value = Viewport> {
    viewport_with_sides(8..=64)
}

/// A viewport with each side drawn independently from `sides`.
///
/// # Panics
/// (When sampled) if `sides` contains 0 or a side above [`Viewport::MAX_SIDE`].
pub fn viewport_with_sides(sides: RangeInclusive<u32>) -> impl Strategy<Value = Viewport> {
    (sides.clone(), sides).prop_map(|(w, h)| Viewport::new(w, h).expect("valid viewport side"))
}

// ---------------------------------------------------------------------------------------------
// Cameras
// ---------------------------------------------------------------------------------------------

/// An orbit angle in degrees: uniform in `[0, 360)`, or one of the axis-aligned and diagonal
/// angles, which look straight at the faces of `quads` and cubes (edges through pixel centres,
/// equal depths across a face).
fn orbit_angle() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => 0.0_f64..360.0,
        1 => select(vec![0.0, 45.0, 90.0, 180.0, 270.0, 315.0]),
    ]
}

/// An elevation in degrees: uniform in `[-89, 89]`, level, or the poles (clamped to ±89° by the
/// camera).
fn orbit_elevation() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -89.0_f64..=89.0,
        1 => select(vec![0.0, 90.0, -90.0]),
    ]
}

/// A random orbit camera: any angle and elevation, a vertical field of view of 5° to 150°, and a
/// distance scale in `[0.2, 3)`. A third of the cameras have a scale below 1: the eye is close to
/// or inside the model's bounding sphere, so the near plane clips triangles.
pub fn orbit_camera() -> impl Strategy<Value = OrbitCamera> {
    prop_oneof![
        2 => orbit_camera_with_distance(1.0..3.0),
        1 => orbit_camera_with_distance(0.2..1.0),
    ]
}

/// A random orbit camera that sees the whole model from outside: distance scale in
/// `[1.05, 3)`, so no triangle is near-clipped and every fragment has a depth strictly inside
/// `(0, 1)`.
pub fn orbit_camera_outside() -> impl Strategy<Value = OrbitCamera> {
    orbit_camera_with_distance(1.05..3.0)
}

/// A random orbit camera with `distance_scale` drawn from `distance`.
pub fn orbit_camera_with_distance(distance: Range<f64>) -> impl Strategy<Value = OrbitCamera> {
    (orbit_angle(), orbit_elevation(), 5.0_f64..150.0, distance).prop_map(
        |(angle_degrees, elevation_degrees, fov_y_degrees, distance_scale)| OrbitCamera {
            angle_degrees,
            elevation_degrees,
            fov_y_degrees,
            distance_scale,
        },
    )
}

/// The identity camera: model x and y in `[-1, 1]` map straight onto the viewport (y up in the
/// model, down in the window), model z is the depth. Used with
/// `View::new(&mesh, &identity_camera(), viewport, CullMode::None)`.
pub fn identity_camera() -> Camera {
    // `DMat4::default()` is the identity; going through `Default` spares the tests a direct
    // dependency on glam.
    Camera {
        view_projection: Default::default(),
    }
}
