//! Rules 6 and 7: the exact scan of a snapped, oriented triangle. Its bounding box gives the pixel
//! centres to test, the three integer edge functions with the fill rule of the window origin (top-left,
//! or bottom-left in fragsim's y-down rows for a lower-left origin) decide coverage, and
//! the depth is interpolated in f64 from the edge values and rounded once to f32.

use super::{PixelRect, ScreenTriangle, View, HALF, ONE, SUBPIXEL_BITS};
use crate::conventions::WindowOrigin;
use crate::fragment::{depth_key, Fragment};

impl View<'_> {
    /// Scans an oriented snapped triangle: every covered pixel centre emits a fragment.
    pub fn scan(&self, tri: &ScreenTriangle, emit: &mut impl FnMut(Fragment)) {
        self.scan_in(tri, self.viewport.rect(), emit);
    }

    /// [`View::scan`] restricted to the pixels of `rect`.
    pub fn scan_in(&self, tri: &ScreenTriangle, rect: PixelRect, emit: &mut impl FnMut(Fragment)) {
        let [a, b, c] = tri.xy;
        let area = edge(a, b, c);
        debug_assert!(area > 0);
        let [lo, hi] = bounding_box(tri.xy);
        let Some(PixelRect {
            x: (x0, x1),
            y: (y0, y1),
        }) = rect.centres_within(lo, hi)
        else {
            return;
        };
        let [x0, x1, y0, y1] = [x0, x1, y0, y1].map(i64::from);
        // Edge i is opposite vertex i, so its value is the barycentric weight of vertex i.
        let edges = [(b, c), (c, a), (a, b)];
        let bias = fill_bias(edges, self.conventions.window_origin);
        let step_x = edges.map(|(p, q)| -(q[1] - p[1]) * ONE);
        let step_y = edges.map(|(p, q)| (q[0] - p[0]) * ONE);
        let start = [x0 * ONE + HALF, y0 * ONE + HALF];
        let mut row = edges.map(|(p, q)| edge(p, q, start));
        let area_f = area as f64;
        let width = i64::from(self.viewport.width);
        for y in y0..=y1 {
            let mut e = row;
            for x in x0..=x1 {
                if (0..3).all(|k| e[k] + bias[k] >= 0) {
                    if let Some(fragment) = fragment_at(tri, e, area_f, y * width + x) {
                        emit(fragment);
                    }
                }
                for k in 0..3 {
                    e[k] += step_x[k];
                }
            }
            for k in 0..3 {
                row[k] += step_y[k];
            }
        }
    }
}

/// The fill rule's bias of each edge for a window origin: 0 where the edge owns the sample
/// points on it, −1 where it does not, so that `e + bias >= 0` is the coverage test of edge value
/// `e` (the single-sample and the per-sample scan share it, so they share the rule).
#[inline]
pub(super) fn fill_bias(edges: [([i64; 2], [i64; 2]); 3], origin: WindowOrigin) -> [i64; 3] {
    edges.map(|(p, q)| {
        let owns = match origin {
            WindowOrigin::UpperLeft => is_top_left(p, q),
            WindowOrigin::LowerLeft => is_bottom_left(p, q),
        };
        if owns {
            0
        } else {
            -1
        }
    })
}

/// The fragment of `tri` at a covered point whose edge values are `e` (twice the area of the
/// triangle is `area`), stored at framebuffer index `pixel`: the depth interpolated in f64 from
/// the edge values and rounded once to f32; `None` where the depth has no key (outside `[0, 1]`).
#[inline]
pub(super) fn fragment_at(
    tri: &ScreenTriangle,
    e: [i64; 3],
    area: f64,
    pixel: i64,
) -> Option<Fragment> {
    let z = (e[0] as f64 * tri.z[0] + e[1] as f64 * tri.z[1] + e[2] as f64 * tri.z[2]) / area;
    depth_key(z as f32).map(|depth_key| Fragment {
        pixel: pixel as u32,
        depth_key,
        prim: tri.prim,
    })
}

/// The bounding box of three window positions: its lowest and highest corner.
#[inline]
pub(super) fn bounding_box<T: Copy + Ord + Into<i64>>([a, b, c]: [[T; 2]; 3]) -> [[i64; 2]; 2] {
    let axis = |i: usize| {
        (
            a[i].min(b[i]).min(c[i]).into(),
            a[i].max(b[i]).max(c[i]).into(),
        )
    };
    let ((x_lo, x_hi), (y_lo, y_hi)) = (axis(0), axis(1));
    [[x_lo, y_lo], [x_hi, y_hi]]
}

/// The first and last pixel whose centre lies in `[lo, hi]` (1/256 pixel) and in the pixel range
/// `[first, last]`; `None` when there is none.
#[inline]
pub(super) fn pixel_span(lo: i64, hi: i64, (first, last): (u32, u32)) -> Option<(u32, u32)> {
    // An arithmetic shift is the floor division by `ONE` (a power of two), in fewer instructions
    // than `div_euclid`: this runs for every triangle of the mesh.
    let from = ((lo - HALF + ONE - 1) >> SUBPIXEL_BITS).max(first.into());
    let to = ((hi - HALF) >> SUBPIXEL_BITS).min(last.into());
    // Both lie in [first, last] when they are ordered, so the conversions are lossless.
    (from <= to).then_some((from as u32, to as u32))
}

/// Twice the signed area of `(a, b, p)`: positive when `p` is on the interior side of `a → b` for
/// a positively oriented triangle in the y-down window.
#[inline]
pub(super) fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top edge: horizontal with the interior below; left edge: the interior to its right. For a
/// positively oriented triangle that is `dy < 0`, or `dy == 0 && dx > 0`.
#[inline]
pub(super) fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx > 0)
}

/// The top-left rule of a y-up window (OpenGL's lower-left origin) seen in fragsim's y-down rows:
/// the window's top edge is fragsim's bottom edge, so a horizontal edge with the interior above
/// (`dy == 0 && dx < 0`) is owned; left edges stay left (`dy < 0`), x is not flipped.
#[inline]
pub(super) fn is_bottom_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx < 0)
}
