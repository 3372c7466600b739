//! The multi-pass k-buffer: Liu, Wei and Xu, "Multi-layer depth peeling via fragment sort"
//! (MSR-TR-2006-81), as bucket depth peeling (Liu et al., HPG 2009, §2 and Table 2, "[Liu 2006]")
//! and FreePipe (Liu et al., I3D 2010, Table 3, "Liu") describe and measure it.
//!
//! **Algorithm.** Depth peeling `K` layers at a time. Geometry pass `p` runs the k-buffer's
//! read–insert–write (`crate::kbuffer`, shared code) over the fragments strictly beyond the
//! pixel's *boundary*, the last layer the previous pass captured: in passes after the first a
//! fragment first `load`s the boundary word (one step) and stops, `Discarded`, when it is not
//! beyond it. A fragment farther than the `K` values it read is `Discarded` too: it is deferred to
//! a later pass by design. Between passes a per-pixel kernel appends the pixel's non-empty slots,
//! in slot order, to its output list (sized by the caller's maximum depth complexity), clears the
//! slots and sets the boundary: past slot `K − 1` when that slot is full, or *complete* (no
//! fragment passes any more) when it is empty. Passes repeat while some pixel is incomplete.
//!
//! **Guarantee.** Serially exact: each pass captures the `K` nearest fragments beyond the
//! boundary, in order, so the output is every fragment in canonical order
//! ([`Promise::All`]; fragments beyond the caller's output capacity are counted as overflow).
//! Passes: `⌊D / K⌋ + 1` for a maximum depth complexity `D` (the last pass finds a slot `K − 1`
//! empty; a pixel whose depth complexity is a multiple of `K` needs that pass to know it is done).
//!
//! **Under hazards** (any interleaving): *progress* holds, as bucket depth peeling (§2) says of
//! Liu et al. ("guarantees to capture at least one fragment per pixel each geometry pass"): every
//! store writes a value that some fragment of this pass read or carried, and every walk that
//! passes the boundary and is not deferred stores a non-empty slot 0, so a pixel with any fragment
//! beyond its boundary captures at least one and its boundary strictly rises: at most `D + 1`
//! passes. *Completeness* does not: a stale write-back can erase a fragment below the new
//! boundary (lost for good), make the pixel look complete early (slot `K − 1` empty while
//! fragments were erased), or capture a fragment twice or out of order. `Oracle::diff` reports
//! all of it; `tests/kbuffer.rs` shows both the progress and the loss under a lockstep schedule.
//!
//! **Memory per pixel:** `8 K` (slots) + 8 (boundary) + `8 D` (output) + 4 (count) bytes.
//!
//! Unlike the paper, whose passes composite each pass's layers into the frame and keep only the
//! `K` render targets (FreePipe's Table 3: 20 MB at 512×512, as the k-buffer), the layers are kept
//! in an output list so that the oracle can check them. Unlike the paper, whose peeling compares
//! depths, the boundary is on `(depth key, primitive id)`, so fragments of equal depth are all
//! peeled rather than merged. Unlike the GPU, which would learn that a pass is needed from an
//! occlusion query over the next pass, the kernel decides from slot `K − 1`, one pass earlier.

use fragsim_raster::{Fragment, Viewport};

use crate::capture::{Capacity, Identity};
use crate::guarantee::Guarantee;
use crate::kbuffer::{Insert, Outcome, Slots, EMPTY};
use crate::memory::{Memory, WordMemory};
use crate::scheme::{check_cap, CaptureError, Layout, Promise, Scheme, Step};

/// The boundary word of a pixel that needs no more passes: every fragment is below it.
const COMPLETE: u64 = u64::MAX;

/// The multi-pass k-buffer over `u64` words.
#[derive(Clone, Debug)]
pub struct KBufferMultipass {
    pixels: usize,
    slots: Slots,
    capacity: u32,
}

/// A fragment's walk in one pass: the boundary test (after the first pass), then the k-buffer's
/// read–insert–write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Peel {
    /// The boundary word to load first, until it is loaded.
    pub boundary: Option<usize>,
    /// The read–insert–write.
    pub insert: Insert,
}

impl KBufferMultipass {
    /// `k` slots per pixel and room for `max_depth_complexity` captured fragments per pixel (the
    /// oracle's `max_depth_complexity()`), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        max_depth_complexity: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let scheme = Self {
            pixels: viewport.pixels(),
            slots: Slots::new("the multi-pass k-buffer", k)?,
            capacity: max_depth_complexity,
        };
        check_cap(&scheme.name(), &scheme.layout(), memory_cap)?;
        Ok(scheme)
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.slots.k
    }

    /// The boundary word of `pixel`: fragments below its value are not in this pass.
    fn boundary(&self, pixel: usize) -> usize {
        self.slots.words(self.pixels) + pixel
    }

    /// The first word of `pixel`'s output list.
    fn output(&self, pixel: usize) -> usize {
        self.slots.words(self.pixels) + self.pixels + pixel * self.capacity as usize
    }
}

impl Scheme for KBufferMultipass {
    type State = Peel;

    fn name(&self) -> String {
        "kbuffer-multipass".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            // Per pixel: how many fragments the passes captured (may pass the capacity).
            words32: self.pixels,
            init32: 0,
            words64: self.slots.words(self.pixels) + self.pixels * (1 + self.capacity as usize),
            init64: EMPTY,
            table_bytes: 0,
        }
    }

    fn identity(&self) -> Identity {
        Identity::KeyAndPrim
    }

    fn guarantee(&self) -> Guarantee {
        Guarantee::ExactWithoutHazards
    }

    fn promise(&self) -> Promise {
        Promise::All(Capacity::PerPixel(self.capacity))
    }

    fn begin(&self, fragment: Fragment) -> Peel {
        Peel {
            // The first pass takes every fragment: there is nothing to load.
            boundary: None,
            insert: self.slots.begin(fragment),
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Peel> {
        let mut peel = self.begin(fragment);
        if pass > 0 {
            peel.boundary = Some(self.boundary(fragment.pixel as usize));
        }
        Some(peel)
    }

    fn step<M: Memory>(&self, peel: &mut Peel, memory: &M) -> Step {
        if let Some(word) = peel.boundary.take() {
            let boundary: u64 = memory.load(word);
            return if peel.insert.value < boundary {
                Step::Discarded
            } else {
                Step::Continue
            };
        }
        match self.slots.step(&mut peel.insert, memory) {
            Outcome::Continue => Step::Continue,
            // An evicted value is beyond this pass's last slot: a later pass takes it.
            Outcome::Stored | Outcome::Evicted => Step::Stored,
            Outcome::FellOff => Step::Discarded,
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let k = self.slots.k as usize;
        let capacity = self.capacity as usize;
        let mut more = false;
        for pixel in 0..self.pixels {
            let boundary = self.boundary(pixel);
            // Before the first pass the boundary words hold nothing meaningful.
            if pass > 0 && WordMemory::<u64>::load(memory, boundary) == COMPLETE {
                continue;
            }
            let mut count = WordMemory::<u32>::load(memory, pixel) as usize;
            let output = self.output(pixel);
            for value in self.slots.occupied(memory, pixel) {
                if count < capacity {
                    WordMemory::<u64>::store(memory, output + count, value);
                }
                count += 1;
            }
            WordMemory::<u32>::store(memory, pixel, count as u32);
            let last: u64 = WordMemory::<u64>::load(memory, pixel * k + k - 1);
            for slot in 0..k {
                WordMemory::<u64>::store(memory, pixel * k + slot, EMPTY);
            }
            // Packed fragments stop at key 0x3F80_0000, so `last + 1` cannot reach COMPLETE.
            let next = if last == EMPTY { COMPLETE } else { last + 1 };
            WordMemory::<u64>::store(memory, boundary, next);
            more |= next != COMPLETE;
        }
        more
    }

    fn pixels(&self) -> usize {
        self.pixels
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let count = WordMemory::<u32>::load(memory, pixel) as usize;
        let stored = count.min(self.capacity as usize);
        let output = self.output(pixel);
        // No sort: the passes' order is the capture's order, hazards included.
        out.extend((0..stored).map(|i| WordMemory::<u64>::load(memory, output + i)));
        (count - stored) as u32
    }
}
