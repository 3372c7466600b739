//! `fragsim bench`: the speed/accuracy trade of every scheme on one scene (the measurement, its
//! Markdown report and chart are `fragsim_measure::bench`'s), and what it prints and writes: its
//! JSON Lines records, the terminal tables, bench.md and the chart.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::approximate::{ApproximateName, ApproximateRow};
use fragsim_measure::bench::report::{markdown, msaa_markdown, speed_accuracy_chart};
use fragsim_measure::bench::{BenchParams, BenchReport, BenchRow};
use fragsim_measure::cells::percent;
use fragsim_measure::colour_judge::EffectName;
use fragsim_measure::images::Images;
use fragsim_measure::multisampled::{MsaaReport, SampledRow};
use fragsim_raster::Conventions;
use serde::Serialize;

use crate::args::{SceneArgs, SchemeArgs, Shard};
use crate::record::Context;
use crate::schemes::SchemeChoice;
use crate::table::{Column, Table};

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

/// One line of bench's JSON Lines: a row with what the whole bench measured.
#[derive(Serialize)]
struct BenchRecord<'a> {
    #[serde(flatten)]
    row: &'a BenchRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// One line of bench's JSON Lines for an approximate scheme: its row with what the whole bench
/// measured.
#[derive(Serialize)]
struct ApproximateRecord<'a> {
    #[serde(flatten)]
    row: &'a ApproximateRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// One line of bench's JSON Lines for a multisampled scheme (`--samples`): its row with what the
/// whole bench measured.
#[derive(Serialize)]
struct SampledRecord<'a> {
    #[serde(flatten)]
    row: &'a SampledRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// Writes the report's records, Markdown and chart into `--out` and prints its table.
///
/// # Errors
/// A file that cannot be written.
fn write_outputs(report: &BenchReport, args: &BenchArgs) -> Result<(), String> {
    let bench_context = Context::of_scene("bench", &args.scene)?.sized(&args.schemes);
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let mut lines = String::new();
    for row in &report.rows {
        let context = bench_context.on(&row.executor, row.threads);
        let record = BenchRecord { row, bench: report };
        lines.push_str(&crate::record::line("bench", &context, &record)?);
        lines.push('\n');
    }
    for row in &report.approximate {
        let context = bench_context.on("primitive-order", row.threads);
        let record = ApproximateRecord { row, bench: report };
        lines.push_str(&crate::record::line(
            "bench-approximate",
            &context,
            &record,
        )?);
        lines.push('\n');
    }
    for row in report.msaa.iter().flat_map(|m| &m.rows) {
        let context = bench_context.on(&row.executor, row.threads);
        let record = SampledRecord { row, bench: report };
        lines.push_str(&crate::record::line("bench-msaa", &context, &record)?);
        lines.push('\n');
    }
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

/// What bench prints on a terminal: the scene line of bench.md and the columns a reader scans
/// first, aligned, in about 120 characters (bench.md holds all 26).
fn terminal_table(report: &BenchReport) -> String {
    let columns: [Column<BenchRow>; 10] = [
        ("scheme", |r| r.scheme.clone()),
        ("executor", |r| r.executor.clone()),
        ("passes", |r| r.passes.to_string()),
        ("B/px", |r| format!("{:.1}", r.bytes_per_pixel)),
        ("lost", |r| r.lost.to_string()),
        ("mismatched px", |r| r.mismatched_pixels.to_string()),
        ("EPR %", |r| {
            r.error_pixel_rate
                .map_or_else(|| "n/a".into(), |e| percent(e, 3))
        }),
        ("PSNR dB", |r| r.colour.cells()[2].clone()),
        ("frame ms", |r| format!("{:.2}", r.time_ms)),
        ("vs DP", |r| {
            r.speedup_vs_depth_peeling
                .map_or_else(|| "n/a".into(), |v| format!("{v:.2}"))
        }),
    ];
    let mut text = markdown(report)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    text.push_str("\n\n");
    text.push_str(&Table::of(&columns, &report.rows, 2).text(2));
    text.push_str(
        "Columns: passes geometry passes a frame; B/px storage bytes a pixel; lost fragments it \
         should have kept; mismatched px pixels whose list differs from the oracle's; EPR % \
         pixels whose 8-bit colour of the effect differs, in % of the covered pixels; PSNR dB of \
         that image; frame ms the median frame; vs DP speed-up over depth peeling.\n",
    );
    text
}

/// What `bench --samples` prints on a terminal under the single-sample table: the line of
/// bench.md that opens the multisampled table, and its columns a reader scans first, aligned
/// (bench.md holds every column and their key).
fn msaa_terminal_table(msaa: &MsaaReport) -> String {
    let columns: [Column<SampledRow>; 10] = [
        ("scheme", |r| r.scheme.clone()),
        ("storage", |r| r.storage.to_string()),
        ("executor", |r| r.executor.clone()),
        ("passes", |r| r.passes.to_string()),
        ("B/px", |r| format!("{:.1}", r.bytes_per_pixel)),
        ("overflow", |r| {
            format!("{} {}", r.overflowed, r.overflow_unit)
        }),
        ("lost", |r| r.lost.to_string()),
        ("wrong samples", |r| r.wrong_samples.to_string()),
        ("EPR %", |r| {
            r.error_pixel_rate
                .map_or_else(|| "n/a".into(), |e| percent(e, 3))
        }),
        ("frame ms", |r| format!("{:.2}", r.time_ms)),
    ];
    let mut text = msaa_markdown(msaa)
        .lines()
        .find(|line| !line.is_empty())
        .unwrap_or_default()
        .to_string();
    text.push_str("\n\n");
    text.push_str(&Table::of(&columns, &msaa.rows, 3).text(2));
    text.push_str(
        "Columns: overflow what found no room (sample fragments, or whole masked nodes); lost \
         sample fragments the scheme owed and is missing (per-sample storage: beyond the \
         overflow); wrong samples samples whose list differs from the per-sample oracle's; the \
         rest as above.\n",
    );
    text
}
