//! The colour error of an image against the exact one, for the approximate schemes (weighted
//! blended OIT, multi-layer alpha blending, tail blending) whose images are almost never equal
//! pixel for pixel, where the paper's error-pixel rate ([`error_pixels`](crate::effects::error_pixels))
//! says only *how many* pixels differ: mean and maximum absolute error per channel, and the
//! peak signal-to-noise ratio.
//!
//! **Definitions.** Over the images' `N` pixels and the channels `c` of their 8-bit sRGB values:
//! the mean absolute error `Σ |a − b| / N` and the maximum `max |a − b|` of each channel, and
//! `PSNR = 10 log10(255² / MSE)` dB with `MSE` the mean squared error over all `3 N` values
//! (the usual definition for 8-bit images; infinite for equal images). The values compared are
//! the encoded 8-bit ones the error-pixel rate compares, so the two measures speak of the same
//! images.

use image::RgbImage;

/// How far a candidate image is from the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourError {
    /// Mean absolute error per channel (R, G, B), in 8-bit units.
    pub mean_abs: [f64; 3],
    /// Largest absolute error per channel, in 8-bit units.
    pub max_abs: [u8; 3],
    /// Peak signal-to-noise ratio in dB (`f64::INFINITY` for equal images).
    pub psnr_db: f64,
}

/// The colour error of `candidate` against `reference`.
///
/// # Errors
/// The images differ in size, or are empty.
pub fn colour_error(reference: &RgbImage, candidate: &RgbImage) -> Result<ColourError, String> {
    if reference.dimensions() != candidate.dimensions() {
        return Err(format!(
            "cannot compare a {:?} image with a {:?} one",
            candidate.dimensions(),
            reference.dimensions()
        ));
    }
    let pixels = u64::from(reference.width()) * u64::from(reference.height());
    if pixels == 0 {
        return Err("cannot compare empty images".into());
    }
    let (mut sum, mut max, mut squares) = ([0u64; 3], [0u8; 3], 0u64);
    for (a, b) in reference.pixels().zip(candidate.pixels()) {
        for c in 0..3 {
            let d = a[c].abs_diff(b[c]);
            sum[c] += u64::from(d);
            max[c] = max[c].max(d);
            squares += u64::from(d) * u64::from(d);
        }
    }
    let mse = squares as f64 / (3 * pixels) as f64;
    Ok(ColourError {
        mean_abs: sum.map(|s| s as f64 / pixels as f64),
        max_abs: max,
        psnr_db: 10.0 * (255.0f64 * 255.0 / mse).log10(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    #[test]
    fn equal_images_have_no_error_and_an_infinite_psnr() {
        let image = RgbImage::from_pixel(3, 2, Rgb([10, 20, 30]));
        let error = colour_error(&image, &image).unwrap();
        assert_eq!(error.mean_abs, [0.0; 3]);
        assert_eq!(error.max_abs, [0; 3]);
        assert!(error.psnr_db.is_infinite());
    }

    /// One pixel of four off by 8 in red and 4 in blue: per-channel means 2, 0, 1; maxima 8, 0,
    /// 4; MSE (64 + 16) / 12, PSNR 10 log10(255² · 12 / 80) ≈ 39.89 dB.
    #[test]
    fn the_figures_of_a_hand_counted_difference() {
        let reference = RgbImage::from_pixel(2, 2, Rgb([100, 100, 100]));
        let mut candidate = reference.clone();
        candidate.put_pixel(1, 0, Rgb([108, 100, 96]));
        let error = colour_error(&reference, &candidate).unwrap();
        assert_eq!(error.mean_abs, [2.0, 0.0, 1.0]);
        assert_eq!(error.max_abs, [8, 0, 4]);
        let expected = 10.0 * (255.0f64 * 255.0 * 12.0 / 80.0).log10();
        assert!((error.psnr_db - expected).abs() < 1e-9, "{}", error.psnr_db);
        assert!((error.psnr_db - 39.89).abs() < 0.01);
        // Symmetric.
        assert_eq!(colour_error(&candidate, &reference).unwrap(), error);
    }

    #[test]
    fn images_of_different_sizes_or_none_are_refused_by_their_sizes() {
        let small = RgbImage::new(1, 1);
        let wide = RgbImage::new(2, 1);
        let refused = colour_error(&small, &wide).unwrap_err();
        assert!(
            refused.contains("(2, 1)") && refused.contains("(1, 1)"),
            "{refused}"
        );
        assert!(colour_error(&RgbImage::new(0, 0), &RgbImage::new(0, 0)).is_err());
    }
}
