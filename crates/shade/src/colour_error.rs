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
//! images. [`colour_error_by_depth`] gives the same figures per bucket of pixels' depth
//! complexity, where an approximate scheme's error lives (past its `K` nodes).

use image::RgbImage;

/// Why two images could not be compared.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CompareError {
    /// The images differ in size.
    #[error("cannot compare a {candidate:?} image with a {reference:?} one")]
    Sizes {
        /// The reference's width and height.
        reference: (u32, u32),
        /// The candidate's width and height.
        candidate: (u32, u32),
    },
    /// The images have no pixel.
    #[error("cannot compare empty images")]
    Empty,
    /// The depth complexity is not one count a pixel.
    #[error("{counts} depth-complexity counts for {pixels} pixels")]
    DepthCounts {
        /// The counts given.
        counts: usize,
        /// The images' pixels.
        pixels: usize,
    },
}

/// How far a candidate image is from the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourDeviation {
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
pub fn colour_error(
    reference: &RgbImage,
    candidate: &RgbImage,
) -> Result<ColourDeviation, CompareError> {
    check_sizes(reference, candidate)?;
    if reference.width() == 0 || reference.height() == 0 {
        return Err(CompareError::Empty);
    }
    let mut sums = Sums::default();
    for (a, b) in reference.pixels().zip(candidate.pixels()) {
        sums.add(a.0, b.0);
    }
    Ok(sums.error())
}

/// Depth-complexity buckets of [`colour_error_by_depth`]: fragments per pixel from `lo` to `hi`
/// inclusive (`hi = u32::MAX`: no upper end). Powers of two, as the hazard charts bucket.
pub const DEPTH_BUCKETS: [(u32, u32); 6] =
    [(1, 1), (2, 4), (5, 8), (9, 16), (17, 32), (33, u32::MAX)];

/// The colour error over the covered pixels of one depth-complexity bucket.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BucketDeviation {
    /// Fewest fragments per pixel of the bucket.
    pub lo: u32,
    /// Most fragments per pixel of the bucket (`u32::MAX`: no upper end).
    pub hi: u32,
    /// Pixels with that many fragments.
    pub pixels: u64,
    /// Of them, those whose 8-bit colour differs.
    pub error_pixels: u64,
    /// The colour error over them (`None`: no pixel in the bucket).
    pub error: Option<ColourDeviation>,
}

impl BucketDeviation {
    /// The bucket's name in tables: `1`, `2–4`, `33+`.
    #[must_use]
    pub fn label(&self) -> String {
        match (self.lo, self.hi) {
            (lo, hi) if lo == hi => lo.to_string(),
            (lo, u32::MAX) => format!("{lo}+"),
            (lo, hi) => format!("{lo}–{hi}"),
        }
    }
}

/// The colour error of `candidate` against `reference` per bucket of [`DEPTH_BUCKETS`], pixel
/// `p` (row-major) having `depth_complexity[p]` fragments; pixels without one are left out (both
/// images show the background there). The approximate schemes' error grows with the fragments a
/// pixel has, which one figure over the whole image hides.
///
/// # Errors
/// The images differ in size, or `depth_complexity` is not one count a pixel.
pub fn colour_error_by_depth(
    reference: &RgbImage,
    candidate: &RgbImage,
    depth_complexity: &[u32],
) -> Result<Vec<BucketDeviation>, CompareError> {
    check_sizes(reference, candidate)?;
    let pixels = reference.width() as usize * reference.height() as usize;
    if depth_complexity.len() != pixels {
        return Err(CompareError::DepthCounts {
            counts: depth_complexity.len(),
            pixels,
        });
    }
    let mut sums = [Sums::default(); DEPTH_BUCKETS.len()];
    for ((a, b), &n) in reference
        .pixels()
        .zip(candidate.pixels())
        .zip(depth_complexity)
    {
        if let Some(i) = DEPTH_BUCKETS
            .iter()
            .position(|&(lo, hi)| (lo..=hi).contains(&n))
        {
            sums[i].add(a.0, b.0);
        }
    }
    Ok(DEPTH_BUCKETS
        .iter()
        .zip(sums)
        .map(|(&(lo, hi), sums)| BucketDeviation {
            lo,
            hi,
            pixels: sums.pixels,
            error_pixels: sums.differing,
            error: (sums.pixels > 0).then(|| sums.error()),
        })
        .collect())
}

fn check_sizes(reference: &RgbImage, candidate: &RgbImage) -> Result<(), CompareError> {
    if reference.dimensions() == candidate.dimensions() {
        return Ok(());
    }
    Err(CompareError::Sizes {
        reference: reference.dimensions(),
        candidate: candidate.dimensions(),
    })
}

/// The running sums every figure is made of, over the pixels added so far.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    pixels: u64,
    differing: u64,
    abs: [u64; 3],
    max: [u8; 3],
    squares: u64,
}

impl Sums {
    fn add(&mut self, a: [u8; 3], b: [u8; 3]) {
        self.pixels += 1;
        self.differing += u64::from(a != b);
        for c in 0..3 {
            let d = a[c].abs_diff(b[c]);
            self.abs[c] += u64::from(d);
            self.max[c] = self.max[c].max(d);
            self.squares += u64::from(d) * u64::from(d);
        }
    }

    /// The figures over at least one pixel.
    fn error(&self) -> ColourDeviation {
        let pixels = self.pixels as f64;
        let mse = self.squares as f64 / (3.0 * pixels);
        ColourDeviation {
            mean_abs: self.abs.map(|s| s as f64 / pixels),
            max_abs: self.max,
            psnr_db: 10.0 * (255.0_f64 * 255.0 / mse).log10(),
        }
    }
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
        let expected = 10.0 * (255.0_f64 * 255.0 * 12.0 / 80.0).log10();
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
        assert_eq!(
            refused,
            CompareError::Sizes {
                reference: (1, 1),
                candidate: (2, 1)
            }
        );
        let refused = refused.to_string();
        assert!(
            refused.contains("(2, 1)") && refused.contains("(1, 1)"),
            "{refused}"
        );
        assert_eq!(
            colour_error(&RgbImage::new(0, 0), &RgbImage::new(0, 0)),
            Err(CompareError::Empty)
        );
    }

    /// Four pixels of 0, 1, 3 and 40 fragments, the one of 3 off by 6 in green: the bucket
    /// `2–4` alone has an error, the empty pixel is in none, the buckets without a pixel have no
    /// figures.
    #[test]
    fn each_bucket_has_the_figures_of_its_own_pixels() {
        let reference = RgbImage::from_pixel(2, 2, Rgb([50, 50, 50]));
        let mut candidate = reference.clone();
        candidate.put_pixel(0, 1, Rgb([50, 56, 50]));
        let buckets = colour_error_by_depth(&reference, &candidate, &[0, 1, 3, 40]).unwrap();
        let labels: Vec<String> = buckets.iter().map(BucketDeviation::label).collect();
        assert_eq!(labels, ["1", "2–4", "5–8", "9–16", "17–32", "33+"]);
        let pixels: Vec<u64> = buckets.iter().map(|b| b.pixels).collect();
        assert_eq!(pixels, [1, 1, 0, 0, 0, 1]);
        let wrong = buckets[1].error.unwrap();
        assert_eq!((buckets[1].error_pixels, wrong.max_abs), (1, [0, 6, 0]));
        assert_eq!(wrong.mean_abs, [0.0, 6.0, 0.0]);
        assert!(buckets[0].error.unwrap().psnr_db.is_infinite());
        assert!(buckets[5].error.unwrap().psnr_db.is_infinite());
        assert!(buckets[2].error.is_none());
        let short = colour_error_by_depth(&reference, &candidate, &[1, 2])
            .unwrap_err()
            .to_string();
        assert!(
            short.contains("2 depth-complexity counts for 4 pixels"),
            "{short}"
        );
    }
}
