//! `fragsim sweep`: the error-pixel rate of each scheme at many view angles around the model
//! (the bucket depth peeling paper's Figure 6), the colour error over the image and per
//! depth-complexity bucket at each angle, and the speed-versus-accuracy scatter.

use std::path::PathBuf;

use clap::Args;
use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_oracle::Oracle;
use serde::Serialize;

use crate::approximate::ApproximateName;
use crate::args::{SceneArgs, SchemeArgs, Shard};
use crate::colour_judge::{ColourColumns, ColourJudge, EffectName};
use crate::record::{bucket_cells, mean_of_channels, percent, ColourByDepth, Context};
use crate::schemes::{family, SchemeChoice, SchemeRunner};
use fragsim_raster::{Conventions, SceneSpec};
use fragsim_shade::colour_error::{BucketError, ColourError, DEPTH_BUCKETS};

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

/// One scheme's measurements over the sweep.
#[derive(Debug, Clone, Serialize)]
pub struct SweepSeries {
    /// Scheme name.
    pub scheme: String,
    /// Error-pixel rate (over covered pixels) per angle; `None` where the effect is unresolvable.
    pub error_pixel_rate: Vec<Option<f64>>,
    /// The colour error against the oracle's image per angle (`None` fields: unresolvable).
    pub colour: Vec<ColourColumns>,
    /// The same per depth-complexity bucket, per angle (no buckets: unresolvable).
    pub colour_by_depth: Vec<ColourByDepth>,
    /// Frame time per angle, ms.
    pub time_ms: Vec<f64>,
}

impl SweepSeries {
    fn named(scheme: &str) -> Self {
        Self {
            scheme: scheme.into(),
            error_pixel_rate: Vec::new(),
            colour: Vec::new(),
            colour_by_depth: Vec::new(),
            time_ms: Vec::new(),
        }
    }
}

/// Runs `sweep`.
///
/// # Errors
/// Scene, parameter or output errors.
pub(crate) fn sweep(args: &SweepArgs) -> Result<Vec<SweepSeries>, String> {
    let pool = args.schemes.pool()?;
    let spec = args.scene.spec(Conventions::REFERENCE);
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let viewport = args.scene.viewport().map_err(|e| e.to_string())?;
    let executor = args.schemes.executors()[0];
    let mut threads = 0;
    let schemes = SchemeChoice::expand(&args.scheme);
    let mut series: Vec<SweepSeries> = Vec::new();
    let mut angles = Vec::new();
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let steps: Vec<u32> = (0..args.angles)
        .filter(|&step| shard.takes(step as usize))
        .collect();
    let progress = crate::progress::bar(steps.len() as u64, "sweep");
    for step in steps {
        progress.set_message(format!("angle {step}"));
        let angle = 360.0 * f64::from(step) / f64::from(args.angles);
        angles.push(angle);
        let at_angle = SceneSpec {
            view_degrees: angle,
            ..spec.clone()
        };
        let orbit = at_angle.orbit();
        let view = args
            .schemes
            .submission(at_angle.view(&scene, viewport).map_err(|e| e.to_string())?);
        crate::oracle_memory::check(&view, args.schemes.memory_cap).map_err(|e| e.to_string())?;
        let oracle = Oracle::build(&view);
        let judge = ColourJudge::new(args.effect, &scene, &view, orbit, &oracle);
        crate::approximate::check_effect(&judge, &args.approximate)?;
        let depth_complexity = oracle.depth_complexity();
        let sizing = args.schemes.sizing();
        let mut runner = SchemeRunner::default();
        for (i, &name) in schemes.iter().enumerate() {
            let named = pool
                .install(|| runner.run(name, executor, &view, &sizing))
                .map_err(|e| e.to_string())?;
            if series.len() <= i {
                series.push(SweepSeries::named(&named.name));
            }
            let judged = judge.judge(&named.run.capture);
            let rate = judged
                .as_ref()
                .map(|judged| judged.errors as f64 / judge.covered.max(1) as f64);
            series[i].error_pixel_rate.push(rate);
            series[i]
                .colour
                .push(ColourColumns::of(judged.as_ref().map(|j| j.colour)));
            series[i].colour_by_depth.push(ColourByDepth::of(
                judged.as_ref().map(|j| (j.reference, &j.image)),
                &depth_complexity,
            )?);
            series[i].time_ms.push(
                (named.run.stats.pass_time + named.run.stats.resolve_time).as_secs_f64() * 1e3,
            );
            threads = named.run.stats.threads;
        }
        if !args.approximate.is_empty() {
            let order = PrimitiveOrder::of_view(&view);
            let raster_ms = pool
                .install(|| crate::frame_timing::time_raster_alone(&view))
                .as_secs_f64()
                * 1e3;
            let nodes = crate::approximate::nodes(args.schemes.k, &oracle);
            for (j, &scheme) in args.approximate.iter().enumerate() {
                let (row, _) = pool.install(|| {
                    crate::approximate::measure(
                        scheme, nodes, &judge, &oracle, &order, 1, raster_ms,
                    )
                })?;
                let i = schemes.len() + j;
                if series.len() <= i {
                    series.push(SweepSeries::named(&row.scheme));
                }
                series[i].error_pixel_rate.push(Some(row.error_pixel_rate));
                series[i].colour.push(row.colour);
                series[i].colour_by_depth.push(row.colour_by_depth);
                series[i].time_ms.push(row.time_ms);
            }
        }
        progress.inc(1);
    }
    progress.finish_and_clear();
    let context = Context::of_scene("sweep", &args.scene)?
        .sized(&args.schemes)
        .on(executor.name(), threads);
    write_outputs(args, &context, &angles, &series)?;
    Ok(series)
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
    outln!(
        "{:<20} {:>12} {:>12} {:>10} {:>8} {:>12} {:>12}",
        "scheme",
        "mean EPR %",
        "max EPR %",
        "mean err",
        "max err",
        "min PSNR dB",
        "mean ms"
    );
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
        outln!(
            "{:<20} {:>12} {:>12} {:>10} {:>8} {:>12} {:>12.2}",
            s.scheme,
            mean_rate,
            max_rate,
            mean_error,
            max_error,
            psnr,
            mean_ms
        );
    }
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
/// over the angles ([`pooled_over_angles`]); schemes whose images all resolve and all equal the
/// oracle's are left out, as are empty buckets.
fn print_depth_table(series: &[SweepSeries]) {
    let differing = |s: &&SweepSeries| {
        s.colour_by_depth
            .iter()
            .flat_map(ColourByDepth::covered)
            .any(|b| b.error_pixels > 0)
    };
    let mut header = true;
    for s in series.iter().filter(differing) {
        if std::mem::take(&mut header) {
            outln!(
                "\ncolour error per depth-complexity bucket (fragments per pixel), over every angle"
            );
            outln!(
                "{:<20} {:>12} {:>10} {:>10} {:>10} {:>8} {:>12}",
                "scheme",
                "fragments/px",
                "pixels",
                "EPR %",
                "mean err",
                "max err",
                "min PSNR dB"
            );
        }
        for bucket in pooled_over_angles(&s.colour_by_depth) {
            let [label, pixels, rate, mean, max, psnr] = bucket_cells(&bucket);
            outln!(
                "{:<20} {label:>12} {pixels:>10} {rate:>10} {mean:>10} {max:>8} {psnr:>12}",
                s.scheme
            );
        }
    }
}

/// One scheme's buckets over every angle: pixels and error pixels summed, the mean absolute
/// error weighted by each angle's pixels (so it is the mean over every pixel of every angle in
/// the bucket), the largest error, and the lowest PSNR of any angle; buckets without a pixel at
/// any angle are left out.
fn pooled_over_angles(angles: &[ColourByDepth]) -> Vec<BucketError> {
    DEPTH_BUCKETS
        .iter()
        .enumerate()
        .filter_map(|(i, &(lo, hi))| {
            let at_angles: Vec<(u64, u64, ColourError)> = angles
                .iter()
                .filter_map(|a| a.buckets.get(i))
                .filter_map(|b| Some((b.pixels, b.error_pixels, b.error?)))
                .collect();
            let pixels: u64 = at_angles.iter().map(|a| a.0).sum();
            (pixels > 0).then(|| {
                let weighted = |c: usize| {
                    at_angles
                        .iter()
                        .map(|(n, _, e)| e.mean_abs[c] * *n as f64)
                        .sum::<f64>()
                        / pixels as f64
                };
                let largest = |c: usize| at_angles.iter().map(|(_, _, e)| e.max_abs[c]).max();
                BucketError {
                    lo,
                    hi,
                    pixels,
                    error_pixels: at_angles.iter().map(|a| a.1).sum(),
                    error: Some(ColourError {
                        mean_abs: [0, 1, 2].map(weighted),
                        max_abs: [0, 1, 2].map(|c| largest(c).unwrap_or(0)),
                        psnr_db: at_angles
                            .iter()
                            .map(|(_, _, e)| e.psnr_db)
                            .fold(f64::INFINITY, f64::min),
                    }),
                }
            })
        })
        .collect()
}
