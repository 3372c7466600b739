//! The order triangles are submitted in: primitive id order, or a seeded permutation of it
//! (`--shuffle SEED`) with every primitive id unchanged.
//!
//! A draw call's primitives reach a GPU's rasterizer in the order of its index buffer; an engine
//! that sorts or batches its draws changes that order without changing the geometry. Order
//! independence is the promise that the captured lists do not depend on it: a shuffled view
//! rasterizes the same fragments (the same pixel, depth key and primitive id each), only in
//! another order, so a scheme's capture differs between two submission orders exactly where the
//! scheme depends on arrival order. The executors submit triangles in [`View::submitted`] order;
//! the oracle, which sorts, does not care.
//!
//! The permutation is a Fisher–Yates shuffle driven by [`SplitMix64`] (fixed and public, as the
//! procedural scenes' generator), so a seed names one order forever.

use super::View;
use crate::rng::SplitMix64;

impl View<'_> {
    /// This view with its triangles submitted in the order of seed `seed`'s permutation of the
    /// primitive ids (the ids themselves unchanged): the same fragments, in another order.
    #[must_use]
    pub fn shuffled(mut self, seed: u64) -> Self {
        let mut order: Vec<u32> = (0..self.triangle_count()).collect();
        let mut rng = SplitMix64::new(seed);
        for i in (1..order.len()).rev() {
            // Multiply-shift rather than `%`: no modulo bias, and the same on every platform.
            #[expect(
                clippy::cast_possible_truncation,
                reason = "the high word of a u64 times i + 1 is at most i, a usize"
            )]
            let j = ((u128::from(rng.next_u64()) * (i as u128 + 1)) >> 64) as usize;
            order.swap(i, j);
        }
        self.submission = order;
        self
    }

    /// The primitive submitted `index`-th (`index < triangle_count()`): `index` itself unless the
    /// view is [`shuffled`](View::shuffled).
    #[must_use]
    #[inline]
    pub fn submitted(&self, index: u32) -> u32 {
        self.submission
            .get(index as usize)
            .copied()
            .unwrap_or(index)
    }

    /// Whether the submission order is a permutation other than primitive id order.
    #[must_use]
    pub fn is_shuffled(&self) -> bool {
        !self.submission.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use crate::{Fragment, OrbitCamera, Scene, Viewport};

    /// Every fragment of `view` in submission order.
    fn submitted(view: &crate::View<'_>) -> Vec<Fragment> {
        let mut all = Vec::new();
        for index in 0..view.triangle_count() {
            view.rasterize(view.submitted(index), &mut |f| all.push(f));
        }
        all
    }

    #[test]
    fn a_shuffle_submits_the_same_fragments_in_another_order_and_a_seed_replays_it() {
        let scene = Scene::procedural("spheres:2").unwrap();
        let view = scene
            .view(Viewport::new(24, 24).unwrap(), &OrbitCamera::default())
            .unwrap();
        assert!(!view.is_shuffled());
        let unshuffled = submitted(&view);
        let shuffled = view.clone().shuffled(7);
        assert!(shuffled.is_shuffled());
        let mut order: Vec<u32> = (0..view.triangle_count())
            .map(|i| shuffled.submitted(i))
            .collect();
        assert_ne!(order, (0..view.triangle_count()).collect::<Vec<_>>());
        order.sort_unstable();
        assert_eq!(order, (0..view.triangle_count()).collect::<Vec<_>>());
        let permuted = submitted(&shuffled);
        assert_ne!(permuted, unshuffled, "the order did not change");
        let key = |f: &Fragment| (f.prim, f.pixel, f.depth_key);
        let (mut a, mut b) = (unshuffled.clone(), permuted.clone());
        a.sort_unstable_by_key(key);
        b.sort_unstable_by_key(key);
        assert_eq!(a, b, "a shuffle changed the fragments");
        assert_eq!(submitted(&view.clone().shuffled(7)), permuted);
        assert_ne!(submitted(&view.shuffled(8)), permuted);
    }
}
