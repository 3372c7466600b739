//! ADP, adaptive bucket depth peeling: HPG 2009 §3.3 (Table 1) and GPU Pro §1.5 (Listings 1.1,
//! 1.2).
//!
//! **Algorithm.** After the shared depth-range pass (see [`crate::bucket`]):
//! 1. *Histogram pass.* The pixel's range is cut into [`ADP_SUBINTERVALS`] = 1024 equal
//!    subintervals; a fragment in subinterval `k` sets bit `k` of its pixel's 1024-bit histogram
//!    (32 u32 words, bit `k` = word `k / 32`, mask `0x8000_0000 >> (k % 32)` as in Listing 1.1)
//!    with one `fetch_or` (the paper's logic-op OR blending).
//! 2. *Equalisation* (the between-pass kernel, Listing 1.2). Per pixel, the set bits are taken in
//!    order and each contributes the upper bound of its subinterval, `k + 1`, to the *equalised
//!    histogram*: the bounds re-divide the range into one subinterval per occupied bit.
//! 3. *Routing pass.* A fragment finds the first bound above its own subinterval (a binary search,
//!    one load per probe: the paper's `EH[k − 1] ≤ d < EH[k]`) and MAX-blends its value into that
//!    bucket (one `fetch_max` of value + 1). The buckets are filled in depth order.
//!
//! Scenes deeper than [`ADP_BATCH`] = 32 layers (the paper's 32 MRT channels) take batches: the
//! equalisation kernel takes the next 32 set bits of the histogram, with the bound of the last
//! set bit before them as the batch's lower edge; the next routing pass discards fragments below
//! the edge or above the last bound and fills the next 32 buckets; and so on until no pixel has
//! set bits left (HPG §3.3, last paragraph).
//!
//! **Guarantee.** Approximate: exact for a pixel when no two of its fragments share one of the
//! 1024 uniform subintervals of its range (fragments farther apart than `(zFar − zNear) / 1024`
//! never do) and the storage suffices. Fragments sharing a subinterval share a bucket and only
//! the largest value survives (HPG: "merged into one layer"); the oracle's diff counts the others
//! as `lost`. Order-independent (OR and MAX are commutative). Storage is sized to the scene's
//! maximum depth complexity, given by the caller: if a pixel has more occupied subintervals than
//! that, the excess ones are not captured by design and each is counted as one overflowed
//! fragment (a lower bound of what it held: any further fragment in it shows as `lost`). Promise:
//! all.
//!
//! **Passes.** Range, histogram, then one routing pass per batch: 3 geometry passes up to 32
//! layers, 4 up to 64, and so on (the paper counts 2 for up to 32: its range pass renders a
//! bounding box). Per fragment: 2 range loads per pass, 1 `fetch_or`; per routing pass 1 load of
//! the lower edge, up to ⌈log₂ 33⌉ = 6 loads of the search, 1 `fetch_max`.
//!
//! **Memory per pixel**, for a scene of depth complexity `N` (`n = min(N, 32)` bounds per batch):
//! 2 range words, 32 histogram words, 1 + `n` equalised-histogram words (u32), and `N` buckets of
//! the bucket type. For `N = 20` (FreePipe's Table 3 setting) and u32 words:
//! 8 + 128 + 84 + 80 = 300 bytes, 75 MiB at 512 × 512, where Table 3 lists 52 MB = 208 bytes a
//! pixel: the histogram and one 20-channel array. That is the peak of a GPU that frees the
//! histogram after equalising (only one batch is needed for 20 layers) and reuses it for the
//! bucket array; here every word lives in one allocation for the whole frame, so it is the sum.
//!
//! Unlike the paper, the equalised histogram holds subinterval indices (`k + 1`), not the float
//! depths `zNear + (k + 1)(zFar − zNear)/1024` of Listing 1.2, and the routing pass compares the
//! fragment's own subinterval index, computed by the same function as in the histogram pass: a
//! float bound recomputed in other arithmetic can route a fragment at a boundary one bucket off,
//! an error the paper's form has and this model does not. Listing 1.1 does not clamp `k`: the
//! farthest fragment (`d = zFar`, exact with a precise range) gets `k = 1024`, which its last
//! `else` branch writes as bit 992; here it is clamped to 1023 (the paper's last subinterval is
//! closed). Listing 1.2 loads `fbcolor0` twice (`fb1` should read `fbcolor1`), also not copied.
//! The GPU Pro chapter's refinement, pairs of buckets keeping a min and a max per subinterval, is
//! not modelled.

use std::marker::PhantomData;

use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use super::{positive, read_single, word_suffix, Blend, Plan, Stage, Walk, RANGE_WORDS};
use crate::common::MdtsWord;
use fragsim_capture::Capacity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// Subintervals of the depth histogram: 8 MRTs × 4 channels × 32 bits.
pub const ADP_SUBINTERVALS: u32 = 1024;

/// Layers per routing pass: the paper's 32 float channels.
pub const ADP_BATCH: u32 = 32;

/// u32 words of the histogram per pixel.
const HISTOGRAM_WORDS: usize = (ADP_SUBINTERVALS / 32) as usize;

/// Aux word of the histogram's first word.
const HISTOGRAM: usize = RANGE_WORDS;

/// Aux word of the batch's lower edge; the bounds follow it.
const LOWER_EDGE: usize = HISTOGRAM + HISTOGRAM_WORDS;

/// ADP's own stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdpStage {
    /// Histogram pass: `fetch_or` of the subinterval's bit.
    Mark {
        /// Aux word of the histogram.
        word: usize,
        /// The bit.
        mask: u32,
    },
    /// Routing pass: load the batch's lower edge.
    LoadLower {
        /// The fragment's subinterval.
        bit: u32,
    },
    /// Routing pass: binary search of the first bound above `bit` in `lo..hi`.
    Search {
        /// The fragment's subinterval.
        bit: u32,
        /// Lowest candidate bucket of the batch.
        lo: u32,
        /// One past the highest candidate (`n` = not in this batch).
        hi: u32,
    },
    /// Routing pass: the MAX-blend write into the bucket.
    Blend(Blend),
}

/// Adaptive bucket depth peeling over bucket words of type `W` (default: the paper's u32 depth).
#[derive(Clone, Debug)]
pub struct Adp<W: MdtsWord = u32> {
    plan: Plan,
    slots: u32,
    _word: PhantomData<W>,
}

impl<W: MdtsWord> Adp<W> {
    /// ADP with buckets for `max_depth` layers per pixel (the scene's maximum depth complexity,
    /// e.g. `Oracle::max_depth_complexity`), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `max_depth == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, max_depth: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        positive("ADP's depth complexity (buckets per pixel)", max_depth)?;
        let aux = LOWER_EDGE + 1 + max_depth.min(ADP_BATCH) as usize;
        let plan = Plan::new::<W>(
            format!("adp{}", word_suffix::<W>()),
            Promise::All(Capacity::PerPixel(max_depth)),
            viewport,
            aux,
            max_depth as usize,
            memory_cap,
        )?;
        Ok(Self {
            plan,
            slots: max_depth,
            _word: PhantomData,
        })
    }

    /// ADP for `max_depth` layers with the default memory cap.
    ///
    /// # Errors
    /// As [`Adp::new`].
    pub fn for_depth(viewport: Viewport, max_depth: u32) -> Result<Self, CaptureError> {
        Self::new(viewport, max_depth, MEMORY_CAP_DEFAULT)
    }

    /// Buckets per pixel (over all batches).
    #[must_use]
    pub fn slots(&self) -> u32 {
        self.slots
    }

    /// Buckets of batch `batch` (0 past the last).
    fn batch_len(&self, batch: u32) -> u32 {
        self.slots
            .saturating_sub(batch.saturating_mul(ADP_BATCH))
            .min(ADP_BATCH)
    }

    /// The pixel's histogram word `i`.
    fn histogram<M: Memory>(&self, memory: &M, pixel: usize, i: usize) -> u32 {
        WordMemory::<u32>::load(memory, self.plan.aux(pixel, HISTOGRAM + i))
    }

    /// The equalisation kernel for `batch`, every pixel: writes the batch's lower edge and bounds.
    /// Returns whether any pixel has a set bit in the batch.
    fn equalise<M: Memory>(&self, memory: &M, batch: u32) -> bool {
        let first = batch * ADP_BATCH;
        let len = self.batch_len(batch) as usize;
        let mut any = false;
        let mut bounds = Vec::with_capacity(len);
        for pixel in 0..self.plan.descriptor.pixels {
            bounds.clear();
            // With no set bit in the batch, the edge is past every subinterval: all discard.
            let mut lower = if batch == 0 { 0 } else { ADP_SUBINTERVALS };
            let mut rank = 0_u32;
            'scan: for i in 0..HISTOGRAM_WORDS {
                let mut bits = self.histogram(memory, pixel, i);
                while bits != 0 {
                    let j = bits.leading_zeros();
                    bits &= !(0x8000_0000 >> j);
                    #[expect(
                        clippy::cast_possible_truncation,
                        reason = "i is below HISTOGRAM_WORDS, a few words of a u32 subinterval count"
                    )]
                    let upper = i as u32 * 32 + j + 1;
                    if rank + 1 == first {
                        lower = upper;
                    } else if rank >= first {
                        if bounds.len() == len {
                            break 'scan;
                        }
                        bounds.push(upper);
                    }
                    rank += 1;
                }
            }
            if bounds.is_empty() {
                lower = ADP_SUBINTERVALS;
            } else {
                any = true;
            }
            let last = bounds.last().copied().unwrap_or(ADP_SUBINTERVALS);
            // Unused bounds repeat the last one, so the search finds the real bucket.
            bounds.resize(len, last);
            WordMemory::<u32>::store(memory, self.plan.aux(pixel, LOWER_EDGE), lower);
            for (b, &bound) in bounds.iter().enumerate() {
                WordMemory::<u32>::store(memory, self.plan.aux(pixel, LOWER_EDGE + 1 + b), bound);
            }
        }
        any
    }

    /// The routing pass's next stage after the search narrowed to `lo..hi`.
    fn searched(&self, walk: &Walk<W, AdpStage>, bit: u32, lo: u32, hi: u32) -> (Step, AdpStage) {
        if lo < hi {
            return (Step::Continue, AdpStage::Search { bit, lo, hi });
        }
        let batch = walk.pass - 2;
        if lo == self.batch_len(batch) {
            // Above the batch's last bound: a later batch's fragment, or beyond the storage.
            return (Step::Discarded, AdpStage::Search { bit, lo, hi });
        }
        let word = self.plan.bucket(
            walk.fragment.pixel as usize,
            (batch * ADP_BATCH + lo) as usize,
        );
        (Step::Continue, AdpStage::Blend(Blend::Single { word }))
    }
}

impl<W: MdtsWord> Scheme for Adp<W> {
    type State = Walk<W, AdpStage>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.plan.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Self::State {
        self.plan.begin(0, fragment)
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Self::State> {
        Some(self.plan.begin(pass, fragment))
    }

    fn step<M: Memory>(&self, walk: &mut Self::State, memory: &M) -> Step {
        let pixel = walk.fragment.pixel as usize;
        let stage = match walk.stage {
            Stage::Own(stage) => stage,
            _ => {
                return self.plan.range_step(walk, memory, |walk| {
                    let bit = Plan::route(walk, ADP_SUBINTERVALS);
                    if walk.pass == 1 {
                        AdpStage::Mark {
                            word: self.plan.aux(pixel, HISTOGRAM + (bit / 32) as usize),
                            mask: 0x8000_0000 >> (bit % 32),
                        }
                    } else {
                        AdpStage::LoadLower { bit }
                    }
                })
            }
        };
        let (step, next) = match stage {
            AdpStage::Mark { word, mask } => {
                WordMemory::<u32>::fetch_or(memory, word, mask);
                (Step::Stored, stage)
            }
            AdpStage::LoadLower { bit } => {
                let lower = WordMemory::<u32>::load(memory, self.plan.aux(pixel, LOWER_EDGE));
                if bit < lower {
                    // An earlier batch's fragment.
                    (Step::Discarded, stage)
                } else {
                    let n = self.batch_len(walk.pass - 2);
                    (Step::Continue, AdpStage::Search { bit, lo: 0, hi: n })
                }
            }
            AdpStage::Search { bit, lo, hi } => {
                let mid = (lo + hi) / 2;
                let word = self.plan.aux(pixel, LOWER_EDGE + 1 + mid as usize);
                if WordMemory::<u32>::load(memory, word) > bit {
                    self.searched(walk, bit, lo, mid)
                } else {
                    self.searched(walk, bit, mid + 1, hi)
                }
            }
            AdpStage::Blend(mut blend) => {
                let step = blend.step(walk.value, memory);
                (step, AdpStage::Blend(blend))
            }
        };
        walk.stage = Stage::Own(next);
        step
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        match pass {
            0 => true,
            1 => {
                self.equalise(memory, 0);
                true
            }
            _ => {
                let next = pass - 1;
                self.batch_len(next) > 0 && self.equalise(memory, next)
            }
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        for slot in 0..self.slots as usize {
            if let Some(value) = read_single::<W, M>(memory, self.plan.bucket(pixel, slot)) {
                out.push(value.decode());
            }
        }
        let occupied: u32 = (0..HISTOGRAM_WORDS)
            .map(|i| self.histogram(memory, pixel, i).count_ones())
            .sum();
        occupied.saturating_sub(self.slots)
    }
}
