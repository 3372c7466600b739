//! The `obj_load` target: any bytes given to the OBJ loader give a mesh that passes validation or
//! an error naming the file, never a panic; a small loaded mesh also renders without panic, every
//! fragment inside the viewport with a depth in `[0, 1]`.

use fragsim::raster::{Mesh, OrbitCamera, Scene, Viewport};

use super::raster::check_fragments;

/// The name errors must mention.
const NAME: &str = "fuzz.obj";

/// Meshes up to this many triangles are also rendered (larger ones cost too much per input).
const RENDER_LIMIT: usize = 64;

/// Loads `data` as OBJ text and checks the outcome.
pub(crate) fn check(data: &[u8]) {
    let mesh = match Mesh::read_obj(&mut &data[..], NAME) {
        Ok(mesh) => mesh,
        Err(error) => {
            let message = error.to_string();
            assert!(
                message.contains(NAME),
                "error does not name the file: {message}"
            );
            return;
        }
    };
    assert!(!mesh.triangles.is_empty(), "a loaded mesh has triangles");
    if let Err(error) = mesh.validate(NAME) {
        panic!("read_obj returned a mesh that fails validation: {error}");
    }
    if mesh.triangles.len() > RENDER_LIMIT {
        return;
    }
    let scene = Scene {
        name: NAME.into(),
        mesh,
    };
    let viewport = Viewport::new(8, 8).expect("8 × 8 is a valid viewport");
    let view = scene
        .view(viewport, &OrbitCamera::default())
        .expect("a mesh with triangles has a view");
    for prim in 0..view.triangle_count() {
        check_fragments(&view, prim);
    }
}
