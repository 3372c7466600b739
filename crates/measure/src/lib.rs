//! fragsim's measurements as a library: `bench` (every scheme's speed and accuracy on one
//! scene), `sweep` (the error over view angles around the model), `hazard` (the k-buffer's
//! hazard rate and the baselines table), the colour judge they share, the approximate OIT
//! schemes' error and the multisampled rows of `bench --samples`.
//!
//! Why a crate of its own: the command line (`fragsim-cli`) is clap glue and printing, and the
//! Python package and a backend's own bench call the same measurements. Each measurement takes a
//! plain parameter struct and returns plain result structs; its reports (Markdown, the terminal
//! tables laid out by [`table::Table`], charts) are functions of those, and [`record`] is the
//! JSON Lines output model every command's records share. It never prints: what it has to say while it runs (steps done, a warning)
//! goes to the caller's [`Progress`], and the only files it writes are the images and charts a
//! caller asks for ([`images::Images`], the reports' charts).

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod approximate;
pub mod bench;
pub mod cells;
pub mod colour_by_depth;
pub mod colour_judge;
pub mod frame_timing;
pub mod hazard;
pub mod images;
pub mod multisampled;
pub mod progress;
pub mod record;
pub mod setup;
pub mod sweep;
pub mod table;

pub use progress::{Progress, Silent};
pub use setup::{SchemeSetup, Shard};

use fragsim_raster::SceneSpec;

/// A scene as tables, titles and records name it: a named scene by its name (`bunny`,
/// `spheres:8`), a mesh file by its file name (never its directory), an engine's matrix as
/// `engine`.
#[must_use]
pub fn scene_name(spec: &SceneSpec) -> String {
    match (&spec.name, &spec.mesh) {
        (Some(name), _) => name.clone(),
        (None, Some(mesh)) => std::path::Path::new(mesh)
            .file_name()
            .map_or_else(|| mesh.clone(), |f| f.to_string_lossy().into_owned()),
        (None, None) => "engine".into(),
    }
}
