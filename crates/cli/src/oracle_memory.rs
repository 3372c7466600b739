//! The memory cap over the oracle's own storage, checked before the oracle is built.
//!
//! The oracle keeps every fragment of the view (8 bytes each) plus three words a pixel (its
//! offsets, and the counts and cursors of its two passes). The fragments are not known before
//! rasterizing, and an adversarial mesh (thousands of coincident screen-filling triangles) makes
//! counting them as slow as building the oracle; so the check bounds them instead, in one pass
//! over the screen triangles that scans no pixel: a triangle holds at most
//! `min(pixel centres in its bounding box, A + P/2 + 1)` pixel centres, where `A` is its area
//! and `P` its perimeter in pixels (the bound on lattice points in a convex region,
//! Nosarzewska 1948). Guarantee: a view whose bound fits the cap is never refused here, and one
//! refused would need at most the bytes the message names (a bound, within a few fragments a
//! triangle of the exact count on large triangles; tiny ones are each counted once at most).

use fragsim_raster::{ScreenTriangle, View};

/// Bytes of the oracle a pixel needs beside its fragments: offset, count, cursor.
const BYTES_PER_PIXEL: u64 = 24;
/// Bytes of one stored fragment (depth key and primitive id).
const BYTES_PER_FRAGMENT: u64 = 8;
/// Units of a pixel in snapped coordinates.
const SUBPIXELS: f64 = 256.0;

/// At most how many fragments `view` rasterizes.
#[must_use]
pub(crate) fn fragments_at_most(view: &View<'_>) -> u64 {
    let viewport = view.viewport();
    let mut total = 0_u64;
    for prim in 0..view.triangle_count() {
        view.screen_triangles(prim, &mut |tri| {
            total = total.saturating_add(triangle_bound(&tri, viewport.width, viewport.height));
        });
    }
    total
}

/// At most how many pixel centres of a `width × height` viewport triangle `tri` covers.
fn triangle_bound(tri: &ScreenTriangle, width: u32, height: u32) -> u64 {
    let xs = tri.xy.map(|p| p[0]);
    let ys = tri.xy.map(|p| p[1]);
    // Pixel centres `i + 0.5` within [lo, hi] (1/256 pixel units), clamped to the viewport.
    let centres = |lo: i64, hi: i64, side: u32| -> u64 {
        let first = (lo - 128).div_euclid(256) + i64::from((lo - 128).rem_euclid(256) != 0);
        let last = (hi - 128).div_euclid(256);
        let (first, last) = (first.max(0), last.min(i64::from(side) - 1));
        u64::try_from(last - first + 1).unwrap_or(0)
    };
    let lo = |v: [i64; 3]| v.into_iter().min().unwrap_or(0);
    let hi = |v: [i64; 3]| v.into_iter().max().unwrap_or(0);
    let boxed = centres(lo(xs), hi(xs), width) * centres(lo(ys), hi(ys), height);
    let p = tri
        .xy
        .map(|v| [v[0] as f64 / SUBPIXELS, v[1] as f64 / SUBPIXELS]);
    let area = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
        - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
        .abs()
        / 2.0;
    let side = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let perimeter = side(p[0], p[1]) + side(p[1], p[2]) + side(p[2], p[0]);
    let lattice = (area + perimeter / 2.0 + 1.0).floor();
    // Past u64 the box bound is the smaller anyway.
    let lattice = if lattice < 1.8e19 {
        lattice as u64
    } else {
        u64::MAX
    };
    boxed.min(lattice)
}

/// Refuses `view` when the oracle's storage could exceed `cap` bytes, before any is allocated.
///
/// # Errors
/// The bound on the oracle's bytes, with how it is made, over the cap.
pub(crate) fn check(view: &View<'_>, cap: u64) -> Result<(), String> {
    let fragments = fragments_at_most(view);
    let pixels = view.viewport().pixels() as u64;
    let bytes = fragments
        .saturating_mul(BYTES_PER_FRAGMENT)
        .saturating_add(pixels.saturating_mul(BYTES_PER_PIXEL));
    if bytes > cap {
        return Err(format!(
            "the oracle of this view would need up to {bytes} bytes (up to {fragments} fragments \
             of {BYTES_PER_FRAGMENT} bytes, bounded from the screen triangles' areas, plus \
             {BYTES_PER_PIXEL} bytes for each of {pixels} pixels), over the memory cap of {cap} \
             bytes (--memory-cap raises it)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(xy: [[i64; 2]; 3]) -> ScreenTriangle {
        ScreenTriangle {
            prim: 0,
            xy,
            z: [0.5; 3],
        }
    }

    #[test]
    fn a_half_viewport_triangle_is_bounded_near_its_area() {
        // Corners of an 8 × 8 viewport: 32 pixels of area, 36 centres below the diagonal.
        let t = tri([[0, 0], [8 * 256, 0], [0, 8 * 256]]);
        let bound = triangle_bound(&t, 8, 8);
        assert!((36..=64).contains(&bound), "{bound}");
    }

    #[test]
    fn a_triangle_between_centres_holds_none() {
        let t = tri([[10, 10], [100, 10], [10, 100]]);
        assert_eq!(triangle_bound(&t, 8, 8), 0);
    }

    #[test]
    fn a_triangle_off_the_viewport_holds_none() {
        let t = tri([[-4096, -4096], [-2048, -4096], [-4096, -2048]]);
        assert_eq!(triangle_bound(&t, 8, 8), 0);
    }
}
