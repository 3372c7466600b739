//! `fragsim hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows
//! and as depth complexity grows, measured with the scheduled executor.
//!
//! For each policy (uniform random, lockstep warps), each width `W` and each seed, the k-buffer
//! runs the scene one fragment per thread under the scheduled executor, and `Oracle::diff` counts
//! the covered pixels whose list differs from the oracle's `K` nearest (a fragment lost,
//! duplicated or out of order). With `W = 1` each walk runs alone, so the rate is 0; the paper's
//! claim is that it grows with `W`. Pixels are also bucketed by their depth complexity.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use fragsim_capture::kbuffer::KBuffer;
use fragsim_capture::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::MEMORY_CAP_DEFAULT;
use fragsim_oracle::Oracle;
use fragsim_shade::plot::{chart, Series};
use serde::Serialize;

use crate::args::SceneArgs;

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
    /// Seeds per (policy, width).
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Directory for hazard.md, hazard.json and the SVG plots.
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

/// One (policy, width) measurement, averaged over seeds.
#[derive(Debug, Clone, Serialize)]
pub struct HazardRow {
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
    /// Extra (duplicated) fragments, summed over seeds.
    pub extra: u64,
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
    /// The measurements.
    pub rows: Vec<HazardRow>,
}

fn bucket(dc: u32) -> usize {
    BUCKETS
        .iter()
        .position(|&(hi, _)| dc <= hi)
        .unwrap_or(BUCKETS.len() - 1)
}

/// Runs `hazard`.
///
/// # Errors
/// Scene, parameter or output errors.
pub fn hazard(args: &HazardArgs) -> Result<HazardReport, String> {
    if args.widths.contains(&0) || args.seeds == 0 {
        return Err("hazard needs widths ≥ 1 and at least one seed".into());
    }
    let scene = args.scene.scene()?;
    let viewport = args.scene.viewport()?;
    let view = scene
        .view(viewport, &args.scene.orbit(args.scene.view))
        .map_err(|e| e.to_string())?;
    let oracle = Oracle::build(&view);
    let scheme = KBuffer::new(viewport, args.k, MEMORY_CAP_DEFAULT).map_err(|e| e.to_string())?;
    let dc = oracle.depth_complexity();
    let mut in_bucket = vec![0usize; BUCKETS.len()];
    for &d in dc.iter().filter(|&&d| d > 0) {
        in_bucket[bucket(d)] += 1;
    }
    let covered: usize = in_bucket.iter().sum();
    let mut rows = Vec::new();
    for (policy, name) in [(Policy::Random, "random"), (Policy::Warps, "warps")] {
        for &width in &args.widths {
            let mut rates = Vec::new();
            let (mut lost, mut extra) = (0, 0);
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
                rates.push(diff.mismatched_pixels as f64 / covered.max(1) as f64);
                lost += diff.lost;
                extra += diff.extra;
                for (p, &d) in dc.iter().enumerate().filter(|&(_, &d)| d > 0) {
                    let expected = oracle.pixel(p);
                    let expected = &expected[..expected.len().min(args.k as usize)];
                    if capture.pixel(p) != expected {
                        bad_in_bucket[bucket(d)] += 1;
                    }
                }
            }
            let seeds = args.seeds as f64;
            rows.push(HazardRow {
                policy: name.into(),
                width,
                rate: rates.iter().sum::<f64>() / seeds,
                rate_per_seed: rates,
                lost,
                extra,
                rate_by_depth_complexity: bad_in_bucket
                    .iter()
                    .zip(&in_bucket)
                    .map(|(&b, &n)| {
                        if n == 0 {
                            0.0
                        } else {
                            b as f64 / (n as f64 * seeds)
                        }
                    })
                    .collect(),
            });
            eprintln!("hazard: {name} W = {width} done");
        }
    }
    let report = HazardReport {
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
        rows,
    };
    write(args, &report)?;
    Ok(report)
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
        "| policy | W | pixels wrong (mean) | per seed | lost | extra |"
    );
    let _ = writeln!(md, "|---|---:|---:|---|---:|---:|");
    for r in &report.rows {
        let per_seed: Vec<String> = r.rate_per_seed.iter().map(|x| format!("{x:.4}")).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | {} | {} | {} |",
            r.policy,
            r.width,
            r.rate,
            per_seed.join(" "),
            r.lost,
            r.extra
        );
    }
    let _ = writeln!(md, "\nFraction of pixels wrong by depth complexity:\n");
    let labels: Vec<String> = report
        .buckets
        .iter()
        .map(|(l, n)| format!("dc {l} ({n} px)"))
        .collect();
    let _ = writeln!(md, "| policy | W | {} |", labels.join(" | "));
    let _ = writeln!(md, "|---|---:|{}", "---:|".repeat(labels.len()));
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
        let _ = writeln!(md, "| {} | {} | {} |", r.policy, r.width, cells.join(" | "));
    }
    std::fs::write(out.join("hazard.md"), &md).map_err(|e| e.to_string())?;
    let json = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    std::fs::write(out.join("hazard.json"), json).map_err(|e| e.to_string())?;
    print!("{md}");
    let by_width: Vec<Series> = ["random", "warps"]
        .iter()
        .map(|&p| {
            let points = report
                .rows
                .iter()
                .filter(|r| r.policy == p)
                .map(|r| ((r.width as f64).log2(), r.rate))
                .collect();
            (p.to_string(), points)
        })
        .collect();
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
            (format!("{} W={}", r.policy, r.width), points)
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
