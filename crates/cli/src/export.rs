//! `fragsim export-scene` (the screen triangles of a view, for backends that skip the vertex
//! stage) and the dumps of `fragsim render --dump DIR` (`docs/dump-format.md`).

use std::path::{Path, PathBuf};

use clap::Args;
use fragsim_oracle::dump::{Dump, DumpScheme};
use fragsim_oracle::scene::SceneAndCamera;
use fragsim_oracle::triangles::TriangleExport;
use fragsim_raster::View;

use crate::args::SceneArgs;
use crate::schemes::{NamedRun, SchemeName};

/// Options of `fragsim export-scene`.
#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    /// The scene and the camera.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The triangle file to write.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// The scene description a dump or an export carries (a mesh file with the hash of its bytes).
fn scene_spec(args: &SceneArgs) -> Result<SceneAndCamera, String> {
    match &args.mesh {
        Some(path) => {
            SceneAndCamera::hashed_mesh(path, args.view, args.elevation).map_err(|e| e.to_string())
        }
        None => Ok(SceneAndCamera::named(
            &args.scene,
            args.view,
            args.elevation,
        )),
    }
}

/// Runs `export-scene`.
///
/// # Errors
/// A scene that cannot be loaded, a bad viewport, a file that cannot be written.
pub fn export_scene(args: &ExportArgs) -> Result<(), String> {
    let spec = scene_spec(&args.scene)?;
    let scene = args.scene.scene()?;
    let view = scene
        .view(args.scene.viewport()?, &spec.orbit())
        .map_err(|e| e.to_string())?;
    let export = TriangleExport::from_view(&view, spec);
    export.write(&args.out).map_err(|e| e.to_string())?;
    outln!(
        "wrote {}: {} screen triangles of {} mesh triangles ({}, {}x{})",
        args.out.display(),
        export.triangles.len(),
        export.mesh_triangles,
        export.scene.describe(),
        args.scene.width,
        args.scene.height
    );
    Ok(())
}

/// Writes scheme `name`'s memory, sized as `run` was, after a serial run, as a dump in `dir/<scheme>/`; returns
/// that directory.
///
/// # Errors
/// A scheme without a dump layout, a directory that cannot be written.
pub(crate) fn write_dump(
    dir: &Path,
    name: SchemeName,
    run: &NamedRun,
    view: &View<'_>,
    scene: &SceneArgs,
) -> Result<PathBuf, String> {
    let scheme = DumpScheme::for_run(name, run.slots.unwrap_or(1), run.counts.as_deref())
        .map_err(|e| e.to_string())?;
    let producer = format!("fragsim {}", env!("CARGO_PKG_VERSION"));
    let spec = SceneAndCamera {
        conventions: view.conventions(),
        ..scene_spec(scene)?
    };
    let dump = Dump::record(view, spec, &scheme, &producer).map_err(|e| e.to_string())?;
    let path = dir.join(name.name());
    dump.write(&path).map_err(|e| e.to_string())?;
    Ok(path)
}
