//! `fragsim hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows
//! and as depth complexity grows, measured with the scheduled executor, on both machines the
//! k-buffer runs on; and, with `--baselines`, the table of `docs/baselines/kbuffer.md` (passes and
//! losses of the k-buffer family and the stencil-routed A-buffer on every executor).
//!
//! For each machine (`--write-back`: render-target write-backs, separate stores), each policy
//! (uniform random, lockstep warps), each width `W` and each seed, the k-buffer runs the scene one
//! fragment per thread under the scheduled executor, and `Oracle::diff` counts the covered pixels
//! whose list differs from the oracle's `K` nearest (a fragment lost, duplicated or out of order).
//! With `W = 1` each walk runs alone, so the rate is 0; the paper's claim is that it grows with
//! `W`. Pixels are also bucketed by their depth complexity. The failure classes are counted apart:
//! render targets can only lose fragments (stale reads); separate stores also tear write-backs,
//! which leaves duplicates and slots out of order.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use fragsim_capture::executor::{run_parallel, run_serial, Executor, Run};
use fragsim_capture::kbuffer::KBuffer;
use fragsim_capture::kbuffer_multipass::KBufferMultipass;
use fragsim_capture::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::stencil_routed::StencilRouted;
use fragsim_capture::{Capture, Scheme, MEMORY_CAP_DEFAULT};
use fragsim_oracle::Oracle;
use fragsim_raster::View;
use fragsim_shade::plot::{chart, Series};
use serde::Serialize;

use crate::args::SceneArgs;
use crate::explain::WriteBackArg;

/// Options of `fragsim hazard`.
#[derive(Debug, Clone, Args)]
pub struct HazardArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// k-buffer slots per pixel.
    #[arg(long, default_value_t = 8)]
    pub k: u32,
    /// Threads in flight, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,32,1024,65536")]
    pub widths: Vec<usize>,
    /// Seeds per (machine, policy, width).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// The k-buffer's machines, comma-separated.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "render-target,separate-stores"
    )]
    pub write_back: Vec<WriteBackArg>,
    /// Instead of the hazard rates: passes and losses of `kbuffer`, `kbuffer-stores`,
    /// `kbuffer-multipass`, `kbuffer-multipass-stores` (for each K of `--ks`), `srab` with 1
    /// and 2 passes (8 and 16 slots) on the serial, parallel and scheduled executors (`baselines.md`).
    #[arg(long)]
    pub baselines: bool,
    /// Slots per pixel for `--baselines`, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "2,4,8")]
    pub ks: Vec<u32>,
    /// Directory for hazard.md, hazard.json and the SVG plots (baselines.md, baselines.json).
    #[arg(long, default_value = "out/hazard")]
    pub out: PathBuf,
}

/// Depth-complexity buckets: inclusive upper bounds.
const BUCKETS: [(u32, &str); 6] = [
    (1, "1"),
    (2, "2"),
    (4, "3–4"),
    (8, "5–8"),
    (16, "9–16"),
    (u32::MAX, "17+"),
];

/// One (machine, policy, width) measurement, over seeds.
#[derive(Debug, Clone, Serialize)]
pub struct HazardRow {
    /// `render-target` or `separate-stores`.
    pub write_back: String,
    /// `random` or `warps`.
    pub policy: String,
    /// Threads in flight.
    pub width: usize,
    /// Fraction of covered pixels that differ from the oracle, per seed.
    pub rate_per_seed: Vec<f64>,
    /// Its mean.
    pub rate: f64,
    /// Fragments lost, summed over seeds.
    pub lost: u64,
    /// Extra fragments (duplicates, or fragments beyond the K nearest), summed over seeds.
    pub extra: u64,
    /// Second and later copies of a fragment in one pixel's slots, summed over seeds.
    pub duplicates: u64,
    /// Pixels whose slots are out of order, summed over seeds.
    pub misordered_pixels: u64,
    /// Per depth-complexity bucket: fraction of that bucket's pixels that differ (over seeds).
    pub rate_by_depth_complexity: Vec<f64>,
}

/// The whole measurement.
#[derive(Debug, Clone, Serialize)]
pub struct HazardReport {
    /// Scene and size.
    pub scene: String,
    /// Width × height.
    pub size: (u32, u32),
    /// Slots per pixel.
    pub k: u32,
    /// Covered pixels.
    pub covered: usize,
    /// Fragments.
    pub fragments: usize,
    /// Bucket labels and the covered pixels in each.
    pub buckets: Vec<(String, usize)>,
    /// The measurements (empty with `--baselines`).
    pub rows: Vec<HazardRow>,
    /// The `--baselines` table (empty without it).
    pub baselines: Vec<BaselineRow>,
}

/// One (scheme, executor) run of `--baselines`.
#[derive(Debug, Clone, Serialize)]
pub struct BaselineRow {
    /// `Scheme::name`.
    pub scheme: String,
    /// Slots per pixel (samples per pass for the stencil-routed A-buffer).
    pub k: u32,
    /// The executor.
    pub executor: String,
    /// Geometry passes.
    pub passes: u32,
    /// Fragments the scheme was not meant to keep (beyond K, or counted overflow).
    pub overflowed: u64,
    /// Fragments lost.
    pub lost: u64,
    /// Extra fragments.
    pub extra: u64,
    /// Second and later copies of a fragment in one pixel.
    pub duplicates: u64,
    /// Pixels out of order.
    pub misordered_pixels: u64,
    /// Pixels that differ.
    pub error_pixels: u64,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
}

fn bucket(dc: u32) -> usize {
    BUCKETS
        .iter()
        .position(|&(hi, _)| dc <= hi)
        .unwrap_or(BUCKETS.len() - 1)
}

/// Second and later copies of a value within one pixel, over every pixel.
fn duplicates(capture: &Capture) -> u64 {
    let mut sorted = Vec::new();
    (0..capture.pixels())
        .map(|p| {
            sorted.clear();
            sorted.extend_from_slice(capture.pixel(p));
            sorted.sort_unstable();
            sorted.windows(2).filter(|w| w[0] == w[1]).count() as u64
        })
        .sum()
}

fn machine_name(write_back: WriteBackArg) -> &'static str {
    match write_back {
        WriteBackArg::RenderTarget => "render-target",
        WriteBackArg::SeparateStores => "separate-stores",
    }
}

/// Runs `hazard`.
///
/// # Errors
/// Scene, parameter or output errors.
pub fn hazard(args: &HazardArgs) -> Result<HazardReport, String> {
    if args.widths.contains(&0) || args.seeds == 0 || args.write_back.is_empty() {
        return Err("hazard needs widths ≥ 1, at least one seed and one machine".into());
    }
    let scene = args.scene.scene()?;
    let viewport = args.scene.viewport()?;
    let view = scene
        .view(viewport, &args.scene.orbit(args.scene.view))
        .map_err(|e| e.to_string())?;
    let oracle = Oracle::build(&view);
    let dc = oracle.depth_complexity();
    let mut in_bucket = vec![0usize; BUCKETS.len()];
    for &d in dc.iter().filter(|&&d| d > 0) {
        in_bucket[bucket(d)] += 1;
    }
    let covered: usize = in_bucket.iter().sum();
    let mut report = HazardReport {
        scene: args
            .scene
            .mesh
            .as_ref()
            .map_or_else(|| args.scene.scene.clone(), |p| p.display().to_string()),
        size: (args.scene.width, args.scene.height),
        k: args.k,
        covered,
        fragments: oracle.fragments(),
        buckets: BUCKETS
            .iter()
            .zip(&in_bucket)
            .map(|(&(_, label), &n)| (label.to_string(), n))
            .collect(),
        rows: Vec::new(),
        baselines: Vec::new(),
    };
    if args.baselines {
        report.baselines = baselines(args, &view, &oracle)?;
        write_baselines(args, &report)?;
        return Ok(report);
    }
    for &write_back in &args.write_back {
        let scheme =
            KBuffer::with_write_back(viewport, args.k, write_back.machine(), MEMORY_CAP_DEFAULT)
                .map_err(|e| e.to_string())?;
        for (policy, name) in [(Policy::Random, "random"), (Policy::Warps, "warps")] {
            for &width in &args.widths {
                let mut row = HazardRow {
                    write_back: machine_name(write_back).into(),
                    policy: name.into(),
                    width,
                    rate_per_seed: Vec::new(),
                    rate: 0.0,
                    lost: 0,
                    extra: 0,
                    duplicates: 0,
                    misordered_pixels: 0,
                    rate_by_depth_complexity: Vec::new(),
                };
                let mut bad_in_bucket = vec![0usize; BUCKETS.len()];
                for seed in 0..args.seeds {
                    let schedule = Schedule {
                        policy,
                        in_flight: width,
                        granularity: Granularity::Fragment,
                        seed,
                    };
                    let capture = run_scheduled(&view, &scheme, &schedule, false).run.capture;
                    let diff = oracle.diff(&capture);
                    row.rate_per_seed
                        .push(diff.mismatched_pixels as f64 / covered.max(1) as f64);
                    row.lost += diff.lost;
                    row.extra += diff.extra;
                    row.misordered_pixels += diff.misordered_pixels;
                    row.duplicates += duplicates(&capture);
                    for (p, &d) in dc.iter().enumerate().filter(|&(_, &d)| d > 0) {
                        let expected = oracle.pixel(p);
                        let expected = &expected[..expected.len().min(args.k as usize)];
                        if capture.pixel(p) != expected {
                            bad_in_bucket[bucket(d)] += 1;
                        }
                    }
                }
                let seeds = args.seeds as f64;
                row.rate = row.rate_per_seed.iter().sum::<f64>() / seeds;
                row.rate_by_depth_complexity = bad_in_bucket
                    .iter()
                    .zip(&in_bucket)
                    .map(|(&b, &n)| {
                        if n == 0 {
                            0.0
                        } else {
                            b as f64 / (n as f64 * seeds)
                        }
                    })
                    .collect();
                report.rows.push(row);
                eprintln!(
                    "hazard: {} {name} W = {width} done",
                    machine_name(write_back)
                );
            }
        }
    }
    write(args, &report)?;
    Ok(report)
}

/// The `--baselines` runs: every (scheme, executor) of the table, diffed against the oracle.
fn baselines(
    args: &HazardArgs,
    view: &View<'_>,
    oracle: &Oracle,
) -> Result<Vec<BaselineRow>, String> {
    let viewport = view.viewport();
    let err = |e: fragsim_capture::CaptureError| e.to_string();
    // The output lists hold every layer (as `render` sizes them).
    let layers = oracle.max_depth_complexity().max(1);
    let mut rows = Vec::new();
    let mut measure = |scheme: &dyn MeasuredScheme, k: u32| {
        for (executor, run) in scheme.runs(view) {
            let diff = oracle.diff(&run.capture);
            rows.push(BaselineRow {
                scheme: scheme.name(),
                k,
                executor: executor.into(),
                passes: run.stats.passes,
                overflowed: diff.overflowed,
                lost: diff.lost,
                extra: diff.extra,
                duplicates: duplicates(&run.capture),
                misordered_pixels: diff.misordered_pixels,
                error_pixels: diff.mismatched_pixels,
                memory_bytes: run.stats.memory_bytes,
            });
        }
        eprintln!("hazard --baselines: {} K = {k} done", scheme.name());
    };
    for &k in &args.ks {
        for &write_back in &args.write_back {
            let machine = write_back.machine();
            measure(
                &KBuffer::with_write_back(viewport, k, machine, MEMORY_CAP_DEFAULT).map_err(err)?,
                k,
            );
            measure(
                &KBufferMultipass::with_write_back(
                    viewport,
                    k,
                    layers,
                    machine,
                    MEMORY_CAP_DEFAULT,
                )
                .map_err(err)?,
                k,
            );
        }
    }
    for passes in [1, 2] {
        measure(
            &StencilRouted::new(viewport, passes, MEMORY_CAP_DEFAULT).map_err(err)?,
            // Its slots (8 a pass): both configurations are named `srab` (the catalog's one
            // spelling), so the column tells them apart.
            8 * passes,
        );
    }
    Ok(rows)
}

/// The scheduled executor's runs in the baselines table: the CLI's `--executor scheduled` (uniform
/// random, 256 fragments in flight, seed 0) and lockstep warps of whole triangles (4,096 in flight,
/// seed 1).
const BASELINE_SCHEDULES: [(&str, Schedule); 2] = [
    (
        "scheduled random 256",
        Schedule {
            policy: Policy::Random,
            in_flight: 256,
            granularity: Granularity::Fragment,
            seed: 0,
        },
    ),
    (
        "scheduled warps 4096 tri",
        Schedule {
            policy: Policy::Warps,
            in_flight: 4096,
            granularity: Granularity::Triangle,
            seed: 1,
        },
    ),
];

/// A scheme behind a vtable, run on every executor of the baselines table.
trait MeasuredScheme {
    fn name(&self) -> String;
    fn runs(&self, view: &View<'_>) -> Vec<(&'static str, Run)>;
}

impl<S: Scheme> MeasuredScheme for S {
    fn name(&self) -> String {
        Scheme::name(self)
    }

    fn runs(&self, view: &View<'_>) -> Vec<(&'static str, Run)> {
        let mut runs = vec![
            (Executor::Serial.name(), run_serial(view, self)),
            (Executor::Parallel.name(), run_parallel(view, self)),
        ];
        for (label, schedule) in &BASELINE_SCHEDULES {
            runs.push((*label, run_scheduled(view, self, schedule, false).run));
        }
        runs
    }
}

fn write_baselines(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "`{}` at {}×{}: {} fragments, {} covered pixels; output lists sized to the maximum depth complexity.\n",
        report.scene, report.size.0, report.size.1, report.fragments, report.covered
    );
    let _ = writeln!(
        md,
        "| scheme | K | executor | passes | overflowed | lost | extra | duplicates | misordered px | error px (of covered) | memory MiB |"
    );
    let _ = writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &report.baselines {
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} ({:.2} %) | {:.1} |",
            r.scheme,
            r.k,
            r.executor,
            r.passes,
            r.overflowed,
            r.lost,
            r.extra,
            r.duplicates,
            r.misordered_pixels,
            r.error_pixels,
            100.0 * r.error_pixels as f64 / report.covered.max(1) as f64,
            r.memory_bytes as f64 / f64::from(1 << 20),
        );
    }
    std::fs::write(out.join("baselines.md"), &md).map_err(|e| e.to_string())?;
    let json = serde_json::to_string_pretty(&report.baselines).map_err(|e| e.to_string())?;
    std::fs::write(out.join("baselines.json"), json).map_err(|e| e.to_string())?;
    out!("{md}");
    Ok(())
}

fn write(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "k-buffer (K = {}) on `{}` at {}×{}: {} fragments, {} covered pixels; {} seeds per row.\n",
        report.k,
        report.scene,
        report.size.0,
        report.size.1,
        report.fragments,
        report.covered,
        args.seeds
    );
    let _ = writeln!(
        md,
        "| write-back | policy | W | pixels wrong (mean) | per seed | lost | extra | duplicates | misordered px |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---|---:|---:|---:|---:|");
    for r in &report.rows {
        let per_seed: Vec<String> = r.rate_per_seed.iter().map(|x| format!("{x:.4}")).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.4} | {} | {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.width,
            r.rate,
            per_seed.join(" "),
            r.lost,
            r.extra,
            r.duplicates,
            r.misordered_pixels
        );
    }
    let _ = writeln!(md, "\nFraction of pixels wrong by depth complexity:\n");
    let labels: Vec<String> = report
        .buckets
        .iter()
        .map(|(l, n)| format!("dc {l} ({n} px)"))
        .collect();
    let _ = writeln!(md, "| write-back | policy | W | {} |", labels.join(" | "));
    let _ = writeln!(md, "|---|---|---:|{}", "---:|".repeat(labels.len()));
    for r in &report.rows {
        let cells: Vec<String> = r
            .rate_by_depth_complexity
            .iter()
            .zip(&report.buckets)
            .map(|(x, (_, n))| {
                if *n == 0 {
                    "–".into()
                } else {
                    format!("{x:.4}")
                }
            })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.width,
            cells.join(" | ")
        );
    }
    std::fs::write(out.join("hazard.md"), &md).map_err(|e| e.to_string())?;
    let json = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    std::fs::write(out.join("hazard.json"), json).map_err(|e| e.to_string())?;
    out!("{md}");
    let mut by_width: Vec<Series> = Vec::new();
    for &write_back in &args.write_back {
        for p in ["random", "warps"] {
            let points = report
                .rows
                .iter()
                .filter(|r| r.policy == p && r.write_back == machine_name(write_back))
                .map(|r| ((r.width as f64).log2(), r.rate))
                .collect();
            by_width.push((format!("{} {p}", machine_name(write_back)), points));
        }
    }
    chart(
        &out.join("hazard_vs_width.svg"),
        &format!(
            "k-buffer (K = {}): pixels wrong vs threads in flight",
            report.k
        ),
        "log2 W (threads in flight)",
        "fraction of covered pixels wrong",
        &by_width,
        false,
    )?;
    let by_dc: Vec<Series> = report
        .rows
        .iter()
        .filter(|r| r.width > 1)
        .map(|r| {
            let points = r
                .rate_by_depth_complexity
                .iter()
                .enumerate()
                .filter(|&(i, _)| report.buckets[i].1 > 0)
                .map(|(i, &x)| (i as f64, x))
                .collect();
            (
                format!("{} {} W={}", r.write_back, r.policy, r.width),
                points,
            )
        })
        .collect();
    chart(
        &out.join("hazard_vs_depth_complexity.svg"),
        "k-buffer: pixels wrong vs depth complexity (buckets 1, 2, 3–4, 5–8, 9–16, 17+)",
        "depth-complexity bucket (0 = dc 1, 1 = dc 2, 2 = 3–4, 3 = 5–8, 4 = 9–16, 5 = 17+)",
        "fraction of the bucket's pixels wrong",
        &by_dc,
        false,
    )
}
