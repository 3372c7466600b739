//! Triangle setup, the stage between the vertex stage and the scan: each triangle either
//! rejected in a few integer operations or set up once into a compact record for the scan.
//!
//! Most triangles of a dense mesh cover no pixel centre (the full dragon at 512², 871,414
//! triangles, has 103,652 fragments), so the common case is a reject. The vertex stage has left
//! each vertex's interval between pixel-centre lines on each axis (`CentreCells`): a
//! triangle whose three vertices lie strictly inside one such interval on either axis has a
//! bounding box that holds no pixel centre, and is dropped after three loads and a few
//! comparisons. The others load their outcodes and snapped positions, and a triangle whose box
//! holds no pixel centre of the rectangle scanned is dropped before its depths are loaded or an
//! edge function is formed; one whose box holds a single centre is tested there first, and
//! dropped without a record when it misses it. A triangle that survives is oriented (rule 5: facing, culling, zero area)
//! and set up into a [`ScanSetup`]: the pixels its box holds, its three edge functions at the
//! first of them and their steps, the fill rule's thresholds and the depth inputs. The scan
//! (`scan.rs`) reads only that record. Triangles that need clipping take the general path
//! ([`View::screen_triangles`]) and each piece is set up the same way.
//!
//! [`View::rasterize_each_in`] runs the stages over a run of triangles in batches: the setup of a
//! batch, then the scan of its records, so that each loop stays small; the fragments come out in
//! the order of triangle after triangle, as [`View::rasterize_in`] gives them.
//!
//! [`View::set_up_each`] hands the records out instead ([`TriangleSetup`]), so that an executor can
//! bin them to screen tiles and scan each tile's part later ([`View::scan_within`]): a triangle is
//! set up once however many tiles and geometry passes scan it.

use super::edges::{bounding_box, edge, fill_thresholds, per_edge};
use super::{PixelRect, ScreenTriangle, Snapped, View, CLIP_BITS, HALF, NOT_IN_FRONT_BIT, ONE};
use crate::conventions::WindowOrigin;
use crate::fragment::Fragment;

/// Triangles that span less than this many pixels on each axis (so that their boxes hold at most
/// this many centres a side) are scanned as one block ([`ScanSetup::block_coverage`]): every
/// centre of the box tested at once, without a branch, then the covered ones visited. Tested one
/// by one, the coverage of a centre is a branch the processor guesses wrong about as often as
/// right on a dense mesh (callgrind's branch simulation put a quarter of the 2048² dragon frame's
/// mispredictions there), and so is the end of a row's run.
pub(super) const BLOCK_SIDE: i64 = 8;

/// Triangles set up before their records are scanned: small enough that a batch's records stay
/// in the first-level cache.
const TRIANGLES_PER_BATCH: usize = 128;

/// A snapped, oriented triangle (or clipped piece) set up for the scan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct ScanSetup {
    /// Primitive id.
    pub(super) prim: u32,
    /// The pixels whose centres the triangle's snapped bounding box holds within the rectangle
    /// scanned: the only pixels the scan may visit.
    pub(super) pixels: PixelRect,
    /// The edge functions `E_i` (edge `i` opposite vertex `i`) at the centre of the first pixel
    /// of `pixels` (its lowest column and row).
    pub(super) origin: [i64; 3],
    /// What one pixel to the right adds to each edge function.
    pub(super) step_x: [i64; 3],
    /// What one pixel down adds to each edge function.
    pub(super) step_y: [i64; 3],
    /// A centre is covered when every `E_i` is at least its threshold: 0 on an edge that owns
    /// the centres on it under the fill rule, 1 on one that does not.
    pub(super) threshold: [i64; 3],
    /// Window depth of each vertex.
    pub(super) z: [f64; 3],
    /// Twice the triangle's area, positive, as f64 (exact: below 2^49).
    pub(super) area: f64,
    /// Whether the triangle's snapped bounding box spans less than [`BLOCK_SIDE`] pixels on
    /// each axis, so that the scan tests its box as one block ([`ScanSetup::block_coverage`]).
    pub(super) block: bool,
}

impl ScanSetup {
    /// This record restricted to the pixels of `rect`, its edge functions moved to the first of
    /// them (exactly: they are linear in the pixel); `None` when no pixel of its box lies there.
    #[inline]
    fn restricted(&self, rect: PixelRect) -> Option<Self> {
        let x = (self.pixels.x.0.max(rect.x.0), self.pixels.x.1.min(rect.x.1));
        let y = (self.pixels.y.0.max(rect.y.0), self.pixels.y.1.min(rect.y.1));
        if x.0 > x.1 || y.0 > y.1 {
            return None;
        }
        let right = i64::from(x.0 - self.pixels.x.0);
        let down = i64::from(y.0 - self.pixels.y.0);
        let moved = |k: usize| self.origin[k] + self.step_x[k] * right + self.step_y[k] * down;
        Some(Self {
            pixels: PixelRect { x, y },
            origin: [moved(0), moved(1), moved(2)],
            ..*self
        })
    }

    /// Sets up an oriented triangle of doubled area `area` (positive) and bounding box
    /// `[lo, hi]` for a scan of `pixels`, which must lie within the box's centres.
    // Always inlined: the record is then written straight into the caller's batch (a call
    // returned it through the stack and copied it, 150 instructions a triangle at 2048²).
    #[inline(always)]
    fn new(
        tri: &ScreenTriangle,
        area: i64,
        [lo, hi]: [[i64; 2]; 2],
        pixels: PixelRect,
        origin: WindowOrigin,
    ) -> Self {
        let [a, b, c] = tri.xy;
        let edges = [(b, c), (c, a), (a, b)];
        let first_centre = [
            i64::from(pixels.x.0) * ONE + HALF,
            i64::from(pixels.y.0) * ONE + HALF,
        ];
        Self {
            prim: tri.prim,
            pixels,
            origin: per_edge(edges, |p, q| edge(p, q, first_centre)),
            step_x: per_edge(edges, |p, q| (p[1] - q[1]) * ONE),
            step_y: per_edge(edges, |p, q| (q[0] - p[0]) * ONE),
            threshold: fill_thresholds(edges, origin),
            z: tri.z,
            area: area as f64,
            block: (hi[0] - lo[0]) | (hi[1] - lo[1]) < BLOCK_SIDE * ONE,
        }
    }

    /// An oriented triangle set up for a scan of the pixels of `rect`; `None` when its bounding
    /// box holds no centre there.
    pub(super) fn within(
        tri: &ScreenTriangle,
        rect: PixelRect,
        origin: WindowOrigin,
    ) -> Option<Self> {
        let [lo, hi] = bounding_box(tri.xy);
        let pixels = rect.centres_within(lo, hi)?;
        let [a, b, c] = tri.xy;
        Some(Self::new(tri, edge(a, b, c), [lo, hi], pixels, origin))
    }
}

/// A triangle, or one piece of a clipped one, set up once by [`View::set_up_each`] for the scan
/// of any rectangle of its pixels ([`View::scan_within`]): what an executor that bins triangles
/// to screen tiles keeps for each tile.
#[derive(Clone, Copy, Debug)]
pub struct TriangleSetup(SetUp);

/// The two kinds of [`TriangleSetup`].
#[derive(Clone, Copy, Debug)]
enum SetUp {
    /// A record for the scan of pixel centres.
    Centres(ScanSetup),
    /// A triangle of a view that rasterizes per sample, with the sample columns its pieces may
    /// cover ([`View::pixel_bounds`]): the sample scan sets its pieces up for each rectangle.
    Samples { prim: u32, pixels: PixelRect },
}

impl TriangleSetup {
    /// The pixels (sample columns, for a view that rasterizes per sample) that its fragments may
    /// cover: every fragment of the triangle lies inside.
    #[must_use]
    #[inline]
    pub fn pixels(&self) -> PixelRect {
        match self.0 {
            SetUp::Centres(record) => record.pixels,
            SetUp::Samples { pixels, .. } => pixels,
        }
    }
}

/// Whether the snapped triangle `xy`, of either orientation, covers the centre of pixel `(x, y)`
/// under the fill rule of `origin`: the scan's coverage test of that centre on the triangle
/// oriented as [`View::oriented`] orients it, without the rest of its record. A triangle of zero
/// area covers nothing.
///
/// The three edge functions of the triangle as given sum to its doubled signed area, and
/// reorienting it negates them: so a centre where all three have one strict sign is inside
/// whatever the orientation, one where they have both strict signs is outside (or the area is
/// zero), and only a centre on an edge needs the orientation and the fill rule.
#[inline]
fn covers_centre(xy: [[i64; 2]; 3], (x, y): (u32, u32), origin: WindowOrigin) -> bool {
    let [a, b, c] = xy;
    let centre = [i64::from(x) * ONE + HALF, i64::from(y) * ONE + HALF];
    let e = [edge(b, c, centre), edge(c, a, centre), edge(a, b, centre)];
    let positive = (e[0] > 0) as u8 + (e[1] > 0) as u8 + (e[2] > 0) as u8;
    let negative = (e[0] < 0) as u8 + (e[1] < 0) as u8 + (e[2] < 0) as u8;
    match (positive, negative) {
        (3, _) | (_, 3) => true,
        (1.., 1..) => false,
        _ => covers_centre_on_an_edge(xy, centre, origin),
    }
}

/// [`covers_centre`] for a centre on an edge of the triangle: oriented, then tested against the
/// fill rule's thresholds as the scan tests it.
#[cold]
fn covers_centre_on_an_edge(
    [a, b, c]: [[i64; 2]; 3],
    centre: [i64; 2],
    origin: WindowOrigin,
) -> bool {
    let area = edge(a, b, c);
    if area == 0 {
        return false;
    }
    let (b, c) = if area < 0 { (c, b) } else { (b, c) };
    let edges = [(b, c), (c, a), (a, b)];
    let e = per_edge(edges, |p, q| edge(p, q, centre));
    let threshold = fill_thresholds(edges, origin);
    e[0] >= threshold[0] && e[1] >= threshold[1] && e[2] >= threshold[2]
}

impl View<'_> {
    /// The setup of triangle `prim` for a scan of `rect`: `visit` gets a record for the triangle,
    /// or for each piece of a clipped one, unless it is rejected, culled, degenerate or its
    /// bounding box holds no pixel centre in `rect`. Not for a view that rasterizes per sample.
    #[inline]
    pub(super) fn set_up_in(&self, prim: u32, rect: PixelRect, visit: &mut impl FnMut(ScanSetup)) {
        let [ia, ib, ic] = self.mesh.triangles[prim as usize];
        let (ka, kb, kc) = (
            self.cells[ia as usize],
            self.cells[ib as usize],
            self.cells[ic as usize],
        );
        let between_centre_lines = |k: usize| ka[k] == kb[k] && kb[k] == kc[k] && ka[k] & 1 == 0;
        if between_centre_lines(0) || between_centre_lines(1) {
            return;
        }
        let origin = self.conventions.window_origin;
        let (a, b, c) = (
            self.window[ia as usize],
            self.window[ib as usize],
            self.window[ic as usize],
        );
        if (a.outcode | b.outcode | c.outcode) & (CLIP_BITS | NOT_IN_FRONT_BIT) != 0
            || a.outcode & b.outcode & c.outcode != 0
        {
            // Rare: rejected by a frustum plane, clipped, or not in front of the eye.
            self.screen_triangles(prim, &mut |tri| {
                if let Some(setup) = ScanSetup::within(&tri, rect, origin) {
                    visit(setup);
                }
            });
            return;
        }
        // The exact reject, on the snapped bounding box within `rect`.
        let axis = |k: usize| {
            let (p, q, r) = (a.xy[k], b.xy[k], c.xy[k]);
            (i64::from(p.min(q).min(r)), i64::from(p.max(q).max(r)))
        };
        let ((x_lo, x_hi), (y_lo, y_hi)) = (axis(0), axis(1));
        let (lo, hi) = ([x_lo, y_lo], [x_hi, y_hi]);
        let Some(pixels) = rect.centres_within(lo, hi) else {
            return;
        };
        let xy = [a.position(), b.position(), c.position()];
        if pixels.x.0 == pixels.x.1
            && pixels.y.0 == pixels.y.1
            && !covers_centre(xy, (pixels.x.0, pixels.y.0), origin)
        {
            // One centre in the box, and the triangle misses it: most survivors of a dense mesh
            // at a low resolution, dropped without a record.
            return;
        }
        let snapped: [Snapped; 3] = [
            (xy[0], self.window_z[ia as usize]),
            (xy[1], self.window_z[ib as usize]),
            (xy[2], self.window_z[ic as usize]),
        ];
        if let Some((tri, area)) = self.oriented(prim, snapped) {
            visit(ScanSetup::new(&tri, area, [lo, hi], pixels, origin));
        }
    }

    /// Sets up the triangles `prims`, in that order, for scans of the framebuffer
    /// ([`View::scan_within`]): `visit` gets a record for each triangle, or for each piece of a
    /// clipped one, in order, unless it is rejected, culled, degenerate or holds no pixel centre
    /// (no sample, for a view that rasterizes per sample).
    pub fn set_up_each(
        &self,
        prims: impl IntoIterator<Item = u32>,
        visit: &mut impl FnMut(TriangleSetup),
    ) {
        if let Some(sampling) = self.sampling {
            for prim in prims {
                if let Some(pixels) = self.sample_bounds(prim, sampling) {
                    visit(TriangleSetup(SetUp::Samples { prim, pixels }));
                }
            }
            return;
        }
        let rect = self.viewport.rect();
        for prim in prims {
            self.set_up_in(prim, rect, &mut |record| {
                visit(TriangleSetup(SetUp::Centres(record)));
            });
        }
    }

    /// Scans the pixels of `rect` of a triangle that this view set up ([`View::set_up_each`]):
    /// exactly the fragments [`View::rasterize_in`] gives there for that triangle (or that piece
    /// of it), in the same order.
    pub fn scan_within(
        &self,
        setup: &TriangleSetup,
        rect: PixelRect,
        emit: &mut impl FnMut(Fragment),
    ) {
        match setup.0 {
            SetUp::Centres(record) => {
                if let Some(part) = record.restricted(rect) {
                    self.scan_set_up(&part, emit);
                }
            }
            SetUp::Samples { prim, .. } => {
                if let Some(sampling) = self.sampling {
                    self.rasterize_samples_in(prim, sampling, rect, emit);
                }
            }
        }
    }

    /// Rasterizes the triangles `prims`, in that order, restricted to the pixels of `rect`:
    /// exactly the fragments of [`View::rasterize_in`] on each triangle, one after the other.
    /// Batches of triangles are set up, then their records scanned.
    pub fn rasterize_each_in(
        &self,
        prims: impl IntoIterator<Item = u32>,
        rect: PixelRect,
        emit: &mut impl FnMut(Fragment),
    ) {
        if let Some(sampling) = self.sampling {
            for prim in prims {
                self.rasterize_samples_in(prim, sampling, rect, emit);
            }
            return;
        }
        let mut prims = prims.into_iter();
        let mut batch = Vec::with_capacity(TRIANGLES_PER_BATCH);
        loop {
            batch.clear();
            let mut taken = 0;
            for prim in prims.by_ref() {
                self.set_up_in(prim, rect, &mut |setup| batch.push(setup));
                taken += 1;
                if taken == TRIANGLES_PER_BATCH {
                    break;
                }
            }
            for setup in &batch {
                self.scan_set_up(setup, emit);
            }
            if taken < TRIANGLES_PER_BATCH {
                return;
            }
        }
    }
}
