//! The difference image of a verdict (`fragsim compare`'s): a pixel's colour says its verdict,
//! the legend beside it says what each colour means and how many pixels have it, and the first
//! differing pixels are ringed and zoomed ([`crate::legend::difference_figure`]).

use std::path::Path;

use fragsim_oracle::compare::flags;
use fragsim_oracle::verdict::Verdict;
use image::{Rgb, RgbImage};

use crate::{DrawError, SaveError};

/// Why the difference image could not be written.
#[derive(Debug, thiserror::Error)]
pub enum DifferenceImageError {
    /// The figure could not be drawn.
    #[error(transparent)]
    Draw(#[from] DrawError),
    /// The figure could not be saved.
    #[error(transparent)]
    Save(#[from] SaveError),
}

/// Colour of a pixel's verdict in the difference image.
fn colour(flags: u8, fragments: usize) -> [u8; 3] {
    let wrong = flags & (flags::MISSING | flags::EXTRA);
    match () {
        () if flags & flags::CORRUPT != 0 => [40, 220, 40],
        () if wrong == flags::MISSING | flags::EXTRA => [220, 50, 220],
        () if wrong == flags::MISSING => [230, 40, 40],
        () if wrong == flags::EXTRA => [60, 90, 255],
        () if flags & flags::MISORDERED != 0 => [250, 220, 0],
        () if flags & flags::MISCOUNTED != 0 => [255, 140, 0],
        () if flags & flags::OVERFLOWED != 0 => [0, 90, 90],
        () if fragments > 0 => [70, 70, 70],
        () => [0, 0, 0],
    }
}

/// The legend of the difference image: every colour a verdict is drawn in, what it means, and how
/// many pixels have it. A verdict's count is the report's (every pixel with that flag), though a
/// pixel of several verdicts is drawn in the colour of the one listed first: the entry says how
/// many of its pixels are drawn above, so that the legend and the text agree ("missing 1" in
/// both where the one missing pixel is also corrupt).
#[must_use]
pub fn legend(v: &Verdict) -> Vec<(Rgb<u8>, String)> {
    // (the flags a pixel must all have, the fragments its reference holds, the meaning): the
    // verdicts in the order their colours win, then the equal pixels, covered or not.
    let meanings: [(u8, usize, &str); 9] = [
        (flags::CORRUPT, 0, "corrupt word"),
        (flags::MISSING | flags::EXTRA, 0, "missing and extra"),
        (flags::MISSING, 0, "missing"),
        (flags::EXTRA, 0, "extra"),
        (flags::MISORDERED, 0, "misordered"),
        (flags::MISCOUNTED, 0, "overflow miscounted"),
        (flags::OVERFLOWED, 0, "overflowed (by design)"),
        (0, 1, "equal, covered"),
        (0, 0, "no fragment"),
    ];
    let mut counts = [(0_u64, 0_u64); 9];
    for (&flags, &n) in v.comparison.verdicts.iter().zip(&v.reference_fragments) {
        let drawn = colour(flags, n as usize);
        for (&(wanted, covered, _), (has, drawn_above)) in meanings.iter().zip(&mut counts) {
            let own = colour(wanted, covered);
            let counted = if wanted == 0 {
                // The equal pixels are counted as drawn.
                drawn == own
            } else {
                flags & wanted == wanted
            };
            if counted {
                *has += 1;
                *drawn_above += u64::from(drawn != own);
            }
        }
    }
    meanings
        .iter()
        .zip(counts)
        .map(|(&(f, n, meaning), (count, drawn_above))| {
            let above = if drawn_above > 0 {
                format!(" ({drawn_above} drawn above)")
            } else {
                String::new()
            };
            (Rgb(colour(f, n)), format!("{meaning}: {count}{above}"))
        })
        .collect()
}

/// Writes the difference image of `v` to `path` (PNG), one column per list (a per-sample
/// layout's samples side by side), with its [`legend`]; returns the legend's entries as the
/// image shows them (`missing: 1`).
///
/// # Errors
/// The figure cannot be drawn or saved.
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
)]
pub fn write_difference_image(
    v: &Verdict,
    path: &Path,
) -> Result<Vec<String>, DifferenceImageError> {
    let legend = legend(v);
    let width = v.width * v.lists_per_pixel;
    let image = RgbImage::from_fn(width, v.height, |x, y| {
        let p = (y * width + x) as usize;
        Rgb(colour(
            v.comparison.verdicts[p],
            v.reference_fragments[p] as usize,
        ))
    });
    let differing = v
        .comparison
        .verdicts
        .iter()
        .enumerate()
        .filter(|&(_, &v)| v & flags::DIFFERS != 0)
        .map(|(p, _)| ((p % width as usize) as u32, (p / width as usize) as u32));
    // Rings only where differences are sparse: dense ones show alone, and rings would hide some.
    let ring = differing.clone().count() <= crate::legend::MARKS;
    let marks: Vec<(u32, u32)> = differing.take(crate::legend::MARKS).collect();
    let figure = crate::legend::difference_figure(&image, &legend, &marks, ring)?;
    crate::save_png(&figure, path)?;
    Ok(legend.into_iter().map(|(_, entry)| entry).collect())
}
