//! `fragsim render`.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use fragsim_oracle::verdict::{judge_run, RunVerdict};
use fragsim_oracle::{Oracle, Ties};
use fragsim_raster::{depth_from_key, Conventions, UpAxis, View};
use serde::Serialize;

use crate::args::{ConventionsArgs, DumpArgs, SceneArgs, SchemeArgs};
use crate::schemes::{check_memory_cap_early, SchemeChoice, SchemeRunner};
use crate::table::Table;

/// Options of `fragsim render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The rasterization conventions (a dump records them).
    #[command(flatten)]
    pub conventions: ConventionsArgs,
    /// Scheme sizing and executors.
    #[command(flatten)]
    pub schemes: SchemeArgs,
    /// Schemes to run, comma-separated, or `all`.
    #[arg(long, value_delimiter = ',', default_value = "mdts,abuffer")]
    pub scheme: Vec<SchemeChoice>,
    /// Directory for the PNG images.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Print JSON Lines instead of a table: one record per scheme and executor
    /// (`docs/json-schema.md`).
    #[arg(long)]
    pub json: bool,
    /// Write no images.
    #[arg(long)]
    pub no_images: bool,
    /// The depth complexity drawn white in depth-complexity.png (and above it, marked `≥`):
    /// a fixed scale, so that maps of different scenes compare; default: the image's maximum.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub scale_max: Option<u32>,
    /// Also write each scheme's per-pixel words as a dump in `DIR/<scheme>/` (docs/dump-format.md),
    /// in fragsim's encoding or the one `--dump-order`, `--dump-payload` and
    /// `--dump-list-numbering` ask.
    #[command(flatten)]
    pub dump: DumpArgs,
    /// The oracle's tie policy for fragments of one pixel at one depth: `by-primitive` (the
    /// canonical order), `keep-duplicates` (compared by depth key) or `merge-equal-depths`
    /// (compared by distinct depth key, as loop32 and 32-bit peeling keep them).
    #[arg(long, default_value = "by-primitive")]
    pub ties: TieChoice,
}

/// `--ties`: [`Ties`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TieChoice {
    /// Ties ordered by primitive id (fragsim's canonical order).
    ByPrimitive,
    /// Every fragment kept, compared by depth key (FreePipe's MDTS on 32-bit keys).
    KeepDuplicates,
    /// Equal depths merged, compared by distinct depth key (nvpro-samples' loop32).
    MergeEqualDepths,
}

impl From<TieChoice> for Ties {
    fn from(choice: TieChoice) -> Self {
        match choice {
            TieChoice::ByPrimitive => Self::ByPrimitive,
            TieChoice::KeepDuplicates => Self::KeepDuplicates,
            TieChoice::MergeEqualDepths => Self::MergeEqualDepths,
        }
    }
}

/// One row of the summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Scheme name.
    pub scheme: String,
    /// What the scheme guarantees (`exact`, `exact-within-capacity(C)`, `exact-distinct-depths`,
    /// `exact-without-hazards`, `exact-in-arrival-order` or `approximate`).
    pub guarantee: String,
    /// Whether this run kept its guarantee (judged by the oracle, on this executor); `true` too
    /// where the guarantee owes nothing on this executor (`guarantee_owed`).
    pub keeps_guarantee: bool,
    /// Whether the guarantee owes exact lists on this executor: not `exact-without-hazards` or
    /// `exact-in-arrival-order` on one that does not serialise each pixel's fragments, nor
    /// `approximate` anywhere. Where it owes nothing the table's verdict says `not owed`.
    pub guarantee_owed: bool,
    /// `serial`, `parallel`, `tiled` or `scheduled` (a record's context carries it).
    #[serde(skip)]
    pub executor: String,
    /// Threads that ran it (a record's context carries them).
    #[serde(skip)]
    pub threads: usize,
    /// Triangles in the scene.
    pub triangles: u32,
    /// Fragments rasterized and inserted, over all passes (the counting pass included).
    pub fragments: u64,
    /// The scene's fragments, the oracle's: `captured + overflowed + lost − extra`.
    pub reference_fragments: u64,
    /// Geometry passes, the counting pass included where one sized the storage.
    pub passes: u32,
    /// The counting pass that sized the storage (its time is inside `pass_ms`), where one ran.
    pub count_pass_ms: Option<f64>,
    /// Largest per-pixel depth complexity.
    pub max_depth_complexity: u32,
    /// Memory operations (steps) performed.
    pub memory_ops: u64,
    /// Fragments captured.
    pub captured: u64,
    /// Fragments the scheme had no room for (beyond K, or past a fixed capacity), as the oracle
    /// predicts from each pixel's fragment count.
    pub overflowed: u64,
    /// The overflow the scheme counted itself.
    pub reported_overflow: u64,
    /// Pixels whose counted overflow differs from the oracle's prediction.
    pub overflow_miscounted_pixels: u64,
    /// Fragments the scheme should have kept but did not.
    pub lost: u64,
    /// Captured fragments the oracle does not have there (a duplicate a race left, a wrong
    /// word): counted in `captured`, so `captured + overflowed + lost − extra` is
    /// `reference_fragments`.
    pub extra: u64,
    /// Pixels that differ from the oracle.
    pub mismatched_pixels: u64,
    /// Pass plus post pass, in milliseconds.
    pub time_ms: f64,
    /// The passes (storage initialisation, rasterization, capture), in milliseconds.
    pub pass_ms: f64,
    /// The post pass (resolve, sort), in milliseconds.
    pub resolve_ms: f64,
    /// Bytes of per-pixel storage the scheme addresses (its layout: viewport × slots).
    pub memory_bytes: u64,
    /// Bytes of per-pixel storage allocated: the tables, the page tables and the pages of words
    /// the frame's writes reached (the larger of the counting pass and the capture where both
    /// ran). The memory cap bounds this.
    pub allocated_bytes: u64,
    /// Slots per pixel (MDTS K or fixed A-buffer capacity); absent for exact storage.
    pub slots_per_pixel: Option<u32>,
}

/// Runs `render`.
///
/// # Errors
/// A scene that cannot be loaded, bad parameters, storage beyond the memory cap, an image that
/// cannot be written.
pub(crate) fn render(args: &RenderArgs) -> Result<Vec<RunSummary>, String> {
    let setup = args.schemes.setup();
    let pool = setup.pool()?;
    let spec = args.scene.spec(args.conventions.conventions());
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let view = setup.submission(
        spec.view(&scene, args.scene.viewport().map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())?,
    );
    crate::args::warn_if_empty(&scene, &view);
    // At more than one sample every scheme and the oracle cover the sample-expanded framebuffer
    // (`docs/semantics.md`, "Multisampling"); the pictures are drawn per pixel.
    let viewport = view.viewport();
    let pixels = view.pixel_viewport();
    let samples = view.samples().map_or(1, |pattern| pattern.count() as usize);
    let schemes = SchemeChoice::expand(&args.scheme);
    let sizing = args.schemes.sizing();
    check_memory_cap_early(&schemes, viewport, &sizing).map_err(|e| e.to_string())?;
    let executors = args.schemes.executors();
    crate::oracle_memory::check(&view, sizing.memory_cap).map_err(|e| e.to_string())?;
    let progress = crate::progress::bar((schemes.len() * executors.len() + 1) as u64, "render");
    progress.set_message("oracle (serial reference)");
    let oracle_start = Instant::now();
    let oracle = Oracle::build(&view);
    let oracle_ms = oracle_start.elapsed().as_secs_f64() * 1e3;
    progress.inc(1);
    let max_dc = oracle.max_depth_complexity();
    let mut runner = SchemeRunner::default();
    // A dump holds the memory of the run it reports, not a serial re-run's.
    runner.keep_memory = args.dump.dir.is_some();
    let mut rows = Vec::new();
    let mut nearest_written = false;
    let mut dumps = args
        .dump
        .dir
        .as_deref()
        .map(|dir| crate::export::DumpStage::new(dir, args.dump.encoding()))
        .transpose()?;
    for &name in &schemes {
        let mut last = None;
        for &executor in executors {
            progress.set_message(format!("{name} on the {executor} executor"));
            let named = pool
                .install(|| runner.run(name, executor, &view, &sizing))
                .map_err(|e| e.to_string())?;
            let run = &named.run;
            let RunVerdict { diff, owed, kept } = judge_run(
                &oracle,
                &run.capture,
                named.guarantee,
                executor.serialises_pixels(),
                args.ties.into(),
            );
            if !args.no_images && !nearest_written {
                // A pixel's nearest depth is the nearest any of its samples captured.
                let nearest: Vec<Option<f32>> = per_pixel(&run.capture.nearest_keys(), samples)
                    .map(|keys| keys.iter().flatten().min().map(|&k| depth_from_key(k)))
                    .collect();
                let image = fragsim_shade::legend::nearest_depth_with_key(
                    pixels.width,
                    pixels.height,
                    &nearest,
                )
                .map_err(|e| e.to_string())?;
                let of_samples = if samples > 1 {
                    " (the nearest of the pixel's samples)"
                } else {
                    ""
                };
                let what = format!(
                    "nearest depth{of_samples} captured by {name} on the {executor} executor"
                );
                let image = fragsim_shade::legend::captioned(&image, &caption(args, &what)?)
                    .map_err(|e| e.to_string())?;
                fragsim_shade::save_png(&image, &args.out.join("nearest-depth.png"))
                    .map_err(|e| e.to_string())?;
                nearest_written = true;
            }
            let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
            rows.push(RunSummary {
                scheme: named.name.clone(),
                guarantee: named.guarantee.to_string(),
                keeps_guarantee: kept,
                guarantee_owed: owed,
                executor: executor.name().into(),
                threads: run.stats.threads,
                triangles: view.triangle_count(),
                fragments: run.stats.counters.fragments,
                reference_fragments: oracle.fragments() as u64,
                passes: run.stats.passes,
                count_pass_ms: run.stats.count_pass_time.map(ms),
                max_depth_complexity: max_dc,
                memory_ops: run.stats.counters.steps,
                captured: diff.captured,
                overflowed: diff.overflowed,
                reported_overflow: diff.reported_overflow,
                overflow_miscounted_pixels: diff.overflow_miscounted_pixels,
                lost: diff.lost,
                extra: diff.extra,
                mismatched_pixels: diff.mismatched_pixels,
                time_ms: ms(run.stats.pass_time + run.stats.resolve_time),
                pass_ms: ms(run.stats.pass_time),
                resolve_ms: ms(run.stats.resolve_time),
                memory_bytes: run.stats.memory_bytes,
                allocated_bytes: run.stats.allocated_bytes,
                slots_per_pixel: named.slots,
            });
            progress.inc(1);
            last = Some(named);
        }
        if let (Some(stage), Some(run)) = (&mut dumps, &last) {
            stage.add(name, run, &view, &spec)?;
        }
    }
    if let Some(stage) = dumps {
        stage.finish()?;
    }
    progress.finish_and_clear();
    if !args.no_images {
        // A pixel's depth complexity is the most fragments any of its samples holds: the
        // table's `maxdc`, and the single-sample count wherever one triangle covers the pixel.
        let complexity: Vec<u32> = per_pixel(&oracle.depth_complexity(), samples)
            .map(|counts| counts.iter().copied().max().unwrap_or(0))
            .collect();
        let heat = fragsim_shade::legend::heat_map_with_bar(
            pixels.width,
            pixels.height,
            &complexity,
            args.scale_max,
        )
        .map_err(|e| e.to_string())?;
        let what = if samples > 1 {
            "depth complexity (the oracle's fragments a pixel: the most any of its samples holds)"
        } else {
            "depth complexity (the oracle's fragments a pixel)"
        };
        let heat = fragsim_shade::legend::captioned(&heat, &caption(args, what)?)
            .map_err(|e| e.to_string())?;
        fragsim_shade::save_png(&heat, &args.out.join("depth-complexity.png"))
            .map_err(|e| e.to_string())?;
    }
    if args.json {
        // stdout stays JSON Lines: where the pictures went goes to stderr.
        if !args.no_images {
            eprintln!(
                "wrote {}: {} ({})",
                args.out.display(),
                IMAGES.join(", "),
                drawn_of(args)?
            );
        }
        let context = crate::record::Context::of_scene("render", &args.scene)?.sized(&args.schemes);
        for row in &rows {
            crate::record::emit("run", &context.on(&row.executor, row.threads), row)?;
        }
    } else {
        print_table(&rows, &scene.name, &view, &oracle, oracle_ms, args)?;
    }
    Ok(rows)
}

/// The pictures `render` writes in its `--out` directory.
const IMAGES: [&str; 2] = ["depth-complexity.png", "nearest-depth.png"];

/// The values of `lists` (the sample-expanded framebuffer's, `samples` a pixel side by side)
/// grouped by pixel, in pixel order: one list a pixel without multisampling.
fn per_pixel<T>(lists: &[T], samples: usize) -> std::slice::ChunksExact<'_, T> {
    lists.chunks_exact(samples)
}

/// What the pictures are drawn of: the scene, then every option that changed them (the view, the
/// elevation, a turned up axis, the size and samples, the conventions that are not the
/// reference's, in a dump header's words). Each caption opens with it, and the line naming
/// where the pictures went repeats it.
///
/// # Errors
/// The mesh file cannot be read (for its name).
fn drawn_of(args: &RenderArgs) -> Result<String, String> {
    let scene = crate::record::Context::of_scene("render", &args.scene)?.scene;
    let up = match args.scene.up {
        UpAxis::Y => String::new(),
        axis => format!(", up {}", axis.name()),
    };
    let samples = match args.conventions.samples {
        1 => String::new(),
        n => format!(" at {n} samples"),
    };
    // The samples are named with the size; the other conventions as a header spells them.
    let conventions = Conventions {
        samples: 1,
        ..args.conventions.conventions()
    };
    let conventions = if conventions.is_reference() {
        String::new()
    } else {
        format!(", conventions {}", conventions.describe())
    };
    Ok(format!(
        "{scene}, view {}°, elevation {}°{up}, {}x{}{samples}{conventions}",
        args.scene.view, args.scene.elevation, args.scene.width, args.scene.height
    ))
}

/// An image's caption: what it is drawn of ([`drawn_of`]), then `what` it shows.
///
/// # Errors
/// The mesh file cannot be read (for its name).
fn caption(args: &RenderArgs, what: &str) -> Result<String, String> {
    Ok(format!("{}: {what}", drawn_of(args)?))
}

/// Prints the table of `rows` under a line naming the scene, its pixels and fragments, then what
/// the columns add up to and where the pictures went.
///
/// # Errors
/// The mesh file cannot be read (for the pictures' line).
fn print_table(
    rows: &[RunSummary],
    scene: &str,
    view: &View<'_>,
    oracle: &Oracle,
    oracle_ms: f64,
    args: &RenderArgs,
) -> Result<(), String> {
    let pixels = view.pixel_viewport();
    // Per sample, the lists and their fragments are the sample-expanded framebuffer's.
    let sampled = view.samples().map_or(String::new(), |pattern| {
        let framebuffer = view.viewport();
        format!(
            " at {} samples ({}x{} sample lists)",
            pattern.count(),
            framebuffer.width,
            framebuffer.height
        )
    });
    outln!(
        "scene {scene}: {} triangles, {}x{} pixels{sampled}, {} fragments, max depth complexity {} (oracle {:.1} ms)",
        rows.first().map_or(0, |r| r.triangles),
        pixels.width,
        pixels.height,
        oracle.fragments(),
        oracle.max_depth_complexity(),
        oracle_ms
    );
    type Cell = fn(&RunSummary) -> String;
    let columns: [(&str, usize, Cell); 18] = [
        ("scheme", 24, |r| r.scheme.clone()),
        ("guarantee", 26, |r| r.guarantee.clone()),
        ("executor", 9, |r| r.executor.clone()),
        ("thr", 3, |r| r.threads.to_string()),
        ("passes", 6, |r| {
            // A counting pass that sized the storage is marked: `2c` = one capture pass after it.
            let counted = if r.count_pass_ms.is_some() { "c" } else { "" };
            format!("{}{counted}", r.passes)
        }),
        ("triangles", 9, |r| r.triangles.to_string()),
        // The scene's fragments, which the accounting columns add up to (a multi-pass scheme
        // rasterizes each of them once a pass: its memory ops tell).
        ("fragments", 10, |r| r.reference_fragments.to_string()),
        ("maxdc", 5, |r| r.max_depth_complexity.to_string()),
        ("time ms", 9, |r| format!("{:.2}", r.time_ms)),
        ("memory B", 11, |r| r.memory_bytes.to_string()),
        ("allocated B", 11, |r| r.allocated_bytes.to_string()),
        ("captured", 9, |r| r.captured.to_string()),
        ("overflow", 8, |r| r.overflowed.to_string()),
        ("lost", 6, |r| r.lost.to_string()),
        ("extra", 6, |r| r.extra.to_string()),
        ("mismatches", 10, |r| r.mismatched_pixels.to_string()),
        ("verdict", 8, |r| {
            if !r.guarantee_owed {
                "not owed"
            } else if r.keeps_guarantee {
                "kept"
            } else {
                "BROKEN"
            }
            .to_string()
        }),
        ("mem ops", 9, |r| r.memory_ops.to_string()),
    ];
    // Each column as wide as its widest cell (a long scheme name widens its column, never
    // pushes the rest out of line), at least its usual width.
    let mut table = Table::new(
        columns.iter().map(|(h, _, _)| (*h).to_string()).collect(),
        3,
    )
    .at_least(columns.iter().map(|&(_, least, _)| least).collect());
    for r in rows {
        table.push(columns.iter().map(|(_, _, cell)| cell(r)).collect());
    }
    out!("{}", table.text(1));
    outln!("captured + overflow + lost − extra = fragments, on every row");
    if rows.iter().any(|r| !r.guarantee_owed) {
        outln!(
            "not owed: the guarantee promises nothing on this executor (a hazard-free or \
             arrival-order one is owed only where each pixel's fragments are serialised: serial, \
             tiled; an approximate one nowhere); the row's counts are what it did"
        );
    }
    if rows.iter().any(|r| r.count_pass_ms.is_some()) {
        outln!("passes marked c include the scheme's own counting pass, which sized its storage");
    }
    if !args.no_images {
        let images: Vec<String> = IMAGES
            .iter()
            .map(|image| args.out.join(image).display().to_string())
            .collect();
        outln!("images of {}: {}", drawn_of(args)?, images.join(", "));
    }
    Ok(())
}
