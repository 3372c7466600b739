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

use crate::{DrawError, SaveError};

mod speed_accuracy;

pub use speed_accuracy::speed_accuracy;

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

/// Series and point colours: the tab10 palette with its pale entries (pink, grey, olive, cyan)
/// darkened, so that each reads on white, as a line or a marker.
fn palette(i: usize) -> RGBColor {
    const COLOURS: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(230, 110, 0),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(200, 60, 160),
        RGBColor(90, 90, 90),
        RGBColor(140, 140, 0),
        RGBColor(0, 140, 160),
    ];
    COLOURS[i % COLOURS.len()]
}

/// The scheme families, in the order of their markers ([`Marker::of_family`]): a family keeps
/// its marker on every chart, whichever families a chart holds.
pub const FAMILIES: [&str; 7] = [
    "mdts",
    "a-buffer",
    "peeling",
    "k-buffer",
    "bucket",
    "approximate",
    "other",
];

/// A point's marker shape: seven shapes told apart at a glance, filled or hollow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled disc.
    Disc,
    /// A filled square.
    Square,
    /// A filled triangle.
    Triangle,
    /// A diagonal cross.
    Cross,
    /// A ring (hollow disc).
    Ring,
    /// A hollow triangle.
    HollowTriangle,
    /// A hollow square.
    HollowSquare,
}

impl Marker {
    /// Every marker, in [`FAMILIES`] order.
    pub const ALL: [Self; 7] = [
        Self::Disc,
        Self::Square,
        Self::Triangle,
        Self::Cross,
        Self::Ring,
        Self::HollowTriangle,
        Self::HollowSquare,
    ];

    /// The marker of `family` (one of [`FAMILIES`]; any other is drawn as `other`).
    #[must_use]
    pub fn of_family(family: &str) -> Self {
        let at = FAMILIES.iter().position(|&f| f == family);
        Self::ALL[at.unwrap_or(FAMILIES.len() - 1)]
    }

    /// Draws the marker centred at `at`.
    fn draw<DB: DrawingBackend>(
        self,
        area: &DrawingArea<DB, Shift>,
        at: (i32, i32),
        colour: RGBColor,
    ) -> DrawResult<DB> {
        let (x, y) = at;
        let (filled, line) = (colour.filled(), colour.stroke_width(2));
        let square = [(x - 5, y - 5), (x + 5, y + 5)];
        match self {
            Self::Disc => area.draw(&Circle::new(at, 6, filled)),
            Self::Ring => area.draw(&Circle::new(at, 6, line)),
            Self::Square => area.draw(&Rectangle::new(square, filled)),
            Self::HollowSquare => area.draw(&Rectangle::new(square, line)),
            Self::Triangle => area.draw(&TriangleMarker::new(at, 7, filled)),
            Self::HollowTriangle => area.draw(&PathElement::new(
                vec![(x, y - 7), (x + 6, y + 4), (x - 6, y + 4), (x, y - 7)],
                line,
            )),
            Self::Cross => area.draw(&Cross::new(at, 6, colour.stroke_width(3))),
        }
    }
}

/// Tick values for a log axis over `lo..hi` (both positive): the 1-2-5 values of each decade
/// inside the range, or every unit of the leading digit (1, 2, 3, … 9) where fewer than four
/// of those fall inside: a narrow range still gets several labelled ticks.
#[expect(
    clippy::cast_possible_truncation,
    reason = "decades of plotted values, far within i32"
)]
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let within = |mantissas: &[f64]| -> Vec<f64> {
        let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (first..=last)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10_f64.powi(e)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let coarse = within(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 4 {
        return coarse;
    }
    within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

/// A tick value as a person writes it: `20`, `1.5`, `0.02`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "the decade of a tick, far within i32"
)]
fn tick_label(v: &f64) -> String {
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Where to write each label of `anchors` (pixel positions of points) so that no two overlap:
/// up and to the right of its point, else moved up a line at a time past the labels already
/// placed. `widths` are the labels' widths in pixels, `line` their height.
fn place_labels(anchors: &[(i32, i32)], widths: &[i32], line: i32) -> Vec<(i32, i32)> {
    let mut placed: Vec<(i32, i32, i32)> = Vec::new();
    anchors
        .iter()
        .zip(widths)
        .map(|(&(x, y), &w)| {
            let (left, mut top) = (x + 7, y - 16);
            while placed.iter().any(|&(l, t, pw)| {
                left < l + pw && l < left + w && top < t + line && t < top + line
            }) {
                top -= line;
            }
            placed.push((left, top, w));
            (left, top)
        })
        .collect()
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
) -> Result<(), SaveError> {
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
) -> Result<(), SaveError> {
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
fn render(path: &Path, size: (u32, u32), picture: &impl Paint) -> Result<(), SaveError> {
    register_font();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| SaveError::CreateDir {
            dir: dir.to_path_buf(),
            source,
        })?;
    }
    let error = |source: DrawError| SaveError::Draw {
        path: path.to_path_buf(),
        source,
    };
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        let mut bytes = vec![0_u8; size.0 as usize * size.1 as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut bytes, size).into_drawing_area();
            picture.paint(&root).map_err(|e| error(e.into()))?;
        }
        image::RgbImage::from_raw(size.0, size.1, bytes)
            .expect("the buffer is the chart's size")
            .save(path)
            .map_err(|source| SaveError::Write {
                path: path.to_path_buf(),
                source,
            })
    } else {
        let root = SVGBackend::new(path, size).into_drawing_area();
        picture.paint(&root).map_err(|e| error(e.into()))
    }
}

pub(crate) type DrawResult<DB> =
    Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

#[expect(
    clippy::cast_possible_truncation,
    reason = "i is a whole, non-negative tick index (checked by the guard)"
)]
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
            // A marker of the series' own shape at every measured point (series of equal values
            // drawn over each other still show both shapes); the lines only join them.
            chart.draw_series(LineSeries::new(data.iter().copied(), style))?;
            let shape = series_marker(i);
            for &p in data {
                shape.draw(root, chart.backend_coord(&p), colour)?;
            }
        }
    }
    draw_legend(&legend_area, &names)?;
    root.present()
}

/// The marker of line series `i`: the shapes in turn, so neighbouring series differ in shape as
/// well as colour.
fn series_marker(i: usize) -> Marker {
    Marker::ALL[i % Marker::ALL.len()]
}

/// Pixels the legend column takes: room for the longest name at the legend's font size.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a legend has a few short names"
)]
fn legend_width(names: &[&str]) -> u32 {
    let longest = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    // About 7 pixels a character at 13 px, plus the marker and margins.
    (longest as u32 * 7 + 60).min(400)
}

/// The series' colours and names, one a row, from the top of `area`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a legend has a few short names"
)]
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    names: &[&str],
) -> DrawResult<DB> {
    let font = ("sans-serif", 13).into_font();
    for (i, name) in names.iter().enumerate() {
        let y = 48 + 20 * i as i32;
        let colour = palette(i);
        area.draw(&PathElement::new(
            vec![(6, y), (30, y)],
            colour.stroke_width(2),
        ))?;
        series_marker(i).draw(area, (18, y), colour)?;
        area.draw(&Text::new(name.to_string(), (38, y - 7), font.clone()))?;
    }
    Ok(())
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
        assert_eq!(dark(500..830, 45..130), 0, "something dark over the plot");
        // Two rows of the table, then the legend under them.
        assert!(dark(880..1280, 90..170) > 50, "no legend under the table");
    }

    #[test]
    fn every_family_has_a_marker_of_its_own() {
        let markers: Vec<super::Marker> = super::FAMILIES
            .iter()
            .map(|f| super::Marker::of_family(f))
            .collect();
        for (i, m) in markers.iter().enumerate() {
            assert!(!markers[..i].contains(m), "{m:?} twice");
        }
        assert_eq!(
            super::Marker::of_family("unknown"),
            super::Marker::of_family("other")
        );
    }

    #[test]
    fn a_narrow_log_axis_still_gets_several_ticks_and_crowded_labels_move_apart() {
        // 4.4 to 21 ms: a single decade mark (10) before; now 5, 6, … 20.
        let ticks = super::log_ticks(4.4, 21.0);
        assert!(ticks.len() >= 4, "{ticks:?}");
        assert!(ticks.iter().all(|t| (4.4..=21.0).contains(t)));
        assert_eq!(super::tick_label(&20.0), "20");
        assert_eq!(super::tick_label(&0.05), "0.05");
        assert_eq!(super::tick_label(&1.5), "1.5");
        // Three points on one spot: their labels are stacked, none over another.
        let placed = super::place_labels(&[(100, 100); 3], &[9, 9, 16], 14);
        for (i, a) in placed.iter().enumerate() {
            for b in &placed[..i] {
                assert!((a.1 - b.1).abs() >= 14, "{placed:?}");
            }
        }
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
