//! `fragsim hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows
//! and as depth complexity grows, measured with the scheduled executor, on both machines the
//! k-buffer runs on; and, with `--baselines`, the table of `docs/baselines/kbuffer.md` (passes and
//! losses of the catalog's k-buffer schemes and the stencil-routed A-buffer on every executor).
//!
//! For each machine (`--write-back`: render-target write-backs, separate stores), each policy
//! (uniform random, lockstep warps), each width `W` and each seed, the k-buffer runs the scene one
//! fragment per thread under the scheduled executor, and `Oracle::diff` counts the covered pixels
//! whose list differs from the oracle's `K` nearest (a fragment lost, duplicated or out of order).
//! The measurements are `fragsim_explain::hazard`'s and `fragsim_explain::baselines`'s; this
//! module holds the options, the progress lines and the tables and plots written.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use fragsim_capture::schemes::kbuffer::KBuffer;
use fragsim_capture::MEMORY_CAP_DEFAULT;
use fragsim_explain::baselines;
use fragsim_explain::hazard::{covered_by_bucket, machine_name, rate, BUCKETS, POLICIES};
pub use fragsim_explain::{
    baselines::BaselineRow,
    hazard::{HazardReport, HazardRow},
};
use fragsim_oracle::Oracle;
use fragsim_shade::plot::{chart, Series};

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
    let in_bucket = covered_by_bucket(&oracle);
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
    let machines: Vec<_> = args.write_back.iter().map(|w| w.machine()).collect();
    if args.baselines {
        // The output lists hold every layer (as `render` sizes them).
        let layers = oracle.max_depth_complexity().max(1);
        for baseline in baselines::table(viewport, &args.ks, &machines, layers)? {
            report
                .baselines
                .extend(baselines::rows(&baseline, &view, &oracle)?);
            eprintln!(
                "hazard --baselines: {} K = {} done",
                baseline.scheme, baseline.k
            );
        }
        write_baselines(args, &report)?;
        return Ok(report);
    }
    for &machine in &machines {
        let scheme = KBuffer::with_write_back(viewport, args.k, machine, MEMORY_CAP_DEFAULT)
            .map_err(|e| e.to_string())?;
        for policy in POLICIES {
            for &width in &args.widths {
                let row = rate(&view, &oracle, &scheme, machine, policy, width, args.seeds);
                report.rows.push(row);
                eprintln!(
                    "hazard: {} {} W = {width} done",
                    machine_name(machine),
                    policy.1
                );
            }
        }
    }
    write(args, &report)?;
    Ok(report)
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
        for (_, p) in POLICIES {
            let points = report
                .rows
                .iter()
                .filter(|r| r.policy == p && r.write_back == machine_name(write_back.machine()))
                .map(|r| ((r.width as f64).log2(), r.rate))
                .collect();
            by_width.push((
                format!("{} {p}", machine_name(write_back.machine())),
                points,
            ));
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
