//! Charts of measured results, as SVG through plotters (text needs no font files in SVG).

use std::path::Path;

use plotters::prelude::*;

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

/// Draws `series` as lines (`scatter = false`) or points (`scatter = true`) into an SVG file.
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
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let points = || series.iter().flat_map(|(_, p)| p.iter().copied());
    let (x0, x1) = range(points().map(|p| p.0));
    let (y0, y1) = range(points().map(|p| p.1));
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    let error = |e: &dyn std::fmt::Display| format!("cannot draw {}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| error(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0.min(0.0)..y1)
        .map_err(|e| error(&e))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()
        .map_err(|e| error(&e))?;
    for (i, (name, data)) in series.iter().enumerate() {
        let colour = palette(i);
        let style = ShapeStyle::from(&colour).stroke_width(2);
        let drawn = if scatter {
            chart.draw_series(data.iter().map(|&p| Circle::new(p, 5, style.filled())))
        } else {
            chart.draw_series(LineSeries::new(data.iter().copied(), style))
        };
        drawn
            .map_err(|e| error(&e))?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(3))
            });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| error(&e))?;
    root.present().map_err(|e| error(&e))
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
}
