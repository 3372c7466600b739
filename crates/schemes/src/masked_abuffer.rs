//! The masked-node A-buffer and linked list: per-pixel storage whose nodes carry a coverage mask,
//! as the multisampled OIT of Bevy and nvpro-samples does, and its per-sample resolve.
//!
//! **Algorithm.** Under multisampling without per-sample shading, a fragment-shader invocation
//! covers one pixel for one primitive and sees the samples it covers as a mask
//! (`gl_SampleMaskIn`, WGSL's `sample_mask`). So here each primitive's per-sample fragments in
//! one pixel (from a view rasterizing per sample, [`fragsim_raster::samples`]) are merged into one
//! [`MaskedNode`]: the union of their sample bits and the nearest of their depth keys
//! ([`merge_samples`](fragsim_capture::merge_samples); fan pieces of one clipped triangle merge too, since they share the
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
//! **As a [`Scheme`].** Its walks start from merged nodes, not from the rasterizer's fragments:
//! its [`Scheme::Input`] is a [`PixelNode`], which every executor gathers from a triangle's
//! per-sample fragments ([`Merging`], the one frame loop's [`WalkInput`] hook), so it runs on
//! the serial, parallel, tiled and scheduled executors like any scheme, one memory operation a
//! step: three a node (claim the slot, store the word, store the mask), five in the linked list
//! (claim the node, exchange the head, store the word, the `next` and the mask). Its capture
//! covers the sample-expanded framebuffer, as every scheme's does at more than one sample: the
//! per-sample resolve, each sample's list the nodes whose mask holds it, keyed by the node's
//! depth. [`MaskedLists::from_per_sample`] reads the node lists back from it, masks included.
//! The A-buffer reports a pixel's dropped nodes on its first sample.

use std::time::Duration;

use fragsim_capture::executors::{run_parallel, run_serial, serial_passes, Run};
use fragsim_capture::{
    Capacity, CaptureError, Descriptor, Guarantee, Identity, MaskedLists, MaskedNode, Promise,
    Scheme, Step, WalkInput,
};
use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{View, Viewport};

mod nodes;

pub use nodes::{Merging, PixelNode};

/// One timed frame of a [`MaskedABuffer`].
#[derive(Clone, Debug)]
pub struct MaskedFrame {
    /// The sorted node lists, with each pixel's dropped nodes.
    pub lists: MaskedLists,
    /// Nodes walked: the fragment-shader invocations, one per pixel a primitive covers.
    pub nodes: u64,
    /// Nodes dropped for lack of storage, as the walks ended.
    pub dropped: u64,
    /// The geometry pass: storage initialisation, rasterization per sample, merging, insertion.
    pub pass_time: Duration,
    /// The post pass: every sample's list read back from its pixel's nodes and sorted.
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
    descriptor: Descriptor,
}

/// Where a node's walk stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeWalk {
    /// Claims a slot from the pixel's counter, or a pool node from the global counter.
    Claim(PixelNode),
    /// Exchanges the pixel's head for pool node `index` (numbered from 1 in the heads).
    Link(PixelNode, usize),
    /// Stores the node's word at `index`; then its `next` (`Some`: the linked list's old head).
    Word(PixelNode, usize, Option<u32>),
    /// Stores the linked list's `next` of node `index`.
    Next(PixelNode, usize, u32),
    /// Stores the mask of the node at `index`: the last step.
    Mask(PixelNode, usize),
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
        let scheme = Self::built(pixels.pixels(), samples, storage)?;
        // Every word is checked, not only the tables (`Descriptor::within`): the nodes are
        // few beside a per-sample scheme's, and the run and the dump both write them all.
        let needed = scheme.layout().bytes();
        if needed > memory_cap {
            return Err(CaptureError::TooMuchMemory {
                scheme: scheme.name(),
                needed,
                cap: memory_cap,
            });
        }
        Ok(scheme)
    }

    /// The scheme, its storage unchecked but for the sample count.
    fn built(pixels: usize, samples: u32, storage: MaskedStorage) -> Result<Self, CaptureError> {
        if !(1..=32).contains(&samples) {
            return Err(CaptureError::BadParameter(format!(
                "{samples} samples per pixel: a coverage mask holds 1 to 32"
            )));
        }
        let (name, layout, guarantee, capacity) = match storage {
            MaskedStorage::Slots(capacity) => {
                let slots = pixels * capacity as usize;
                (
                    "abuffer-masked",
                    Layout::counters_and_slots(pixels + slots, slots),
                    Guarantee::ExactWithinCapacity(capacity),
                    Capacity::PerPixel(capacity),
                )
            }
            // The pool's one counter counts what it drops in all, never per pixel: exact while
            // the frame's nodes fit it, a node lost past it.
            MaskedStorage::Pool(nodes) => (
                "linked-list-masked",
                Layout::counters_and_slots(pixels + 1 + 2 * nodes, nodes),
                Guarantee::Exact,
                Capacity::Unbounded,
            ),
        };
        Ok(Self {
            pixels,
            samples,
            storage,
            descriptor: Descriptor {
                name: name.into(),
                layout,
                identity: Identity::MaskedNodes(samples),
                guarantee,
                promise: Promise::All(capacity),
                pixels: pixels * samples as usize,
                counts_every_drop: true,
            },
        })
    }

    /// Where the nodes are kept.
    #[must_use]
    pub fn storage(&self) -> MaskedStorage {
        self.storage
    }

    /// Samples a pixel.
    #[must_use]
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The linked list's global counter (the `u32` word after the heads); node `i` (0-based)'s
    /// `next` is at `counter + 1 + i`, its mask at `counter + 1 + pool + i`.
    fn counter(&self) -> usize {
        self.pixels
    }

    /// The `u32` word of the mask of the node at `index` (a slot, or a pool node).
    fn mask_word(&self, index: usize) -> usize {
        match self.storage {
            MaskedStorage::Slots(_) => self.pixels + index,
            MaskedStorage::Pool(nodes) => self.counter() + 1 + nodes + index,
        }
    }

    /// One frame: every triangle of `view` (rasterizing per sample with this scheme's sample
    /// count) merged into nodes and inserted, on the serial executor or on the parallel one
    /// (the current rayon pool, std atomics); then the post pass.
    ///
    /// # Errors
    /// A view that does not rasterize per sample at this scheme's sample count, or on another
    /// number of pixels.
    pub fn capture(&self, view: &View<'_>, parallel: bool) -> Result<MaskedLists, CaptureError> {
        self.frame(view, parallel).map(|frame| frame.lists)
    }

    /// [`MaskedABuffer::capture`], timed: the geometry pass and the post pass apart, as
    /// `bench --samples` reports them.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`].
    pub fn frame(&self, view: &View<'_>, parallel: bool) -> Result<MaskedFrame, CaptureError> {
        self.check_view(view)?;
        let run = if parallel {
            run_parallel(view, self)
        } else {
            run_serial(view, self)
        };
        Ok(self.masked_frame(&run))
    }

    /// The node lists and counts of a frame-loop run of this scheme.
    ///
    /// # Panics
    /// If `run` is not a capture of this scheme (another promise, another number of pixels).
    #[must_use]
    pub fn masked_frame(&self, run: &Run) -> MaskedFrame {
        let fragsim_capture::Keeps::All { overflow, .. } = &run.capture.keeps else {
            panic!("a masked-node capture keeps all its nodes");
        };
        MaskedFrame {
            lists: MaskedLists::from_per_sample(self.samples, &run.capture, overflow),
            nodes: run.stats.counters.fragments,
            dropped: run.stats.counters.dropped,
            pass_time: run.stats.pass_time,
            resolve_time: run.stats.resolve_time,
        }
    }

    /// Refuses a view of another pixel count or sample count than this scheme's.
    fn check_view(&self, view: &View<'_>) -> Result<(), CaptureError> {
        let view_samples = view.samples().map_or(1, |p| p.count());
        if view_samples != self.samples || view.pixel_viewport().pixels() != self.pixels {
            return Err(CaptureError::OtherView {
                scheme: self.name(),
                pixels: self.pixels,
                samples: self.samples,
                view_pixels: view.pixel_viewport().pixels(),
                view_samples,
            });
        }
        Ok(())
    }

    /// The pass alone, on the serial executor's loop in submission order, into `memory` (of
    /// the scheme's layout): the words a dump records (`fragsim_dump`), before the post pass;
    /// returns the nodes walked.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`].
    pub fn insert_all<M: Memory>(&self, view: &View<'_>, memory: &M) -> Result<u64, CaptureError> {
        self.check_view(view)?;
        Ok(serial_passes(view, self, memory).0.fragments)
    }

    /// The counting pass that sizes a masked-node A-buffer to the scene (`--capacity auto`): one
    /// geometry pass that merges nodes as [`MaskedABuffer::frame`] does and only counts them, a
    /// `fetch_add` each, every walk ending [`Step::Dropped`]; its frame's
    /// [`MaskedLists::overflow`] holds every pixel's node count (no node is stored). Its memory
    /// is one `u32` counter a pixel.
    ///
    /// # Errors
    /// A sample count outside 1 to 32.
    pub fn node_counter(pixels: Viewport, samples: u32) -> Result<Self, CaptureError> {
        // Capacity 0, which `new` refuses for a capture: every insertion only counts.
        Self::built(pixels.pixels(), samples, MaskedStorage::Slots(0))
    }

    /// The frame of the [`MaskedABuffer::node_counter`] of `view`.
    ///
    /// # Errors
    /// As [`MaskedABuffer::capture`], or a sample count outside 1 to 32.
    pub fn count_nodes(
        pixels: Viewport,
        samples: u32,
        view: &View<'_>,
        parallel: bool,
    ) -> Result<MaskedFrame, CaptureError> {
        Self::node_counter(pixels, samples)?.frame(view, parallel)
    }

    /// The post pass in nodes: each pixel's stored nodes (its slots, or its list walked from the
    /// head) sorted, and the A-buffer's per-pixel overflow read from its counter. What a dump's
    /// words hold, read without the per-sample resolve.
    #[must_use]
    pub fn node_lists<M: Memory>(&self, memory: &M) -> MaskedLists {
        let mut lists = MaskedLists {
            samples: self.samples,
            offsets: vec![0],
            nodes: Vec::new(),
            overflow: Vec::with_capacity(self.pixels),
        };
        for pixel in 0..self.pixels {
            let start = lists.nodes.len();
            let overflow = self.stored_nodes(memory, pixel, |node| lists.nodes.push(node));
            lists.nodes[start..].sort_unstable_by_key(|n| n.packed());
            lists.offsets.push(lists.nodes.len());
            lists.overflow.push(overflow);
        }
        lists
    }

    /// Hands `pixel`'s stored nodes to `each`, in storage order; returns the nodes the pixel's
    /// counter counted past its slots (0 for the pool, whose one counter counts for all).
    fn stored_nodes<M: Memory>(
        &self,
        memory: &M,
        pixel: usize,
        mut each: impl FnMut(MaskedNode),
    ) -> u32 {
        let node_at = |index: usize| {
            MaskedNode::unpacked(
                WordMemory::<u64>::load(memory, index),
                WordMemory::<u32>::load(memory, self.mask_word(index)),
            )
        };
        match self.storage {
            MaskedStorage::Slots(capacity) => {
                let count = WordMemory::<u32>::load(memory, pixel);
                let stored = count.min(capacity);
                for slot in 0..stored as usize {
                    each(node_at(pixel * capacity as usize + slot));
                }
                count - stored
            }
            MaskedStorage::Pool(_) => {
                let mut node = WordMemory::<u32>::load(memory, pixel) as usize;
                while node != 0 {
                    each(node_at(node - 1));
                    node = WordMemory::<u32>::load(memory, self.counter() + node) as usize;
                }
                0
            }
        }
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

impl Scheme for MaskedABuffer {
    type State = NodeWalk;
    type Input = PixelNode;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn gathering(&self) -> <PixelNode as WalkInput>::Gathering {
        Merging::new(self.samples)
    }

    fn begin(&self, node: PixelNode) -> NodeWalk {
        NodeWalk::Claim(node)
    }

    fn step<M: Memory>(&self, walk: &mut NodeWalk, memory: &M) -> Step {
        match (*walk, self.storage) {
            (NodeWalk::Claim(node), MaskedStorage::Slots(capacity)) => {
                let slot = WordMemory::<u32>::fetch_add(memory, node.pixel as usize, 1);
                if slot >= capacity {
                    return Step::Dropped;
                }
                let index = node.pixel as usize * capacity as usize + slot as usize;
                *walk = NodeWalk::Word(node, index, None);
            }
            (NodeWalk::Claim(node), MaskedStorage::Pool(nodes)) => {
                let taken = WordMemory::<u32>::fetch_add(memory, self.counter(), 1);
                if taken as usize >= nodes {
                    return Step::Dropped;
                }
                *walk = NodeWalk::Link(node, taken as usize);
            }
            (NodeWalk::Link(node, index), _) => {
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "pool indices are below the pool, which `with_storage` keeps under u32::MAX"
                )]
                let numbered = index as u32 + 1;
                let next = WordMemory::<u32>::swap(memory, node.pixel as usize, numbered);
                *walk = NodeWalk::Word(node, index, Some(next));
            }
            (NodeWalk::Word(node, index, next), _) => {
                WordMemory::<u64>::store(memory, index, node.node.packed());
                *walk = match next {
                    Some(next) => NodeWalk::Next(node, index, next),
                    None => NodeWalk::Mask(node, index),
                };
            }
            (NodeWalk::Next(node, index, next), _) => {
                WordMemory::<u32>::store(memory, self.counter() + 1 + index, next);
                *walk = NodeWalk::Mask(node, index);
            }
            (NodeWalk::Mask(node, index), _) => {
                WordMemory::<u32>::store(memory, self.mask_word(index), node.node.mask);
                return Step::Stored;
            }
        }
        Step::Continue
    }

    /// Sample `sample_index % samples` of pixel `sample_index / samples`: the pixel's nodes
    /// whose mask holds it, sorted; the pixel's dropped nodes on its first sample.
    fn resolve_pixel<M: Memory>(&self, memory: &M, sample_index: usize, out: &mut Vec<u64>) -> u32 {
        let samples = self.samples as usize;
        let (pixel, sample) = (sample_index / samples, sample_index % samples);
        let start = out.len();
        let overflow = self.stored_nodes(memory, pixel, |node| {
            if node.mask >> sample & 1 == 1 {
                out.push(node.packed());
            }
        });
        out[start..].sort_unstable();
        if sample == 0 {
            overflow
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests;
