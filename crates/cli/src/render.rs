//! `fragsim render`.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use fragsim_oracle::{Oracle, Ties};
use fragsim_raster::{depth_from_key, Viewport};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;

use crate::args::{SceneArgs, SchemeArgs};
use crate::schemes::{check_memory_cap_early, Executors, SchemeName, Sizing};

/// Options of `fragsim render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Scheme sizing and executors.
    #[command(flatten)]
    pub schemes: SchemeArgs,
    /// Schemes to run, comma-separated, or `all`.
    #[arg(long, value_delimiter = ',', default_value = "mdts,abuffer")]
    pub scheme: Vec<SchemeName>,
    /// Directory for the PNG images.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Print the summary as JSON (one object per scheme and executor) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write no images.
    #[arg(long)]
    pub no_images: bool,
    /// Also write each scheme's per-pixel words as a dump in `DIR/<scheme>/` (docs/dump-format.md).
    #[arg(long, value_name = "DIR")]
    pub dump: Option<PathBuf>,
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
            TieChoice::ByPrimitive => Ties::ByPrimitive,
            TieChoice::KeepDuplicates => Ties::KeepDuplicates,
            TieChoice::MergeEqualDepths => Ties::MergeEqualDepths,
        }
    }
}

/// One row of the summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Scheme name.
    pub scheme: String,
    /// `exact`, `exact-distinct-depths` or `approximate` (see `SchemeName::guarantee`).
    pub guarantee: &'static str,
    /// `serial` or `parallel`.
    pub executor: String,
    /// Threads that ran it.
    pub threads: usize,
    /// Scene name.
    pub scene: String,
    /// Viewport width.
    pub width: u32,
    /// Viewport height.
    pub height: u32,
    /// Triangles in the scene.
    pub triangles: u32,
    /// Fragments rasterized and inserted, over all passes.
    pub fragments: u64,
    /// Geometry passes.
    pub passes: u32,
    /// Largest per-pixel depth complexity.
    pub max_depth_complexity: u32,
    /// Memory operations (steps) performed.
    pub memory_ops: u64,
    /// Fragments captured.
    pub captured: u64,
    /// Fragments the scheme had no room for (beyond K, or past a fixed capacity), counted.
    pub overflowed: u64,
    /// Fragments the scheme should have kept but did not.
    pub lost: u64,
    /// Pixels that differ from the oracle.
    pub mismatches: u64,
    /// Pass plus post pass, in milliseconds.
    pub time_ms: f64,
    /// The pass (storage initialisation, rasterization, capture), in milliseconds.
    pub pass_ms: f64,
    /// The post pass (resolve, sort), in milliseconds.
    pub resolve_ms: f64,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
    /// Slots per pixel (MDTS K or fixed A-buffer capacity); absent for exact storage.
    pub slots_per_pixel: Option<u32>,
}

/// Runs `render`.
///
/// # Errors
/// A scene that cannot be loaded, bad parameters, storage beyond the memory cap, an image that
/// cannot be written.
pub fn render(args: &RenderArgs) -> Result<Vec<RunSummary>, String> {
    let pool = args.schemes.pool()?;
    let scene = args.scene.scene()?;
    let viewport = args.scene.viewport()?;
    let view = scene
        .view(viewport, &args.scene.orbit(args.scene.view))
        .map_err(|e| e.to_string())?;
    let schemes = SchemeName::expand(&args.scheme);
    check_memory_cap_early(
        &schemes,
        viewport,
        args.schemes.k,
        args.schemes.capacity,
        args.schemes.memory_cap,
    )?;
    let executors = args.schemes.executors();
    let progress = progress_bar(args.json, (schemes.len() * executors.len() + 1) as u64);
    progress.set_message("oracle (serial reference)");
    let oracle_start = Instant::now();
    let oracle = Oracle::build(&view);
    let oracle_ms = oracle_start.elapsed().as_secs_f64() * 1e3;
    progress.inc(1);
    let max_dc = oracle.max_depth_complexity();
    let depth_complexity = oracle.depth_complexity();
    let sizing = Sizing {
        k: args.schemes.k,
        capacity: args.schemes.capacity,
        depth_complexity: &depth_complexity,
        max_depth_complexity: max_dc,
        memory_cap: args.schemes.memory_cap,
    };
    let mut runner = Executors::default();
    let mut rows = Vec::new();
    let mut nearest_written = false;
    for &name in &schemes {
        for &executor in executors {
            progress.set_message(format!("{name:?} on the {executor} executor"));
            let named = pool.install(|| runner.run(name, executor, &view, &sizing))?;
            let run = named.run;
            let diff = oracle.diff_with(&run.capture, args.ties.into());
            if !args.no_images && !nearest_written {
                let nearest: Vec<Option<f32>> = run
                    .capture
                    .nearest_keys()
                    .into_iter()
                    .map(|k| k.map(depth_from_key))
                    .collect();
                let image = fragsim_shade::nearest_depth(viewport.width, viewport.height, &nearest);
                fragsim_shade::save_png(&image, &args.out.join("nearest-depth.png"))?;
                nearest_written = true;
            }
            let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
            rows.push(RunSummary {
                scheme: named.name,
                guarantee: name.guarantee(),
                executor: executor.into(),
                threads: run.stats.threads,
                scene: scene.name.clone(),
                width: viewport.width,
                height: viewport.height,
                triangles: view.triangle_count(),
                fragments: run.stats.counters.fragments,
                passes: run.stats.passes,
                max_depth_complexity: max_dc,
                memory_ops: run.stats.counters.steps,
                captured: diff.captured,
                overflowed: diff.overflowed,
                lost: diff.lost,
                mismatches: diff.mismatched_pixels,
                time_ms: ms(run.stats.pass_time + run.stats.resolve_time),
                pass_ms: ms(run.stats.pass_time),
                resolve_ms: ms(run.stats.resolve_time),
                memory_bytes: run.stats.memory_bytes,
                slots_per_pixel: named.slots,
            });
            progress.inc(1);
        }
        if let Some(dir) = &args.dump {
            crate::export::write_dump(dir, name, &view, &sizing, &args.scene)?;
        }
    }
    progress.finish_and_clear();
    if !args.no_images {
        let heat =
            fragsim_shade::heat_map(viewport.width, viewport.height, &oracle.depth_complexity());
        fragsim_shade::save_png(&heat, &args.out.join("depth-complexity.png"))?;
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
        );
    } else {
        print_table(&rows, &scene.name, viewport, &oracle, oracle_ms, args);
    }
    Ok(rows)
}

fn progress_bar(hidden: bool, len: u64) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if hidden {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    bar
}

fn print_table(
    rows: &[RunSummary],
    scene: &str,
    viewport: Viewport,
    oracle: &Oracle,
    oracle_ms: f64,
    args: &RenderArgs,
) {
    println!(
        "scene {scene}: {} triangles, {}x{} pixels, {} fragments, max depth complexity {} (oracle {:.1} ms)",
        rows.first().map_or(0, |r| r.triangles),
        viewport.width,
        viewport.height,
        oracle.fragments(),
        oracle.max_depth_complexity(),
        oracle_ms
    );
    type Cell = fn(&RunSummary) -> String;
    let columns: [(&str, usize, Cell); 15] = [
        ("scheme", 19, |r| r.scheme.clone()),
        ("guarantee", 22, |r| r.guarantee.to_string()),
        ("executor", 9, |r| r.executor.clone()),
        ("thr", 3, |r| r.threads.to_string()),
        ("passes", 6, |r| r.passes.to_string()),
        ("triangles", 9, |r| r.triangles.to_string()),
        ("fragments", 10, |r| r.fragments.to_string()),
        ("maxdc", 5, |r| r.max_depth_complexity.to_string()),
        ("time ms", 9, |r| format!("{:.2}", r.time_ms)),
        ("memory B", 11, |r| r.memory_bytes.to_string()),
        ("captured", 9, |r| r.captured.to_string()),
        ("overflow", 8, |r| r.overflowed.to_string()),
        ("lost", 6, |r| r.lost.to_string()),
        ("mismatches", 10, |r| r.mismatches.to_string()),
        ("mem ops", 9, |r| r.memory_ops.to_string()),
    ];
    let line = |cells: Vec<String>| {
        let padded: Vec<String> = cells
            .iter()
            .zip(&columns)
            .enumerate()
            .map(|(i, (cell, (_, width, _)))| {
                if i < 3 {
                    format!("{cell:<width$}")
                } else {
                    format!("{cell:>width$}")
                }
            })
            .collect();
        println!("{}", padded.join(" "));
    };
    line(
        columns
            .iter()
            .map(|(header, _, _)| (*header).to_string())
            .collect(),
    );
    for r in rows {
        line(columns.iter().map(|(_, _, cell)| cell(r)).collect());
    }
    let pixels = viewport.pixels() as u64;
    let max_dc = u64::from(oracle.max_depth_complexity());
    let exact = pixels * 4 + oracle.fragments() as u64 * 8 + (pixels + 1) * 4;
    let fixed = pixels * (4 + max_dc * 8);
    println!(
        "memory sized to the scene: A-buffer exact {exact} B ({:.1} B/pixel) vs fixed capacity {max_dc} {fixed} B ({:.1} B/pixel); MDTS K={max_dc}: {} B",
        exact as f64 / pixels as f64,
        fixed as f64 / pixels as f64,
        pixels * max_dc * 8
    );
    if !args.no_images {
        println!(
            "images: {}/depth-complexity.png, {}/nearest-depth.png",
            args.out.display(),
            args.out.display()
        );
    }
}
