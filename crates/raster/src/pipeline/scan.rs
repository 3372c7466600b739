//! Rules 6 and 7: the exact scan of a triangle set up by `setup.rs`. Only covered pixel centres
//! are visited: each row's covered centres are one run (the triangle is convex), whose ends
//! follow exactly from the three integer edge functions with the fill rule of the window origin
//! (top-left, or bottom-left in fragsim's y-down rows for a lower-left origin); per covered
//! centre only the depth is interpolated, in f64 from the edge values, and rounded once to f32.

use glam::Vec4;

use super::edges::fragment_at;
use super::setup::{ScanSetup, BLOCK_SIDE};
use super::{PixelRect, ScreenTriangle, View};
use crate::fragment::Fragment;

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
    for (value, step) in values.iter_mut().zip(by) {
        *value += step;
    }
}

/// Boxes at most this many pixels wide are scanned by testing each centre of a row, wider ones
/// by their covered runs. The full dragon's rows at 2048² hold 1.2 covered centres on average,
/// and finding a run (three edges classified, up to two divisions) cost about 34 instructions a
/// row there, more than testing two or three centres.
const NARROW_BOX_WIDTH: i64 = 3;

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
        let mut covered = 0_u64;
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
        let columns = ((1_u64 << (last_column + 1)) - 1) * 0x0101_0101_0101_0101;
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
