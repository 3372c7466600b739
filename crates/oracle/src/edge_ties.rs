//! Implementation-defined edge ties: which triangle owns a sample lying exactly on an edge.
//!
//! fragsim's coverage test is exact in integers (`docs/semantics.md` §4): a sample is on an edge
//! when that edge's function is exactly 0 there, and only there does a fill rule decide. Vulkan
//! and OpenGL leave the rule to the implementation ("exactly one of the triangles sharing the
//! edge"), so a conforming implementation may decide every such sample by any of the four
//! axis-aligned rules ([`EdgeTies`]: top or bottom edges, left or right edges own their samples),
//! the same rule throughout. This module gives each rule's thresholds (from the rasterizer's own
//! fill rule, [`fill_thresholds`], so that the workspace keeps one fill rule) and, for a view,
//! the samples exactly on an edge whose coverage depends on the rule ([`TiePoints`]): enough to
//! turn the oracle built under fragsim's rule into the oracle of any other.
//!
//! Guarantee: [`thresholds`] under [`pipeline_rule`] are the pipeline's own; the oracle
//! [`TiePoints::oracle_under`] gives is, list for list, what the pipeline would rasterize with
//! that rule's thresholds (a unit test rasterizes every sample of a soup of triangles under each
//! rule and compares).

use fragsim_raster::{
    depth_key, edge_function as edge, fill_thresholds, EdgeTies, View, WindowOrigin,
};

use crate::Oracle;
use fragsim_capture::PixelLists;
use fragsim_raster::samples::SamplePattern;

/// `rule`, declared in the API's window of `origin`, in fragsim's y-down rows: a lower-left
/// window's top edges are fragsim's bottom ones (x is not flipped).
#[must_use]
pub fn in_rows(rule: EdgeTies, origin: WindowOrigin) -> EdgeTies {
    match origin {
        WindowOrigin::UpperLeft => rule,
        WindowOrigin::LowerLeft => EdgeTies::of(!rule.top(), rule.left()),
    }
}

/// The rule fragsim's pipeline rasterizes with, in rows: the top-left rule of the window `origin`
/// names (`docs/semantics.md` §9).
#[must_use]
pub fn pipeline_rule(origin: WindowOrigin) -> EdgeTies {
    in_rows(EdgeTies::TopLeft, origin)
}

/// The fill threshold of each edge `(p, q)` of a positively oriented triangle under `rule` (in
/// rows): a sample is covered by an edge where the edge's value is at least its threshold, 0
/// where the edge owns the samples on it, 1 where it does not.
///
/// The rasterizer's fill rule gives the two left rules (top-left for an upper-left origin,
/// bottom-left for a lower-left one). A right rule is a left rule seen in a mirror: mirroring x
/// and reversing each edge (the mirrored triangle is negatively oriented) keeps every edge
/// value, turns right edges into left ones and keeps horizontal edges' sense, so the rule's
/// thresholds are the left rule's of the mirrored, reversed edges.
#[must_use]
pub fn thresholds(edges: [([i64; 2], [i64; 2]); 3], rule: EdgeTies) -> [i64; 3] {
    let horizontal = if rule.top() {
        WindowOrigin::UpperLeft
    } else {
        WindowOrigin::LowerLeft
    };
    if rule.left() {
        fill_thresholds(edges, horizontal)
    } else {
        let mirror = |p: [i64; 2]| [-p[0], p[1]];
        fill_thresholds(edges.map(|(p, q)| (mirror(q), mirror(p))), horizontal)
    }
}

/// The rules (in rows) an implementation declaring `declared` in the window of `origin` may
/// follow: the declared one, or any of the four.
#[must_use]
pub fn candidates(declared: Option<EdgeTies>, origin: WindowOrigin) -> Vec<EdgeTies> {
    match declared {
        Some(rule) => vec![in_rows(rule, origin)],
        None => EdgeTies::ALL.to_vec(),
    }
}

/// A fragment at a sample exactly on an edge of its triangle, whose coverage the rule decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct TiePoint {
    /// The list it belongs to (the sample-expanded framebuffer's index).
    list: u32,
    /// Its word, `key << 32 | prim`.
    word: u64,
    /// Bit `r`: covered under [`EdgeTies::ALL`]`[r]` (in rows).
    covered: u8,
}

/// Every sample of a view that lies exactly on an edge of a (snapped, clipped, oriented) triangle
/// and whose coverage differs between the four rules, with the fragment it carries there.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TiePoints {
    points: Vec<TiePoint>,
}

impl TiePoints {
    /// The tie points of `view`: each edge of each screen triangle walked for the lattice points
    /// of every sample position on it (the perimeter, not the area), each judged under the four
    /// rules, its depth the pipeline's (`docs/semantics.md` §5).
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        clippy::shadow_unrelated,
        reason = "sample indices are below the pattern's count, at most 16; depths are f32, as a GPU's; list indices are below the sample-expanded viewport's pixels, at most Viewport::MAX_SIDE² (SampleError::TooWide); `p` and `q` are each edge's ends, as edge() names them"
    )]
    pub fn of(view: &View<'_>) -> Self {
        let pixels = view.pixel_viewport();
        let pattern = view.samples().unwrap_or(SamplePattern::CENTRE);
        let n = i64::from(pattern.count());
        let (width, height) = (i64::from(pixels.width), i64::from(pixels.height));
        let mut points = Vec::new();
        let mut seen: Vec<[i64; 3]> = Vec::new();
        for prim in 0..view.triangle_count() {
            view.screen_triangles(prim, &mut |tri| {
                let [a, b, c] = tri.xy;
                let area = edge(a, b, c);
                let edges = [(b, c), (c, a), (a, b)];
                let rules = EdgeTies::ALL.map(|rule| thresholds(edges, rule));
                seen.clear();
                for s in 0..n {
                    let offset = pattern.fixed_offset(s as usize);
                    for (p, q) in edges {
                        lattice_on_segment(p, q, offset, (width, height), &mut |i, j| {
                            if seen.contains(&[i, j, s]) {
                                return;
                            }
                            seen.push([i, j, s]);
                            let at = [i * ONE + offset[0], j * ONE + offset[1]];
                            let e = edges.map(|(p, q)| edge(p, q, at));
                            let covered = (0..4).fold(0_u8, |bits, r| {
                                let passes = (0..3).all(|k| e[k] >= rules[r][k]);
                                bits | u8::from(passes) << r
                            });
                            if covered == 0 || covered == 0b1111 {
                                return;
                            }
                            // The pipeline's depth at a covered sample (`scan.rs`): f64 from the
                            // edge values, left to right, rounded once to f32.
                            let z = (e[0] as f64 * tri.z[0]
                                + e[1] as f64 * tri.z[1]
                                + e[2] as f64 * tri.z[2])
                                / area as f64;
                            if let Some(key) = depth_key(z as f32) {
                                points.push(TiePoint {
                                    list: ((j * width + i) * n + s) as u32,
                                    word: u64::from(key) << 32 | u64::from(prim),
                                    covered,
                                });
                            }
                        });
                    }
                }
            });
        }
        Self { points }
    }

    /// Whether no sample's coverage depends on the rule.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// How many fragments rule `a` and rule `b` disagree on.
    #[must_use]
    pub fn differences(&self, a: EdgeTies, b: EdgeTies) -> usize {
        let (a, b) = (index(a), index(b));
        self.points
            .iter()
            .filter(|t| (t.covered >> a ^ t.covered >> b) & 1 == 1)
            .count()
    }

    /// `oracle`, built under rule `from`, as rule `to` would have built it: the fragments on an
    /// edge that `to` does not cover taken out, those it covers and `from` does not put in, each
    /// changed list sorted again; `None` when the two rules agree everywhere.
    #[must_use]
    pub fn oracle_under(&self, oracle: &Oracle, from: EdgeTies, to: EdgeTies) -> Option<Oracle> {
        let (from, to) = (index(from), index(to));
        let mut changes: Vec<(u32, u64, bool)> = self
            .points
            .iter()
            .filter(|t| (t.covered >> from ^ t.covered >> to) & 1 == 1)
            .map(|t| (t.list, t.word, t.covered >> to & 1 == 1))
            .collect();
        if changes.is_empty() {
            return None;
        }
        changes.sort_unstable();
        let mut lists = PixelLists::with_pixels(oracle.pixels());
        let mut next = changes.iter().peekable();
        for p in 0..oracle.pixels() {
            let mut list = oracle.pixel(p).to_vec();
            let mut changed = false;
            while let Some(&&(_, word, add)) = next.peek().filter(|c| c.0 as usize == p) {
                next.next();
                changed = true;
                if add {
                    list.push(word);
                } else if let Some(at) = list.iter().position(|&w| w == word) {
                    list.remove(at);
                }
            }
            if changed {
                list.sort_unstable();
            }
            lists.push_pixel(list);
        }
        Some(Oracle { lists })
    }
}

/// One pixel in the fixed-point grid (1/256 pixel).
const ONE: i64 = 1 << fragsim_raster::SUBPIXEL_BITS;

/// The position of `rule` in [`EdgeTies::ALL`].
#[expect(
    clippy::cast_possible_truncation,
    reason = "EdgeTies::ALL has a few rules"
)]
fn index(rule: EdgeTies) -> u32 {
    EdgeTies::ALL.iter().position(|&r| r == rule).unwrap_or(0) as u32
}

/// Calls `visit(i, j)` for every sample position `(i · ONE + offset.x, j · ONE + offset.y)` of a
/// `width × height` pixel grid lying exactly on the segment from `p` to `q` (ends included): a
/// horizontal segment's samples on its row, otherwise at most one per row, where the segment's
/// x there is an integer on the sample's column.
#[expect(
    clippy::shadow_unrelated,
    reason = "each axis's span takes its own sample offset"
)]
fn lattice_on_segment(
    p: [i64; 2],
    q: [i64; 2],
    offset: [i64; 2],
    (width, height): (i64, i64),
    visit: &mut impl FnMut(i64, i64),
) {
    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
    // The first and last grid index whose sample lies in `[lo, hi]` on an axis of `side` pixels.
    let span = |lo: i64, hi: i64, offset: i64, side: i64| {
        let first = (lo - offset + ONE - 1).div_euclid(ONE).max(0);
        let last = (hi - offset).div_euclid(ONE).min(side - 1);
        first..=last
    };
    if dy == 0 {
        if (p[1] - offset[1]).rem_euclid(ONE) != 0 {
            return;
        }
        let j = (p[1] - offset[1]).div_euclid(ONE);
        if !(0..height).contains(&j) {
            return;
        }
        for i in span(p[0].min(q[0]), p[0].max(q[0]), offset[0], width) {
            visit(i, j);
        }
        return;
    }
    for j in span(p[1].min(q[1]), p[1].max(q[1]), offset[1], height) {
        let y = j * ONE + offset[1];
        let run = dx * (y - p[1]);
        if run % dy != 0 {
            continue;
        }
        let x = p[0] + run / dy;
        if (x - offset[0]).rem_euclid(ONE) != 0 {
            continue;
        }
        let i = (x - offset[0]).div_euclid(ONE);
        if (0..width).contains(&i) {
            visit(i, j);
        }
    }
}

#[cfg(test)]
mod tests;
