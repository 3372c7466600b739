//! Rules 6 and 7: the exact scan of a triangle set up by `setup.rs`. Only covered pixel centres
//! are visited: each row's covered centres are one run (the triangle is convex), whose ends
//! follow exactly from the three integer edge functions with the fill rule of the window origin
//! (top-left, or bottom-left in fragsim's y-down rows for a lower-left origin); per covered
//! centre only the depth is interpolated, in f64 from the edge values, and rounded once to f32.

use glam::Vec4;

use super::setup::ScanSetup;
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
        if let Some(setup) = ScanSetup::within(tri, rect, self.conventions.window_origin) {
            self.scan_set_up(&setup, emit);
        }
    }

    /// Emits the fragment of every covered centre of a set-up triangle: rows top to bottom,
    /// within a row the run of covered centres left to right.
    #[inline]
    pub(super) fn scan_set_up(&self, setup: &ScanSetup, emit: &mut impl FnMut(Fragment)) {
        let PixelRect {
            x: (x0, x1),
            y: (y0, y1),
        } = setup.pixels;
        let last = i64::from(x1 - x0);
        let width = i64::from(self.viewport.width);
        let mut row = setup.origin;
        let mut row_pixel = i64::from(y0) * width + i64::from(x0);
        let step = setup.step_x;
        if setup.block {
            // Most triangles of a dense mesh: their whole box at once.
            let mut covered = setup.block_coverage(last, i64::from(y1 - y0));
            while covered != 0 {
                let bit = i64::from(covered.trailing_zeros());
                let (down, right) = (bit / BLOCK_SIDE, bit % BLOCK_SIDE);
                let e = [
                    row[0] + step[0] * right + setup.step_y[0] * down,
                    row[1] + step[1] * right + setup.step_y[1] * down,
                    row[2] + step[2] * right + setup.step_y[2] * down,
                ];
                let pixel = row_pixel + down * width + right;
                if let Some(fragment) = fragment_at(setup.prim, setup.z, e, setup.area, pixel) {
                    emit(fragment);
                }
                covered &= covered - 1;
            }
            return;
        }
        if last < NARROW_BOX_WIDTH {
            // A narrow box: its few centres of a row cost less tested one by one than the
            // divisions that find the row's covered run. (One loop for both kinds of box,
            // testing inside the run's loop, cost the A-buffer 2 % more instructions at 2048².)
            for _ in y0..=y1 {
                let mut e = row;
                for pixel in row_pixel..=row_pixel + last {
                    if setup.covers(e) {
                        if let Some(fragment) =
                            fragment_at(setup.prim, setup.z, e, setup.area, pixel)
                        {
                            emit(fragment);
                        }
                    }
                    advance(&mut e, step);
                }
                advance(&mut row, setup.step_y);
                row_pixel += width;
            }
            return;
        }
        for _ in y0..=y1 {
            if let Some((first, end)) = setup.covered_run(row, last) {
                let mut e = [
                    row[0] + step[0] * first,
                    row[1] + step[1] * first,
                    row[2] + step[2] * first,
                ];
                for pixel in row_pixel + first..=row_pixel + end {
                    if let Some(fragment) = fragment_at(setup.prim, setup.z, e, setup.area, pixel) {
                        emit(fragment);
                    }
                    advance(&mut e, step);
                }
            }
            advance(&mut row, setup.step_y);
            row_pixel += width;
        }
    }
}

/// Adds `by` to each edge value of `values`: one step along a row or down a column.
#[inline]
fn advance(values: &mut [i64; 3], by: [i64; 3]) {
    for (value, by) in values.iter_mut().zip(by) {
        *value += by;
    }
}

/// Boxes at most this many pixels wide are scanned by testing each centre of a row, wider ones
/// by their covered runs. The full dragon's rows at 2048² hold 1.2 covered centres on average,
/// and finding a run (three edges classified, up to two divisions) cost about 34 instructions a
/// row there, more than testing two or three centres.
const NARROW_BOX_WIDTH: i64 = 3;

/// Triangles that span less than this many pixels on each axis (so that their boxes hold at most
/// this many centres a side) are scanned as one block ([`ScanSetup::block_coverage`]): every
/// centre of the box tested at once, without a branch, then the covered ones visited. Tested one
/// by one, the coverage of a centre is a branch the processor guesses wrong about as often as
/// right on a dense mesh (callgrind's branch simulation put a quarter of the 2048² dragon frame's
/// mispredictions there), and so is the end of a row's run.
pub(super) const BLOCK_SIDE: i64 = 8;

impl ScanSetup {
    /// The covered centres of a box of at most [`BLOCK_SIDE`] × [`BLOCK_SIDE`] pixels whose last
    /// column and row are `last_column` and `last_row` (offsets from its first pixel): bit
    /// `BLOCK_SIDE · down + right` set when the centre `right` pixels right of and `down` below
    /// the first is covered.
    ///
    /// Every centre of the box is tested at once, four centres of a row in one four-lane vector
    /// per edge (glam's `Vec4`: SSE2 on x86-64, NEON on ARM), in f32, which is exact here: the
    /// record's triangle spans less than [`BLOCK_SIDE`] pixels (2,048 grid units) on each axis,
    /// so each step (a vertex difference times 256) is below 2^19, the edge value
    /// `(b − a) × (p − a)` at the first centre (inside the box) is below 2 · 2,048 · 2,048 = 2^23,
    /// and every value formed from it and at most seven steps along each axis stays below
    /// 2^23 + 14 · 2^19 < 2^24: integers that f32 holds exactly, as it does their sums and the
    /// products of a step by at most 7.
    #[inline]
    fn block_coverage(&self, last_column: i64, last_row: i64) -> u64 {
        const COLUMNS: Vec4 = Vec4::new(0.0, 1.0, 2.0, 3.0);
        let lane = |value: i64| Vec4::splat(value as f32);
        let mut left = [Vec4::ZERO; 3];
        let mut right = [Vec4::ZERO; 3];
        let mut down = [Vec4::ZERO; 3];
        let mut below = [Vec4::ZERO; 3];
        for k in 0..3 {
            let step = lane(self.step_x[k]);
            left[k] = lane(self.origin[k]) + COLUMNS * step;
            right[k] = left[k] + 4.0 * step;
            down[k] = lane(self.step_y[k]);
            below[k] = lane(self.threshold[k] - 1);
        }
        let inside = |half: &[Vec4; 3]| {
            let edge = |k: usize| half[k].cmpgt(below[k]);
            u64::from((edge(0) & edge(1) & edge(2)).bitmask())
        };
        let wide = last_column >= 4;
        let mut covered = 0u64;
        // Four rows always, without a branch (most boxes have at most four), four more when the
        // box has them; rows past the last are masked off below.
        for rows in [0..4, 4..8] {
            if rows.start > last_row {
                break;
            }
            for row in rows {
                let mut bits = inside(&left);
                if wide {
                    bits |= inside(&right) << 4;
                }
                covered |= bits << (BLOCK_SIDE * row);
                for k in 0..3 {
                    left[k] += down[k];
                    right[k] += down[k];
                }
            }
        }
        let columns = ((1u64 << (last_column + 1)) - 1) * 0x0101_0101_0101_0101;
        covered & columns & (u64::MAX >> (BLOCK_SIDE * (BLOCK_SIDE - 1 - last_row)))
    }

    /// Whether a centre whose edge values are `e` is covered: every edge value at least its
    /// threshold (rule 6, with the fill rule's ownership of the centres on an edge).
    #[inline]
    fn covers(&self, e: [i64; 3]) -> bool {
        e[0] >= self.threshold[0] && e[1] >= self.threshold[1] && e[2] >= self.threshold[2]
    }

    /// The covered centres of one row of the scan: the first and last offset from the row's
    /// first pixel (within `0..=last`) whose edge values are all at least their thresholds, given
    /// the edge values `row` at offset 0; `None` when no centre of the row is covered.
    ///
    /// Edge `k` at offset `d` is `row[k] + step_x[k] · d`, linear in `d`: an edge that grows
    /// along the row bounds the run from the left, one that falls bounds it from the right, and
    /// each bound is an exact integer division of non-negative numbers.
    #[inline]
    fn covered_run(&self, row: [i64; 3], last: i64) -> Option<(i64, i64)> {
        let (mut first, mut end) = (0, last);
        let edges = row.into_iter().zip(self.step_x).zip(self.threshold);
        for ((value, step), threshold) in edges {
            if value >= threshold {
                // Covered by this edge at offset 0: only a falling edge can end the run.
                if step < 0 && value + step * last < threshold {
                    // The last offset `d` with `value + step · d ≥ threshold`.
                    end = end.min((value - threshold) / -step);
                }
            } else {
                // Not covered at offset 0: only a growing edge can start the run, and only
                // where it reaches its threshold before the row's last pixel.
                if step <= 0 || value + step * last < threshold {
                    return None;
                }
                // The first offset `d` with `value + step · d ≥ threshold` (a ceiling division).
                first = first.max((threshold - value - 1) / step + 1);
            }
        }
        (first <= end).then_some((first, end))
    }
}

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
