//! `fragsim export-scene` (the screen triangles of a view, for backends that skip the vertex
//! stage) and the dumps of `fragsim render --dump DIR` (`docs/dump-format.md`).

use std::path::{Path, PathBuf};

use clap::Args;
use fragsim_catalog::DumpLayout;
use fragsim_dump::triangles::TriangleExport;
use fragsim_dump::{masked_spec, Dump, DumpScheme, Encoding};
use fragsim_raster::{SceneSpec, View};

use crate::args::{ConventionsArgs, SceneArgs};
use crate::schemes::{NamedRun, SchemeName};

/// Options of `fragsim export-scene`.
#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    /// The scene and the camera.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The rasterization conventions, as `render` takes them (the export's scene records them).
    #[command(flatten)]
    pub conventions: ConventionsArgs,
    /// The binary triangle file to write (`FRAGTRI1`, `docs/dump-format.md` §3; `.tri` by custom).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Print one JSON Lines record (`docs/json-schema.md`) instead of the sentence.
    #[arg(long)]
    pub json: bool,
}

/// `export-scene`'s one JSON Lines record.
#[derive(serde::Serialize)]
struct ExportRecord {
    /// The file written.
    out: String,
    /// Screen triangles written (the pieces of clipped triangles each count).
    screen_triangles: usize,
    /// Triangles of the mesh.
    mesh_triangles: u32,
}

/// The scene a dump or an export of `view` records: `spec` with its mesh file hashed
/// ([`SceneSpec::hashed`]), as recorded of `view` ([`SceneSpec::recorded`]).
fn recorded_spec(spec: &SceneSpec, view: &View<'_>) -> Result<SceneSpec, String> {
    let hashed = spec.clone().hashed().map_err(|e| e.to_string())?;
    Ok(hashed.recorded(view))
}

/// Runs `export-scene`.
///
/// # Errors
/// A scene that cannot be loaded, a bad viewport, a file that cannot be written.
pub(crate) fn export_scene(args: &ExportArgs) -> Result<(), String> {
    // A file's missing folders are a mistyped path far more often than a wish: refuse them, as
    // `cp` does, rather than create a tree nobody asked for.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        if !dir.is_dir() {
            return Err(format!(
                "export-scene --out {}: the folder {} does not exist (create it first)",
                args.out.display(),
                dir.display()
            ));
        }
    }
    let spec = args.scene.spec(args.conventions.conventions());
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let view = spec
        .view(&scene, args.scene.viewport().map_err(|e| e.to_string())?)
        .map_err(|e| e.to_string())?;
    let spec = recorded_spec(&spec, &view)?;
    // The records are in pixels whatever the sample count (a backend scans them at the samples
    // the scene's conventions name), so the header's size is the render target's, not the
    // sample-expanded framebuffer's.
    let pixels = view.pixel_viewport();
    let export = TriangleExport {
        width: pixels.width,
        height: pixels.height,
        ..TriangleExport::from_view(&view, spec)
    };
    export.write(&args.out).map_err(|e| e.to_string())?;
    if args.json {
        let context = crate::record::Context::new(
            "export-scene",
            &export.scene,
            args.scene.width,
            args.scene.height,
        );
        let record = ExportRecord {
            out: args.out.display().to_string(),
            screen_triangles: export.triangles.len(),
            mesh_triangles: export.mesh_triangles,
        };
        return crate::record::emit("export", &context, &record);
    }
    outln!(
        "wrote {} (binary FRAGTRI1): {} screen triangles of {} mesh triangles ({}, {}x{})",
        args.out.display(),
        export.triangles.len(),
        export.mesh_triangles,
        export.scene.describe(),
        args.scene.width,
        args.scene.height
    );
    Ok(())
}

/// The dumps of `render --dump DIR`: each written into a staging directory inside `DIR` and moved
/// to `DIR/<scheme>/` only when every chosen scheme's is written ([`DumpStage::finish`]), so that a
/// failure leaves no half-written dump (dropping an unfinished stage removes it).
pub(crate) struct DumpStage {
    dir: PathBuf,
    staging: PathBuf,
    encoding: Encoding,
    written: Vec<&'static str>,
}

impl DumpStage {
    /// Creates `dir` and its staging directory, for dumps written in `encoding`.
    ///
    /// # Errors
    /// A directory that cannot be created.
    pub(crate) fn new(dir: &Path, encoding: Encoding) -> Result<Self, String> {
        let staging = dir.join(format!(".fragsim-partial-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&staging);
        std::fs::create_dir_all(&staging)
            .map_err(|e| format!("cannot create {}: {e}", staging.display()))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            staging,
            encoding,
            written: Vec::new(),
        })
    }

    /// Stages scheme `name`'s memory as `run` left it ([`NamedRun::memory`]: the executors must
    /// have kept it), so that the dump holds the words of the run reported, a racy one's
    /// included; a scheme whose memory has no dump layout is skipped with the reason on stderr.
    ///
    /// # Errors
    /// A run that kept no memory, or a dump that cannot be recorded or written.
    pub(crate) fn add(
        &mut self,
        name: SchemeName,
        run: &NamedRun,
        view: &View<'_>,
        scene: &SceneSpec,
    ) -> Result<(), String> {
        if name.entry().dump == Some(DumpLayout::MaskedNodes) {
            return self.add_nodes(name, run, view, scene);
        }
        let scheme = match DumpScheme::for_run(
            name,
            run.slots.unwrap_or(1),
            &run.sizes,
            run.counts.as_deref(),
        ) {
            Ok(scheme) => scheme,
            Err(why) => {
                eprintln!("render --dump: skipped {name}: {why}");
                return Ok(());
            }
        };
        let producer = format!("fragsim {}", env!("CARGO_PKG_VERSION"));
        let spec = recorded_spec(scene, view)?;
        let (layout, ignored) = scheme.spec_in(&self.encoding);
        if !ignored.is_empty() {
            eprintln!(
                "render --dump: {name}'s layout has no {}: written without",
                ignored.join(" or ")
            );
        }
        // A scheme dumped under its own name wrote its layout's words; one dumped under another
        // entry's layout (loop64, zbuffer and mdts-probe as mdts, the A-buffer variants as
        // abuffer) keeps its memory otherwise, and is written as that entry's serial run, whose
        // lists are the same under every interleaving (they are atomic schemes).
        let own_words = DumpLayout::header_scheme(name) == Some(name);
        let dump = match (&run.memory, own_words) {
            (Some(memory), true) => Dump::of_memory(
                view,
                spec,
                &scheme,
                memory.words32.clone(),
                memory.words64.clone(),
                &producer,
            ),
            (None, true) => {
                return Err(format!("render --dump: {name}: the run kept no memory"));
            }
            (_, false) => Dump::record(view, spec, &scheme, &producer),
        }
        .and_then(|dump| dump.in_layout(layout))
        .map_err(|e| format!("render --dump: {name}: {e}"))?;
        dump.write(&self.staging.join(name.name()))
            .map_err(|e| e.to_string())?;
        self.written.push(name.name());
        Ok(())
    }

    /// Stages the words of a masked-node run ([`DumpLayout::MaskedNodes`]): its counters, node
    /// words and masks as the run left them, in the masked-node layout.
    ///
    /// # Errors
    /// A run that kept no memory, or a dump that cannot be recorded or written.
    fn add_nodes(
        &mut self,
        name: SchemeName,
        run: &NamedRun,
        view: &View<'_>,
        scene: &SceneSpec,
    ) -> Result<(), String> {
        let memory = run
            .memory
            .as_ref()
            .ok_or_else(|| format!("render --dump: {name}: the run kept no memory"))?;
        let producer = format!("fragsim {}", env!("CARGO_PKG_VERSION"));
        let spec = recorded_spec(scene, view)?;
        let (layout, ignored) = masked_spec(&self.encoding);
        if !ignored.is_empty() {
            eprintln!(
                "render --dump: {name}'s layout has no {}: written without",
                ignored.join(" or ")
            );
        }
        let capacity = run.slots.unwrap_or(1);
        let words64 = memory.words64.clone();
        let dump =
            Dump::masked_of_memory(view, spec, capacity, &memory.words32, words64, &producer)
                .and_then(|dump| dump.in_layout(layout))
                .map_err(|e| format!("render --dump: {name}: {e}"))?;
        dump.write(&self.staging.join(name.name()))
            .map_err(|e| e.to_string())?;
        self.written.push(name.name());
        Ok(())
    }

    /// Moves every staged dump to `DIR/<scheme>/`, replacing an older one.
    ///
    /// # Errors
    /// A directory that cannot be replaced or moved.
    pub(crate) fn finish(self) -> Result<(), String> {
        // Every place is checked before anything moves: a file in a dump's place fails the
        // whole, with nothing written.
        for name in &self.written {
            let target = self.dir.join(name);
            if target.exists() && !target.is_dir() {
                return Err(format!(
                    "cannot write the {name} dump: {} is not a directory",
                    target.display()
                ));
            }
        }
        for name in &self.written {
            let target = self.dir.join(name);
            if target.exists() {
                std::fs::remove_dir_all(&target)
                    .map_err(|e| format!("cannot replace {}: {e}", target.display()))?;
            }
            std::fs::rename(self.staging.join(name), &target)
                .map_err(|e| format!("cannot move a dump to {}: {e}", target.display()))?;
        }
        Ok(())
    }
}

impl Drop for DumpStage {
    fn drop(&mut self) {
        // Finished or failed, the staging directory goes: it holds only unfinished dumps.
        let _ = std::fs::remove_dir_all(&self.staging);
    }
}
