//! Masked nodes, the capture of multisampled storage that keeps one node a primitive and pixel:
//! a primitive's samples in one pixel merged into one node ([`merge_samples`]), and the sorted
//! node lists a frame leaves ([`MaskedLists`]), with their per-sample resolve. The masked-node
//! A-buffer (`fragsim_schemes::masked_abuffer`) leaves them; the oracle builds its own from
//! per-sample fragments to judge it; a dump reads them back.

use fragsim_raster::Fragment;

use crate::capture::{Capacity, Capture, Identity, Keeps, PixelLists};

/// One primitive's coverage of one pixel: its nearest depth key over the samples it covers, and
/// the mask of those samples (bit `s`: sample `s`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MaskedNode {
    /// The smallest depth key of the primitive's samples in the pixel.
    pub depth_key: u32,
    /// Primitive id.
    pub prim: u32,
    /// Covered samples.
    pub mask: u32,
}

impl MaskedNode {
    /// The node's identity in the canonical packing: depth key high, primitive id low.
    #[must_use]
    pub fn packed(self) -> u64 {
        (u64::from(self.depth_key) << 32) | u64::from(self.prim)
    }

    /// The node of a packed identity ([`MaskedNode::packed`]) and a mask.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a node's word packs the depth key (high 32 bits) and the primitive id (low 32)"
    )]
    pub fn unpacked(packed: u64, mask: u32) -> Self {
        Self {
            depth_key: (packed >> 32) as u32,
            prim: packed as u32,
            mask,
        }
    }
}

/// Merges per-sample fragments (their `pixel` a sample index of `samples` samples a pixel) into
/// one node per pixel and primitive; calls `emit(pixel, node)` in `(pixel, primitive)` order.
/// Sorts `fragments` in place.
pub fn merge_samples(
    samples: u32,
    fragments: &mut [Fragment],
    emit: &mut impl FnMut(u32, MaskedNode),
) {
    fragments.sort_unstable_by_key(|f| (f.pixel / samples, f.prim, f.depth_key));
    let mut rest = &*fragments;
    while let Some(first) = rest.first() {
        let (pixel, prim) = (first.pixel / samples, first.prim);
        let same = rest
            .iter()
            .take_while(|f| f.pixel / samples == pixel && f.prim == prim)
            .count();
        let mask = rest[..same]
            .iter()
            .fold(0_u32, |mask, f| mask | 1 << (f.pixel % samples));
        // Sorted by depth key within the group: the first is the nearest.
        emit(
            pixel,
            MaskedNode {
                depth_key: first.depth_key,
                prim,
                mask,
            },
        );
        rest = &rest[same..];
    }
}

/// Every pixel's nodes in `(depth key, primitive id)` order, with the nodes each pixel dropped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MaskedLists {
    /// Samples a pixel.
    pub samples: u32,
    /// `offsets[p]..offsets[p + 1]` are pixel `p`'s nodes.
    pub offsets: Vec<usize>,
    /// The nodes of every pixel.
    pub nodes: Vec<MaskedNode>,
    /// Nodes each pixel dropped for lack of storage, where the storage counts them per pixel
    /// (the A-buffer's counters); all 0 for an oracle's view and for a pool's lists, whose one
    /// counter counts them in all (the masked-node A-buffer's `MaskedFrame::dropped`).
    pub overflow: Vec<u32>,
}

impl MaskedLists {
    /// Pixel `p`'s nodes.
    #[must_use]
    pub fn pixel(&self, p: usize) -> &[MaskedNode] {
        &self.nodes[self.offsets[p]..self.offsets[p + 1]]
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The lists of `nodes` (pixel, node) in any order over `pixels` pixels, sorted.
    #[must_use]
    pub fn from_nodes(samples: u32, pixels: usize, mut nodes: Vec<(u32, MaskedNode)>) -> Self {
        nodes.sort_unstable_by_key(|&(pixel, node)| (pixel, node.packed()));
        let mut offsets = Vec::with_capacity(pixels + 1);
        offsets.push(0);
        let mut at = 0;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
        )]
        for pixel in 0..pixels as u32 {
            while at < nodes.len() && nodes[at].0 == pixel {
                at += 1;
            }
            offsets.push(at);
        }
        Self {
            samples,
            offsets,
            nodes: nodes.into_iter().map(|(_, node)| node).collect(),
            overflow: vec![0; pixels],
        }
    }

    /// The node lists that a per-sample resolve ([`MaskedLists::per_sample`], of `samples`
    /// samples a pixel) spells out: each node's mask is the samples whose lists hold it. The
    /// inverse of the per-sample resolve, so nothing a capture holds is lost; `overflow` is
    /// each pixel's count, which the per-sample resolve reports on the pixel's first sample.
    ///
    /// # Panics
    /// If `lists` does not cover a whole number of pixels, or `overflow` has another length.
    #[must_use]
    pub fn from_per_sample(samples: u32, lists: &PixelLists, overflow: &[u32]) -> Self {
        let per_pixel = samples as usize;
        assert_eq!(lists.pixels() % per_pixel, 0, "the samples of whole pixels");
        assert_eq!(overflow.len(), lists.pixels(), "an overflow count a sample");
        let pixels = lists.pixels() / per_pixel;
        let mut nodes: Vec<MaskedNode> = Vec::new();
        let mut offsets = Vec::with_capacity(pixels + 1);
        offsets.push(0);
        for pixel in 0..pixels {
            let start = nodes.len();
            for sample in 0..samples {
                for &packed in lists.pixel(pixel * per_pixel + sample as usize) {
                    let covering = nodes[start..].iter_mut().find(|n| n.packed() == packed);
                    match covering {
                        Some(node) => node.mask |= 1 << sample,
                        None => nodes.push(MaskedNode::unpacked(packed, 1 << sample)),
                    }
                }
            }
            nodes[start..].sort_unstable_by_key(|n| n.packed());
            offsets.push(nodes.len());
        }
        Self {
            samples,
            offsets,
            nodes,
            overflow: overflow.iter().step_by(per_pixel).copied().collect(),
        }
    }

    /// The lists as a capture of one list a pixel: each node's packed identity
    /// ([`MaskedNode::packed`]), masks left out, kept as `capacity` nodes a pixel keep them,
    /// with the pixels' overflow. What the node-by-node comparisons judge, the masks apart.
    #[must_use]
    pub fn packed_capture(&self, capacity: Capacity) -> Capture {
        let keeps = Keeps::All {
            capacity,
            overflow: self.overflow.clone(),
        };
        let mut capture = Capture::with_pixels(self.pixels(), Identity::KeyAndPrim, keeps);
        for p in 0..self.pixels() {
            capture
                .lists
                .push_pixel(self.pixel(p).iter().map(|n| n.packed()));
        }
        capture
    }

    /// The resolve per sample: each sample's list (indexed by sample index, as a per-sample
    /// oracle's) holds the nodes whose mask covers it, in node order, each packed with the node's
    /// depth key. What a per-sample blend reads, and what is compared with the per-sample oracle.
    #[must_use]
    pub fn per_sample(&self) -> PixelLists {
        let mut lists = PixelLists::with_pixels(self.pixels() * self.samples as usize);
        for p in 0..self.pixels() {
            for s in 0..self.samples {
                let covering = self.pixel(p).iter().filter(|n| n.mask >> s & 1 == 1);
                lists.push_pixel(covering.map(|n| n.packed()));
            }
        }
        lists
    }
}
