//! `fragsim hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows
//! and as depth complexity grows, measured with the scheduled executor, on both machines the
//! k-buffer runs on; and, with `--baselines`, the table of `docs/baselines/kbuffer.md` (passes and
//! losses of the catalog's k-buffer schemes and the stencil-routed A-buffer on every executor).
//!
//! For each machine (`--write-back`: render-target write-backs, separate stores), each policy
//! (uniform random, lockstep warps), each width `W` and each seed, the k-buffer runs the scene one
//! fragment per thread under the scheduled executor, and `Oracle::diff` counts the covered pixels
//! whose list differs from the oracle's `K` nearest (a fragment lost, duplicated or out of order).
//! The measurement is `fragsim_measure::hazard`'s; this module holds the options and the tables,
//! records and plots written.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::Args;
use fragsim_explain::hazard::{machine_name, POLICIES};
use fragsim_measure::hazard::HazardReport;
use fragsim_measure::hazard::{Campaign, HazardParams};
use fragsim_raster::Conventions;
use fragsim_shade::plot::{chart, chart_with_ticks, Series};
use serde::Serialize;

use crate::args::SceneArgs;
use crate::explain::WriteBackArg;
use crate::record::{Context, Slots};

/// Options of `fragsim hazard`.
#[derive(Debug, Clone, Args)]
pub struct HazardArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// k-buffer slots per pixel.
    #[arg(long, default_value_t = 8)]
    pub k: u32,
    /// Threads in flight `W`, comma-separated: how many fragments the scheduled executor keeps
    /// walking at once (not the viewport's `--width`; `--widths` is the older spelling).
    #[arg(
        long,
        value_name = "W,...",
        alias = "widths",
        value_delimiter = ',',
        default_value = "1,32,1024,65536"
    )]
    pub threads_in_flight: Vec<usize>,
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
    /// Directory for hazard.md, hazard.json and the PNG plots (baselines.md, baselines.json).
    #[arg(long, default_value = "out/hazard")]
    pub out: PathBuf,
    /// Write the plots as SVG instead of PNG.
    #[arg(long, conflicts_with = "no_images")]
    pub svg: bool,
    /// Write no plots; hazard.md and hazard.json are still written.
    #[arg(long)]
    pub no_images: bool,
    /// Print JSON Lines instead of the tables: one record per (machine, policy, width), or per
    /// baseline row (`docs/json-schema.md`).
    #[arg(long)]
    pub json: bool,
}

/// One line of hazard's JSON Lines: a row of the rates (the context carries the scheduled
/// executor and the threads in flight).
#[derive(Serialize)]
struct HazardRecord<'a> {
    scheme: &'static str,
    write_back: &'a str,
    policy: &'a str,
    seeds: u64,
    /// Fraction of covered pixels whose list differs from the oracle's K nearest, mean over
    /// the seeds.
    mismatched_pixel_rate: f64,
    /// The same, per seed.
    mismatched_pixel_rate_per_seed: &'a [f64],
    lost: u64,
    extra: u64,
    duplicates: u64,
    misordered_pixels: u64,
    /// The rate among the pixels of each depth-complexity bucket (`dc_1`, `dc_2`, `dc_3_4`, …);
    /// `null` for a bucket without pixels.
    #[serde(flatten)]
    by_depth_complexity: std::collections::BTreeMap<String, Option<f64>>,
}

/// One line of `hazard --baselines`' JSON Lines (the context carries K and the executor).
#[derive(Serialize)]
struct BaselineRecord<'a> {
    scheme: &'a str,
    passes: u32,
    overflowed: u64,
    lost: u64,
    extra: u64,
    duplicates: u64,
    misordered_pixels: u64,
    error_pixels: u64,
    /// `error_pixels` over the covered pixels.
    error_pixel_rate: f64,
    memory_bytes: u64,
}

/// Runs `hazard`.
///
/// # Errors
/// Scene, parameter or output errors.
pub(crate) fn hazard(args: &HazardArgs) -> Result<HazardReport, String> {
    let campaign = if args.baselines {
        Campaign::Baselines {
            ks: args.ks.clone(),
        }
    } else {
        Campaign::Rates {
            k: args.k,
            threads_in_flight: args.threads_in_flight.clone(),
            seeds: args.seeds,
        }
    };
    let params = HazardParams {
        scene: args.scene.spec(Conventions::REFERENCE),
        viewport: args.scene.viewport().map_err(|e| e.to_string())?,
        write_back: args.write_back.iter().map(|w| w.machine()).collect(),
        campaign,
    };
    let report = fragsim_measure::hazard::hazard(&params, &crate::progress::Bars::default())?;
    if args.baselines {
        write_baselines(args, &report)?;
    } else {
        write(args, &report)?;
    }
    Ok(report)
}

fn write_baselines(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "`{}` at {}×{}: {} fragments, {} covered pixels; output lists sized to the maximum depth complexity.\n",
        report.scene, report.width, report.height, report.fragments, report.covered
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
    write_file(out, "baselines.md", &md)?;
    let json = serde_json::to_string_pretty(&report.baselines).map_err(|e| e.to_string())?;
    write_file(out, "baselines.json", &json)?;
    if !args.json {
        out!("{md}");
        return say_wrote(args, &["baselines.md", "baselines.json"]);
    }
    let context = Context::of_scene("hazard", &args.scene)?;
    for r in &report.baselines {
        let mut context = context.on(&r.executor, 0);
        context.threads = None;
        context.k = Some(Slots::Fixed(r.k));
        let record = BaselineRecord {
            scheme: &r.scheme,
            passes: r.passes,
            overflowed: r.overflowed,
            lost: r.lost,
            extra: r.extra,
            duplicates: r.duplicates,
            misordered_pixels: r.misordered_pixels,
            error_pixels: r.error_pixels,
            error_pixel_rate: r.error_pixels as f64 / report.covered.max(1) as f64,
            memory_bytes: r.memory_bytes,
        };
        crate::record::emit("baseline", &context, &record)?;
    }
    say_wrote(args, &["baselines.md", "baselines.json"])
}

/// Hazard's JSON Lines: one record per row.
fn print_json(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let mut context = Context::of_scene("hazard", &args.scene)?;
    context.k = Some(Slots::Fixed(report.k));
    for r in &report.rows {
        let by_depth_complexity = report
            .buckets
            .iter()
            .zip(&r.rate_by_depth_complexity)
            .map(|((label, n), &rate)| {
                let key = format!("mismatched_pixel_rate_dc_{}", label.replace('–', "_"));
                (key, (*n > 0).then_some(rate))
            })
            .collect();
        let record = HazardRecord {
            scheme: "kbuffer",
            write_back: &r.write_back,
            policy: &r.policy,
            seeds: args.seeds,
            mismatched_pixel_rate: r.rate,
            mismatched_pixel_rate_per_seed: &r.rate_per_seed,
            lost: r.lost,
            extra: r.extra,
            duplicates: r.duplicates,
            misordered_pixels: r.misordered_pixels,
            by_depth_complexity,
        };
        crate::record::emit(
            "hazard",
            &context.on("scheduled", r.threads_in_flight),
            &record,
        )?;
    }
    Ok(())
}

/// What hazard.md's tables mean, under them.
const KEY: &str = "
Key: **W** threads in flight: how many fragments the scheduled executor keeps walking at once, one \
thread each (W = 1 runs each walk alone: no hazard); **write-back** the k-buffer's machine \
(`render-target`: the K slots read in one step and written back in one, write-backs committed in \
order, so only a stale read loses; `separate-stores`: K loads and K stores, one step each, as CUDA \
code does, so write-backs also tear); **policy** how the scheduled executor picks the next step \
(`random`: any thread in flight, uniformly; `warps`: warps of 32 threads in round-robin, one step \
per lane in lane order); **pixels wrong %** covered pixels whose slots differ from the oracle's K \
nearest, in percent, mean over the seeds (JSON: the fraction, `mismatched_pixel_rate`); **per \
seed** the same for each seed, 0, 1, … (`mismatched_pixel_rate_per_seed`); **lost**, **extra**, \
**duplicates** fragments summed over the seeds; **misordered px** pixels whose slots are out of \
order; **dc** a pixel's depth complexity (its fragments), bucketed, with the covered pixels in \
each bucket.
";

/// `rate` (a fraction) as the tables print rates: a percentage.
fn percent(rate: f64) -> String {
    format!("{:.2}", 100.0 * rate)
}

/// Writes `text` to `name` in `out`, naming the file in an error.
fn write_file(out: &std::path::Path, name: &str, text: &str) -> Result<(), String> {
    let path = out.join(name);
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
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
        report.width,
        report.height,
        report.fragments,
        report.covered,
        args.seeds
    );
    let _ = writeln!(
        md,
        "| write-back | policy | W | pixels wrong % (mean) | per seed % | lost | extra | duplicates | misordered px |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---|---:|---:|---:|---:|");
    for r in &report.rows {
        let per_seed: Vec<String> = r.rate_per_seed.iter().map(|&x| percent(x)).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.threads_in_flight,
            percent(r.rate),
            per_seed.join(" "),
            r.lost,
            r.extra,
            r.duplicates,
            r.misordered_pixels
        );
    }
    let _ = writeln!(
        md,
        "\nPixels wrong by depth complexity, % of the bucket's pixels:\n"
    );
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
            .map(|(&x, (_, n))| if *n == 0 { "–".into() } else { percent(x) })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.threads_in_flight,
            cells.join(" | ")
        );
    }
    md.push_str(KEY);
    write_file(out, "hazard.md", &md)?;
    let json = serde_json::to_string_pretty(report).map_err(|e| e.to_string())?;
    write_file(out, "hazard.json", &json)?;
    if args.json {
        print_json(args, report)?;
    } else {
        out!("{md}");
    }
    if args.no_images {
        return say_wrote(args, &["hazard.md", "hazard.json"]);
    }
    let ext = if args.svg { "svg" } else { "png" };
    let mut by_width: Vec<Series> = Vec::new();
    for &write_back in &args.write_back {
        for (_, p) in POLICIES {
            let points = report
                .rows
                .iter()
                .filter(|r| r.policy == p && r.write_back == machine_name(write_back.machine()))
                .map(|r| ((r.threads_in_flight as f64).log2(), 100.0 * r.rate))
                .collect();
            by_width.push((
                format!("{} {p}", machine_name(write_back.machine())),
                points,
            ));
        }
    }
    let vs_width = format!("hazard-vs-width.{ext}");
    chart(
        &out.join(&vs_width),
        &format!(
            "k-buffer (K = {}): pixels wrong vs threads in flight",
            report.k
        ),
        "log2 W (threads in flight)",
        "% of covered pixels wrong",
        &by_width,
        false,
    )
    .map_err(|e| e.to_string())?;
    let by_dc: Vec<Series> = report
        .rows
        .iter()
        .filter(|r| r.threads_in_flight > 1)
        .map(|r| {
            let points = r
                .rate_by_depth_complexity
                .iter()
                .enumerate()
                .filter(|&(i, _)| report.buckets[i].1 > 0)
                .map(|(i, &x)| (i as f64, 100.0 * x))
                .collect();
            (
                format!("{} {} W={}", r.write_back, r.policy, r.threads_in_flight),
                points,
            )
        })
        .collect();
    let ticks: Vec<String> = report
        .buckets
        .iter()
        .map(|(label, n)| format!("{label} ({n} px)"))
        .collect();
    let vs_dc = format!("hazard-vs-depth-complexity.{ext}");
    chart_with_ticks(
        &out.join(&vs_dc),
        (
            &format!(
                "k-buffer (K = {}): pixels wrong vs depth complexity",
                report.k
            ),
            "depth complexity of the pixel (bucket, pixels in it)",
            "% of the bucket's pixels wrong",
        ),
        &by_dc,
        false,
        Some(&ticks),
    )
    .map_err(|e| e.to_string())?;
    say_wrote(args, &["hazard.md", "hazard.json", &vs_width, &vs_dc])
}

/// Says which files went where: on stdout after the tables, on stderr under `--json` (stdout
/// stays JSON Lines).
fn say_wrote(args: &HazardArgs, files: &[&str]) -> Result<(), String> {
    let wrote = format!("wrote {}: {}", args.out.display(), files.join(", "));
    if args.json {
        eprintln!("{wrote}");
    } else {
        outln!("{wrote}");
    }
    Ok(())
}
