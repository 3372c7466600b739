//! Bevy's first order-independent transparency (Bevy 0.15, `bevy_core_pipeline::oit`): an
//! A-buffer with a per-pixel layer counter and a fixed `layer_count`.
//!
//! **Algorithm** (the WGSL `oit_draw`, modelled from its published description). Each pixel owns a
//! counter `layer_ids[p]` (0 after the resolve pass) and `layer_count` layers, laid out layer-major
//! as Bevy's buffer is: layer `l` of pixel `p` at `p + l * pixels`. A fragment takes
//! `layer_id = atomicAdd(&layer_ids[p], 1)`; if `layer_id < layer_count` it stores itself in
//! layer `layer_id` (a plain store); otherwise it *stores* `layer_count` back into the counter
//! (`atomicStore`, so the counter cannot run away) and is discarded. The resolve pass reads
//! `min(layer_ids[p], layer_count)` layers, sorts them and blends them.
//!
//! **Guarantee.** Exact while a pixel's depth complexity is at most `layer_count`. Beyond it the
//! first `layer_count` *arrivals* are kept, not the nearest, and the rest are discarded silently:
//! the counter is clamped back to `layer_count`, so the resolve cannot tell that anything was
//! lost. Under any interleaving a pixel of depth complexity `n` loses exactly
//! `max(0, n − layer_count)` fragments (fetch-and-add hands out distinct layer ids, and the clamp
//! only ever stores `layer_count` over a counter already at or past it). The promise is therefore
//! [`Promise::All`] over [`Capacity::PerPixelUncounted`]: the scheme reports no overflow, and
//! the oracle supplies the count it cannot keep (`max(0, n − layer_count)` per pixel) and checks
//! that exactly that many are missing. One geometry pass; memory: one counter and
//! `layer_count` 64-bit layers per pixel; two memory operations per kept fragment, two per
//! discarded one.
//!
//! Unlike Bevy, which packs colour and depth into the layer, a layer holds the fragment's
//! `depth_key << 32 | prim` (the colour is a function of the primitive); unlike the GPU, the
//! resolve does not reset the counters (every frame starts from fresh storage).

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::sort::insertion_sort;
use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step};

/// Bevy 0.15's layer-counter A-buffer.
#[derive(Clone, Debug)]
pub struct LayerCounter {
    descriptor: Descriptor,
    layer_count: u32,
}

/// A fragment's progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerStep {
    /// Before the `atomicAdd` on the pixel's counter.
    Count {
        /// The pixel.
        pixel: u32,
        /// The value to store.
        value: u64,
    },
    /// A layer was taken: the store is next.
    Write {
        /// The word of the layer.
        word: usize,
        /// The value to store.
        value: u64,
    },
    /// No layer left: the clamp of the counter back to `layer_count` is next.
    Clamp {
        /// The pixel.
        pixel: u32,
    },
}

impl LayerCounter {
    /// `layer_count` layers per pixel, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `layer_count == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        layer_count: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        if layer_count == 0 {
            return Err(CaptureError::BadParameter(
                "the layer counter needs a layer_count of at least 1".into(),
            ));
        }
        let pixels = viewport.pixels();
        let descriptor = Descriptor {
            name: "layer-counter".into(),
            layout: Layout::counters_and_slots(pixels, pixels * layer_count as usize),
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::ExactWithinCapacity(layer_count),
            promise: Promise::All(Capacity::PerPixelUncounted(layer_count)),
            pixels,
            counts_every_drop: true,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            layer_count,
        })
    }

    /// Layers per pixel.
    #[must_use]
    pub fn layer_count(&self) -> u32 {
        self.layer_count
    }
}

impl Scheme for LayerCounter {
    type State = LayerStep;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> LayerStep {
        LayerStep::Count {
            pixel: fragment.pixel,
            value: fragment.packed(),
        }
    }

    fn step<M: Memory>(&self, state: &mut LayerStep, memory: &M) -> Step {
        match *state {
            LayerStep::Count { pixel, value } => {
                let layer_id = WordMemory::<u32>::fetch_add(memory, pixel as usize, 1);
                *state = if layer_id < self.layer_count {
                    LayerStep::Write {
                        word: pixel as usize + layer_id as usize * self.descriptor.pixels,
                        value,
                    }
                } else {
                    LayerStep::Clamp { pixel }
                };
                Step::Continue
            }
            LayerStep::Write { word, value } => {
                WordMemory::<u64>::store(memory, word, value);
                Step::Stored
            }
            LayerStep::Clamp { pixel } => {
                WordMemory::<u32>::store(memory, pixel as usize, self.layer_count);
                Step::Dropped
            }
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let count = WordMemory::<u32>::load(memory, pixel).min(self.layer_count) as usize;
        let start = out.len();
        out.extend(
            (0..count).map(|layer| {
                WordMemory::<u64>::load(memory, pixel + layer * self.descriptor.pixels)
            }),
        );
        insertion_sort(&mut out[start..]);
        // The clamped counter hides the discarded fragments: nothing is reported as overflow.
        0
    }
}
