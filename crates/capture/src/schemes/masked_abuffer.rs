//! The masked-node A-buffer and linked list: per-pixel storage whose nodes carry a coverage mask,
//! as the multisampled OIT of Bevy and nvpro-samples does, and its per-sample resolve.
//!
//! **Algorithm.** Under multisampling without per-sample shading, a fragment-shader invocation
//! covers one pixel for one primitive and sees the samples it covers as a mask
//! (`gl_SampleMaskIn`, WGSL's `sample_mask`). So here each primitive's per-sample fragments in
//! one pixel (from a view rasterizing per sample, [`fragsim_raster::samples`]) are merged into one
//! [`MaskedNode`]: the union of their sample bits and the nearest of their depth keys
//! ([`merge_samples`]; fan pieces of one clipped triangle merge too, since they share the
//! primitive id). In the A-buffer ([`MaskedStorage::Slots`]) each node takes a slot of its pixel
//! with a `fetch_add` on the pixel's counter and writes its packed `(depth key, primitive id)`
//! word and its mask with two plain stores. In the linked list ([`MaskedStorage::Pool`], the
//! masked form of `linked_list.rs`) it takes a node of one pool shared by every pixel with a
//! `fetch_add` on the global counter, swaps itself in as its pixel's head with an exchange, and
//! writes its word, its mask and the old head as its `next`. The post pass sorts each pixel's nodes by `(depth key, primitive id)` ([`MaskedLists`]); the
//! resolve that blends per sample ([`MaskedLists::per_sample`]) gives each sample the nodes whose
//! mask holds it, in that order.
//!
//! **Guarantee.** The node lists equal the per-pixel view of the per-sample oracle (its
//! fragments merged by the same rule) exactly, while every pixel's nodes fit `capacity`: the
//! slot numbers of `fetch_add` are distinct under any interleaving, as in the A-buffer
//! (`abuffer.rs`). The per-sample resolve is *approximate*: one depth a node orders a sample by
//! the node's nearest depth, not the sample's own, so two primitives that cross inside a pixel
//! may be blended in the wrong order at some samples; the error is measured against the
//! per-sample oracle (`docs/results.md`, "Multisampling"). Past `capacity` (past the pool) a
//! whole node (every sample it covers) is dropped and counted: per pixel by the A-buffer's
//! counters, in all by the linked list's one counter. The linked list's lists are exact while
//! the whole frame's nodes fit the pool, the exchange linking every allocated node exactly once
//! under any interleaving, as in the linked list.
//!
//! **Memory.** The A-buffer: one `u32` counter per pixel, and per slot one `u64` word and one
//! `u32` mask: `4 + 12 × capacity` bytes a pixel, against `n × (4 + 8 × capacity)` for the
//! A-buffer run per sample over `n` samples. The linked list: one `u32` head per pixel, the
//! counter, and per pool node a `u64` word, a `u32` mask and a `u32` next: `4 + 16 × nodes` bytes
//! a pixel for a pool of `nodes` a pixel.
//!
//! **Departures.** It is not a [`Scheme`](crate::Scheme): its walks start from merged nodes, not
//! from the rasterizer's fragments, so it runs its own serial and parallel loops over the view's
//! triangles ([`MaskedABuffer::capture`]), on the same [`Memory`] seam, three operations a node
//! (the linked list: five).

use std::time::{Duration, Instant};

use fragsim_memory::{AtomicMemory, Layout, Memory, SerialMemory, WordMemory};
use fragsim_raster::{Fragment, View, Viewport};
use rayon::prelude::*;

use crate::capture::PixelLists;
use crate::scheme::CaptureError;

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
    /// counter counts them in all ([`MaskedFrame::dropped`]).
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

/// One timed frame of a [`MaskedABuffer`].
#[derive(Clone, Debug)]
pub struct MaskedFrame {
    /// The sorted node lists, with each pixel's dropped nodes.
    pub lists: MaskedLists,
    /// Sample fragments rasterized (before merging).
    pub fragments: u64,
    /// Nodes dropped for lack of storage, as the counters counted them.
    pub dropped: u64,
    /// The geometry pass: storage allocation, rasterization per sample, merging, insertion.
    pub pass_time: Duration,
    /// The post pass: every pixel's stored nodes read back and sorted.
    pub resolve_time: Duration,
}

/// Where masked nodes are kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaskedStorage {
    /// This many slots per pixel, handed out by the pixel's counter: the masked-node A-buffer.
    Slots(u32),
    /// A pool of this many nodes shared by every pixel, handed out by one global counter and
    /// linked into per-pixel lists by a head exchange: the masked-node linked list.
    Pool(usize),
}

/// Masked-node storage: the A-buffer (`capacity` masked nodes per pixel) or the linked list (a
/// pool of masked nodes).
#[derive(Clone, Debug)]
pub struct MaskedABuffer {
    pixels: usize,
    samples: u32,
    storage: MaskedStorage,
}

impl MaskedABuffer {
    /// `capacity` nodes for each pixel of `pixels`, at `samples` samples a pixel.
    ///
    /// # Errors
    /// `capacity == 0`, a sample count outside 1 to 32 (a mask is one `u32`), or storage beyond
    /// `memory_cap` bytes.
    pub fn new(
        pixels: Viewport,
        samples: u32,
        capacity: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        Self::with_storage(pixels, samples, MaskedStorage::Slots(capacity), memory_cap)
    }

    /// Masked nodes kept in `storage` for each pixel of `pixels`, at `samples` samples a pixel.
    ///
    /// # Errors
    /// No slot or no node, a pool beyond 32-bit node indices, a sample count outside 1 to 32 (a
    /// mask is one `u32`), or storage beyond `memory_cap` bytes.
    pub fn with_storage(
        pixels: Viewport,
        samples: u32,
        storage: MaskedStorage,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        match storage {
            MaskedStorage::Slots(0) => {
                return Err(CaptureError::BadParameter(
                    "the masked-node A-buffer needs a capacity of at least 1 node per pixel".into(),
                ))
            }
            MaskedStorage::Pool(nodes) if nodes == 0 || nodes >= u32::MAX as usize => {
                return Err(CaptureError::BadParameter(format!(
                    "the masked-node pool needs 1 to {} nodes, got {nodes}",
                    u32::MAX - 1
                )))
            }
            _ => {}
        }
        if !(1..=32).contains(&samples) {
            return Err(CaptureError::BadParameter(format!(
                "{samples} samples per pixel: a coverage mask holds 1 to 32"
            )));
        }
        let scheme = Self {
            pixels: pixels.pixels(),
            samples,
            storage,
        };
        let needed = scheme.layout().bytes();
        if needed > memory_cap {
            return Err(CaptureError::TooMuchMemory {
                scheme: scheme.name().into(),
                needed,
                cap: memory_cap,
            });
        }
        Ok(scheme)
    }

    /// `abuffer-masked` or `linked-list-masked`, as `bench --samples` names the rows.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self.storage {
            MaskedStorage::Slots(_) => "abuffer-masked",
            MaskedStorage::Pool(_) => "linked-list-masked",
        }
    }

    /// Where the nodes are kept.
    #[must_use]
    pub fn storage(&self) -> MaskedStorage {
        self.storage
    }

    /// The words. The A-buffer: `u32` counters then masks, `u64` node words. The linked list:
    /// `u32` heads, the counter, the nodes' `next` then their masks, `u64` node words.
    #[must_use]
    pub fn layout(&self) -> Layout {
        match self.storage {
            MaskedStorage::Slots(capacity) => {
                let slots = self.pixels * capacity as usize;
                Layout::counters_and_slots(self.pixels + slots, slots)
            }
            MaskedStorage::Pool(nodes) => {
                Layout::counters_and_slots(self.pixels + 1 + 2 * nodes, nodes)
            }
        }
    }

    /// The linked list's global counter (the `u32` word after the heads); node `i` (0-based)'s
    /// `next` is at `counter + 1 + i`, its mask at `counter + 1 + pool + i`.
    fn counter(&self) -> usize {
        self.pixels
    }

    /// Inserts `node` into pixel `pixel`. The A-buffer: `fetch_add` on the pixel's counter, then
    /// the word and the mask into the slot it handed out. The linked list: `fetch_add` on the
    /// global counter, the exchange of the pixel's head for the node (numbered from 1: 0 ends a
    /// list), then the word, the mask and the old head as `next`. Returns whether the node was
    /// stored (else it was dropped, and the counter, which keeps counting, says so).
    pub fn insert<M: Memory>(&self, pixel: u32, node: MaskedNode, memory: &M) -> bool {
        let pixel = pixel as usize;
        match self.storage {
            MaskedStorage::Slots(capacity) => {
                let slot = WordMemory::<u32>::fetch_add(memory, pixel, 1);
                if slot >= capacity {
                    return false;
                }
                let index = pixel * capacity as usize + slot as usize;
                WordMemory::<u64>::store(memory, index, node.packed());
                WordMemory::<u32>::store(memory, self.pixels + index, node.mask);
            }
            MaskedStorage::Pool(nodes) => {
                let taken = WordMemory::<u32>::fetch_add(memory, self.counter(), 1);
                if taken as usize >= nodes {
                    return false;
                }
                let next = WordMemory::<u32>::swap(memory, pixel, taken + 1);
                let index = taken as usize;
                WordMemory::<u64>::store(memory, index, node.packed());
                WordMemory::<u32>::store(memory, self.counter() + 1 + index, next);
                WordMemory::<u32>::store(memory, self.counter() + 1 + nodes + index, node.mask);
            }
        }
        true
    }

    /// One frame: every triangle of `view` (rasterizing per sample with this scheme's sample
    /// count) merged into nodes and inserted, serially in submission order or on the current
    /// rayon pool with std atomics; then the post pass.
    ///
    /// # Errors
    /// A view that does not rasterize per sample at this scheme's sample count, or on another
    /// number of pixels.
    pub fn capture(&self, view: &View<'_>, parallel: bool) -> Result<MaskedLists, CaptureError> {
        self.frame(view, parallel).map(|frame| frame.lists)
    }

    /// [`MaskedABuffer::capture`], timed: the geometry pass (storage allocation, rasterization,
    /// merging, insertion) and the post pass apart, as `bench --samples` reports them.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`].
    pub fn frame(&self, view: &View<'_>, parallel: bool) -> Result<MaskedFrame, CaptureError> {
        self.check_view(view)?;
        let layout = self.layout();
        let start = Instant::now();
        // The two memories are two types (std atomics, plain cells): one timed body each.
        let (lists, fragments, pass_time, resolve_time) = if parallel {
            let memory: AtomicMemory = layout.allocate();
            let fragments = (0..view.triangle_count())
                .into_par_iter()
                .map_init(Vec::new, |scratch, index| {
                    self.insert_triangle(view, view.submitted(index), scratch, &memory)
                })
                .sum();
            let pass_time = start.elapsed();
            let lists = (self.resolve(&memory), self.dropped(&memory));
            (lists, fragments, pass_time, start.elapsed() - pass_time)
        } else {
            let memory: SerialMemory = layout.allocate();
            let fragments = self.insert_all(view, &memory)?;
            let pass_time = start.elapsed();
            let lists = (self.resolve(&memory), self.dropped(&memory));
            (lists, fragments, pass_time, start.elapsed() - pass_time)
        };
        let (lists, dropped) = lists;
        Ok(MaskedFrame {
            lists,
            fragments,
            dropped,
            pass_time,
            resolve_time,
        })
    }

    /// Refuses a view of another pixel count or sample count than this scheme's.
    fn check_view(&self, view: &View<'_>) -> Result<(), CaptureError> {
        if view.samples().map(|p| p.count()) != Some(self.samples)
            || view.pixel_viewport().pixels() != self.pixels
        {
            return Err(CaptureError::OtherView {
                scheme: self.name().into(),
                pixels: self.pixels,
                samples: self.samples,
                view_pixels: view.pixel_viewport().pixels(),
                view_samples: view.samples().map_or(1, |p| p.count()),
            });
        }
        Ok(())
    }

    /// The pass alone, serially in submission order, into `memory` (of [`MaskedABuffer::layout`]):
    /// the words a dump records (`fragsim_dump`), before the post pass; returns the
    /// sample fragments rasterized.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`].
    pub fn insert_all<M: Memory>(&self, view: &View<'_>, memory: &M) -> Result<u64, CaptureError> {
        self.check_view(view)?;
        let mut scratch = Vec::new();
        Ok((0..view.triangle_count())
            .map(|index| self.insert_triangle(view, view.submitted(index), &mut scratch, memory))
            .sum())
    }

    /// The counting pass that sizes a masked-node A-buffer to the scene (`--capacity auto`): one
    /// geometry pass that merges nodes as [`MaskedABuffer::frame`] does and only counts them, a
    /// `fetch_add` each; the frame's [`MaskedLists::overflow`] holds every pixel's node count
    /// (no node is stored). Its memory is one `u32` counter a pixel.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`], or a sample count outside 1 to 32.
    pub fn count_nodes(
        pixels: Viewport,
        samples: u32,
        view: &View<'_>,
        parallel: bool,
    ) -> Result<MaskedFrame, CaptureError> {
        let mut counter = Self::new(pixels, samples, 1, u64::MAX)?;
        // Capacity 0, which `new` refuses for a capture: every insertion only counts.
        counter.storage = MaskedStorage::Slots(0);
        counter.frame(view, parallel)
    }

    /// Rasterizes triangle `prim` per sample into `scratch`, merges and inserts its nodes;
    /// returns the sample fragments rasterized.
    fn insert_triangle<M: Memory>(
        &self,
        view: &View<'_>,
        prim: u32,
        scratch: &mut Vec<Fragment>,
        memory: &M,
    ) -> u64 {
        scratch.clear();
        view.rasterize(prim, &mut |f| scratch.push(f));
        merge_samples(self.samples, scratch, &mut |pixel, node| {
            self.insert(pixel, node, memory);
        });
        scratch.len() as u64
    }

    /// The post pass: each pixel's stored nodes (its slots, or its list walked from the head)
    /// sorted, and the A-buffer's per-pixel overflow read from its counter.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a node's word packs the depth key (high 32 bits) and the primitive id (low 32)"
    )]
    pub fn resolve<M: Memory>(&self, memory: &M) -> MaskedLists {
        let mut lists = MaskedLists {
            samples: self.samples,
            offsets: vec![0],
            nodes: Vec::new(),
            overflow: Vec::with_capacity(self.pixels),
        };
        let node_at = |index: usize, mask: usize| {
            let packed = WordMemory::<u64>::load(memory, index);
            MaskedNode {
                depth_key: (packed >> 32) as u32,
                prim: packed as u32,
                mask: WordMemory::<u32>::load(memory, mask),
            }
        };
        for pixel in 0..self.pixels {
            let start = lists.nodes.len();
            let mut overflow = 0;
            match self.storage {
                MaskedStorage::Slots(capacity) => {
                    let count = WordMemory::<u32>::load(memory, pixel);
                    let stored = count.min(capacity);
                    for slot in 0..stored as usize {
                        let index = pixel * capacity as usize + slot;
                        lists.nodes.push(node_at(index, self.pixels + index));
                    }
                    overflow = count - stored;
                }
                MaskedStorage::Pool(nodes) => {
                    let mut node = WordMemory::<u32>::load(memory, pixel) as usize;
                    while node != 0 {
                        let index = node - 1;
                        let mask = self.counter() + 1 + nodes + index;
                        lists.nodes.push(node_at(index, mask));
                        node = WordMemory::<u32>::load(memory, self.counter() + 1 + index) as usize;
                    }
                }
            }
            lists.nodes[start..].sort_unstable_by_key(|n| n.packed());
            lists.offsets.push(lists.nodes.len());
            lists.overflow.push(overflow);
        }
        lists
    }

    /// Nodes dropped for lack of storage, from the counters: each pixel's count past its slots,
    /// or the global count past the pool.
    #[must_use]
    pub fn dropped<M: Memory>(&self, memory: &M) -> u64 {
        match self.storage {
            MaskedStorage::Slots(capacity) => (0..self.pixels)
                .map(|pixel| {
                    u64::from(WordMemory::<u32>::load(memory, pixel).saturating_sub(capacity))
                })
                .sum(),
            MaskedStorage::Pool(nodes) => {
                let taken = WordMemory::<u32>::load(memory, self.counter());
                (taken as usize).saturating_sub(nodes) as u64
            }
        }
    }
}

#[cfg(test)]
mod tests;
