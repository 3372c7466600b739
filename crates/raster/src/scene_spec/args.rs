//! The command-line options that name a scene spec, shared by every command that takes one
//! (`fragsim`'s and `fragsim-wgpu`'s), and their value parsers, for a command whose options are
//! shaped otherwise (a list of angles), so that each checks the same ranges.

use std::path::PathBuf;

use clap::Args;

use super::SceneSpec;
use crate::{Conventions, UpAxis, Viewport, ViewportError, DEFAULT_SCENE_NAME};

/// Why an angle option's value is refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AngleError {
    /// The text is not a finite number.
    #[error("expected a finite number of degrees, got {text:?}")]
    NotFinite {
        /// The text given.
        text: String,
    },
    /// An elevation beyond ±89 degrees.
    #[error(
        "the elevation must be between -{MAX_ELEVATION} and {MAX_ELEVATION} degrees \
         (the camera cannot look along its up axis), got {degrees}"
    )]
    Elevation {
        /// The elevation given, in degrees.
        degrees: f64,
    },
}

/// The scene and the camera.
#[derive(Debug, Clone, Args)]
pub struct SceneArgs {
    /// A mesh file (OBJ, or PLY: ASCII or binary, optionally gzipped) instead of a named scene.
    #[arg(long, value_name = "PATH", conflicts_with = "scene")]
    pub mesh: Option<PathBuf>,
    /// A named scene: `bunny` (embedded), `bunny-spheres:N:SEED`, `spheres:N`, `soup:COUNT:SEED`, `quads:N` (parameters optional).
    #[arg(long, value_name = "NAME", default_value = DEFAULT_SCENE_NAME)]
    pub scene: String,
    /// Viewport width in pixels.
    // Negative values reach the range check (and its message) instead of being taken for a flag.
    #[arg(long, default_value_t = 512, allow_negative_numbers = true,
          value_parser = side())]
    pub width: u32,
    /// Viewport height in pixels.
    #[arg(long, default_value_t = 512, allow_negative_numbers = true,
          value_parser = side())]
    pub height: u32,
    /// Orbit angle of the camera around the model, in degrees.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true, value_parser = degrees)]
    pub view: f64,
    /// Camera elevation above the model's equator, in degrees, within ±89 (the camera cannot
    /// look straight down its up axis).
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true, value_parser = elevation)]
    pub elevation: f64,
    /// The model's up axis in its file: `y` (OBJ's custom), `z` (most scanner and CAD files: a
    /// z-up model otherwise lies on its side), `x`, `-y`, `-z` or `-x`. The camera orbits that
    /// axis; the mesh and its primitive ids stay as they are (a dump records the turned camera as
    /// its `view_projection`).
    #[arg(long, value_name = "AXIS", default_value = "y", allow_hyphen_values = true,
          value_parser = UpAxis::parse)]
    pub up: UpAxis,
}

impl SceneArgs {
    /// The spec these options name under `conventions` (a mesh file unhashed:
    /// [`SceneSpec::hashed`] reads it).
    #[must_use]
    pub fn spec(&self, conventions: Conventions) -> SceneSpec {
        let spec = match &self.mesh {
            Some(path) => SceneSpec::mesh(path, self.view, self.elevation),
            None => SceneSpec::named(&self.scene, self.view, self.elevation),
        };
        SceneSpec {
            up: self.up,
            conventions,
            ..spec
        }
    }

    /// The viewport.
    ///
    /// # Errors
    /// A side out of range.
    pub fn viewport(&self) -> Result<Viewport, ViewportError> {
        Viewport::new(self.width, self.height)
    }
}

/// A viewport side: 1 to [`Viewport::MAX_SIDE`] pixels.
#[must_use]
pub fn side() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(Viewport::MAX_SIDE))
}

/// An angle in degrees: any finite number.
///
/// # Errors
/// Not a number, or not finite.
pub fn degrees(text: &str) -> Result<f64, AngleError> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(AngleError::NotFinite { text: text.into() }),
    }
}

/// The largest elevation the orbit camera takes (`OrbitCamera` clamps beyond it): refused
/// rather than quietly clamped.
const MAX_ELEVATION: f64 = 89.0;

/// An elevation in degrees, within ±89.
///
/// # Errors
/// Not a finite number, or beyond ±89.
pub fn elevation(text: &str) -> Result<f64, AngleError> {
    let degrees = degrees(text)?;
    if degrees.abs() > MAX_ELEVATION {
        return Err(AngleError::Elevation { degrees });
    }
    Ok(degrees)
}
