//! The order a GPU's rasterizer hands a pixel its fragments in: submission order. The ordered
//! fragment-shader interlock (`fragsim_schemes::kbuffer::interlock_ordered`) runs a pixel's
//! critical sections in this order.
//!
//! **What it is.** For each pixel, the primitives that cover it, in the order they were
//! submitted ([`View::submitted`]): a fragment's *rank* at its pixel is the number of the
//! pixel's fragments submitted before it. The hardware knows this order for free (rasterization
//! is in order); an executor here may run triangles in any order, so the order is written down
//! before the frame, by a serial rasterization of the view in submission order
//! ([`PrimitiveOrder::of_view`]), or from a hand-written stream whose order is its submission
//! order ([`PrimitiveOrder::of_fragments`]). It is the rasterizer's knowledge, not the scheme's
//! memory: no step reads it, and it is not counted in a scheme's storage.
//!
//! **Guarantee.** [`PrimitiveOrder::rank`] of a fragment of the recorded stream is its index
//! among its pixel's fragments in submission order; of any other fragment (another view, a
//! primitive that does not cover the pixel), `None`. A triangle covers a pixel at most once, so a
//! (pixel, primitive) pair names one fragment; a stream that repeats a pair keeps the pair's
//! first rank.

use fragsim_raster::{Fragment, View};

/// Every pixel's primitives in submission order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PrimitiveOrder {
    /// Pixel `p`'s entries are `ranked[offsets[p]..offsets[p + 1]]`.
    offsets: Vec<usize>,
    /// `(primitive, rank)`, each pixel's sorted by primitive (a binary search finds a rank).
    ranked: Vec<(u32, u32)>,
}

impl PrimitiveOrder {
    /// The order of `view`'s fragments as its triangles are submitted.
    #[must_use]
    pub fn of_view(view: &View<'_>) -> Self {
        let mut stream = Vec::new();
        for index in 0..view.triangle_count() {
            view.rasterize(view.submitted(index), &mut |f| stream.push(f));
        }
        Self::of_fragments(view.viewport().pixels(), &stream)
    }

    /// The order of `stream` (its submission order) on `pixels` pixels; fragments of pixels
    /// past `pixels` are left out.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a pixel's rank is below its fragment count, at most one per triangle, and triangle ids are u32"
    )]
    pub fn of_fragments(pixels: usize, stream: &[Fragment]) -> Self {
        let on_screen = |f: &&Fragment| (f.pixel as usize) < pixels;
        let mut offsets = vec![0; pixels + 1];
        for f in stream.iter().filter(on_screen) {
            offsets[f.pixel as usize + 1] += 1;
        }
        for p in 0..pixels {
            offsets[p + 1] += offsets[p];
        }
        let mut fill = offsets.clone();
        let mut ranked = vec![(0, 0); offsets[pixels]];
        for f in stream.iter().filter(on_screen) {
            let p = f.pixel as usize;
            // The rank is the place in arrival order, before the pixel's entries are sorted.
            ranked[fill[p]] = (f.prim, (fill[p] - offsets[p]) as u32);
            fill[p] += 1;
        }
        for p in 0..pixels {
            // Stable: a repeated pair keeps its first rank first.
            ranked[offsets[p]..offsets[p + 1]].sort_by_key(|&(prim, _)| prim);
        }
        Self { offsets, ranked }
    }

    /// The number of `fragment`'s pixel's fragments submitted before it, if the recorded stream
    /// holds it.
    #[must_use]
    pub fn rank(&self, fragment: Fragment) -> Option<u32> {
        let p = fragment.pixel as usize;
        let entries = &self.ranked[*self.offsets.get(p)?..*self.offsets.get(p + 1)?];
        let first = entries.partition_point(|&(prim, _)| prim < fragment.prim);
        entries
            .get(first)
            .filter(|&&(prim, _)| prim == fragment.prim)
            .map(|&(_, rank)| rank)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fragment(pixel: u32, prim: u32) -> Fragment {
        Fragment {
            pixel,
            depth_key: 0,
            prim,
        }
    }

    #[test]
    fn a_rank_is_the_place_in_the_pixels_submission_order() {
        // Pixel 0 receives primitives 9, 2, 5 in that order; pixel 1 receives 2.
        let stream = [
            fragment(0, 9),
            fragment(0, 2),
            fragment(1, 2),
            fragment(0, 5),
        ];
        let order = PrimitiveOrder::of_fragments(2, &stream);
        let ranks: Vec<_> = stream.iter().map(|&f| order.rank(f)).collect();
        assert_eq!(ranks, [Some(0), Some(1), Some(0), Some(2)]);
        // Not in the stream, or off the viewport.
        assert_eq!(order.rank(fragment(1, 9)), None);
        assert_eq!(order.rank(fragment(2, 2)), None);
        assert_eq!(PrimitiveOrder::default().rank(fragment(0, 0)), None);
    }
}
