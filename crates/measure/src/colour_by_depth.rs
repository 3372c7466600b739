//! The colour error of an effect's image per depth-complexity bucket ([`ColourByDepth`]), as
//! `bench` and `sweep` rows and records carry it: where an approximate or lossy scheme's error
//! lives is in the deep pixels, which the whole image's mean hides.

use fragsim_shade::colour_error::{colour_error_by_depth, BucketDeviation, DEPTH_BUCKETS};
use image::RgbImage;
use serde::Serialize;

use crate::colour_judge::ColourColumns;

/// The colour error of an effect's image per depth-complexity bucket, as `bench` and `sweep`
/// records carry it: for each bucket of [`DEPTH_BUCKETS`] (fragments per pixel, from the
/// oracle), six flat fields named `<quantity>_dc_<bucket>` (`dc_1`, `dc_2_4`, …, `dc_33+`):
/// `pixels` (covered pixels in the bucket), `error_pixels` (of them, those whose 8-bit colour
/// differs), `error_pixel_rate` (the fraction; `null` for an empty bucket), `mean_abs_error`,
/// `max_abs_error`, `psnr_db` (as the whole image's, over the bucket's pixels alone; `null` for
/// an empty bucket). Every field is `null` where there is no image (the words cannot resolve the
/// effect), so that every record has every field.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ColourByDepth {
    /// One entry per bucket of [`DEPTH_BUCKETS`], in order; empty where there is no image.
    pub buckets: Vec<BucketDeviation>,
}

impl ColourByDepth {
    /// The buckets of `candidate` against `reference` (`None`: no image), pixel `p` having
    /// `depth_complexity[p]` fragments.
    ///
    /// # Errors
    /// The images differ in size, or `depth_complexity` is not one count a pixel (a bug).
    pub fn of(
        images: Option<(&RgbImage, &RgbImage)>,
        depth_complexity: &[u32],
    ) -> Result<Self, String> {
        let buckets = match images {
            Some((reference, candidate)) => {
                colour_error_by_depth(reference, candidate, depth_complexity)
                    .map_err(|e| e.to_string())?
            }
            None => Vec::new(),
        };
        Ok(Self { buckets })
    }

    /// The buckets with pixels in them.
    pub fn covered(&self) -> impl Iterator<Item = &BucketDeviation> {
        self.buckets.iter().filter(|b| b.pixels > 0)
    }
}

impl Serialize for ColourByDepth {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(DEPTH_BUCKETS.len() * 6))?;
        for (i, &(lo, hi)) in DEPTH_BUCKETS.iter().enumerate() {
            let suffix = match (lo, hi) {
                (lo, hi) if lo == hi => format!("dc_{lo}"),
                (lo, u32::MAX) => format!("dc_{lo}+"),
                (lo, hi) => format!("dc_{lo}_{hi}"),
            };
            let bucket = self.buckets.get(i);
            let colour = ColourColumns::of(bucket.and_then(|b| b.error));
            let rate = bucket
                .filter(|b| b.pixels > 0)
                .map(|b| b.error_pixels as f64 / b.pixels as f64);
            map.serialize_entry(&format!("pixels_{suffix}"), &bucket.map(|b| b.pixels))?;
            map.serialize_entry(
                &format!("error_pixels_{suffix}"),
                &bucket.map(|b| b.error_pixels),
            )?;
            map.serialize_entry(&format!("error_pixel_rate_{suffix}"), &rate)?;
            map.serialize_entry(&format!("mean_abs_error_{suffix}"), &colour.mean_abs_error)?;
            map.serialize_entry(&format!("max_abs_error_{suffix}"), &colour.max_abs_error)?;
            map.serialize_entry(&format!("psnr_db_{suffix}"), &colour.psnr_db)?;
        }
        map.end()
    }
}
