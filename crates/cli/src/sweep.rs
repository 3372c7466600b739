//! `fragsim sweep`: the error-pixel rate of each scheme at many view angles around the model
//! (the bucket depth peeling paper's Figure 6), the colour error over the image and per
//! depth-complexity bucket at each angle, and the speed-versus-accuracy scatter. The measurement
//! is `fragsim_measure::sweep`'s; this module holds the options and the table, records and charts.

use std::path::PathBuf;

use clap::Args;
use fragsim_measure::approximate::ApproximateName;
use fragsim_measure::cells::{bucket_cells, family, mean_of_channels, percent};
use fragsim_measure::colour_by_depth::ColourByDepth;
use fragsim_measure::colour_judge::{ColourColumns, EffectName};
use fragsim_measure::sweep::{SweepParams, SweepReport, SweepSeries};
use fragsim_raster::Conventions;
use serde::Serialize;

use crate::args::{SceneArgs, SchemeArgs, Shard};
use crate::record::Context;
use crate::schemes::SchemeChoice;
use crate::table::Table;

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

/// One line of sweep's JSON Lines: a scheme at one angle (the context carries the angle).
#[derive(Serialize)]
struct SweepRecord<'a> {
    scheme: &'a str,
    effect: &'static str,
    /// `None` where the scheme's words cannot resolve the effect.
    error_pixel_rate: Option<f64>,
    #[serde(flatten)]
    colour: ColourColumns,
    #[serde(flatten)]
    colour_by_depth: &'a ColourByDepth,
    time_ms: f64,
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
    write_outputs(args, &context, &report.angles, &report.series)?;
    Ok(report)
}

fn write_outputs(
    args: &SweepArgs,
    context: &Context,
    angles: &[f64],
    series: &[SweepSeries],
) -> Result<(), String> {
    let scene = &context.scene;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let mut lines = String::new();
    for s in series {
        let measured = angles
            .iter()
            .zip(&s.error_pixel_rate)
            .zip(&s.colour)
            .zip(&s.colour_by_depth)
            .zip(&s.time_ms);
        for ((((&angle, &rate), &colour), colour_by_depth), &time_ms) in measured {
            let record = SweepRecord {
                scheme: &s.scheme,
                effect: args.effect.label(),
                error_pixel_rate: rate,
                colour,
                colour_by_depth,
                time_ms,
            };
            lines.push_str(&crate::record::line(
                "sweep",
                &context.at_angle(angle),
                &record,
            )?);
            lines.push('\n');
        }
    }
    let path = args.out.join("sweep.jsonl");
    std::fs::write(&path, &lines).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let per_angle: Vec<fragsim_shade::plot::Series> = series
        .iter()
        .map(|s| {
            let points = angles
                .iter()
                .zip(&s.error_pixel_rate)
                .filter_map(|(&a, r)| r.map(|r| (a, r * 100.0)))
                .collect();
            (s.scheme.clone(), points)
        })
        .collect();
    let title = format!(
        "{scene}: error pixels of {} per view angle",
        args.effect.label()
    );
    if args.no_images {
        return print_summary(args, series, &lines, &["sweep.jsonl"]);
    }
    fragsim_shade::plot::chart(
        &args.out.join("sweep-epr.png"),
        &title,
        "view angle (degrees)",
        "EPR (% of covered pixels)",
        &per_angle,
        false,
    )
    .map_err(|e| e.to_string())?;
    let scatter: Vec<fragsim_shade::plot::Point> = series
        .iter()
        .filter_map(|s| {
            Some(fragsim_shade::plot::Point {
                label: s.scheme.clone(),
                family: family(&s.scheme),
                time_ms: mean(s.time_ms.iter().copied())?,
                rate: mean(s.error_pixel_rate.iter().flatten().copied())?,
                mean_error: mean(s.colour.iter().filter_map(mean_of_channels)),
            })
        })
        .collect();
    fragsim_shade::plot::speed_accuracy(
        &args.out.join("sweep-speed-accuracy.png"),
        &format!("{scene}: speed against accuracy (means over the sweep)"),
        "mean frame time (ms, log scale)",
        &scatter,
    )
    .map_err(|e| e.to_string())?;
    print_summary(
        args,
        series,
        &lines,
        &["sweep.jsonl", "sweep-epr.png", "sweep-speed-accuracy.png"],
    )
}

/// Prints the JSON Lines or the table, then the files written (on stderr under `--json`, so
/// that stdout stays JSON Lines).
fn print_summary(
    args: &SweepArgs,
    series: &[SweepSeries],
    lines: &str,
    written: &[&str],
) -> Result<(), String> {
    let wrote = format!("wrote {}: {}", args.out.display(), written.join(", "));
    if args.json {
        out!("{lines}");
        eprintln!("{wrote}");
        return Ok(());
    }
    let mut table = Table::new(
        [
            "scheme",
            "mean EPR %",
            "max EPR %",
            "mean err",
            "max err",
            "min PSNR dB",
            "mean ms",
        ]
        .map(String::from)
        .into(),
        1,
    )
    .at_least(vec![20, 12, 12, 10, 8, 12, 12]);
    for s in series {
        let rates: Vec<f64> = s.error_pixel_rate.iter().flatten().copied().collect();
        let mean_rate = mean(rates.iter().copied()).map_or("n/a".into(), |r| percent(r, 4));
        let max_rate = rates
            .iter()
            .copied()
            .reduce(f64::max)
            .map_or("n/a".into(), |r| percent(r, 4));
        let mean_ms = mean(s.time_ms.iter().copied()).unwrap_or(0.0);
        let [mean_error, max_error, psnr] = colour_over_angles(&s.colour);
        table.push(vec![
            s.scheme.clone(),
            mean_rate,
            max_rate,
            mean_error,
            max_error,
            psnr,
            format!("{mean_ms:.2}"),
        ]);
    }
    out!("{}", table.text(1));
    // The two kinds of figure count different things: say which, so that a small rate beside a
    // large error (one pixel far off) reads as it is.
    outln!(
        "EPR: error-pixel rate, the % of covered pixels whose 8-bit colour differs from the \
         oracle's image (never printed as 0 when one differs); err: the absolute difference of a \
         colour channel (0 to 255), mean over the channels and pixels, max of any pixel"
    );
    print_depth_table(series);
    outln!("{wrote}");
    Ok(())
}

/// The mean of `values` (`None`: there are none).
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0_usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The sweep table's colour cells of one scheme: the mean over the angles of the mean absolute
/// error (the channels' mean), the largest error at any angle, and the lowest PSNR (`inf`: every
/// angle's image equal to the oracle's); `n/a` where no angle's image resolves.
fn colour_over_angles(colour: &[ColourColumns]) -> [String; 3] {
    let Some(mean_error) = mean(colour.iter().filter_map(mean_of_channels)) else {
        return ["n/a".into(), "n/a".into(), "n/a".into()];
    };
    let max = colour
        .iter()
        .filter_map(|c| c.max_abs_error)
        .flatten()
        .max()
        .unwrap_or(0);
    let psnr = colour
        .iter()
        .filter_map(|c| c.psnr_db)
        .reduce(f64::min)
        .map_or("inf".into(), |p| format!("{p:.2}"));
    [format!("{mean_error:.3}"), max.to_string(), psnr]
}

/// The sweep's second table: each scheme's colour error per depth-complexity bucket, pooled
/// over the angles ([`SweepSeries::colour_by_depth_over_angles`]); schemes whose images all
/// resolve and all equal the oracle's are left out, as are empty buckets.
fn print_depth_table(series: &[SweepSeries]) {
    let differing = |s: &&SweepSeries| {
        s.colour_by_depth
            .iter()
            .flat_map(ColourByDepth::covered)
            .any(|b| b.error_pixels > 0)
    };
    let mut table = Table::new(
        [
            "scheme",
            "fragments/px",
            "pixels",
            "EPR %",
            "mean err",
            "max err",
            "min PSNR dB",
        ]
        .map(String::from)
        .into(),
        1,
    )
    .at_least(vec![20, 12, 10, 10, 10, 8, 12]);
    for s in series.iter().filter(differing) {
        for bucket in s.colour_by_depth_over_angles() {
            let mut row = vec![s.scheme.clone()];
            row.extend(bucket_cells(&bucket));
            table.push(row);
        }
    }
    if !table.is_empty() {
        outln!(
            "\ncolour error per depth-complexity bucket (fragments per pixel), over every angle"
        );
        out!("{}", table.text(1));
    }
}
