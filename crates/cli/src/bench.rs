//! `fragsim bench`: the speed/accuracy trade of every scheme on one scene (the measurement, its
//! Markdown report, terminal tables, JSON Lines records and chart are `fragsim_measure::bench`'s),
//! and what it prints and writes: the records, the terminal tables, bench.md and the chart.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::approximate::ApproximateName;
use fragsim_measure::bench::report::{
    markdown, msaa_terminal_table, records, speed_accuracy_chart, terminal_table,
};
use fragsim_measure::bench::{BenchParams, BenchReport};
use fragsim_measure::colour_judge::EffectName;
use fragsim_measure::images::Images;
use fragsim_raster::Conventions;

use crate::args::{SceneArgs, SchemeArgs, Shard};
use crate::record::Context;
use crate::schemes::SchemeChoice;

/// Options of `fragsim bench`.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// The scene.
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Scheme sizing and executors.
    #[command(flatten)]
    pub schemes: SchemeArgs,
    /// Schemes to run, comma-separated, or `all`.
    #[arg(long, value_delimiter = ',', default_value = "all")]
    pub scheme: Vec<SchemeChoice>,
    /// Frames timed per scheme and executor (the median, min and max are reported).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// The effect whose image is compared with the oracle's.
    #[arg(long, default_value = "transparency")]
    pub effect: EffectName,
    /// Directory for bench.jsonl, bench.md, the images and the speed/accuracy chart (its own,
    /// so that the sweep's files do not mix with the bench's).
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
    /// Print JSON Lines instead of the table: one record per scheme and executor
    /// (`docs/json-schema.md`; bench.jsonl holds the same).
    #[arg(long)]
    pub json: bool,
    /// Write no images (effect images, difference images, the chart); bench.jsonl and bench.md
    /// are still written.
    #[arg(long)]
    pub no_images: bool,
    /// Also measure multisampling at this many samples a pixel (1, 2, 4, 8 or 16: the standard
    /// patterns, `docs/semantics.md` §11): the oracle's transparency image resolved from them
    /// against the single-sample image (`bench-oracle-transparency-msaa<N>.png`, its difference
    /// image and the `msaa` fields), and after the single-sample rows, one `bench-msaa` row per
    /// multisampled scheme against the per-sample oracle: every `--scheme` run per sample
    /// (storage × N), the masked-node A-buffer (`--capacity` nodes a pixel, each carrying a
    /// coverage mask) and the masked-node linked list (a pool of `--capacity` nodes a pixel),
    /// these two on the serial and parallel executors.
    #[arg(long, value_name = "N")]
    pub samples: Option<u32>,
    /// Approximate OIT schemes to measure beside the catalog's, by their transparency image
    /// (`wboit`, `mlab`, `tail-blend`; MLAB and tail blending with `--k` nodes), comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub approximate: Vec<ApproximateName>,
    /// Measure only shard I of N of the rows (cargo-nextest's `count:I/N`): of the (scheme,
    /// executor) rows in `--scheme` × `--executor` order, then the `--approximate` rows, row `k`
    /// (from 0) when `k mod N = I − 1`. The shards' bench.jsonl files together hold the
    /// unsharded bench's rows (times apart; `vs DP` where depth peeling ran in the same shard).
    /// Not with `--samples`.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse, conflicts_with = "samples")]
    pub shard: Option<Shard>,
}

/// Runs `bench`: measures, then writes and prints the report.
///
/// # Errors
/// Scene, parameter or output errors.
pub(crate) fn bench(args: &BenchArgs) -> Result<BenchReport, String> {
    let images = if args.no_images {
        None
    } else {
        let context = Context::of_scene("bench", &args.scene)?;
        Some(Images {
            dir: args.out.clone(),
            scene: format!(
                "{}, view {}°, elevation {}°, {}x{}",
                context.scene,
                args.scene.view,
                args.scene.elevation,
                args.scene.width,
                args.scene.height
            ),
        })
    };
    let params = BenchParams {
        scene: args.scene.spec(Conventions::REFERENCE),
        viewport: args.scene.viewport().map_err(|e| e.to_string())?,
        schemes: SchemeChoice::expand(&args.scheme),
        setup: args.schemes.setup(),
        frames: args.frames,
        effect: args.effect,
        samples: args.samples,
        approximate: args.approximate.clone(),
        shard: args.shard.unwrap_or(Shard::WHOLE),
        images,
    };
    let report = fragsim_measure::bench::bench(&params, &crate::progress::Bars::default())?;
    write_outputs(&report, args)?;
    Ok(report)
}

/// Writes the report's records, Markdown and chart into `--out` and prints its table.
///
/// # Errors
/// A file that cannot be written.
fn write_outputs(report: &BenchReport, args: &BenchArgs) -> Result<(), String> {
    let bench_context = Context::of_scene("bench", &args.scene)?.sized(&args.schemes);
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let lines = records(report, &bench_context)?;
    let json_path = args.out.join("bench.jsonl");
    std::fs::write(&json_path, &lines)
        .map_err(|e| format!("cannot write {}: {e}", json_path.display()))?;
    let markdown = markdown(report);
    let md_path = args.out.join("bench.md");
    std::fs::write(&md_path, &markdown)
        .map_err(|e| format!("cannot write {}: {e}", md_path.display()))?;
    let wrote = if args.no_images {
        format!("wrote {}: bench.jsonl, bench.md", args.out.display())
    } else {
        speed_accuracy_chart(report, &args.out.join("bench-speed-accuracy.png"))?;
        format!(
            "wrote {}: bench.jsonl, bench.md, bench-speed-accuracy.png and the effect and \
             difference images",
            args.out.display()
        )
    };
    // Under `--json` stdout stays JSON Lines: where the files went goes to stderr.
    if args.json {
        out!("{lines}");
        eprintln!("{wrote}");
    } else {
        out!("{}", terminal_table(report));
        if let Some(msaa) = &report.msaa {
            out!("\n{}", msaa_terminal_table(msaa));
        }
        let tables = if report.msaa.is_some() {
            "every column, with their key, the per-depth tables and the multisampled table"
        } else {
            "every column, with their key, and the per-depth tables"
        };
        outln!("{wrote} (bench.md: {tables})");
    }
    Ok(())
}
