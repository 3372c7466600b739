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

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans parses"));
    });
}

/// A named series of `(x, y)` points.
pub type Series = (String, Vec<(f64, f64)>);

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
    register_font();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let error = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    let labels = (title, x_label, y_label);
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        let mut bytes = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut bytes, SIZE).into_drawing_area();
            draw(&root, labels, series, scatter).map_err(|e| error(&e))?;
        }
        image::RgbImage::from_raw(SIZE.0, SIZE.1, bytes)
            .expect("the buffer is the chart's size")
            .save(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    } else {
        let root = SVGBackend::new(path, SIZE).into_drawing_area();
        draw(&root, labels, series, scatter).map_err(|e| error(&e))
    }
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    (title, x_label, y_label): (&str, &str, &str),
    series: &[Series],
    scatter: bool,
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
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d(x0.min(if scatter { 0.0 } else { x0 })..x1, y_start..y_end)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, (name, data)) in series.iter().enumerate() {
        let colour = palette(i);
        let style = ShapeStyle::from(&colour).stroke_width(2);
        let drawn = if scatter {
            // The scheme's name beside its point: a scatter of many schemes is read point by point.
            let font = ("sans-serif", 13).into_font().color(&colour);
            chart.draw_series(data.iter().map(|&p| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), 6, style.filled())
                    + Text::new(name.clone(), (9, -16), font.clone())
            }))?
        } else {
            chart.draw_series(LineSeries::new(data.iter().copied(), style))?
        };
        drawn.label(name.clone()).legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(3))
        });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()?;
    root.present()
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
