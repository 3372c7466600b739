//! The scene a dump or a triangle export names: the mesh (a named scene, or a file with the hash
//! of its bytes), the camera (fragsim's orbit, or the engine's own view-projection matrix) and the
//! conventions it was rasterized under: enough to rebuild the engine's view and its oracle
//! ([`SceneAndCamera::load`], then [`SceneAndCamera::view`]).
//!
//! The mesh hash is FNV-1a 64 of the file's bytes ([`mesh_hash`]), written `fnv1a64:` and 16 hex
//! digits. It guards against a different file under the same name (a re-export, another
//! decimation, a dump that travelled), not against an adversary: for that a 64-bit
//! non-cryptographic hash is enough (two different files collide with probability about 2^−64),
//! it needs no dependency, and any backend computes it in a few lines (`docs/dump-format.md`).

use std::path::{Path, PathBuf};

use fragsim_raster::{Camera, Conventions, OrbitCamera, Scene, VertexPrecision, View, Viewport};
use serde::{Deserialize, Serialize};

use crate::dump::{err, io_err, DumpError};

/// An engine's own view-projection matrix, as its vertex shader used it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewProjection {
    /// Model space to clip space, row by row: `clip = M · (x, y, z, 1)` with `M[r][c]` at
    /// `r * 4 + c` (a column-major GLSL `mat4` is written transposed).
    pub row_major: [f64; 16],
    /// The precision of the engine's values: `f32` (a GPU uniform: each entry is rounded to the
    /// nearest f32, so the shortest decimal of an f32 names it exactly) or `f64` (used as given).
    pub precision: VertexPrecision,
}

/// The algorithm prefix of [`mesh_hash`].
pub const MESH_HASH_PREFIX: &str = "fnv1a64:";

/// The content hash of a mesh file's bytes: FNV-1a 64 (offset basis `0xcbf29ce484222325`,
/// prime `0x100000001b3`), as `fnv1a64:` and 16 lower-case hex digits.
#[must_use]
pub fn mesh_hash(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(0x100_0000_01b3)
    });
    format!("{MESH_HASH_PREFIX}{hash:016x}")
}

/// The scene and camera that produced a dump: enough to rebuild the view and its oracle.
///
/// Its numbers are exact across the file: serde_json is built with `float_roundtrip`, so a
/// decimal parses to the nearest f64, and writes the shortest decimal that parses back to the same
/// bits (ryu), so encode then parse gives every finite value back bit for bit. JSON has no NaN or
/// infinity: [`SceneAndCamera::check_finite`] refuses them before a header is written (serde_json would
/// write `null`), and a decimal past the f64 range is a parse error.
///
/// An unknown field is refused by name (a misspelt `fov_y_degres` would otherwise judge the dump
/// under the default field of view).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneAndCamera {
    /// A named scene (`Scene::procedural`: `bunny`, `spheres:8`, …); absent when `mesh` is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A mesh file (OBJ or PLY), as given to `--mesh`; a relative path is looked up from the working
    /// directory, then from the dump's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Orbit angle around the model, degrees (`--view`); may be left out (0) with a
    /// `view_projection`.
    #[serde(default)]
    pub view_degrees: f64,
    /// Elevation above the model's equator, degrees (`--elevation`); may be left out (0) with a
    /// `view_projection`.
    #[serde(default)]
    pub elevation_degrees: f64,
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov_y_degrees: f64,
    /// Eye distance as a multiple of the distance at which the bounding sphere fits.
    #[serde(default = "default_distance")]
    pub distance_scale: f64,
    // The engine's scene: one block, so that the layout fields of the header stay apart.
    /// The content hash of the mesh file ([`mesh_hash`]); a file whose bytes hash otherwise is
    /// refused. Absent: not checked (dumps written before hashes existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh_hash: Option<String>,
    /// The engine's view-projection matrix; when present it replaces the orbit (whose fields are
    /// then ignored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_projection: Option<ViewProjection>,
    /// The conventions the scene was rasterized under; absent: [`Conventions::REFERENCE`], so
    /// every dump written before conventions existed reads as before.
    #[serde(default, skip_serializing_if = "Conventions::is_reference")]
    pub conventions: Conventions,
}

fn default_fov() -> f64 {
    OrbitCamera::default().fov_y_degrees
}

fn default_distance() -> f64 {
    OrbitCamera::default().distance_scale
}

impl SceneAndCamera {
    /// A named scene seen from the default orbit at `view_degrees` and `elevation_degrees`.
    #[must_use]
    pub fn named(name: &str, view_degrees: f64, elevation_degrees: f64) -> Self {
        Self {
            name: Some(name.into()),
            mesh: None,
            view_degrees,
            elevation_degrees,
            fov_y_degrees: default_fov(),
            distance_scale: default_distance(),
            mesh_hash: None,
            view_projection: None,
            conventions: Conventions::REFERENCE,
        }
    }

    /// A mesh file seen from the default orbit, with the hash of the file's bytes
    /// ([`SceneAndCamera::mesh`] plus [`SceneAndCamera::mesh_hash`]).
    ///
    /// # Errors
    /// The file cannot be read.
    pub fn hashed_mesh(
        path: &Path,
        view_degrees: f64,
        elevation_degrees: f64,
    ) -> Result<Self, DumpError> {
        let bytes = std::fs::read(path).map_err(|e| io_err("read mesh", path, e))?;
        Ok(Self {
            mesh_hash: Some(mesh_hash(&bytes)),
            ..Self::mesh(path, view_degrees, elevation_degrees)
        })
    }

    /// A mesh file seen from the default orbit at `view_degrees` and `elevation_degrees`.
    #[must_use]
    pub fn mesh(path: &Path, view_degrees: f64, elevation_degrees: f64) -> Self {
        Self {
            mesh: Some(path.display().to_string()),
            name: None,
            ..Self::named("", view_degrees, elevation_degrees)
        }
    }

    /// The orbit camera.
    #[must_use]
    pub fn orbit(&self) -> OrbitCamera {
        OrbitCamera {
            angle_degrees: self.view_degrees,
            elevation_degrees: self.elevation_degrees,
            fov_y_degrees: self.fov_y_degrees,
            distance_scale: self.distance_scale,
        }
    }

    /// Loads the scene; a relative mesh path missing from the working directory is looked up in
    /// `beside` (the dump's directory). A mesh whose bytes do not hash to
    /// [`SceneAndCamera::mesh_hash`] is refused.
    ///
    /// # Errors
    /// Neither a name nor a mesh, a mesh file in neither place (both named), a file of another
    /// hash, or a scene that cannot be loaded.
    pub fn load(&self, beside: Option<&Path>) -> Result<Scene, DumpError> {
        let scene = match (&self.mesh, &self.name) {
            (Some(mesh), _) => {
                let path = find_mesh(mesh, beside)?;
                if let Some(expected) = &self.mesh_hash {
                    let bytes = std::fs::read(&path).map_err(|e| io_err("read mesh", &path, e))?;
                    let found = mesh_hash(&bytes);
                    if found != *expected {
                        return err(format!(
                            "mesh {}: its bytes hash to {found}, the scene names {expected}: \
                             a different file (pass --mesh PATH to name the one it was made of)",
                            path.display()
                        ));
                    }
                }
                Scene::from_file(&path)
            }
            (None, Some(name)) => Scene::procedural(name),
            (None, None) => return err("the scene names neither a mesh nor a named scene"),
        };
        scene.map_err(|e| DumpError::Invalid(format!("scene: {e}")))
    }

    /// The camera on `viewport`: the engine's matrix, or the orbit's for `scene` (with the
    /// projection of the conventions' depth range, [`OrbitCamera::camera_for`]).
    ///
    /// # Errors
    /// A matrix declared f32 with an entry beyond f32's range.
    pub fn camera(&self, scene: &Scene, viewport: Viewport) -> Result<Camera, DumpError> {
        match &self.view_projection {
            Some(matrix) => Ok(Camera::from_row_major(engine_matrix(matrix)?)),
            None => Ok(scene.orbit_camera(viewport, &self.orbit(), self.conventions.depth_range)),
        }
    }

    /// The view this scene names: `scene` (from [`SceneAndCamera::load`]) through
    /// [`SceneAndCamera::camera`] on `viewport`, rasterized under the conventions.
    ///
    /// # Errors
    /// A bad matrix, conventions fragsim cannot rasterize under, a scene without triangles.
    pub fn view<'s>(&self, scene: &'s Scene, viewport: Viewport) -> Result<View<'s>, DumpError> {
        let camera = self.camera(scene, viewport)?;
        scene
            .view_under(viewport, &camera, self.conventions)
            .map_err(|e| DumpError::Invalid(format!("scene: {e}")))
    }

    /// Refuses a NaN or infinite number, which JSON cannot hold (serde_json would silently write
    /// `null`, which then fails to parse as a number far from its cause), and an f32 matrix entry
    /// beyond f32's range.
    ///
    /// # Errors
    /// The first field that is not finite, by name (`view_projection.row_major[i]` for a matrix
    /// entry).
    pub fn check_finite(&self) -> Result<(), DumpError> {
        let orbit = [
            ("view_degrees", self.view_degrees),
            ("elevation_degrees", self.elevation_degrees),
            ("fov_y_degrees", self.fov_y_degrees),
            ("distance_scale", self.distance_scale),
        ]
        .map(|(field, value)| (field.to_string(), value));
        let matrix = self.view_projection.iter().flat_map(|m| {
            (0..16).map(|i| (format!("view_projection.row_major[{i}]"), m.row_major[i]))
        });
        for (field, value) in orbit.into_iter().chain(matrix) {
            if !value.is_finite() {
                return err(format!(
                    "scene {field} is {value}: numbers in a header must be finite (JSON has no NaN or infinity)"
                ));
            }
        }
        if let Some(matrix) = &self.view_projection {
            engine_matrix(matrix)?;
        }
        Ok(())
    }

    /// A short description for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        let scene = self.mesh.as_deref().or(self.name.as_deref()).unwrap_or("?");
        let camera = match &self.view_projection {
            Some(_) => "the engine's view-projection matrix".to_string(),
            None => format!(
                "view {}°, elevation {}°",
                self.view_degrees, self.elevation_degrees
            ),
        };
        if self.conventions.is_reference() {
            format!("{scene}, {camera}")
        } else {
            format!("{scene}, {camera}, conventions {:?}", self.conventions)
        }
    }
}

/// The file a dump's relative mesh path names: in the working directory, else beside the dump.
fn find_mesh(mesh: &str, beside: Option<&Path>) -> Result<PathBuf, DumpError> {
    let path = PathBuf::from(mesh);
    if path.exists() || path.is_absolute() {
        return Ok(path);
    }
    match beside {
        Some(dir) if dir.join(&path).exists() => Ok(dir.join(&path)),
        Some(dir) => err(format!(
            "mesh {mesh}: no such file in the working directory ({}) nor beside the dump ({}); \
             pass --mesh PATH to name it",
            std::env::current_dir().map_or_else(|_| "?".into(), |d| d.display().to_string()),
            dir.join(&path).display()
        )),
        // Not found: loading names the path.
        None => Ok(path),
    }
}

/// The matrix the engine's vertex shader held: an f32 matrix's entries each rounded to the nearest
/// f32 (exact for the shortest f32 decimal an engine prints, or any with 9 significant digits).
///
/// # Errors
/// An f32 matrix with an entry beyond f32's range, by index.
fn engine_matrix(matrix: &ViewProjection) -> Result<[f64; 16], DumpError> {
    let mut entries = matrix.row_major;
    if matrix.precision == VertexPrecision::F32 {
        for (i, value) in entries.iter_mut().enumerate() {
            let single = *value as f32;
            if !single.is_finite() {
                return err(format!(
                    "scene view_projection.row_major[{i}] is {value}, beyond f32's range, \
                     but the matrix's precision is f32"
                ));
            }
            *value = f64::from(single);
        }
    }
    Ok(entries)
}
