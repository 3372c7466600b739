//! Images read at a glance: a picture with a panel beside it that says what its colours mean
//! (the heat map's colour bar with units, the nearest depth's near/far key, a difference
//! image's legend) and, for differences, zoomed insets of the first differing pixels with
//! their places marked, so that one wrong pixel in 512 × 512 is seen.
//!
//! Guarantee: the picture's own pixels are copied unchanged into the top-left corner of the
//! figure, but for the rings drawn around marked pixels (never on the pixel itself);
//! everything else is the panel. Text is
//! drawn with the charts' embedded font ([`crate::plot`]).

use image::{Rgb, RgbImage};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::DrawError;

/// Width of the panel beside the picture, in pixels.
const PANEL: u32 = 260;
/// The least height of a figure: a panel's text needs it beside a small picture.
const MIN_HEIGHT: u32 = 300;

/// `picture` with a panel of [`PANEL`] pixels at its right, filled by `panel` (given the
/// panel's area and the picture's size), and any `below` height of panel under the picture.
fn figure(
    picture: &RgbImage,
    below: u32,
    panel: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), DrawError>,
) -> Result<RgbImage, DrawError> {
    crate::plot::register_font();
    let (w, h) = picture.dimensions();
    let size = (w + PANEL, (h + below).max(MIN_HEIGHT));
    let mut out = RgbImage::from_pixel(size.0, size.1, Rgb([255, 255, 255]));
    for (x, y, p) in picture.enumerate_pixels() {
        out.put_pixel(x, y, *p);
    }
    {
        let root = BitMapBackend::with_buffer(&mut out, size).into_drawing_area();
        panel(&root)?;
        root.present().map_err(DrawError::from)?;
    }
    Ok(out)
}

fn text<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &str,
    at: (i32, i32),
    size: i32,
) -> Result<(), DrawError> {
    area.draw(&Text::new(
        s.to_string(),
        at,
        ("sans-serif", size).into_font(),
    ))
    .map_err(DrawError::from)
}

fn fill<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    corners: [(i32, i32); 2],
    colour: Rgb<u8>,
) -> Result<(), DrawError> {
    let [r, g, b] = colour.0;
    area.draw(&Rectangle::new(corners, RGBColor(r, g, b).filled()))
        .map_err(DrawError::from)
}

/// The depth-complexity heat map of `counts` with a colour bar: `scale_max` fixes the count
/// drawn white (counts above it are white too, the bar says `≥`), so that maps of different
/// scenes compare; `None` scales to this image's maximum, and the bar says so.
///
/// # Errors
/// Text cannot be drawn (a font error).
#[expect(
    clippy::cast_possible_truncation,
    reason = "tick rows lie between the bar's top and bottom, within the picture"
)]
pub fn heat_map_with_bar(
    width: u32,
    height: u32,
    counts: &[u32],
    scale_max: Option<u32>,
) -> Result<RgbImage, DrawError> {
    let max_seen = counts.iter().copied().max().unwrap_or(0);
    let top = scale_max.unwrap_or(max_seen).max(1);
    let picture = crate::heat_map_scaled(width, height, counts, top);
    let x0 = width as i32 + 20;
    figure(&picture, 0, |area| {
        text(area, "depth complexity", (x0, 8), 16)?;
        text(area, "(fragments per pixel)", (x0, 28), 13)?;
        let (bar_top, bar_bottom) = (56, 256);
        for y in bar_top..=bar_bottom {
            let t = (bar_bottom - y) as f32 / (bar_bottom - bar_top) as f32;
            fill(area, [(x0, y), (x0 + 24, y + 1)], crate::ramp(t))?;
        }
        for value in bar_ticks(top) {
            let y = bar_bottom - ((bar_bottom - bar_top) as f32 * value as f32 / top as f32) as i32;
            fill(area, [(x0 + 24, y), (x0 + 30, y + 1)], Rgb([0, 0, 0]))?;
            let label = if value == top && max_seen > top {
                format!("≥ {value}")
            } else {
                value.to_string()
            };
            text(area, &label, (x0 + 34, y - 7), 13)?;
        }
        let scale = match scale_max {
            Some(n) => format!("fixed scale: {n} (--scale-max)"),
            None => "scale: this image's maximum".to_string(),
        };
        text(area, &scale, (x0 - 10, bar_bottom + 16), 12)?;
        text(
            area,
            &format!("maximum here: {max_seen}"),
            (x0 - 10, bar_bottom + 32),
            12,
        )
    })
}

/// The counts the colour bar labels, for a scale whose top is `top`: every count up to 10 (a
/// reader counts layers one by one there), above that the multiples of a round step (1, 2 or 5
/// times a power of ten) giving at most 8 intervals, and always the top itself; a multiple closer
/// to the top than half a step is left out so that the two labels do not overlap.
fn bar_ticks(top: u32) -> Vec<u32> {
    if top <= 10 {
        return (0..=top).collect();
    }
    let mut step = 1;
    'search: loop {
        for factor in [1, 2, 5] {
            if top <= step * factor * 8 {
                step *= factor;
                break 'search;
            }
        }
        step *= 10;
    }
    let mut ticks: Vec<u32> = (0..top).step_by(step as usize).collect();
    if ticks
        .last()
        .is_some_and(|&last| 2 * (top - last) < step && last > 0)
    {
        ticks.pop();
    }
    ticks.push(top);
    ticks
}

/// The nearest depth of each pixel (`crate::nearest_depth`) with its key: white is near, dark
/// is far (the depths at both ends named), black is no fragment.
///
/// # Errors
/// Text cannot be drawn (a font error).
pub fn nearest_depth_with_key(
    width: u32,
    height: u32,
    nearest: &[Option<f32>],
) -> Result<RgbImage, DrawError> {
    let picture = crate::nearest_depth(width, height, nearest);
    let present = nearest.iter().flatten();
    let lo = present.clone().copied().fold(f32::INFINITY, f32::min);
    let hi = present.copied().fold(f32::NEG_INFINITY, f32::max);
    let x0 = width as i32 + 20;
    figure(&picture, 0, |area| {
        text(area, "nearest depth", (x0, 8), 16)?;
        text(area, "(window z of the first fragment)", (x0 - 10, 28), 12)?;
        let (bar_top, bar_bottom) = (56, 216);
        for y in bar_top..=bar_bottom {
            let t = (y - bar_top) as f32 / (bar_bottom - bar_top) as f32;
            #[expect(
                clippy::cast_possible_truncation,
                reason = "t is in [0, 1]: the grey is in [40, 255]"
            )]
            let v = (255.0 - 215.0 * t).round() as u8;
            fill(area, [(x0, y), (x0 + 24, y + 1)], Rgb([v, v, v]))?;
        }
        area.draw(&Rectangle::new(
            [(x0, bar_top), (x0 + 24, bar_bottom)],
            BLACK.stroke_width(1),
        ))
        .map_err(DrawError::from)?;
        let (near, far) = if lo.is_finite() {
            (
                format!("near (white): {lo:.4}"),
                format!("far (dark): {hi:.4}"),
            )
        } else {
            ("near (white)".into(), "far (dark)".into())
        };
        text(area, &near, (x0 + 30, bar_top - 6), 13)?;
        text(area, &far, (x0 + 30, bar_bottom - 8), 13)?;
        fill(
            area,
            [(x0, bar_bottom + 20), (x0 + 24, bar_bottom + 36)],
            Rgb([0, 0, 0]),
        )?;
        text(area, "no fragment", (x0 + 30, bar_bottom + 21), 13)
    })
}

/// `figure` with `caption` in a strip below it (the scene, the view, the scheme: what a picture
/// shows, in the picture), its words wrapped to the figure's width.
///
/// # Errors
/// Text cannot be drawn (a font error).
#[expect(
    clippy::cast_possible_truncation,
    reason = "a legend has a few lines, a picture a side of at most 16384 pixels"
)]
pub fn captioned(figure: &RgbImage, caption: &str) -> Result<RgbImage, DrawError> {
    const LINE: u32 = 17;
    // The embedded font's 13-pixel glyphs average under 7 pixels.
    let per_line = (figure.width().saturating_sub(12) / 7).max(16) as usize;
    let mut lines: Vec<String> = Vec::new();
    for word in caption.split(' ') {
        match lines.last_mut() {
            Some(line) if line.chars().count() + 1 + word.chars().count() <= per_line => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    let (w, h) = figure.dimensions();
    let size = (w, h + 8 + LINE * lines.len() as u32);
    crate::plot::register_font();
    let mut out = RgbImage::from_pixel(size.0, size.1, Rgb([255, 255, 255]));
    for (x, y, p) in figure.enumerate_pixels() {
        out.put_pixel(x, y, *p);
    }
    {
        let root = BitMapBackend::with_buffer(&mut out, size).into_drawing_area();
        for (i, line) in lines.iter().enumerate() {
            text(&root, line, (6, (h + 4 + LINE * i as u32) as i32), 13)?;
        }
        root.present().map_err(DrawError::from)?;
    }
    Ok(out)
}

/// How many differing pixels get a zoomed inset.
pub const INSETS: usize = 4;
/// Pixels of the picture on each side of an inset's centre.
const INSET_RADIUS: u32 = 7;
/// Zoom of an inset.
const INSET_ZOOM: u32 = 8;

/// A difference image with its `legend` (colour, meaning, count) beside it, a ring around each
/// of `marks` (the first differing pixels, in order) when `ring` (sparse differences, which a
/// ring makes visible; dense ones are visible alone and a ring would hide some) and, below,
/// zoomed insets of the first [`INSETS`] of them, each with its pixel outlined and its
/// coordinates named.
///
/// # Errors
/// Text cannot be drawn (a font error).
#[expect(
    clippy::cast_possible_truncation,
    reason = "a legend has a few lines, a picture a side of at most 16384 pixels; a legend has a few lines, a picture a side of at most 16384 pixels; at most INSETS insets; a legend has a few lines, a picture a side of at most 16384 pixels; at most INSETS insets; sx and sy are checked to lie in the picture"
)]
pub fn difference_figure(
    picture: &RgbImage,
    legend: &[(Rgb<u8>, String)],
    marks: &[(u32, u32)],
    ring: bool,
) -> Result<RgbImage, DrawError> {
    let side = (2 * INSET_RADIUS + 1) * INSET_ZOOM;
    let insets = marks.len().min(INSETS);
    let (w, h) = picture.dimensions();
    // The insets go below the picture and below the legend's text, whichever is lower.
    let legend_bottom = 64 + 22 * legend.len() as u32;
    let inset_top = h.max(legend_bottom) + 28;
    let below = if insets > 0 {
        inset_top + side + 12 - h
    } else {
        0
    };
    let mut out = figure(picture, below, |area| {
        let x0 = w as i32 + 16;
        text(area, "difference", (x0, 8), 16)?;
        for (i, (colour, meaning)) in legend.iter().enumerate() {
            let y = 36 + 22 * i as i32;
            fill(area, [(x0, y), (x0 + 16, y + 16)], *colour)?;
            area.draw(&Rectangle::new(
                [(x0, y), (x0 + 16, y + 16)],
                BLACK.stroke_width(1),
            ))
            .map_err(DrawError::from)?;
            text(area, meaning, (x0 + 22, y + 1), 13)?;
        }
        let note_y = 44 + 22 * legend.len() as i32;
        if marks.is_empty() {
            text(area, "no differing pixel", (x0, note_y), 13)?;
        } else if ring {
            text(
                area,
                "white rings: first differing pixels",
                (x0, note_y),
                13,
            )?;
        }
        // White edged in black: a colour no legend entry uses, seen on dark and bright pixels.
        for &(x, y) in marks.iter().filter(|_| ring) {
            for (radius, colour, stroke) in [(10, BLACK, 4), (10, WHITE, 2)] {
                area.draw(&Circle::new(
                    (x as i32, y as i32),
                    radius,
                    colour.stroke_width(stroke),
                ))
                .map_err(DrawError::from)?;
            }
        }
        for (i, &(x, y)) in marks.iter().take(INSETS).enumerate() {
            let left = i as i32 * (side as i32 + 12) + 4;
            let top = inset_top as i32;
            text(
                area,
                &format!("({x}, {y}) ×{INSET_ZOOM}"),
                (left, top - 20),
                13,
            )?;
            area.draw(&Rectangle::new(
                [(left - 1, top - 1), (left + side as i32, top + side as i32)],
                BLACK.stroke_width(1),
            ))
            .map_err(DrawError::from)?;
        }
        Ok(())
    })?;
    // The insets' pixels, copied after the panel so that nothing is drawn over them, then the
    // centre pixel outlined.
    for (i, &(cx, cy)) in marks.iter().take(INSETS).enumerate() {
        let left = i as u32 * (side + 12) + 4;
        let top = inset_top;
        for dy in 0..side {
            for dx in 0..side {
                let sx = i64::from(cx) + i64::from(dx / INSET_ZOOM) - i64::from(INSET_RADIUS);
                let sy = i64::from(cy) + i64::from(dy / INSET_ZOOM) - i64::from(INSET_RADIUS);
                let p = if (0..i64::from(w)).contains(&sx) && (0..i64::from(h)).contains(&sy) {
                    *picture.get_pixel(sx as u32, sy as u32)
                } else {
                    Rgb([255, 255, 255])
                };
                if left + dx < out.width() && top + dy < out.height() {
                    out.put_pixel(left + dx, top + dy, p);
                }
            }
        }
        let (c0, c1) = (
            INSET_RADIUS * INSET_ZOOM,
            (INSET_RADIUS + 1) * INSET_ZOOM - 1,
        );
        // The centre pixel outlined as the rings are: white inside, black around it.
        for (inset, colour) in [(1, Rgb([0, 0, 0])), (0, Rgb([255, 255, 255]))] {
            let (lo, hi) = (c0 - inset, c1 + inset);
            for t in lo..=hi {
                for (x, y) in [(t, lo), (t, hi), (lo, t), (hi, t)] {
                    if left + x < out.width() && top + y < out.height() {
                        out.put_pixel(left + x, top + y, colour);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// How many differing pixels get a ring.
pub const MARKS: usize = 16;

/// An effect's difference image (`crate::effects::difference_image`: error pixels red) as a
/// [`difference_figure`]: its legend with the counts, and the first differing pixels (in raster
/// order) ringed and zoomed.
///
/// # Errors
/// Text cannot be drawn (a font error).
pub fn effect_difference_figure(
    reference: &RgbImage,
    candidate: &RgbImage,
) -> Result<RgbImage, DrawError> {
    let picture = crate::effects::difference_image(reference, candidate);
    let differing: Vec<(u32, u32)> = reference
        .enumerate_pixels()
        .filter(|&(x, y, p)| candidate.get_pixel(x, y) != p)
        .map(|(x, y, _)| (x, y))
        .collect();
    let legend = [
        (
            Rgb([255, 0, 0]),
            format!("8-bit colour differs: {} px", differing.len()),
        ),
        (
            Rgb([100, 100, 100]),
            "equal (candidate, dimmed)".to_string(),
        ),
    ];
    let ring = differing.len() <= MARKS;
    let marks: Vec<(u32, u32)> = differing.into_iter().take(MARKS).collect();
    difference_figure(&picture, &legend, &marks, ring)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_colour_bar_labels_every_count_of_a_shallow_scene_and_round_steps_of_a_deep_one() {
        assert_eq!(bar_ticks(1), [0, 1], "a scale of one");
        assert_eq!(
            bar_ticks(6),
            [0, 1, 2, 3, 4, 5, 6],
            "no count skipped up to 10"
        );
        assert_eq!(
            bar_ticks(40),
            [0, 5, 10, 15, 20, 25, 30, 35, 40],
            "steps of 5"
        );
        assert_eq!(
            bar_ticks(37),
            [0, 5, 10, 15, 20, 25, 30, 37],
            "35 too close to 37"
        );
        assert_eq!(
            bar_ticks(1000),
            [0, 200, 400, 600, 800, 1000],
            "steps of 200"
        );
        for top in 1..3000 {
            let ticks = bar_ticks(top);
            assert!(ticks.len() <= 11, "{top}: {ticks:?}");
            assert_eq!(ticks.last(), Some(&top), "{top}: the top is labelled");
            assert!(ticks.windows(2).all(|w| w[0] < w[1]), "{top}: increasing");
        }
    }

    #[test]
    fn the_picture_is_copied_unchanged_and_the_panel_is_drawn() {
        let counts = [0, 1, 2, 3];
        let figure = heat_map_with_bar(2, 2, &counts, Some(3)).unwrap();
        assert_eq!(figure.dimensions(), (2 + PANEL, MIN_HEIGHT));
        let plain = crate::heat_map_scaled(2, 2, &counts, 3);
        for (x, y, p) in plain.enumerate_pixels() {
            assert_eq!(figure.get_pixel(x, y), p);
        }
        let inked = figure.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(inked > 500, "{inked} pixels of bar and text");
    }

    #[test]
    fn an_inset_zooms_the_differing_pixel() {
        let mut picture = RgbImage::from_pixel(64, 64, Rgb([70, 70, 70]));
        picture.put_pixel(40, 30, Rgb([230, 40, 40]));
        let legend = [(Rgb([230, 40, 40]), "missing".to_string())];
        let figure = difference_figure(&picture, &legend, &[(40, 30)], true).unwrap();
        // The inset's centre block, just inside its outline, is the differing pixel's colour.
        let (left, top) = (4, (64 + 22) + 28);
        let inside = INSET_RADIUS * INSET_ZOOM + 2;
        assert_eq!(
            figure.get_pixel(left + inside, top + inside),
            &Rgb([230, 40, 40])
        );
    }
}
