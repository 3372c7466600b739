//! What `sweep` reports: its JSON Lines records, the terminal tables (each scheme's error over the
//! angles, its colour error per depth-complexity bucket) and the two charts (the error-pixel
//! rate per angle, speed against accuracy). Text and files, never stdout: the command line
//! prints them.

use std::path::Path;

use fragsim_shade::plot::{chart, speed_accuracy, Point, Series};

use serde::Serialize;

use super::{SweepReport, SweepSeries};
use crate::cells::{bucket_cells, family, mean_of_channels, percent};
use crate::colour_by_depth::ColourByDepth;
use crate::colour_judge::{ColourColumns, EffectName};
use crate::record::{line, Context};
use crate::table::Table;

/// The mean of `values` (`None`: there are none).
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0_usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The sweep's two charts in `dir`, `sweep-epr.png` (each scheme's error-pixel rate of `effect`
/// per angle) and `sweep-speed-accuracy.png` (each scheme's means over the sweep), titled with
/// `scene`.
///
/// # Errors
/// A chart cannot be drawn or written.
pub fn charts(
    report: &SweepReport,
    dir: &Path,
    scene: &str,
    effect: EffectName,
) -> Result<(), String> {
    let per_angle: Vec<Series> = report
        .series
        .iter()
        .map(|s| {
            let points = report
                .angles
                .iter()
                .zip(&s.error_pixel_rate)
                .filter_map(|(&a, r)| r.map(|r| (a, r * 100.0)))
                .collect();
            (s.scheme.clone(), points)
        })
        .collect();
    chart(
        &dir.join("sweep-epr.png"),
        &format!("{scene}: error pixels of {} per view angle", effect.label()),
        "view angle (degrees)",
        "EPR (% of covered pixels)",
        &per_angle,
        false,
    )
    .map_err(|e| e.to_string())?;
    let scatter: Vec<Point> = report
        .series
        .iter()
        .filter_map(|s| {
            Some(Point {
                label: s.scheme.clone(),
                family: family(&s.scheme),
                time_ms: mean(s.time_ms.iter().copied())?,
                rate: mean(s.error_pixel_rate.iter().flatten().copied())?,
                mean_error: mean(s.colour.iter().filter_map(mean_of_channels)),
            })
        })
        .collect();
    speed_accuracy(
        &dir.join("sweep-speed-accuracy.png"),
        &format!("{scene}: speed against accuracy (means over the sweep)"),
        "mean frame time (ms, log scale)",
        &scatter,
    )
    .map_err(|e| e.to_string())
}

/// What `sweep` prints on a terminal: a row per scheme (its error-pixel rate and colour error
/// over the angles, its mean frame time) with the key of its figures, then, where a scheme's
/// images differ from the oracle's, the colour error per depth-complexity bucket.
#[must_use]
pub fn terminal_tables(series: &[SweepSeries]) -> String {
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
    let mut text = table.text(1);
    // The two kinds of figure count different things: say which, so that a small rate beside a
    // large error (one pixel far off) reads as it is.
    text.push_str(
        "EPR: error-pixel rate, the % of covered pixels whose 8-bit colour differs from the \
         oracle's image (never printed as 0 when one differs); err: the absolute difference of a \
         colour channel (0 to 255), mean over the channels and pixels, max of any pixel\n",
    );
    text.push_str(&depth_table(series));
    text
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
/// over the angles ([`SweepSeries::colour_by_depth_over_angles`]), under a blank line and its
/// title; schemes whose images all resolve and all equal the oracle's are left out, as are empty
/// buckets, and the table altogether (an empty string) where no row is left.
fn depth_table(series: &[SweepSeries]) -> String {
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
    if table.is_empty() {
        return String::new();
    }
    format!(
        "\ncolour error per depth-complexity bucket (fragments per pixel), over every angle\n{}",
        table.text(1)
    )
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

/// sweep's JSON Lines (`docs/json-schema.md`; sweep.jsonl holds the same): a `sweep` line per
/// scheme and angle, in `context` (the scene's, sized, on the sweep's executor) at the angle.
///
/// # Errors
/// A record cannot be serialised (a bug).
pub fn records(
    report: &SweepReport,
    context: &Context,
    effect: EffectName,
) -> Result<String, String> {
    let mut lines = String::new();
    for s in &report.series {
        let measured = report
            .angles
            .iter()
            .zip(&s.error_pixel_rate)
            .zip(&s.colour)
            .zip(&s.colour_by_depth)
            .zip(&s.time_ms);
        for ((((&angle, &rate), &colour), colour_by_depth), &time_ms) in measured {
            let record = SweepRecord {
                scheme: &s.scheme,
                effect: effect.label(),
                error_pixel_rate: rate,
                colour,
                colour_by_depth,
                time_ms,
            };
            lines.push_str(&line("sweep", &context.at_angle(angle), &record)?);
            lines.push('\n');
        }
    }
    Ok(lines)
}
