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
//! `fragsim_measure::hazard`'s, and so are its JSON Lines records; this module holds the options
//! and what is printed and written where.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::hazard::{report, HazardReport};
use fragsim_measure::hazard::{Campaign, HazardParams};
use fragsim_raster::Conventions;

use crate::args::SceneArgs;
use crate::explain::WriteBackArg;
use crate::record::Context;

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
    for line in report::baseline_records(report, &context)? {
        outln!("{line}");
    }
    say_wrote(args, &["baselines.md", "baselines.json"])
}

/// Hazard's JSON Lines: one record per row.
fn print_json(args: &HazardArgs, report: &HazardReport) -> Result<(), String> {
    let context = Context::of_scene("hazard", &args.scene)?;
    for line in report::records(report, &context, args.seeds)? {
        outln!("{line}");
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
