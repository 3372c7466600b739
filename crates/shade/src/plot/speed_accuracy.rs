//! The speed/accuracy chart: frame time against the error-pixel rate, one marker shape a scheme
//! family, each point numbered and listed in a table beside the chart, the Pareto front joined.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::SaveError;

use super::{
    log_ticks, palette, pareto_front, place_labels, render, tick_label, DrawResult, Marker, Paint,
    Point, FAMILIES,
};

/// The speed/accuracy chart's least size: the chart, and the table of its points beside it
/// (taller where the table needs it).
const WIDE: (u32, u32) = (1280, 640);

/// Width of the column beside the chart: the table, then the legend.
const TABLE_WIDTH: u32 = 440;

/// Pixels between the lines of the table and of the legend (13-pixel text).
const LEGEND_LINE: i32 = 20;

/// The speed/accuracy chart of `points`: frame time on a log axis, the error-pixel rate in
/// percent on another, one marker shape a family ([`Marker::of_family`], the same on every
/// chart), each point numbered (the numbers moved apart where points crowd) and listed in a table
/// beside the chart, and the Pareto front (the points nothing beats on both) joined by a line.
///
/// # Errors
/// The file cannot be written.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a plot has a few dozen points and families"
)]
pub fn speed_accuracy(
    path: &Path,
    title: &str,
    x_label: &str,
    points: &[Point],
) -> Result<(), SaveError> {
    let families = families(points).len() as i32;
    // The table's rows, the legend's (the Pareto line, a family a line) and the note under them.
    let column = 40 + LEGEND_LINE * (points.len() as i32 + 1) + LEGEND_LINE * (families + 2) + 40;
    let size = (WIDE.0, WIDE.1.max(column as u32));
    render(
        path,
        size,
        &SpeedAccuracy {
            title,
            x_label,
            points,
        },
    )
}

struct SpeedAccuracy<'a> {
    title: &'a str,
    x_label: &'a str,
    points: &'a [Point],
}

/// The families of `points`, in [`FAMILIES`] order: the legend's rows.
fn families(points: &[Point]) -> Vec<&'static str> {
    let mut present: Vec<&'static str> = Vec::new();
    for p in points {
        if !present.contains(&p.family) {
            present.push(p.family);
        }
    }
    present.sort_by_key(|&f| FAMILIES.iter().position(|&known| known == f));
    present
}

impl Paint for SpeedAccuracy<'_> {
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a plot has a few dozen points and families"
    )]
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        root.fill(&WHITE)?;
        let (width, height) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(width - TABLE_WIDTH);
        let times = self.points.iter().map(|p| p.time_ms.max(1e-3));
        let lo = times.clone().fold(f64::INFINITY, f64::min);
        let hi = times.fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if lo.is_finite() {
            (lo / 1.5, hi * 1.5)
        } else {
            (0.1, 10.0)
        };
        // EPR on a log axis too (one scheme near 100 % would squash the rest at 0 on a linear
        // one); an exact scheme's 0 is drawn on the floor, a decade under the least rate seen.
        let rates = self.points.iter().map(|p| p.rate * 100.0);
        let top = rates.clone().fold(0.0, f64::max).max(1e-3) * 2.0;
        let least = rates.filter(|&r| r > 0.0).fold(f64::INFINITY, f64::min);
        let floor = if least.is_finite() {
            10_f64.powf(least.log10().floor() - 1.0)
        } else {
            1e-3
        };
        let y = |rate: f64| (rate * 100.0).max(floor);
        let (y_lo, y_hi) = (floor * 0.7, top);
        let mut chart = ChartBuilder::on(&left)
            .caption(self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d(
                (lo..hi).log_scale().with_key_points(log_ticks(lo, hi)),
                (y_lo..y_hi).log_scale().with_key_points(
                    std::iter::once(floor)
                        .chain(log_ticks(y_lo, y_hi).into_iter().filter(|&t| t > floor))
                        .collect(),
                ),
            )?;
        // The floor's tick names what it stands for: a rate of 0, not of `floor` %.
        let rate_label = |v: &f64| {
            if (v / floor - 1.0).abs() < 1e-9 {
                "0 (exact)".to_string()
            } else {
                tick_label(v)
            }
        };
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc("EPR (% of covered pixels, log scale)")
            .x_label_formatter(&tick_label)
            .y_label_formatter(&rate_label)
            .light_line_style(WHITE)
            .bold_line_style(BLACK.mix(0.08))
            .label_style(("sans-serif", 14))
            .draw()?;
        // The floor line, across the plot; its meaning is written under the table, where no
        // point's number can land on it (the fastest exact points sit on this line).
        let (floor_start, floor_end) = (
            chart.backend_coord(&(lo, floor)),
            chart.backend_coord(&(hi, floor)),
        );
        root.draw(&PathElement::new(
            vec![floor_start, floor_end],
            BLACK.mix(0.3).stroke_width(1),
        ))?;
        let front = pareto_front(self.points);
        chart.draw_series(LineSeries::new(
            front
                .iter()
                .map(|&i| (self.points[i].time_ms.max(1e-3), y(self.points[i].rate))),
            BLACK.mix(0.5).stroke_width(2),
        ))?;
        let anchors: Vec<(i32, i32)> = self
            .points
            .iter()
            .map(|p| chart.backend_coord(&(p.time_ms.max(1e-3), y(p.rate))))
            .collect();
        // The numbers: 7 pixels a digit at 13 px, moved up where they would overprint.
        let widths: Vec<i32> = (1..=self.points.len())
            .map(|n| 7 * n.to_string().len() as i32 + 2)
            .collect();
        let labels = place_labels(&anchors, &widths, 14);
        let number_font = ("sans-serif", 13).into_font();
        for (i, p) in self.points.iter().enumerate() {
            Marker::of_family(p.family).draw(root, anchors[i], palette(i))?;
            root.draw(&Text::new(
                (i + 1).to_string(),
                labels[i],
                number_font.clone(),
            ))?;
        }
        // The table beside the chart: number, marker, scheme, time, EPR, mean error; Pareto
        // points starred. Black 13-pixel text (a colour would be pale on white); the marker in
        // the point's colour ties the row to its point.
        let font = ("sans-serif", 13).into_font();
        right.draw(&Text::new(
            "#      scheme   time ms   EPR %   mean err   (* Pareto)",
            (4, 14),
            font.clone(),
        ))?;
        for (i, p) in self.points.iter().enumerate() {
            let row = 14 + LEGEND_LINE * (i as i32 + 1);
            let star = if front.contains(&i) { "*" } else { "" };
            right.draw(&Text::new(
                format!("{}{star}", i + 1),
                (4, row),
                font.clone(),
            ))?;
            Marker::of_family(p.family).draw(&right, (38, row + 7), palette(i))?;
            right.draw(&Text::new(
                format!(
                    "{}   {:.2}   {:.3}   {}",
                    p.label,
                    p.time_ms,
                    p.rate * 100.0,
                    p.mean_error.map_or("n/a".into(), |e| format!("{e:.3}"))
                ),
                (50, row),
                font.clone(),
            ))?;
        }
        // The legend under the table: the Pareto line, then the marker of each family shown.
        let families = families(self.points);
        let legend_top = 14 + LEGEND_LINE * (self.points.len() as i32 + 2) + 7;
        right.draw(&PathElement::new(
            vec![(6, legend_top), (30, legend_top)],
            BLACK.mix(0.5).stroke_width(2),
        ))?;
        right.draw(&Text::new(
            "Pareto front (nothing is both faster and more accurate)",
            (38, legend_top - 7),
            font.clone(),
        ))?;
        for (f, family) in families.iter().enumerate() {
            let at = legend_top + LEGEND_LINE * (f as i32 + 1);
            Marker::of_family(family).draw(&right, (18, at), BLACK)?;
            right.draw(&Text::new(
                format!("family {family}"),
                (38, at - 7),
                font.clone(),
            ))?;
        }
        right.draw(&Text::new(
            "EPR 0 (exact) is drawn on the chart's grey floor line",
            (4, height as i32 - 20),
            font.color(&BLACK.mix(0.8)),
        ))?;
        root.present()
    }
}
