//! A [`Camera`] from an arbitrary 4 × 4 matrix, without naming glam (the root package does not
//! depend on it): the public fields of the orbit camera's matrix are overwritten.

use fragsim::raster::{Camera, OrbitCamera};

/// The camera whose view-projection matrix has these columns (`columns[c][r]` is row `r` of
/// column `c`, as glam stores it).
pub(crate) fn camera_from_columns(columns: [[f64; 4]; 4]) -> Camera {
    let mut camera = OrbitCamera::default().camera(([0.0; 3], [1.0; 3]), 1.0);
    let m = &mut camera.view_projection;
    for (axis, column) in [&mut m.x_axis, &mut m.y_axis, &mut m.z_axis, &mut m.w_axis]
        .into_iter()
        .zip(columns)
    {
        axis.x = column[0];
        axis.y = column[1];
        axis.z = column[2];
        axis.w = column[3];
    }
    camera
}

/// Clip space = model space: x and y in `[-1, 1]` span the viewport, z is the depth, w = 1.
pub(crate) fn identity_camera() -> Camera {
    camera_from_columns([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ])
}
