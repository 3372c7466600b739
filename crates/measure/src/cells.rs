//! How the reports write their numbers: a rate as a percentage that never reads zero when it is
//! not ([`percent`]), a bucket's cells, an image's mean error over its channels, and the family
//! a scheme is drawn as on the charts. Shared by the reports here and the command line's tables.

use fragsim_shade::colour_error::BucketDeviation;

use crate::colour_judge::ColourColumns;

/// The mean absolute error of an image over its three channels, as tables and charts print it
/// (`None`: no image).
#[must_use]
pub fn mean_of_channels(colour: &ColourColumns) -> Option<f64> {
    colour.mean_abs_error.map(|m| m.iter().sum::<f64>() / 3.0)
}

/// `fraction` as a percentage with `decimals` decimals for a table cell, where a rate that is not
/// zero never prints as zero: one error pixel in a million is `<0.001`, not `0.000` beside a
/// colour error of 68.
#[must_use]
pub fn percent(fraction: f64, decimals: usize) -> String {
    let percent = fraction * 100.0;
    let smallest = 10_f64.powi(-i32::try_from(decimals).unwrap_or(i32::MAX));
    if percent > 0.0 && percent < smallest / 2.0 {
        format!("<{smallest:.decimals$}")
    } else {
        format!("{percent:.decimals$}")
    }
}

/// A table's cells of one bucket: its name, pixels, EPR % of them, and the colour error's mean,
/// maximum and PSNR cells (as the whole image's: `inf` for a bucket equal to the oracle's).
#[must_use]
pub fn bucket_cells(bucket: &BucketDeviation) -> [String; 6] {
    let [mean, max, psnr] = ColourColumns::of(bucket.error).cells();
    [
        bucket.label(),
        bucket.pixels.to_string(),
        percent(bucket.error_pixels as f64 / bucket.pixels.max(1) as f64, 3),
        mean,
        max,
        psnr,
    ]
}

/// The family a scheme belongs to, as charts mark it (one marker shape a family): `mdts`,
/// `a-buffer` (A-buffers, linked lists, the layer counter, the stencil-routed A-buffer),
/// `peeling` (depth peeling and the z-buffer), `k-buffer` (k-buffers and loop32), `bucket`
/// (bucket and adaptive depth peeling), `approximate` (WBOIT, MLAB, tail blending:
/// `--approximate`).
#[must_use]
pub fn family(scheme: &str) -> &'static str {
    const FAMILIES: [(&str, &str); 15] = [
        ("mdts", "mdts"),
        ("abuffer", "a-buffer"),
        ("linked-list", "a-buffer"),
        ("layer-counter", "a-buffer"),
        ("srab", "a-buffer"),
        ("peeling", "peeling"),
        ("dual-peeling", "peeling"),
        ("zbuffer", "peeling"),
        ("kbuffer", "k-buffer"),
        ("loop32", "k-buffer"),
        ("bdp", "bucket"),
        ("adp", "bucket"),
        ("wboit", "approximate"),
        ("mlab", "approximate"),
        ("tail-blend", "approximate"),
    ];
    FAMILIES
        .iter()
        .find(|(prefix, _)| scheme.starts_with(prefix))
        .map_or("other", |&(_, family)| family)
}

#[cfg(test)]
mod tests {
    use super::{family, percent};

    #[test]
    fn a_rate_that_is_not_zero_never_prints_as_zero() {
        assert_eq!(percent(0.0, 3), "0.000", "zero is zero");
        assert_eq!(percent(1e-6, 3), "<0.001", "one pixel in a million");
        assert_eq!(percent(1e-7, 4), "<0.0001", "the cell's own precision");
        assert_eq!(percent(0.012_34, 3), "1.234", "rounded as before");
        assert_eq!(percent(1.0, 3), "100.000", "every pixel");
    }

    /// Every scheme's family has its own marker on the charts (`fragsim_shade::plot::FAMILIES`),
    /// so a family looks the same on bench's chart and sweep's.
    #[test]
    fn every_catalog_family_has_a_chart_marker() {
        for entry in fragsim_catalog::CATALOG {
            let family = family(entry.name);
            assert!(
                fragsim_shade::plot::FAMILIES.contains(&family),
                "{}: {family}",
                entry.name
            );
        }
    }
}
