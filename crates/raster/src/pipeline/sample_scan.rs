//! Rules 6 and 7 per sample (`docs/semantics.md`, "Multisampling"): the scan of a snapped,
//! oriented triangle at every sample position of a [`SamplePattern`] instead of the pixel centre.
//!
//! The edge functions, the fill rule and the depth interpolation are those of the single-sample
//! scan (`scan.rs`), evaluated at `pixel corner + sample offset` in the same 1/256-pixel fixed
//! point: each edge value is the value at the pixel's upper-left corner plus the sample's exact
//! integer offset along the edge's gradient, so at the centre it is the very integer the
//! single-sample scan computes, and so is the depth. The scan lives beside the single-sample one
//! rather than inside it, so that the hot single-sample loop stays as it is.
//!
//! Fragments index the sample-expanded framebuffer ([`crate::samples`]): sample `s` of pixel
//! `(x, y)` is column `x * n + s`. A rectangle given to the scan (a tile) is in those columns.

use super::edges::{bounding_box, edge, fill_thresholds, fragment_at};
use super::{PixelRect, ScreenTriangle, View, Viewport, ONE};
use crate::fragment::Fragment;
use crate::samples::{SampleError, SamplePattern};

/// The most samples a pattern has.
const MAX_SAMPLES: usize = 16;

/// A view's multisampling: its pattern and the sample-expanded framebuffer fragments index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Sampling {
    pattern: SamplePattern,
    framebuffer: Viewport,
}

impl Sampling {
    /// The sample-expanded framebuffer.
    pub(super) fn framebuffer(self) -> Viewport {
        self.framebuffer
    }
}

impl View<'_> {
    /// This view rasterizing one fragment per covered sample of `pattern`, into the
    /// sample-expanded framebuffer ([`crate::samples`]): [`View::viewport`] becomes that
    /// framebuffer, so the oracle and every scheme built on the view work per sample.
    /// [`SamplePattern::CENTRE`] rasterizes exactly the fragments of the view without a pattern.
    ///
    /// # Errors
    /// An expanded framebuffer wider than [`Viewport::MAX_SIDE`].
    pub fn with_samples(mut self, pattern: SamplePattern) -> Result<Self, SampleError> {
        let framebuffer = pattern.expand(self.viewport)?;
        self.sampling = Some(Sampling {
            pattern,
            framebuffer,
        });
        Ok(self)
    }

    /// The sample pattern, when the view rasterizes per sample ([`View::with_samples`]).
    #[must_use]
    pub fn samples(&self) -> Option<SamplePattern> {
        self.sampling.map(|s| s.pattern)
    }

    /// The render target in pixels, whether or not the view rasterizes per sample (then
    /// [`View::viewport`] is the sample-expanded framebuffer).
    #[must_use]
    pub fn pixel_viewport(&self) -> Viewport {
        self.viewport
    }

    /// [`View::rasterize_in`] of a sampled view: `rect` in sample columns.
    pub(super) fn rasterize_samples_in(
        &self,
        prim: u32,
        sampling: Sampling,
        rect: PixelRect,
        emit: &mut impl FnMut(Fragment),
    ) {
        self.screen_triangles(prim, &mut |tri| {
            self.scan_samples_in(&tri, sampling, rect, emit);
        });
    }

    /// [`View::pixel_bounds`] of a sampled view: the sample columns of every pixel one of whose
    /// samples the bounding boxes of the triangle's pieces hold.
    pub(super) fn sample_bounds(&self, prim: u32, sampling: Sampling) -> Option<PixelRect> {
        let n = sampling.pattern.count();
        let mut bounds: Option<PixelRect> = None;
        self.screen_triangles(prim, &mut |tri| {
            if let Some((x, y)) = sample_pixels(&tri, sampling.pattern, self.viewport.rect()) {
                let piece = PixelRect {
                    x: (x.0 * n, x.1 * n + n - 1),
                    y,
                };
                bounds = Some(bounds.map_or(piece, |b| b.union(piece)));
            }
        });
        bounds
    }

    /// Scans an oriented snapped triangle at every sample of the pattern whose column lies in
    /// `rect`: every covered sample emits a fragment, rows top to bottom, pixels left to right,
    /// samples in index order.
    fn scan_samples_in(
        &self,
        tri: &ScreenTriangle,
        sampling: Sampling,
        rect: PixelRect,
        emit: &mut impl FnMut(Fragment),
    ) {
        let pattern = sampling.pattern;
        let n = pattern.count();
        let pixels = PixelRect {
            x: (rect.x.0 / n, rect.x.1 / n),
            y: rect.y,
        };
        let Some(((x0, x1), (y0, y1))) = sample_pixels(tri, pattern, pixels) else {
            return;
        };
        let [a, b, c] = tri.xy;
        let area = edge(a, b, c);
        debug_assert!(
            area > 0,
            "set-up triangles are oriented with a positive area"
        );
        // Edge i is opposite vertex i, so its value is the barycentric weight of vertex i.
        let edges = [(b, c), (c, a), (a, b)];
        let threshold = fill_thresholds(edges, self.conventions.window_origin);
        // The gradient of edge (p, q) is (−(q_y − p_y), q_x − p_x) per 1/256 pixel.
        let gradient = edges.map(|(p, q)| [-(q[1] - p[1]), q[0] - p[0]]);
        let mut offsets = [[0_i64; 3]; MAX_SAMPLES];
        for (s, offset) in offsets.iter_mut().enumerate().take(n as usize) {
            let [ox, oy] = pattern.fixed_offset(s);
            *offset = gradient.map(|[gx, gy]| gx * ox + gy * oy);
        }
        let step_x = gradient.map(|[gx, _]| gx * ONE);
        let step_y = gradient.map(|[_, gy]| gy * ONE);
        let corner = [i64::from(x0) * ONE, i64::from(y0) * ONE];
        let mut row = edges.map(|(p, q)| edge(p, q, corner));
        let area_f = area as f64;
        let samples = n as usize;
        let (n, width) = (i64::from(n), i64::from(sampling.framebuffer.width));
        let columns = i64::from(rect.x.0)..=i64::from(rect.x.1);
        for y in i64::from(y0)..=i64::from(y1) {
            let mut at_corner = row;
            for x in i64::from(x0)..=i64::from(x1) {
                for (s, offset) in offsets.iter().enumerate().take(samples) {
                    let column = x * n + s as i64;
                    let e: [i64; 3] = std::array::from_fn(|k| at_corner[k] + offset[k]);
                    if !columns.contains(&column) || !(0..3).all(|k| e[k] >= threshold[k]) {
                        continue;
                    }
                    if let Some(fragment) =
                        fragment_at(tri.prim, tri.z, e, area_f, y * width + column)
                    {
                        emit(fragment);
                    }
                }
                for k in 0..3 {
                    at_corner[k] += step_x[k];
                }
            }
            for k in 0..3 {
                row[k] += step_y[k];
            }
        }
    }
}

/// The pixels of `within` one of whose samples the triangle's bounding box holds; `None` when
/// there is none.
fn sample_pixels(
    tri: &ScreenTriangle,
    pattern: SamplePattern,
    within: PixelRect,
) -> Option<((u32, u32), (u32, u32))> {
    let [lo, hi] = bounding_box(tri.xy);
    let [min_offset, max_offset] = pattern.fixed_extent();
    let x = sample_span(lo[0], hi[0], min_offset[0], max_offset[0], within.x)?;
    let y = sample_span(lo[1], hi[1], min_offset[1], max_offset[1], within.y)?;
    Some((x, y))
}

/// The first and last pixel in `[first, last]` with a sample offset in `[min_offset,
/// max_offset]` (1/256 pixel from its corner) that can lie in `[lo, hi]`; with one sample at the
/// centre, exactly the pixels whose centres lie there.
#[expect(
    clippy::cast_possible_truncation,
    reason = "both lie in [first, last], u32s, when they are ordered"
)]
fn sample_span(
    lo: i64,
    hi: i64,
    min_offset: i64,
    max_offset: i64,
    (first, last): (u32, u32),
) -> Option<(u32, u32)> {
    let from = (lo - max_offset + ONE - 1)
        .div_euclid(ONE)
        .max(first.into());
    let to = (hi - min_offset).div_euclid(ONE).min(last.into());
    (from <= to).then_some((from as u32, to as u32))
}
