//! Multi-layer alpha blending (MLAB, Salvi & Vaidyanathan, I3D 2014), the capture half: `K`
//! nodes per pixel, kept sorted inside a fragment-shader-interlock critical section, the two
//! farthest merged into one when a fragment arrives at a full pixel.
//!
//! **Algorithm.** Each pixel owns `K` nodes. A node is what MLAB's node is, less its colour: the
//! depth of the nearest fragment it holds (here, as everywhere in the catalog, that fragment's
//! `u64` `depth_key << 32 | prim`, so that ties order as the oracle orders them) and how many
//! fragments were merged into it. A fragment's walk is **one** step, the critical section: take
//! the pixel's lock ([`Memory::lock`], as [`kbuffer::interlock`](crate::kbuffer::interlock)
//! does), load the `K` nodes, insert the fragment as a node of one in depth order, and if that
//! makes `K + 1` nodes merge the last two (the farther node's fragments join the nearer one,
//! which keeps its depth), store the `K` nodes, unlock. A step that merged ends
//! [`Step::Dropped`]: one fragment left the node list (its colour, on a GPU, went into its
//! neighbour's).
//!
//! **Guarantee.** The node list is exactly the pixel's `K` nearest fragments, in canonical
//! order, under **any** interleaving: [`Guarantee::Exact`], [`Promise::Nearest`]`(K)`, judged
//! by the oracle on every executor like any catalog scheme. Proof, by induction over a pixel's
//! critical sections (the lock makes each indivisible): if the nodes' depths are the `K`
//! nearest of the fragments so far, inserting the newcomer gives `K + 1` depths that contain
//! the `K` nearest of the fragments now seen, and merging the last two drops the farthest of
//! them. Every fragment is in exactly one node, so the nodes' counts add up to the pixel's
//! fragments, and each fragment beyond the `K` kept ends exactly one walk `Dropped`.
//!
//! **What is not judged here, and why.** MLAB's point is its colour: a merged node blends the
//! colours of its fragments in the order they were merged, and a later fragment that belongs
//! between two merged ones is composited in the wrong place. That colour is an *approximation*
//! of the exact image, and it is not a fragment list the oracle could diff: the capture crate
//! knows no colours. So the catalog entry holds MLAB's node structure to the oracle (where MLAB
//! promises exactness: the nodes' depths), and its image is measured, never judged, by
//! `fragsim_shade::approximate`'s `Mlab` (the same merge rule, with colour) through
//! `fragsim bench --approximate mlab`: error pixels, mean and maximum colour error, PSNR, per
//! depth-complexity bucket. The catalog row's own transparency image is that of its node
//! depths (the `K` nearest, as MDTS's), not MLAB's merged colour.
//!
//! **Cost.** One geometry pass, 1 step and 1 locked operation per fragment when uncontended
//! (each retry under contention is one more), `K` loads of each array and, always, `K` stores
//! of each. Memory: `12 K + 4` bytes per pixel here (a `u64` depth and a `u32` count a node, the
//! lock); the paper's node is a 32-bit depth and an RGBA8 word (8 bytes, Salvi & Vaidyanathan
//! §4), and its interlock costs no memory.
//!
//! **Sources.** Salvi & Vaidyanathan, "Multi-layer Alpha Blending", I3D 2014 (nodes of depth,
//! colour and transmittance; the two farthest merged when full; Intel's PixelSync as the
//! critical section).
//!
//! **Departures.** The critical section is the unordered interlock's (mutual exclusion in any
//! order); the paper's PixelSync is ordered. For the node depths the order cannot matter (the
//! `K` nearest of a set do not depend on arrival order); the counts, like MLAB's colours, do,
//! and `bench --approximate` blends in primitive order, as an ordered interlock would. Nodes
//! hold a fragment count instead of colour and transmittance (see above).

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::kbuffer::EMPTY;
use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// MLAB's `K` nodes per pixel, merged when full, inside a per-pixel critical section.
#[derive(Clone, Debug)]
pub struct Mlab {
    descriptor: Descriptor,
    k: u32,
}

impl Mlab {
    /// MLAB with `k` nodes per pixel, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, k: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(
                "mlab needs at least one node per pixel (K ≥ 1)".into(),
            ));
        }
        let descriptor = Descriptor {
            name: "mlab".into(),
            layout: Layout {
                // `u32` words: `p` is pixel `p`'s lock, then `K` counts a pixel.
                words32: viewport.pixels() * (1 + k as usize),
                init32: 0,
                words64: viewport.pixels() * k as usize,
                init64: EMPTY,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::Exact,
            promise: Promise::Nearest(k),
            pixels: viewport.pixels(),
            counts_every_drop: true,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            k,
        })
    }

    /// Like [`Mlab::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`Mlab::new`].
    pub fn with_k(viewport: Viewport, k: u32) -> Result<Self, CaptureError> {
        Self::new(viewport, k, MEMORY_CAP_DEFAULT)
    }

    /// The `u32` word of node `node` of pixel `pixel`'s count (words `0..pixels` are the locks).
    fn count_word(&self, pixel: usize, node: usize) -> usize {
        self.descriptor.pixels + pixel * self.k as usize + node
    }

    /// Pixel `pixel`'s nodes as `(depth, fragments merged into it)`, nearest first, empty nodes
    /// left out.
    #[must_use]
    pub fn nodes<M: Memory>(&self, memory: &M, pixel: usize) -> Vec<(u64, u32)> {
        let k = self.k as usize;
        (0..k)
            .map(|i| {
                (
                    WordMemory::<u64>::load(memory, pixel * k + i),
                    WordMemory::<u32>::load(memory, self.count_word(pixel, i)),
                )
            })
            .filter(|&(depth, _)| depth != EMPTY)
            .collect()
    }
}

impl Scheme for Mlab {
    type State = Fragment;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Fragment {
        fragment
    }

    /// The whole critical section: lock, load the nodes, insert, merge the two farthest if
    /// there are `K + 1`, store, unlock.
    fn step<M: Memory>(&self, fragment: &mut Fragment, memory: &M) -> Step {
        let (pixel, k) = (fragment.pixel as usize, self.k as usize);
        memory.lock(pixel);
        let mut nodes = self.nodes(memory, pixel);
        let entry = fragment.packed();
        let at = nodes.partition_point(|&(depth, _)| depth < entry);
        nodes.insert(at, (entry, 1));
        let merged = nodes.len() > k;
        if merged {
            let (_, farther) = nodes.pop().expect("K + 1 nodes");
            nodes.last_mut().expect("K ≥ 1 nodes").1 += farther;
        }
        for i in 0..k {
            let (depth, count) = nodes.get(i).copied().unwrap_or((EMPTY, 0));
            WordMemory::<u64>::store(memory, pixel * k + i, depth);
            WordMemory::<u32>::store(memory, self.count_word(pixel, i), count);
        }
        memory.unlock(pixel);
        if merged {
            Step::Dropped
        } else {
            Step::Stored
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // Already in canonical order: every section leaves the nodes sorted.
        out.extend(
            self.nodes(memory, pixel)
                .into_iter()
                .map(|(depth, _)| depth),
        );
        // What was merged is not in the list: the executors count it from the walks.
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::one_pixel::{fragment, one_pixel};
    use fragsim_memory::SerialMemory;

    /// Every arrival order of five fragments of one pixel: the nodes are the `K` nearest, their
    /// counts add up to five, and exactly the fragments beyond `K` end a walk dropped.
    #[test]
    fn the_nodes_are_the_k_nearest_and_count_every_fragment_in_any_order() {
        let stream = [
            fragment(7, 0),
            fragment(2, 1),
            fragment(9, 2),
            fragment(2, 3),
            fragment(5, 4),
        ];
        let mut sorted: Vec<u64> = stream.iter().map(|f| f.packed()).collect();
        sorted.sort_unstable();
        for k in 1..=6_u32 {
            let scheme = Mlab::with_k(one_pixel(), k).unwrap();
            // The 120 permutations: `n` in mixed radix 5·4·3·2·1, each digit a rotation of one
            // prefix (the longest fixes the last place, and so on down).
            for n in 0..120 {
                let mut perm: Vec<usize> = (0..stream.len()).collect();
                let mut rest = n;
                for len in (1..=perm.len()).rev() {
                    perm[..len].rotate_left(rest % len);
                    rest /= len;
                }
                let memory: SerialMemory = scheme.layout().allocate();
                let mut dropped = 0;
                for &i in &perm {
                    let mut steps = 0;
                    dropped +=
                        usize::from(scheme.insert(stream[i], &memory, &mut steps) == Step::Dropped);
                    assert_eq!(steps, 1, "one critical section a fragment");
                }
                let kept = (k as usize).min(stream.len());
                assert_eq!(
                    scheme.resolve(&memory).pixel(0),
                    &sorted[..kept],
                    "K {k}, {perm:?}"
                );
                let nodes = scheme.nodes(&memory, 0);
                assert_eq!(nodes.iter().map(|node| node.1).sum::<u32>(), 5, "{nodes:?}");
                assert_eq!(dropped, stream.len() - kept, "K {k}, {perm:?}");
            }
        }
    }

    /// K = 2: far, farther, then the nearest; the last merge folds both far fragments into one
    /// node at the nearer's depth, so the node counts are 1 and 2.
    #[test]
    fn a_merge_folds_the_farther_node_into_the_nearer() {
        let scheme = Mlab::with_k(one_pixel(), 2).unwrap();
        let memory: SerialMemory = scheme.layout().allocate();
        let mut steps = 0;
        for f in [fragment(5, 0), fragment(6, 1)] {
            assert_eq!(scheme.insert(f, &memory, &mut steps), Step::Stored);
        }
        assert_eq!(
            scheme.insert(fragment(1, 2), &memory, &mut steps),
            Step::Dropped
        );
        assert_eq!(
            scheme.nodes(&memory, 0),
            vec![(fragment(1, 2).packed(), 1), (fragment(5, 0).packed(), 2)]
        );
    }

    #[test]
    fn no_nodes_and_storage_beyond_the_cap_are_refused_by_name() {
        let zero = Mlab::with_k(one_pixel(), 0).unwrap_err();
        assert!(zero.to_string().contains("mlab"), "{zero}");
        // What is allocated before any fragment (the page tables of its words) is checked
        // when the scheme is built; its pages as a frame writes them.
        let least = Mlab::new(one_pixel(), 4, u64::MAX)
            .unwrap()
            .layout()
            .least_bytes();
        let capped = Mlab::new(one_pixel(), 4, least - 1).unwrap_err();
        assert!(
            matches!(capped, CaptureError::TooMuchMemory { needed, .. } if needed == least),
            "{capped:?}"
        );
    }
}
