//! "Loop32" of nvpro-samples `vk_order_independent_transparency` (NVIDIA, `oitLoop.frag.glsl`):
//! MDTS's `imageAtomicMin` insertion loop with a tie rule, then a colour pass.
//!
//! **Algorithm** (modelled from the sample's published description), two geometry passes over
//! `K` 32-bit depth slots and `K` colour slots per pixel, laid out layer-major as the sample's
//! buffer (slot `i` of pixel `p` at `p + i * pixels`), every depth slot cleared to `0xFFFFFFFF`:
//! 1. *Depth pass.* With the sample's `USE_EARLYDEPTH` (on by default): load slot `K − 1` and
//!    discard the fragment if its depth key is larger; load slot `K / 2` and start there if the
//!    key is larger. Then, slot by slot, `ztest = imageAtomicMin(&slot[i], zcur)`; **stop if
//!    `ztest` is empty or equal to `zcur`**; else `zcur = max(ztest, zcur)` goes to slot `i + 1`.
//!    This is FreePipe's MDTS walk (`crate::mdts`) except for the stop on an equal depth.
//! 2. *Colour pass.* A fragment loads slot `K − 1` and goes to the tail blend (not captured here)
//!    if its key is larger; otherwise it binary-searches the slots for its key (one load a probe)
//!    and stores its colour, here its primitive id, into the matching colour slot (a plain store).
//!
//! The resolve reads the slots nearest first and pairs each depth with its colour.
//!
//! **Guarantee and departure.** Under any interleaving the depth slots end holding the `K`
//! smallest *distinct* depth keys, ascending, each once: a carried value passes slot `i` only when
//! the slot holds a smaller value, and slots only decrease, so two copies of one key can never
//! settle in two slots; one that meets its copy stops. **Equal depths merge**: two fragments of a
//! pixel at one depth key take one slot, and in the colour pass both store into it and the last
//! store wins. So against the oracle's canonical order (ties by primitive id) loop32 departs
//! exactly where a key among a pixel's `K` nearest distinct keys belongs to two or more fragments,
//! while FreePipe's MDTS keeps them all; against the oracle asked to merge equal depths
//! (`Ties::MergeEqualDepths`) it is exact up to `K`. The early-depth loads change no result (slots
//! only decrease, so a slot seen smaller than the key stays smaller). Two geometry passes; memory:
//! `2K` 32-bit words per pixel.
//!
//! Unlike the sample, which packs an 8-bit sRGB colour, the colour slot holds the primitive id
//! (the effects colour by primitive); unlike the GPU, the tail blend of fragments past `K` is not
//! modelled: they are outside the promise ([`Promise::Nearest`]).

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step};

/// The empty depth slot.
const EMPTY: u32 = u32::MAX;

/// nvpro-samples' loop32: two passes, equal depths merge.
#[derive(Clone, Debug)]
pub struct Loop32 {
    descriptor: Descriptor,
    k: u32,
}

/// A fragment's progress through one of the two passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Loop32Step {
    /// Depth pass: the early test against slot `K − 1`.
    LastSlot {
        /// The pixel.
        pixel: u32,
        /// The depth key.
        z: u32,
    },
    /// Depth pass: the early test against slot `K / 2`.
    MiddleSlot {
        /// The pixel.
        pixel: u32,
        /// The depth key.
        z: u32,
    },
    /// Depth pass: the `atomicMin` on slot `slot`, carrying `z`.
    Insert {
        /// The pixel.
        pixel: u32,
        /// The slot tested next.
        slot: u32,
        /// The carried depth key.
        z: u32,
    },
    /// Colour pass: the tail test against slot `K − 1`.
    Tail {
        /// The pixel.
        pixel: u32,
        /// The depth key.
        z: u32,
        /// The colour (primitive id).
        prim: u32,
    },
    /// Colour pass: the binary search, the key being in slots `start..=end`.
    Search {
        /// The pixel.
        pixel: u32,
        /// The depth key.
        z: u32,
        /// The colour.
        prim: u32,
        /// First candidate slot.
        start: u32,
        /// Last candidate slot.
        end: u32,
    },
    /// Colour pass: the store into the colour slot.
    Colour {
        /// The 32-bit word of the colour slot.
        word: usize,
        /// The colour.
        prim: u32,
    },
}

impl Loop32 {
    /// `k` depth and colour slots per pixel (the sample's `OIT_LAYERS`), within `memory_cap`.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, k: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(
                "loop32 needs K ≥ 1 layers per pixel, got K = 0".into(),
            ));
        }
        let descriptor = Descriptor {
            name: "loop32".into(),
            layout: Layout {
                words32: 2 * k as usize * viewport.pixels(),
                init32: EMPTY,
                words64: 0,
                init64: 0,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee: Guarantee::ExactDistinctDepths,
            promise: Promise::Nearest(k),
            pixels: viewport.pixels(),
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            k,
        })
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.k
    }

    /// The depth word of `pixel`'s slot `slot`.
    fn depth_word(&self, pixel: u32, slot: u32) -> usize {
        pixel as usize + slot as usize * self.descriptor.pixels
    }

    /// The colour word of `pixel`'s slot `slot`.
    fn colour_word(&self, pixel: u32, slot: u32) -> usize {
        self.depth_word(pixel, slot) + self.k as usize * self.descriptor.pixels
    }

    /// The depth key in `pixel`'s slot `slot` (a plain load).
    fn load<M: Memory>(&self, memory: &M, pixel: u32, slot: u32) -> u32 {
        WordMemory::<u32>::load(memory, self.depth_word(pixel, slot))
    }

    /// The search's next state: a probe, or the store once one slot is left.
    fn search(&self, pixel: u32, z: u32, prim: u32, start: u32, end: u32) -> Loop32Step {
        if start < end {
            Loop32Step::Search {
                pixel,
                z,
                prim,
                start,
                end,
            }
        } else {
            Loop32Step::Colour {
                word: self.colour_word(pixel, start),
                prim,
            }
        }
    }
}

impl Scheme for Loop32 {
    type State = Loop32Step;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Loop32Step {
        Loop32Step::LastSlot {
            pixel: fragment.pixel,
            z: fragment.depth_key,
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Loop32Step> {
        match pass {
            0 => Some(self.begin(fragment)),
            1 => Some(Loop32Step::Tail {
                pixel: fragment.pixel,
                z: fragment.depth_key,
                prim: fragment.prim,
            }),
            _ => None,
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, _memory: &M) -> bool {
        pass == 0
    }

    fn step<M: Memory>(&self, state: &mut Loop32Step, memory: &M) -> Step {
        let words = memory;
        match *state {
            Loop32Step::LastSlot { pixel, z } => {
                if z > self.load(words, pixel, self.k - 1) {
                    return Step::Dropped;
                }
                *state = Loop32Step::MiddleSlot { pixel, z };
            }
            Loop32Step::MiddleSlot { pixel, z } => {
                let half = self.k / 2;
                let slot = if z > self.load(words, pixel, half) {
                    half
                } else {
                    0
                };
                *state = Loop32Step::Insert { pixel, slot, z };
            }
            Loop32Step::Insert { pixel, slot, z } => {
                let ztest = WordMemory::<u32>::fetch_min(words, self.depth_word(pixel, slot), z);
                if ztest == EMPTY {
                    return Step::Stored;
                }
                if ztest == z {
                    // An equal depth is already there: the two merge.
                    return Step::Discarded;
                }
                if slot + 1 == self.k {
                    return Step::Dropped;
                }
                *state = Loop32Step::Insert {
                    pixel,
                    slot: slot + 1,
                    z: z.max(ztest),
                };
            }
            Loop32Step::Tail { pixel, z, prim } => {
                if self.load(words, pixel, self.k - 1) < z {
                    return Step::Discarded;
                }
                *state = self.search(pixel, z, prim, 0, self.k - 1);
            }
            Loop32Step::Search {
                pixel,
                z,
                prim,
                start,
                end,
            } => {
                let mid = (start + end) / 2;
                *state = if self.load(words, pixel, mid) < z {
                    self.search(pixel, z, prim, mid + 1, end)
                } else {
                    self.search(pixel, z, prim, start, mid)
                };
            }
            Loop32Step::Colour { word, prim } => {
                WordMemory::<u32>::store(words, word, prim);
                return Step::Stored;
            }
        }
        Step::Continue
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let words = memory;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
        )]
        let pixel = pixel as u32;
        for slot in 0..self.k {
            let z = self.load(words, pixel, slot);
            if z == EMPTY {
                break;
            }
            let prim = WordMemory::<u32>::load(words, self.colour_word(pixel, slot));
            out.push(u64::from(z) << 32 | u64::from(prim));
        }
        0
    }
}
