//! The one output model of `--json` (`docs/json-schema.md`): every command prints JSON Lines,
//! one flat record per line (a scheme on an executor, a sweep angle, a differing pixel, …).
//!
//! Guarantee: every record opens with the same context fields ([`Context`]: `record`,
//! `fragsim_version`, `command`, the scene and its mesh hash, the viewport, the camera, K and
//! capacity, executor, threads), each present on every line (`null` where the command has no
//! such thing), and a quantity has one name everywhere (`time_ms`, `mismatched_pixels`, …).
//! Rates are fractions in JSON; the tables print them as percentages and say so.
//!
//! The records are built here, as lines of text ([`line()`]); the command line prints them.

use fragsim_catalog::{Count, Sizing};
use fragsim_raster::SceneSpec;
#[cfg(feature = "args")]
use fragsim_raster::{scene_spec::args::SceneArgs, Conventions};
use serde::Serialize;

/// A slot count as a record writes it: a number, or `"auto"` when the scene sized it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slots {
    /// A fixed count.
    Fixed(u32),
    /// `auto`: sized by a counting pass (the run's own `slots_per_pixel` says to what).
    Auto,
}

impl Serialize for Slots {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Fixed(n) => serializer.serialize_u32(*n),
            Self::Auto => serializer.serialize_str("auto"),
        }
    }
}

impl From<Count> for Slots {
    fn from(count: Count) -> Self {
        match count {
            Count::Fixed(n) => Self::Fixed(n),
            Count::Auto => Self::Auto,
        }
    }
}

/// The fields every record carries, in this order, before its own.
#[derive(Debug, Clone, Serialize)]
pub struct Context {
    /// The version of fragsim that wrote the record.
    pub fragsim_version: &'static str,
    /// The subcommand (`render`, `bench`, `sweep`, `compare`, `hazard`, `explain`,
    /// `export-scene`).
    pub command: &'static str,
    /// The scene: a named scene (`bunny`, `spheres:8`) or a mesh file's name (never its
    /// directory).
    pub scene: String,
    /// The content hash of the mesh file (`fnv1a64:…`, as dumps write it); `null` for a named
    /// scene, which its name fixes.
    pub mesh_hash: Option<String>,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// Orbit angle of the camera, degrees (`null` for an engine's own matrix).
    pub view_degrees: Option<f64>,
    /// Elevation of the camera, degrees (`null` for an engine's own matrix).
    pub elevation_degrees: Option<f64>,
    /// `--k` as given: a number or `"auto"` (`null` where no scheme is sized by it).
    pub k: Option<Slots>,
    /// `--capacity` as given: a number or `"auto"` (`null` where no scheme is sized by it).
    pub capacity: Option<Slots>,
    /// The executor of the record's run (`null` where nothing ran on one).
    pub executor: Option<String>,
    /// Threads of the record's run (`null` where nothing ran).
    pub threads: Option<usize>,
}

impl Context {
    /// The context of `command` on the scene and camera of `spec`, at `width × height`.
    #[must_use]
    pub fn new(command: &'static str, spec: &SceneSpec, width: u32, height: u32) -> Self {
        let scene = crate::scene_name(spec);
        let orbit = spec.view_projection.is_none();
        Self {
            fragsim_version: env!("CARGO_PKG_VERSION"),
            command,
            scene,
            mesh_hash: spec.mesh_hash.clone(),
            width,
            height,
            view_degrees: orbit.then_some(spec.view_degrees),
            elevation_degrees: orbit.then_some(spec.elevation_degrees),
            k: None,
            capacity: None,
            executor: None,
            threads: None,
        }
    }

    /// The context of `command` on the scene options (the mesh file hashed).
    ///
    /// # Errors
    /// The mesh file cannot be read.
    #[cfg(feature = "args")]
    pub fn of_scene(command: &'static str, scene: &SceneArgs) -> Result<Self, String> {
        let spec = scene
            .spec(Conventions::REFERENCE)
            .hashed()
            .map_err(|e| e.to_string())?;
        Ok(Self::new(command, &spec, scene.width, scene.height))
    }

    /// With `--k` and `--capacity` of `sizing` (the scheme options, turned into their sizes).
    #[must_use]
    pub fn sized(mut self, sizing: impl Into<Sizing>) -> Self {
        let sizing = sizing.into();
        self.k = Some(sizing.k.into());
        self.capacity = Some(sizing.capacity.into());
        self
    }

    /// With the executor and threads of one run.
    #[must_use]
    pub fn on(&self, executor: &str, threads: usize) -> Self {
        Self {
            executor: Some(executor.into()),
            threads: Some(threads),
            ..self.clone()
        }
    }

    /// At orbit angle `degrees` (a sweep's).
    #[must_use]
    pub fn at_angle(&self, degrees: f64) -> Self {
        Self {
            view_degrees: Some(degrees),
            ..self.clone()
        }
    }
}

/// One line: the record's kind, the context, then the record's own fields.
#[derive(Serialize)]
struct Line<'a, T: Serialize> {
    record: &'static str,
    #[serde(flatten)]
    context: &'a Context,
    #[serde(flatten)]
    fields: &'a T,
}

/// One record of kind `record` as one line of JSON (no newline).
///
/// # Errors
/// The record cannot be serialised (a map with non-string keys: a bug).
pub fn line<T: Serialize>(
    record: &'static str,
    context: &Context,
    fields: &T,
) -> Result<String, String> {
    serde_json::to_string(&Line {
        record,
        context,
        fields,
    })
    .map_err(|e| e.to_string())
}
