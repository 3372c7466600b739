//! Charts of measured results through plotters: PNG (the bitmap backend, encoded by `image`) or
//! SVG, chosen by the file's extension.
//!
//! Text is laid out with DejaVu Sans, embedded in the binary (`assets/DejaVuSans.ttf`, under the
//! Bitstream Vera licence beside it, which allows redistribution with software), so charts need
//! no system fonts.

use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

/// DejaVu Sans (Bitstream Vera licence: `assets/DejaVuSans-LICENSE.txt`).
const FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Chart size in pixels.
const SIZE: (u32, u32) = (900, 560);

pub(crate) fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans parses"));
    });
}

/// A named series of `(x, y)` points.
pub type Series = (String, Vec<(f64, f64)>);

/// One scheme on a speed/accuracy chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// What the table beside the chart calls it (`mdts (parallel)`).
    pub label: String,
    /// Its family: one marker shape a family.
    pub family: &'static str,
    /// Frame time, ms (drawn on a log axis).
    pub time_ms: f64,
    /// Error-pixel rate, a fraction (drawn as a percentage).
    pub rate: f64,
    /// The image's mean absolute colour error (8-bit units, the mean of the channels'), printed
    /// in the table beside the chart: EPR counts the pixels that differ, this says by how much
    /// (`None`: not measured).
    pub mean_error: Option<f64>,
}

/// The points no other point beats on both time and rate (ties kept), fastest first: the
/// schemes worth choosing.
#[must_use]
pub fn pareto_front(points: &[Point]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a]
            .time_ms
            .total_cmp(&points[b].time_ms)
            .then(points[a].rate.total_cmp(&points[b].rate))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].rate < best {
            best = points[i].rate;
            front.push(i);
        }
    }
    front
}

fn palette(i: usize) -> RGBColor {
    const COLOURS: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    COLOURS[i % COLOURS.len()]
}

fn range(values: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let lo = values.clone().fold(f64::INFINITY, f64::min);
    let hi = values.fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    if hi > lo {
        (lo, hi + (hi - lo) * 0.05)
    } else {
        (lo - 0.5, hi + 0.5)
    }
}

/// Draws `series` as lines (`scatter = false`) or labelled points (`scatter = true`) into a PNG
/// file (a path ending in `.png`) or an SVG file (any other).
///
/// # Errors
/// The file cannot be written.
pub fn chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    scatter: bool,
) -> Result<(), String> {
    chart_with_ticks(path, (title, x_label, y_label), series, scatter, None)
}

/// [`chart`] with the x axis labelled by `ticks` (`ticks[i]` at `x = i`, only there) instead
/// of numbers: the axis of discrete buckets.
///
/// # Errors
/// The file cannot be written.
pub fn chart_with_ticks(
    path: &Path,
    labels: (&str, &str, &str),
    series: &[Series],
    scatter: bool,
    ticks: Option<&[String]>,
) -> Result<(), String> {
    let lines = Lines {
        labels,
        series,
        scatter,
        ticks,
    };
    render(path, SIZE, &lines)
}

/// A picture drawn the same on any plotters backend.
trait Paint {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB>;
}

/// A line chart or a scatter ([`chart_with_ticks`]).
struct Lines<'a> {
    labels: (&'a str, &'a str, &'a str),
    series: &'a [Series],
    scatter: bool,
    ticks: Option<&'a [String]>,
}

impl Paint for Lines<'_> {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        draw(root, self.labels, self.series, self.scatter, self.ticks)
    }
}

/// Draws `picture` into a PNG file (a path ending in `.png`) or an SVG file (any other) of
/// `size` pixels, creating its directory.
fn render(path: &Path, size: (u32, u32), picture: &impl Paint) -> Result<(), String> {
    register_font();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let error = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        let mut bytes = vec![0u8; size.0 as usize * size.1 as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut bytes, size).into_drawing_area();
            picture.paint(&root).map_err(|e| error(&e))?;
        }
        image::RgbImage::from_raw(size.0, size.1, bytes)
            .expect("the buffer is the chart's size")
            .save(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    } else {
        let root = SVGBackend::new(path, size).into_drawing_area();
        picture.paint(&root).map_err(|e| error(&e))
    }
}

pub(crate) type DrawResult<DB> =
    Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (title, x_label, y_label): (&str, &str, &str),
    series: &[Series],
    scatter: bool,
    ticks: Option<&[String]>,
) -> DrawResult<DB> {
    let points = || series.iter().flat_map(|(_, p)| p.iter().copied());
    let (x0, x1) = range(points().map(|p| p.0));
    let (y0, y1) = range(points().map(|p| p.1));
    // Rates and times are never negative: the axis starts at 0 (and spans 1 when all are 0).
    let y_start = if points().all(|p| p.1 >= 0.0) {
        0.0
    } else {
        y0.min(0.0)
    };
    let y_end = if y1 > y_start { y1 } else { y_start + 1.0 };
    root.fill(&WHITE)?;
    // The legend in a column of its own beside the plot: drawn inside, it hid the lines it named.
    let names: Vec<&str> = series.iter().map(|(name, _)| name.as_str()).collect();
    let (plot_area, legend_area) =
        root.split_horizontally(root.dim_in_pixel().0 - legend_width(&names));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(x0.min(if scatter { 0.0 } else { x0 })..x1, y_start..y_end)?;
    // A bucket's name at its integer position only: the axis is discrete.
    let tick = |x: &f64| {
        let i = x.round();
        match ticks {
            Some(ticks) if (x - i).abs() < 1e-6 && i >= 0.0 => {
                ticks.get(i as usize).cloned().unwrap_or_default()
            }
            _ => String::new(),
        }
    };
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 14));
    if let Some(ticks) = ticks {
        mesh.x_label_formatter(&tick).x_labels(ticks.len() * 2 + 1);
    }
    mesh.draw()?;
    for (i, (name, data)) in series.iter().enumerate() {
        let colour = palette(i);
        let style = ShapeStyle::from(&colour).stroke_width(2);
        if scatter {
            // The scheme's name beside its point: a scatter of many schemes is read point by point.
            let font = ("sans-serif", 13).into_font().color(&colour);
            chart.draw_series(data.iter().map(|&p| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), 6, style.filled())
                    + Text::new(name.clone(), (9, -16), font.clone())
            }))?;
        } else {
            // A dot at every measured point: the lines only join them.
            chart.draw_series(data.iter().map(|&p| Circle::new(p, 3, style.filled())))?;
            chart.draw_series(LineSeries::new(data.iter().copied(), style))?;
        }
    }
    draw_legend(&legend_area, &names)?;
    root.present()
}

/// Pixels the legend column takes: room for the longest name at the legend's font size.
fn legend_width(names: &[&str]) -> u32 {
    let longest = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    // About 7 pixels a character at 13 px, plus the colour swatch and margins.
    (longest as u32 * 7 + 56).min(400)
}

/// The series' colours and names, one a row, from the top of `area`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    names: &[&str],
) -> DrawResult<DB> {
    let font = ("sans-serif", 13).into_font();
    for (i, name) in names.iter().enumerate() {
        let y = 48 + 20 * i as i32;
        let colour = palette(i);
        area.draw(&PathElement::new(
            vec![(8, y), (28, y)],
            colour.stroke_width(3),
        ))?;
        area.draw(&Circle::new((18, y), 3, colour.filled()))?;
        area.draw(&Text::new(name.to_string(), (34, y - 7), font.clone()))?;
    }
    Ok(())
}

/// The speed/accuracy chart's size: the chart, and the table of its points beside it.
const WIDE: (u32, u32) = (1280, 640);

/// Pixels between the lines of the speed/accuracy chart's legend.
const LEGEND_LINE: i32 = 20;

/// The speed/accuracy chart of `points`: frame time on a log axis, the error-pixel rate in
/// percent, one marker shape a family, each point numbered and listed in a table beside the
/// chart (labels beside points collide when many schemes are exact), and the Pareto front (the
/// points nothing beats on both) joined by a line.
///
/// # Errors
/// The file cannot be written.
pub fn speed_accuracy(
    path: &Path,
    title: &str,
    x_label: &str,
    points: &[Point],
) -> Result<(), String> {
    render(
        path,
        WIDE,
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

/// The families in order of first appearance: a family's index picks its marker.
fn families(points: &[Point]) -> Vec<&'static str> {
    let mut seen = Vec::new();
    for p in points {
        if !seen.contains(&p.family) {
            seen.push(p.family);
        }
    }
    seen
}

/// Marker `shape` (0 circle, 1 triangle, 2 square, 3 cross, then filled/hollow variants) at `at`.
fn marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    shape: usize,
    colour: RGBColor,
) -> DrawResult<DB> {
    let filled = shape < 4;
    let style = if filled {
        colour.filled()
    } else {
        colour.stroke_width(2)
    };
    match shape % 4 {
        0 => area.draw(&Circle::new(at, 6, style)),
        1 => area.draw(&TriangleMarker::new(at, 7, style)),
        2 => area.draw(&Rectangle::new(
            [(at.0 - 5, at.1 - 5), (at.0 + 5, at.1 + 5)],
            style,
        )),
        _ => area.draw(&Cross::new(at, 6, colour.stroke_width(3))),
    }
}

impl Paint for SpeedAccuracy<'_> {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        root.fill(&WHITE)?;
        let (left, right) = root.split_horizontally(WIDE.0 - 400);
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
            10f64.powf(least.log10().floor() - 1.0)
        } else {
            1e-3
        };
        let y = |rate: f64| (rate * 100.0).max(floor);
        let mut chart = ChartBuilder::on(&left)
            .caption(self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d((lo..hi).log_scale(), (floor * 0.7..top).log_scale())?;
        let whole = |v: &f64| format!("{v:.0}");
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc("EPR (% of covered pixels, log scale)")
            .x_labels(6)
            .y_labels(8)
            .x_label_formatter(&whole)
            .light_line_style(WHITE)
            .label_style(("sans-serif", 14))
            .draw()?;
        // The floor line's meaning is written in the table's column, under the table, where no
        // point's number can land on it (the fastest exact points sit on this line).
        let bottom = chart.backend_coord(&(lo, floor));
        root.draw(&PathElement::new(
            vec![bottom, (bottom.0 + (WIDE.0 as i32 - 520), bottom.1)],
            BLACK.mix(0.3).stroke_width(1),
        ))?;
        let front = pareto_front(self.points);
        chart.draw_series(LineSeries::new(
            front
                .iter()
                .map(|&i| (self.points[i].time_ms.max(1e-3), y(self.points[i].rate))),
            BLACK.mix(0.5).stroke_width(2),
        ))?;
        let families = families(self.points);
        for (i, p) in self.points.iter().enumerate() {
            let at = chart.backend_coord(&(p.time_ms.max(1e-3), y(p.rate)));
            let shape = families.iter().position(|&f| f == p.family).unwrap_or(0);
            let colour = palette(i);
            marker(root, at, shape, colour)?;
            root.draw(&Text::new(
                (i + 1).to_string(),
                (at.0 + 7, at.1 - 16),
                ("sans-serif", 12).into_font().color(&colour),
            ))?;
        }
        // The legend in the column beside the chart, under the table (drawn inside the chart, it
        // hid the points of slow, inaccurate schemes): the Pareto line, then a marker a family.
        let legend_top = WIDE.1 as i32 - 40 - LEGEND_LINE * (families.len() as i32 + 1);
        let legend_font = ("sans-serif", 13).into_font();
        right.draw(&PathElement::new(
            vec![(6, legend_top), (22, legend_top)],
            BLACK.mix(0.5).stroke_width(2),
        ))?;
        right.draw(&Text::new(
            "Pareto front (nothing is both faster and more accurate)",
            (30, legend_top - 7),
            legend_font.clone(),
        ))?;
        for (f, family) in families.iter().enumerate() {
            let at = legend_top + LEGEND_LINE * (f as i32 + 1);
            marker(&right, (14, at), f, BLACK)?;
            right.draw(&Text::new(
                format!("family {family}"),
                (30, at - 7),
                legend_font.clone(),
            ))?;
        }
        // The table: number, scheme, time, EPR, mean error; Pareto points starred; above the
        // legend.
        let rows = self.points.len().max(1) as i32;
        let line = ((legend_top - 40) / (rows + 1)).clamp(8, 20);
        let size = (line - 4).clamp(8, 14);
        let font = ("sans-serif", size).into_font();
        right.draw(&Text::new(
            "#  scheme  time ms  EPR %  mean err  (* Pareto)",
            (4, 14),
            font.clone(),
        ))?;
        for (i, p) in self.points.iter().enumerate() {
            let y = 14 + line * (i as i32 + 1);
            let star = if front.contains(&i) { "*" } else { " " };
            right.draw(&Text::new(
                format!(
                    "{}{star} {}  {:.2}  {:.3}  {}",
                    i + 1,
                    p.label,
                    p.time_ms,
                    p.rate * 100.0,
                    p.mean_error.map_or("n/a".into(), |e| format!("{e:.3}"))
                ),
                (4, y),
                font.clone().color(&palette(i)),
            ))?;
        }
        right.draw(&Text::new(
            "EPR 0 (exact) is drawn on the chart's grey floor line",
            (4, WIDE.1 as i32 - 16),
            ("sans-serif", 13).into_font().color(&BLACK.mix(0.7)),
        ))?;
        root.present()
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn writes_an_svg_with_the_labels() {
        let path = std::env::temp_dir().join(format!("fragsim-plot-{}.svg", std::process::id()));
        let series = vec![
            ("a".to_string(), vec![(0.0, 1.0), (1.0, 2.0)]),
            ("b".to_string(), vec![(0.5, 0.5)]),
        ];
        super::chart(&path, "title", "x", "y", &series, false).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.contains("<svg") && svg.contains("title"));
        std::fs::remove_file(path).unwrap();
    }

    /// The legend is drawn in the column beside the chart, under the table, not over the
    /// plot: with a fast inaccurate point and a slow exact one, the plot's upper right (where
    /// the legend's box was, and where slow inaccurate schemes land) has no dark pixel, and
    /// the column's lower part has the legend's.
    #[test]
    fn the_speed_accuracy_legend_sits_beside_the_plot() {
        let path = std::env::temp_dir().join(format!("fragsim-legend-{}.png", std::process::id()));
        let point = |label: &str, family, time_ms, rate| super::Point {
            label: label.into(),
            family,
            time_ms,
            rate,
            mean_error: Some(rate),
        };
        let points = [point("fast", "a", 1.0, 0.9), point("slow", "b", 100.0, 0.0)];
        super::speed_accuracy(&path, "title", "x", &points).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        std::fs::remove_file(&path).unwrap();
        let dark = |xs: std::ops::Range<u32>, ys: std::ops::Range<u32>| {
            xs.flat_map(|x| ys.clone().map(move |y| (x, y)))
                .filter(|&(x, y)| image.get_pixel(x, y).0.iter().all(|&c| c < 100))
                .count()
        };
        assert_eq!(dark(500..860, 45..130), 0, "something dark over the plot");
        assert!(dark(880..1280, 500..600) > 50, "no legend under the table");
    }

    #[test]
    fn writes_a_png_with_text_and_no_system_fonts() {
        let path = std::env::temp_dir().join(format!("fragsim-plot-{}.png", std::process::id()));
        let series = vec![("a".to_string(), vec![(1.0, 0.5)])];
        super::chart(&path, "title", "x", "y", &series, true).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), super::SIZE);
        // The caption's glyphs are drawn: dark pixels in the top band, which is otherwise white.
        let dark = (0..super::SIZE.0)
            .flat_map(|x| (0..30).map(move |y| (x, y)))
            .filter(|&(x, y)| image.get_pixel(x, y)[0] < 128)
            .count();
        assert!(dark > 20, "{dark} dark pixels in the caption band");
        std::fs::remove_file(path).unwrap();
    }
}
