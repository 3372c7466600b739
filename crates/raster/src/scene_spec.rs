//! The scene spec: what a command line names and a dump or a triangle export records — the mesh
//! (a named scene, or a file with the hash of its bytes), the camera (fragsim's orbit around the
//! model's up axis, or the engine's own view-projection matrix) and the conventions it is
//! rasterized under: enough to rebuild the view and its oracle ([`SceneSpec::load`], then
//! [`SceneSpec::view`] on a viewport). Every command reads its scene through it: the command
//! line's options (`args::SceneArgs`, with the `args` feature) and a dump header's `scene`
//! object (its JSON, `docs/dump-format.md`) give the same value.
//!
//! The mesh hash is FNV-1a 64 of the file's bytes ([`mesh_hash`]), written `fnv1a64:` and 16 hex
//! digits. It guards against a different file under the same name (a re-export, another
//! decimation, a dump that travelled), not against an adversary: for that a 64-bit
//! non-cryptographic hash is enough (two different files collide with probability about 2^−64),
//! it needs no dependency, and any backend computes it in a few lines (`docs/dump-format.md`).

#[cfg(feature = "args")]
pub mod args;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::files::read_regular;
use crate::{
    Camera, Conventions, OrbitCamera, Scene, SceneError, UpAxis, VertexPrecision, View, Viewport,
    MESH_BYTES_LIMIT,
};

/// Why a scene spec names no scene fragsim can load or view.
#[derive(Debug, thiserror::Error)]
pub enum SceneSpecError {
    /// The mesh file's bytes hash otherwise than the spec says.
    #[error(
        "mesh {}: its bytes hash to {found}, the scene names {expected}: \
         a different file (pass --mesh PATH to name the one it was made of)",
        path.display()
    )]
    OtherMesh {
        /// The file found.
        path: PathBuf,
        /// Its hash.
        found: String,
        /// The hash the spec names.
        expected: String,
    },
    /// A relative mesh path found neither beside the dump nor in the working directory.
    #[error(
        "mesh {mesh}: no such file beside the dump ({}) nor in the working directory \
         ({working_dir}); pass --mesh PATH to name it",
        beside.display()
    )]
    MeshNotFound {
        /// The path as the spec names it.
        mesh: String,
        /// The working directory, as displayed.
        working_dir: String,
        /// The path beside the dump that was tried.
        beside: PathBuf,
    },
    /// Neither a mesh nor a named scene.
    #[error("the scene names neither a mesh nor a named scene")]
    NoScene,
    /// The scene cannot be loaded or viewed (its own message).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A number JSON cannot hold.
    #[error(
        "scene {field} is {value}: numbers in a header must be finite (JSON has no NaN or infinity)"
    )]
    NotFinite {
        /// The field, by name (`view_projection.row_major[i]` for a matrix entry).
        field: String,
        /// Its value.
        value: f64,
    },
    /// A nonzero entry of an f32 matrix outside f32's normal range (infinite, zero or
    /// subnormal as an f32).
    #[error(
        "scene view_projection.row_major[{index}] is {value}, outside f32's normal range, \
         but the matrix's precision is f32"
    )]
    BeyondF32 {
        /// The entry's index, row by row.
        index: usize,
        /// Its value.
        value: f64,
    },
}

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
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |hash, &byte| {
        (hash ^ u64::from(byte)).wrapping_mul(0x100_0000_01b3)
    });
    format!("{MESH_HASH_PREFIX}{hash:016x}")
}

/// The scene, camera and conventions of a view: enough to rebuild it and its oracle.
///
/// Its numbers are exact across a file: `serde_json` is built with `float_roundtrip`, so a
/// decimal parses to the nearest f64, and writes the shortest decimal that parses back to the same
/// bits (ryu), so encode then parse gives every finite value back bit for bit. JSON has no NaN or
/// infinity: [`SceneSpec::check_finite`] refuses them before a header is written (`serde_json` would
/// write `null`), and a decimal past the f64 range is a parse error.
///
/// An unknown field is refused by name (a misspelt `fov_y_degres` would otherwise judge the dump
/// under the default field of view).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// A named scene (`Scene::procedural`: `bunny`, `spheres:8`, …); absent when `mesh` is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A mesh file (OBJ or PLY), as given to `--mesh`; a relative path in a dump is looked up
    /// beside the dump, then from the working directory.
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
    /// The model's up axis, which the orbit goes around (`--up`). Not in the JSON: a dump or an
    /// export records a turned orbit as its matrix ([`SceneSpec::recorded`]), so a spec read
    /// from a file is +y.
    #[serde(skip)]
    pub up: UpAxis,
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

impl SceneSpec {
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
            up: UpAxis::Y,
            mesh_hash: None,
            view_projection: None,
            conventions: Conventions::REFERENCE,
        }
    }

    /// A mesh file seen from the default orbit, with the hash of the file's bytes
    /// ([`SceneSpec::mesh`] then [`SceneSpec::hashed`]).
    ///
    /// # Errors
    /// The file cannot be read.
    pub fn hashed_mesh(
        path: &Path,
        view_degrees: f64,
        elevation_degrees: f64,
    ) -> Result<Self, SceneSpecError> {
        Self::mesh(path, view_degrees, elevation_degrees).hashed()
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

    /// This spec with the hash of its mesh file's bytes (a named scene as it is).
    ///
    /// # Errors
    /// The file cannot be read.
    pub fn hashed(self) -> Result<Self, SceneSpecError> {
        let Some(mesh) = &self.mesh else {
            return Ok(self);
        };
        let path = PathBuf::from(mesh);
        let bytes = read_mesh(&path)?;
        Ok(Self {
            mesh_hash: Some(mesh_hash(&bytes)),
            ..self
        })
    }

    /// What a dump or an export of `view` (this spec's view) records: the view's conventions, and
    /// an orbit around another up axis as the view's matrix, turn included, which the orbit's
    /// fields cannot describe.
    #[must_use]
    pub fn recorded(&self, view: &View<'_>) -> Self {
        let turned = || {
            (self.up != UpAxis::Y).then(|| ViewProjection {
                row_major: Camera {
                    view_projection: view.view_projection(),
                }
                .row_major(),
                precision: VertexPrecision::F64,
            })
        };
        Self {
            conventions: view.conventions(),
            view_projection: self.view_projection.or_else(turned),
            up: UpAxis::Y,
            ..self.clone()
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

    /// Loads the scene; a relative mesh path is looked up in `beside` (the dump's directory)
    /// first, then in the working directory. A mesh whose bytes do not hash to
    /// [`SceneSpec::mesh_hash`] is refused.
    ///
    /// # Errors
    /// Neither a name nor a mesh, a mesh file in neither place (both named), a file of another
    /// hash, or a scene that cannot be loaded.
    pub fn load(&self, beside: Option<&Path>) -> Result<Scene, SceneSpecError> {
        let scene = match (&self.mesh, &self.name) {
            (Some(mesh), _) => {
                let path = find_mesh(mesh, beside)?;
                if let Some(expected) = &self.mesh_hash {
                    let found = mesh_hash(&read_mesh(&path)?);
                    if found != *expected {
                        return Err(SceneSpecError::OtherMesh {
                            path,
                            found,
                            expected: expected.clone(),
                        });
                    }
                }
                Scene::from_file(&path)
            }
            (None, Some(name)) => Scene::procedural(name),
            (None, None) => return Err(SceneSpecError::NoScene),
        };
        Ok(scene?)
    }

    /// The camera on `viewport`: the engine's matrix, or the orbit's for `scene` around its up
    /// axis (with the projection of the conventions' depth range, [`OrbitCamera::camera_for`]).
    ///
    /// # Errors
    /// A matrix declared f32 with a nonzero entry outside f32's normal range.
    pub fn camera(&self, scene: &Scene, viewport: Viewport) -> Result<Camera, SceneSpecError> {
        match &self.view_projection {
            Some(matrix) => Ok(Camera::from_row_major(engine_matrix(matrix)?)),
            None => Ok(scene.orbit_camera_up(
                viewport,
                &self.orbit(),
                self.conventions.depth_range,
                self.up,
            )),
        }
    }

    /// The view this spec names: `scene` (from [`SceneSpec::load`]) through
    /// [`SceneSpec::camera`] on `viewport`, rasterized under the conventions (at more than one
    /// sample, a view rasterizing per sample whose [`View::pixel_viewport`] is `viewport`).
    ///
    /// # Errors
    /// A bad matrix, conventions fragsim cannot rasterize under, a scene without triangles.
    pub fn view<'s>(
        &self,
        scene: &'s Scene,
        viewport: Viewport,
    ) -> Result<View<'s>, SceneSpecError> {
        let camera = self.camera(scene, viewport)?;
        Ok(scene.view_under(viewport, &camera, self.conventions)?)
    }

    /// Refuses a NaN or infinite number, which JSON cannot hold (`serde_json` would silently write
    /// `null`, which then fails to parse as a number far from its cause), and a nonzero f32 matrix
    /// entry outside f32's normal range.
    ///
    /// # Errors
    /// The first field that is not finite, by name (`view_projection.row_major[i]` for a matrix
    /// entry).
    pub fn check_finite(&self) -> Result<(), SceneSpecError> {
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
                return Err(SceneSpecError::NotFinite { field, value });
            }
        }
        if let Some(view_projection) = &self.view_projection {
            engine_matrix(view_projection)?;
        }
        Ok(())
    }

    /// A short description for reports: the scene, the camera (a turned orbit's up axis named),
    /// and the conventions that are not the reference's, as a dump header spells them
    /// ([`Conventions::describe`]).
    #[must_use]
    pub fn describe(&self) -> String {
        let scene = self.mesh.as_deref().or(self.name.as_deref()).unwrap_or("?");
        let camera = match &self.view_projection {
            Some(_) => "the engine's view-projection matrix".to_string(),
            // A turned orbit (`--up`) is named: it changes every picture of the scene.
            None if self.up != UpAxis::Y => format!(
                "view {}°, elevation {}°, up {}",
                self.view_degrees,
                self.elevation_degrees,
                self.up.name()
            ),
            None => format!(
                "view {}°, elevation {}°",
                self.view_degrees, self.elevation_degrees
            ),
        };
        if self.conventions.is_reference() {
            format!("{scene}, {camera}")
        } else {
            format!(
                "{scene}, {camera}, conventions {}",
                self.conventions.describe()
            )
        }
    }
}

/// The bytes of the mesh file at `path`.
fn read_mesh(path: &Path) -> Result<Vec<u8>, SceneSpecError> {
    read_regular(path, MESH_BYTES_LIMIT, "a mesh file may have")
        .map_err(|e| SceneSpecError::Scene(SceneError::Mesh(e.into())))
}

/// The file a dump's relative mesh path names: beside the dump (the file it was made with,
/// when the dump travelled with its mesh), else in the working directory.
fn find_mesh(mesh: &str, beside: Option<&Path>) -> Result<PathBuf, SceneSpecError> {
    let path = PathBuf::from(mesh);
    if path.is_absolute() {
        return Ok(path);
    }
    let Some(dir) = beside else {
        // Not found: loading names the path.
        return Ok(path);
    };
    if dir.join(&path).exists() {
        return Ok(dir.join(&path));
    }
    if path.exists() {
        return Ok(path);
    }
    Err(SceneSpecError::MeshNotFound {
        mesh: mesh.into(),
        working_dir: std::env::current_dir()
            .map_or_else(|_| "?".into(), |d| d.display().to_string()),
        beside: dir.join(&path),
    })
}

/// The matrix the engine's vertex shader held: an f32 matrix's entries each rounded to the nearest
/// f32 (exact for the shortest f32 decimal an engine prints, or any with 9 significant digits).
///
/// # Errors
/// An f32 matrix with a nonzero entry outside f32's normal range, by index.
fn engine_matrix(matrix: &ViewProjection) -> Result<[f64; 16], SceneSpecError> {
    let mut entries = matrix.row_major;
    if matrix.precision == VertexPrecision::F32 {
        for (index, value) in entries.iter_mut().enumerate() {
            #[expect(
                clippy::cast_possible_truncation,
                reason = "the f32 value of an f32-precision entry is the one checked against f32's normal range"
            )]
            let single = *value as f32;
            // Infinite, or a nonzero value that f32 holds as zero or a subnormal (which a GPU
            // may flush to zero).
            if !single.is_finite() || (*value != 0.0 && !single.is_normal()) {
                return Err(SceneSpecError::BeyondF32 {
                    index,
                    value: *value,
                });
            }
            *value = f64::from(single);
        }
    }
    Ok(entries)
}

#[cfg(test)]
mod tests;
