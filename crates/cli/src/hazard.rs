//! `fragsim hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows
//! and as depth complexity grows, measured with the scheduled executor, on both machines the
//! k-buffer runs on; and, with `--baselines`, the table of `docs/baselines/kbuffer.md` (passes and
//! losses of the catalog's k-buffer schemes and the stencil-routed A-buffer on every executor).
//!
//! For each machine (`--write-back`: render-target write-backs, separate stores), each policy
//! (uniform random, lockstep warps), each width `W` and each seed, the k-buffer runs the scene one
//! fragment per thread under the scheduled executor, and `Oracle::diff` counts the covered pixels
//! whose list differs from the oracle's `K` nearest (a fragment lost, duplicated or out of order).
//! The measurement and its reports (hazard.md, baselines.md, the charts) are
//! `fragsim_measure::hazard`'s; this module holds the options, the JSON Lines records and what is
//! printed and written where.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::hazard::{report, HazardReport};
use fragsim_measure::hazard::{Campaign, HazardParams};
use fragsim_raster::Conventions;
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
    let md = report::baselines_markdown(report);
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

/// Writes `text` to `name` in `out`, naming the file in an error.
fn write_file(out: &std::path::Path, name: &str, text: &str) -> Result<(), String> {
    let path = out.join(name);
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn write(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let md = report::markdown(report);
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
    let [vs_width, vs_dc] = report::charts(report, out, ext)?;
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
