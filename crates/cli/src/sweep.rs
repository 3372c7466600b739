//! `fragsim sweep`: the error-pixel rate of each scheme at many view angles around the model
//! (the bucket depth peeling paper's Figure 6), the colour error over the image and per
//! depth-complexity bucket at each angle, and the speed-versus-accuracy scatter. The measurement
//! is `fragsim_measure::sweep`'s, and so are its records, tables and charts (`sweep::report`);
//! this module holds the options, and writes and prints them.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::approximate::ApproximateName;
use fragsim_measure::colour_judge::EffectName;
use fragsim_measure::sweep::report::{charts, records, terminal_tables};
use fragsim_measure::sweep::{SweepParams, SweepReport};
use fragsim_raster::Conventions;

use crate::args::{SceneArgs, SchemeArgs, Shard};
use crate::record::Context;
use crate::schemes::SchemeChoice;

/// Options of `fragsim sweep`.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    /// The scene (`--view` is refused: the sweep sets the angle).
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Scheme sizing and executors (the first executor chosen runs).
    #[command(flatten)]
    pub schemes: SchemeArgs,
    /// Schemes to sweep, comma-separated, or `all`.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "bdp,bdp-single,bdp2,adp,mdts-packed,mdts"
    )]
    pub scheme: Vec<SchemeChoice>,
    /// View angles, evenly spaced over a full turn.
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u32).range(1..=3600))]
    pub angles: u32,
    /// The effect whose image is compared with the oracle's.
    #[arg(long, default_value = "transparency")]
    pub effect: EffectName,
    /// Directory for sweep.jsonl and the PNG charts (its own, so that bench's files do not mix
    /// with the sweep's).
    #[arg(long, default_value = "out/sweep")]
    pub out: PathBuf,
    /// Write no charts; sweep.jsonl is still written.
    #[arg(long)]
    pub no_images: bool,
    /// Sweep only shard I of N of the angles (cargo-nextest's `count:I/N`): angle step `k`
    /// (from 0) when `k mod N = I − 1`. The shards' sweep.jsonl files together hold the
    /// unsharded sweep's records (times apart).
    #[arg(long, value_name = "I/N", value_parser = Shard::parse)]
    pub shard: Option<Shard>,
    /// Print JSON Lines instead of the table: one record per scheme and angle
    /// (`docs/json-schema.md`; sweep.jsonl holds the same).
    #[arg(long)]
    pub json: bool,
    /// Approximate OIT schemes swept beside the catalog's, judged by their transparency image
    /// (`wboit`, `mlab`, `tail-blend`; MLAB and tail blending with `--k` nodes), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub approximate: Vec<ApproximateName>,
}

/// Runs `sweep`.
///
/// # Errors
/// Scene, parameter or output errors.
pub(crate) fn sweep(args: &SweepArgs) -> Result<SweepReport, String> {
    let params = SweepParams {
        scene: args.scene.spec(Conventions::REFERENCE),
        viewport: args.scene.viewport().map_err(|e| e.to_string())?,
        schemes: SchemeChoice::expand(&args.scheme),
        setup: args.schemes.setup(),
        angles: args.angles,
        effect: args.effect,
        shard: args.shard.unwrap_or(Shard::WHOLE),
        approximate: args.approximate.clone(),
    };
    let report = fragsim_measure::sweep::sweep(&params, &crate::progress::Bars::default())?;
    let context = Context::of_scene("sweep", &args.scene)?
        .sized(&args.schemes)
        .on(&report.executor, report.threads);
    write_outputs(args, &context, &report)?;
    Ok(report)
}

/// Writes sweep.jsonl and the charts into `--out`, then prints the records or the tables.
fn write_outputs(args: &SweepArgs, context: &Context, report: &SweepReport) -> Result<(), String> {
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let lines = records(report, context, args.effect)?;
    let path = args.out.join("sweep.jsonl");
    std::fs::write(&path, &lines).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let written: &[&str] = if args.no_images {
        &["sweep.jsonl"]
    } else {
        charts(report, &args.out, &context.scene, args.effect)?;
        &["sweep.jsonl", "sweep-epr.png", "sweep-speed-accuracy.png"]
    };
    // Under `--json` stdout stays JSON Lines: where the files went goes to stderr.
    let wrote = format!("wrote {}: {}", args.out.display(), written.join(", "));
    if args.json {
        out!("{lines}");
        eprintln!("{wrote}");
    } else {
        out!("{}", terminal_tables(&report.series));
        outln!("{wrote}");
    }
    Ok(())
}
