//! The scene and orbit camera a dump or a triangle export names: enough to rebuild the view and
//! its oracle.

use std::path::{Path, PathBuf};

use fragsim_raster::{OrbitCamera, Scene};
use serde::{Deserialize, Serialize};

use crate::dump::{err, DumpError};

/// The scene and orbit camera that produced a dump: enough to rebuild the view and its oracle.
///
/// Its numbers are exact across the file: serde_json is built with `float_roundtrip`, so a
/// decimal parses to the nearest f64, and writes the shortest decimal that parses back to the same
/// bits (ryu), so encode then parse gives every finite value back bit for bit. JSON has no NaN or
/// infinity: [`SceneAndCamera::check_finite`] refuses them before a header is written (serde_json would
/// write `null`), and a decimal past the f64 range is a parse error.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneAndCamera {
    /// A named scene (`Scene::procedural`: `bunny`, `spheres:8`, …); absent when `mesh` is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A mesh file (OBJ or PLY), as given to `--mesh`; a relative path is looked up from the working
    /// directory, then from the dump's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Orbit angle around the model, degrees (`--view`).
    pub view_degrees: f64,
    /// Elevation above the model's equator, degrees (`--elevation`).
    pub elevation_degrees: f64,
    /// Vertical field of view, degrees.
    #[serde(default = "default_fov")]
    pub fov_y_degrees: f64,
    /// Eye distance as a multiple of the distance at which the bounding sphere fits.
    #[serde(default = "default_distance")]
    pub distance_scale: f64,
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
        }
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
    /// `beside` (the dump's directory).
    ///
    /// # Errors
    /// Neither a name nor a mesh, or a scene that cannot be loaded.
    pub fn load(&self, beside: Option<&Path>) -> Result<Scene, DumpError> {
        let scene = match (&self.mesh, &self.name) {
            (Some(mesh), _) => {
                let mut path = PathBuf::from(mesh);
                if let Some(dir) = beside.filter(|_| path.is_relative() && !path.exists()) {
                    path = dir.join(path);
                }
                Scene::from_file(&path)
            }
            (None, Some(name)) => Scene::procedural(name),
            (None, None) => return err("the scene names neither a mesh nor a named scene"),
        };
        scene.map_err(|e| DumpError(format!("scene: {e}")))
    }

    /// Refuses a NaN or infinite number, which JSON cannot hold (serde_json would silently write
    /// `null`, which then fails to parse as a number far from its cause).
    ///
    /// # Errors
    /// The first field that is not finite, by name.
    pub fn check_finite(&self) -> Result<(), DumpError> {
        for (field, value) in [
            ("view_degrees", self.view_degrees),
            ("elevation_degrees", self.elevation_degrees),
            ("fov_y_degrees", self.fov_y_degrees),
            ("distance_scale", self.distance_scale),
        ] {
            if !value.is_finite() {
                return err(format!(
                    "scene {field} is {value}: numbers in a header must be finite (JSON has no NaN or infinity)"
                ));
            }
        }
        Ok(())
    }

    /// A short description for reports.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{}, view {}°, elevation {}°",
            self.mesh.as_deref().or(self.name.as_deref()).unwrap_or("?"),
            self.view_degrees,
            self.elevation_degrees
        )
    }
}
