//! `fragsim export-scene` (the screen triangles of a view, for backends that skip the vertex
//! stage) and the dumps of `fragsim render --dump DIR` (`docs/dump-format.md`).

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use fragsim_capture::mdts::Direction;
use fragsim_oracle::dump::{Dump, DumpScheme, SceneSpec, TriangleExport};
use fragsim_raster::View;

use crate::args::{Count, SceneArgs};
use crate::schemes::{SchemeName, Sizing};

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

/// The scene description a dump or an export carries.
fn scene_spec(args: &SceneArgs) -> SceneSpec {
    match &args.mesh {
        Some(path) => SceneSpec::mesh(path, args.view, args.elevation),
        None => SceneSpec::named(&args.scene, args.view, args.elevation),
    }
}

/// Runs `export-scene`.
///
/// # Errors
/// A scene that cannot be loaded, a bad viewport, a file that cannot be written.
pub fn export_scene(args: &ExportArgs) -> Result<(), String> {
    let spec = scene_spec(&args.scene);
    let scene = args.scene.scene()?;
    let view = scene
        .view(args.scene.viewport()?, &spec.orbit())
        .map_err(|e| e.to_string())?;
    let export = TriangleExport::from_view(&view, spec);
    export.write(&args.out).map_err(|e| e.to_string())?;
    println!(
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

/// The dump layout of a `render` scheme, with K and capacity resolved as `render` resolves them.
fn dump_scheme(name: SchemeName, sizing: &Sizing<'_>) -> Result<DumpScheme, String> {
    let k = sizing.k.resolve(sizing.max_depth_complexity);
    Ok(match name {
        SchemeName::Mdts => DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        },
        SchemeName::MdtsDesc => DumpScheme::Mdts {
            k,
            direction: Direction::Descending,
        },
        SchemeName::Mdts32 => DumpScheme::Mdts32 { k },
        SchemeName::Abuffer | SchemeName::AbufferBitonic => match sizing.capacity {
            Count::Auto => DumpScheme::ABufferExact {
                counts: sizing.depth_complexity.to_vec(),
                sorted: false,
            },
            Count::Fixed(capacity) => DumpScheme::ABufferFixed {
                capacity,
                sorted: false,
            },
        },
        SchemeName::AbufferFixed => DumpScheme::ABufferFixed {
            capacity: sizing.capacity.resolve(sizing.max_depth_complexity),
            sorted: false,
        },
        #[allow(unreachable_patterns)]
        other => return Err(format!("scheme {other:?} has no dump layout")),
    })
}

/// Writes scheme `name`'s memory, after a serial run, as a dump in `dir/<scheme>/`; returns
/// that directory.
///
/// # Errors
/// A scheme without a dump layout, a directory that cannot be written.
pub(crate) fn write_dump(
    dir: &Path,
    name: SchemeName,
    view: &View<'_>,
    sizing: &Sizing<'_>,
    scene: &SceneArgs,
) -> Result<PathBuf, String> {
    let scheme = dump_scheme(name, sizing)?;
    let producer = format!("fragsim {}", env!("CARGO_PKG_VERSION"));
    let dump =
        Dump::record(view, scene_spec(scene), &scheme, &producer).map_err(|e| e.to_string())?;
    let sub = name
        .to_possible_value()
        .map_or_else(|| format!("{name:?}"), |v| v.get_name().to_string());
    let path = dir.join(sub);
    dump.write(&path).map_err(|e| e.to_string())?;
    Ok(path)
}
