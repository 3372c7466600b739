//! The integer edge functions and what the setup, the scan and the per-sample scan share of
//! them: the fill rule's thresholds, a triangle's bounding box, and a covered point's depth.

use crate::conventions::WindowOrigin;
use crate::fragment::{depth_key, Fragment};

/// The fill rule's threshold of each edge for a window origin: a sample point is covered by an
/// edge when the edge's value there is at least the threshold, 0 where the edge owns the points
/// on it and 1 where it does not (the single-sample and the per-sample scan share it, so they
/// share the rule).
#[inline]
pub fn fill_thresholds(edges: [([i64; 2], [i64; 2]); 3], origin: WindowOrigin) -> [i64; 3] {
    per_edge(edges, |p, q| {
        let owns = match origin {
            WindowOrigin::UpperLeft => is_top_left(p, q),
            WindowOrigin::LowerLeft => is_bottom_left(p, q),
        };
        i64::from(!owns)
    })
}

/// `f` of each edge `(p, q)`, written out rather than through `array::map`, which the profile
/// showed left as a call in the per-triangle path.
#[inline]
pub(super) fn per_edge<T>(
    edges: [([i64; 2], [i64; 2]); 3],
    f: impl Fn([i64; 2], [i64; 2]) -> T,
) -> [T; 3] {
    let [(a, b), (c, d), (e, g)] = edges;
    [f(a, b), f(c, d), f(e, g)]
}

/// The fragment of primitive `prim` (window depths `z` at its vertices, twice its area `area`)
/// at a covered point whose edge values are `e`, stored at framebuffer index `pixel`: the depth
/// interpolated in f64 from the edge values and rounded once to f32; `None` where the depth has
/// no key (outside `[0, 1]`).
#[inline]
#[expect(
    clippy::cast_possible_truncation,
    reason = "depths are f32, as a GPU's; the pixel index is below the viewport's width × height, at most Viewport::MAX_SIDE² = 2^28"
)]
pub(super) fn fragment_at(
    prim: u32,
    z: [f64; 3],
    e: [i64; 3],
    area: f64,
    pixel: i64,
) -> Option<Fragment> {
    let depth = (e[0] as f64 * z[0] + e[1] as f64 * z[1] + e[2] as f64 * z[2]) / area;
    depth_key(depth as f32).map(|depth_key| Fragment {
        pixel: pixel as u32,
        depth_key,
        prim,
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

/// Twice the signed area of `(a, b, p)`: positive when `p` is on the interior side of `a → b` for
/// a positively oriented triangle in the y-down window.
#[inline]
pub fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top edge: horizontal with the interior below; left edge: the interior to its right. For a
/// positively oriented triangle that is `dy < 0`, or `dy == 0 && dx > 0`.
#[inline]
pub(super) fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    // Without short-circuits: the edge's direction is as good as random on a mesh, and a
    // branch on it was guessed wrong for one triangle in ten at 2048² (callgrind).
    (dy < 0) | ((dy == 0) & (dx > 0))
}

/// The top-left rule of a y-up window (OpenGL's lower-left origin) seen in fragsim's y-down rows:
/// the window's top edge is fragsim's bottom edge, so a horizontal edge with the interior above
/// (`dy == 0 && dx < 0`) is owned; left edges stay left (`dy < 0`), x is not flipped.
#[inline]
pub(super) fn is_bottom_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    (dy < 0) | ((dy == 0) & (dx < 0))
}
