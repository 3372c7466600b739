//! `fragsim render`.

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, ValueEnum};
use fragsim_capture::abuffer::{ABuffer, PostSort};
use fragsim_capture::executor::{run_parallel, run_serial, Run};
use fragsim_capture::mdts::{Direction, Mdts};
use fragsim_capture::{Scheme, MEMORY_CAP_DEFAULT};
use fragsim_oracle::Oracle;
use fragsim_raster::{depth_from_key, OrbitCamera, Scene, View, Viewport, DEFAULT_SCENE_NAME};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;

/// Options of `fragsim render`.
#[derive(Debug, Clone, Args)]
pub struct RenderArgs {
    /// A mesh file (OBJ, or PLY: ASCII or binary, optionally gzipped) instead of a named scene.
    #[arg(long, value_name = "PATH", conflicts_with = "scene")]
    pub mesh: Option<PathBuf>,
    /// A named scene: bunny (embedded), spheres[:N], soup[:COUNT[:SEED]], quads[:N].
    #[arg(long, value_name = "NAME", default_value = DEFAULT_SCENE_NAME)]
    pub scene: String,
    /// Viewport width in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Viewport height in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// MDTS slots per pixel; `auto` sizes K to the scene's maximum depth complexity.
    #[arg(long, default_value = "auto", value_parser = parse_count)]
    pub k: Count,
    /// A-buffer slots per pixel; `exact` sizes each pixel's list from a counting pass.
    #[arg(long, default_value = "exact", value_parser = parse_count)]
    pub capacity: Count,
    /// Schemes to run, comma-separated, or `all`.
    #[arg(long, value_delimiter = ',', default_value = "mdts,abuffer")]
    pub scheme: Vec<SchemeName>,
    /// Executor: serial, parallel or all.
    #[arg(long, default_value = "parallel")]
    pub executor: ExecutorChoice,
    /// Orbit angle of the camera around the model, in degrees.
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true, value_parser = finite)]
    pub view: f64,
    /// Camera elevation above the model's equator, in degrees.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true, value_parser = finite)]
    pub elevation: f64,
    /// Threads of the parallel executor (default: one per core).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Directory for the PNG images.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Print the summary as JSON (one object per scheme and executor) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write no images.
    #[arg(long)]
    pub no_images: bool,
    /// Refuse schemes whose per-pixel storage would exceed this many bytes.
    #[arg(long, default_value_t = MEMORY_CAP_DEFAULT)]
    pub memory_cap: u64,
}

/// A slot count: a number, or derived from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// Sized from the scene's depth complexity.
    Auto,
    /// Exactly this many.
    Fixed(u32),
}

fn parse_count(text: &str) -> Result<Count, String> {
    match text {
        "auto" | "exact" => Ok(Count::Auto),
        _ => match text.parse::<u32>() {
            Ok(0) => Err("must be at least 1 (a scheme with 0 slots stores nothing)".into()),
            Ok(n) => Ok(Count::Fixed(n)),
            Err(_) => Err(format!(
                "expected a positive integer, `auto` or `exact`, got {text:?}"
            )),
        },
    }
}

fn finite(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number of degrees, got {text:?}")),
    }
}

/// The schemes `render` can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SchemeName {
    /// MDTS, 64-bit words (depth key and primitive id), ascending.
    Mdts,
    /// MDTS, 32-bit depth keys as in FreePipe's Table 1.
    Mdts32,
    /// MDTS with `atomicMax`, descending.
    MdtsDesc,
    /// A-buffer, storage sized exactly by a counting pass, insertion-sorted.
    Abuffer,
    /// A-buffer as above, bitonic-sorted.
    AbufferBitonic,
    /// A-buffer with a fixed capacity per pixel (`--capacity`, or the maximum depth complexity).
    AbufferFixed,
    /// Every scheme above.
    All,
}

/// Which executors run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExecutorChoice {
    /// One thread, submission order.
    Serial,
    /// rayon, one logical thread per triangle, std atomics.
    Parallel,
    /// Both.
    All,
}

/// One row of the summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Scheme name.
    pub scheme: String,
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
    let threads = args
        .threads
        .map_or_else(rayon::current_num_threads, |t| t as usize);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let scene = match &args.mesh {
        Some(path) => Scene::from_file(path),
        None => Scene::procedural(&args.scene),
    }
    .map_err(|e| e.to_string())?;
    let viewport = Viewport::new(args.width, args.height)?;
    let orbit = OrbitCamera {
        angle_degrees: args.view,
        elevation_degrees: args.elevation,
        ..OrbitCamera::default()
    };
    let view = scene.view(viewport, &orbit).map_err(|e| e.to_string())?;
    let schemes = expand(&args.scheme);
    let executors: &[&str] = match args.executor {
        ExecutorChoice::Serial => &["serial"],
        ExecutorChoice::Parallel => &["parallel"],
        ExecutorChoice::All => &["serial", "parallel"],
    };
    let progress = progress_bar(args.json, (schemes.len() * executors.len() + 1) as u64);
    progress.set_message("oracle (serial reference)");
    let oracle_start = Instant::now();
    let oracle = Oracle::build(&view);
    let oracle_ms = oracle_start.elapsed().as_secs_f64() * 1e3;
    progress.inc(1);
    let max_dc = oracle.max_depth_complexity();
    let auto = |count: Count| match count {
        Count::Auto => max_dc.max(1),
        Count::Fixed(n) => n,
    };
    let mut rows = Vec::new();
    let mut nearest_written = false;
    for &name in &schemes {
        for &executor in executors {
            progress.set_message(format!("{name:?} on the {executor} executor"));
            let (run, scheme_name, slots) =
                pool.install(|| run_named(name, executor, &view, &oracle, args, auto))?;
            let diff = oracle.diff(&run.capture);
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
                scheme: scheme_name,
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
                slots_per_pixel: slots,
            });
            progress.inc(1);
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

fn expand(names: &[SchemeName]) -> Vec<SchemeName> {
    use SchemeName::*;
    if names.contains(&All) {
        return vec![
            Mdts,
            Mdts32,
            MdtsDesc,
            Abuffer,
            AbufferBitonic,
            AbufferFixed,
        ];
    }
    let mut unique = Vec::new();
    for &n in names {
        if !unique.contains(&n) {
            unique.push(n);
        }
    }
    unique
}

/// Builds the named scheme and runs it; returns the run, the scheme's name and its slots per pixel.
fn run_named(
    name: SchemeName,
    executor: &str,
    view: &View<'_>,
    oracle: &Oracle,
    args: &RenderArgs,
    auto: impl Fn(Count) -> u32,
) -> Result<(Run, String, Option<u32>), String> {
    fn go<S: Scheme>(executor: &str, view: &View<'_>, scheme: &S) -> (Run, String) {
        let run = if executor == "serial" {
            run_serial(view, scheme)
        } else {
            run_parallel(view, scheme)
        };
        (run, scheme.name())
    }
    let viewport = view.viewport();
    let cap = args.memory_cap;
    let k = auto(args.k);
    let err = |e: fragsim_capture::CaptureError| e.to_string();
    let (run, slots) = match name {
        SchemeName::Mdts => (
            go(
                executor,
                view,
                &Mdts::<u64>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
            ),
            Some(k),
        ),
        SchemeName::Mdts32 => (
            go(
                executor,
                view,
                &Mdts::<u32>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
            ),
            Some(k),
        ),
        SchemeName::MdtsDesc => (
            go(
                executor,
                view,
                &Mdts::<u64>::new(viewport, k, Direction::Descending, cap).map_err(err)?,
            ),
            Some(k),
        ),
        SchemeName::Abuffer | SchemeName::AbufferBitonic => {
            let sort = if name == SchemeName::Abuffer {
                PostSort::Insertion
            } else {
                PostSort::Bitonic
            };
            match args.capacity {
                Count::Auto => (
                    go(
                        executor,
                        view,
                        &ABuffer::exact(&oracle.depth_complexity(), sort, cap).map_err(err)?,
                    ),
                    None,
                ),
                Count::Fixed(c) => (
                    go(
                        executor,
                        view,
                        &ABuffer::fixed(viewport, c, sort, cap).map_err(err)?,
                    ),
                    Some(c),
                ),
            }
        }
        SchemeName::AbufferFixed => {
            let c = auto(args.capacity);
            (
                go(
                    executor,
                    view,
                    &ABuffer::fixed(viewport, c, PostSort::Insertion, cap).map_err(err)?,
                ),
                Some(c),
            )
        }
        SchemeName::All => unreachable!("expanded before running"),
    };
    let (run, scheme_name) = run;
    Ok((run, scheme_name, slots))
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
    let columns: [(&str, usize, Cell); 13] = [
        ("scheme", 16, |r| r.scheme.clone()),
        ("executor", 9, |r| r.executor.clone()),
        ("thr", 3, |r| r.threads.to_string()),
        ("passes", 6, |r| r.passes.to_string()),
        ("triangles", 9, |r| r.triangles.to_string()),
        ("fragments", 10, |r| r.fragments.to_string()),
        ("maxdc", 5, |r| r.max_depth_complexity.to_string()),
        ("time ms", 9, |r| format!("{:.2}", r.time_ms)),
        ("memory B", 11, |r| r.memory_bytes.to_string()),
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
                if i < 2 {
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
