//! Images of captures: the depth-complexity heat map, the nearest-layer depth, the
//! multi-fragment effects ([`effects`]: transparency, translucency, Fresnel, and their
//! multisample resolve), the approximate OIT schemes'
//! transparency ([`approximate`]: WBOIT, MLAB, tail blending), with the error-pixel rate
//! and, for approximate images, the colour error ([`colour_error`]: mean and maximum absolute
//! error per channel, PSNR),
//! the deferred attribute pass that gives captures what shading needs beyond their words
//! ([`deferred`]: normals, primitive ids of key-only captures), and the difference image of a
//! verdict ([`verdict_image`]: a colour per pixel's verdict, with its legend).
//!
//! ```
//! let counts = vec![0, 1, 2, 3];
//! let image = fragsim_shade::heat_map(2, 2, &counts);
//! assert_eq!(image.dimensions(), (2, 2));
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

use std::path::Path;

pub mod approximate;
pub mod colour_error;
pub mod deferred;
pub mod effects;
mod error;
pub mod legend;
pub mod plot;
pub mod verdict_image;

pub use error::{DrawError, SaveError};

use image::{Rgb, RgbImage};

/// Control points of the heat map's colour ramp (black → blue → red → yellow → white),
/// interpolated linearly in sRGB: a perceptually ordered ramp that stays readable in greyscale.
const RAMP: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [0.1, 0.1, 0.8],
    [0.85, 0.1, 0.1],
    [1.0, 0.85, 0.0],
    [1.0, 1.0, 1.0],
];

/// Depth complexity per pixel as colour: 0 is black, the maximum is white.
#[must_use]
pub fn heat_map(width: u32, height: u32, counts: &[u32]) -> RgbImage {
    let max = counts.iter().copied().max().unwrap_or(0).max(1);
    heat_map_scaled(width, height, counts, max)
}

/// Depth complexity per pixel as colour on a fixed scale: 0 is black, `max` (and above) white.
#[must_use]
pub fn heat_map_scaled(width: u32, height: u32, counts: &[u32], max: u32) -> RgbImage {
    let max = max.max(1);
    RgbImage::from_fn(width, height, |x, y| {
        let c = counts[(y * width + x) as usize];
        ramp(c as f32 / max as f32)
    })
}

/// The heat map's colour at `t` in [0, 1] of its scale.
#[expect(
    clippy::cast_possible_truncation,
    reason = "t is clamped to [0, 1]: the index is within RAMP and each channel, in [0, 1], scales to a byte"
)]
pub(crate) fn ramp(t: f32) -> Rgb<u8> {
    let scaled = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f32;
    let i = (scaled.floor() as usize).min(RAMP.len() - 2);
    let f = scaled - i as f32;
    let c = [0, 1, 2].map(|ch| RAMP[i][ch] + (RAMP[i + 1][ch] - RAMP[i][ch]) * f);
    Rgb(c.map(|v| (v * 255.0).round() as u8))
}

/// Nearest depth per pixel as grey, stretched over the depths present (near is white, far is
/// dark); pixels with no fragment are black.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the depth is within [lo, lo + span]: the grey is in [40, 255]"
)]
pub fn nearest_depth(width: u32, height: u32, nearest: &[Option<f32>]) -> RgbImage {
    let present = nearest.iter().flatten();
    let lo = present.clone().copied().fold(f32::INFINITY, f32::min);
    let hi = present.copied().fold(f32::NEG_INFINITY, f32::max);
    let span = if hi > lo { hi - lo } else { 1.0 };
    RgbImage::from_fn(width, height, |x, y| {
        match nearest[(y * width + x) as usize] {
            None => Rgb([0, 0, 0]),
            Some(d) => {
                let v = (255.0 - 215.0 * (d - lo) / span).round() as u8;
                Rgb([v, v, v])
            }
        }
    })
}

/// Writes `image` as a PNG at `path`, creating parent directories.
///
/// # Errors
/// The directory or file could not be written.
pub fn save_png(image: &RgbImage, path: &Path) -> Result<(), SaveError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| SaveError::CreateDir {
            dir: dir.to_path_buf(),
            source,
        })?;
    }
    image.save(path).map_err(|source| SaveError::Write {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_ends_are_black_and_white() {
        assert_eq!(ramp(0.0), Rgb([0, 0, 0]));
        assert_eq!(ramp(1.0), Rgb([255, 255, 255]));
    }

    #[test]
    fn nearest_is_brightest_and_empty_is_black() {
        let img = nearest_depth(3, 1, &[Some(0.2), Some(0.8), None]);
        assert_eq!(img.get_pixel(0, 0), &Rgb([255, 255, 255]));
        assert_eq!(img.get_pixel(1, 0), &Rgb([40, 40, 40]));
        assert_eq!(img.get_pixel(2, 0), &Rgb([0, 0, 0]));
    }
}
