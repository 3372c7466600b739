//! "Loop64" of nvpro-samples `vk_order_independent_transparency` (NVIDIA, `oitLoop64.frag.glsl`):
//! loop32's insertion in **one** pass, on 64-bit words packing the depth with the colour, for
//! GPUs with 64-bit atomics (`GL_NV_shader_atomic_int64`).
//!
//! **Algorithm** (the sample's colour pass, read from its source). Each pixel owns `K` 64-bit
//! slots (the sample's `OIT_LAYERS`), laid out layer-major as its A-buffer (slot `i` of pixel `p`
//! at `p + i * pixels`), cleared to all ones. A fragment packs `zcur = depth_bits << 32 | colour`.
//! With the sample's `USE_EARLYDEPTH`: load slot `K − 1` and give up (the fragment goes to the
//! tail) if `zcur` is larger; load slot `K / 2` and start there if `zcur` is larger. Then, slot by
//! slot, `ztest = atomicMin(&slot[i], zcur)`; **stop when `ztest` is empty**; else
//! `zcur = max(ztest, zcur)` goes to slot `i + 1`; a value carried past slot `K − 1` is evicted
//! to the tail. Unlike loop32, nothing stops on an equal depth: the comparison is of whole
//! words. The resolve reads the slots nearest first, up to the first empty one.
//!
//! **Guarantee.** This is FreePipe's MDTS walk ([`mdts`](crate::mdts)) on 64-bit words,
//! with two early loads that change no result: slots only decrease, so a word found larger than
//! the fragment's stays larger (the fragment is not among the `K` nearest words, or slots below
//! `K / 2` all hold smaller words). Under any interleaving each pixel ends with the `K` smallest
//! words, ascending: [`Guarantee::Exact`], [`Promise::Nearest`]`(K)`; every fragment not kept
//! ends one walk `Dropped` (its own early test, or the walk that carried it past slot `K − 1`).
//! What the words order is the sample's question: with a real colour in the low half, fragments
//! at one depth are ordered by colour, not primitive, and two of one depth and one colour are
//! two equal words (both kept, indistinguishable, which changes no image); here the low half is
//! the primitive id, so the order is the canonical one and the capture is checked fragment for
//! fragment. One geometry pass (loop32: two); at most `K + 2` memory operations per fragment;
//! memory: `8 K` bytes per pixel (loop32's too: `K` depth and `K` colour words).
//!
//! **Departures.** The low half is the primitive id, not packed sRGB (the effects colour by
//! primitive); the tail blend of what does not fit is not modelled (those fragments are outside
//! the promise, and counted as drops); no MSAA (the sample has none for loop64 either).

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step};

/// An empty slot.
const EMPTY: u64 = u64::MAX;

/// nvpro-samples' loop64.
#[derive(Clone, Debug)]
pub struct Loop64 {
    descriptor: Descriptor,
    k: u32,
}

/// A fragment's progress.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Loop64Step {
    /// The early test against slot `K − 1`.
    LastSlot {
        /// The pixel.
        pixel: u32,
        /// The packed word.
        z: u64,
    },
    /// The early test against slot `K / 2`.
    MiddleSlot {
        /// The pixel.
        pixel: u32,
        /// The packed word.
        z: u64,
    },
    /// The `atomicMin` on slot `slot`, carrying `z`.
    Insert {
        /// The pixel.
        pixel: u32,
        /// The slot tested next.
        slot: u32,
        /// The carried word.
        z: u64,
    },
}

impl Loop64 {
    /// `k` slots per pixel (the sample's `OIT_LAYERS`), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, k: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(
                "loop64 needs K ≥ 1 layers per pixel, got K = 0".into(),
            ));
        }
        let descriptor = Descriptor {
            name: "loop64".into(),
            layout: Layout {
                words32: 0,
                init32: 0,
                words64: k as usize * viewport.pixels(),
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

    /// The word of `pixel`'s slot `slot`.
    fn word(&self, pixel: u32, slot: u32) -> usize {
        pixel as usize + slot as usize * self.descriptor.pixels
    }

    /// `pixel`'s slot `slot` (a plain load).
    fn load<M: Memory>(&self, memory: &M, pixel: u32, slot: u32) -> u64 {
        WordMemory::<u64>::load(memory, self.word(pixel, slot))
    }
}

impl Scheme for Loop64 {
    type State = Loop64Step;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Loop64Step {
        Loop64Step::LastSlot {
            pixel: fragment.pixel,
            z: fragment.packed(),
        }
    }

    fn step<M: Memory>(&self, state: &mut Loop64Step, memory: &M) -> Step {
        match *state {
            Loop64Step::LastSlot { pixel, z } => {
                if z > self.load(memory, pixel, self.k - 1) {
                    return Step::Dropped;
                }
                *state = Loop64Step::MiddleSlot { pixel, z };
            }
            Loop64Step::MiddleSlot { pixel, z } => {
                let half = self.k / 2;
                let slot = if z > self.load(memory, pixel, half) {
                    half
                } else {
                    0
                };
                *state = Loop64Step::Insert { pixel, slot, z };
            }
            Loop64Step::Insert { pixel, slot, z } => {
                let ztest = WordMemory::<u64>::fetch_min(memory, self.word(pixel, slot), z);
                if ztest == EMPTY {
                    return Step::Stored;
                }
                if slot + 1 == self.k {
                    return Step::Dropped;
                }
                *state = Loop64Step::Insert {
                    pixel,
                    slot: slot + 1,
                    z: z.max(ztest),
                };
            }
        }
        Step::Continue
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
        )]
        let pixel = pixel as u32;
        out.extend(
            (0..self.k)
                .map(|slot| self.load(memory, pixel, slot))
                .take_while(|&z| z != EMPTY),
        );
        // What fell off is not in memory: the executors count it from the walks.
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::one_pixel::fragment;
    use fragsim_capture::executors::scheduled::run_fragments_in_order;

    /// Every interleaving of three walks' first steps (each order of the three fragments,
    /// stepped round-robin), `K` = 2: the two smallest words kept, one drop, and equal depths
    /// kept apart (no stop on an equal depth, unlike loop32).
    #[test]
    fn the_two_smallest_words_are_kept_in_every_round_robin_order() {
        let fragments = [fragment(4, 0), fragment(4, 1), fragment(9, 2)];
        let scheme = Loop64::new(Viewport::new(1, 1).unwrap(), 2, u64::MAX).unwrap();
        for first in 0..3_u32 {
            for second in (0..3).filter(|&s| s != first) {
                let third = 3 - first - second;
                let order: Vec<u32> = [first, second, third].repeat(4);
                let run = run_fragments_in_order(&scheme, &fragments, &order, false);
                let expected = [fragments[0].packed(), fragments[1].packed()];
                assert_eq!(run.run.capture.pixel(0), expected.as_slice(), "{order:?}");
                assert_eq!(run.run.stats.counters.dropped, 1, "{order:?}");
            }
        }
    }

    /// The early test: a fragment farther than slot `K − 1` takes one step and writes nothing.
    #[test]
    fn a_fragment_beyond_the_last_slot_gives_up_after_one_load() {
        let scheme = Loop64::new(Viewport::new(1, 1).unwrap(), 1, u64::MAX).unwrap();
        let memory: fragsim_memory::SerialMemory = scheme.layout().allocate();
        let mut steps = 0;
        assert_eq!(
            scheme.insert(fragment(3, 0), &memory, &mut steps),
            Step::Stored
        );
        let before = steps;
        assert_eq!(
            scheme.insert(fragment(5, 1), &memory, &mut steps),
            Step::Dropped
        );
        assert_eq!(steps - before, 1);
        assert_eq!(scheme.resolve(&memory).pixel(0), &[fragment(3, 0).packed()]);
        assert!(Loop64::new(Viewport::new(1, 1).unwrap(), 0, u64::MAX).is_err());
    }
}
