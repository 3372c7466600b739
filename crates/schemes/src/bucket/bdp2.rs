//! BDP2, bucket depth peeling with two capture passes: HPG 2009 §3.2 (multi-pass paragraph) and
//! GPU Pro §1.4.
//!
//! **Algorithm.** The range pass, then BDP's capture pass with 16 pairs (see [`super::Bdp`]): pair
//! `k` of the first bucket array ends holding `(dmin¹_k, dmax¹_k)`. A second geometry pass routes
//! every fragment to the same bucket `k`, loads `dmin¹_k` and `dmax¹_k`, discards the fragment
//! when `d ≤ dmin¹_k` or `d ≥ dmax¹_k` (it was captured by the first pass), and otherwise
//! MAX-blends it into pair `k` of a second bucket array, which ends holding the second minimum and
//! maximum `(dmin²_k, dmax²_k)`. The post pass reads each bucket as
//! `dmin¹_k ≤ dmin²_k ≤ dmax²_k ≤ dmax¹_k` (HPG eq. 5), each distinct value once.
//!
//! The GPU Pro chapter prints the discard condition as `d ≥ dmax¹_k or d ≤ dmin²_k`: a typo for
//! `dmin¹_k` (HPG §3.2 has `dmin¹_k`; `dmin²_k` does not exist until the second pass is over).
//!
//! **Guarantee.** Approximate: exact for a pixel whose buckets each receive at most 4 fragments
//! with distinct values; from a bucket with more, everything but its two smallest and two largest
//! is lost, and the oracle's diff counts it as `lost`. A superset of BDP's capture with the same
//! range and buckets. Order-independent (MAX blending and a read-only first array in pass 2).
//! Promise: all, overflow 0.
//!
//! **Passes.** 3 geometry passes: range, first capture, second capture (the paper counts 2, its
//! range pass renders a bounding box). Per fragment in the second pass: 2 range loads, 2 loads of
//! the first array, then 2 `fetch_max` or a discard.
//!
//! **Memory per pixel.** 2 u32 range words plus two arrays of `2B` words: with the paper's 16
//! pairs and u32 words 8 + 256 = 264 bytes (66 MiB at 512 × 512; FreePipe's Table 3 lists 64 MB for
//! BDP2, the two bucket arrays alone), 8 + 512 with u64 words.

use std::marker::PhantomData;

use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use super::{
    positive, push_distinct, read_pair, word_suffix, Blend, Plan, Stage, Walk, RANGE_WORDS,
};
use crate::common::MdtsWord;
use fragsim_capture::Capacity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// BDP2's own stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bdp2Stage<W> {
    /// Second pass: load the first array's min channel of the fragment's bucket.
    LoadMin {
        /// Bucket word of the first array's pair.
        first: usize,
        /// Bucket word of the second array's pair.
        second: usize,
    },
    /// Second pass: load the first array's max channel, then discard or blend.
    LoadMax {
        /// Bucket word of the first array's pair.
        first: usize,
        /// Bucket word of the second array's pair.
        second: usize,
        /// The first array's minimum of the bucket.
        min: W,
    },
    /// A MAX-blend write (first array in the first capture pass, second array in the second).
    Blend(Blend),
}

/// Bucket depth peeling with two capture passes (after the range pass), over bucket words of
/// type `W` (default: the paper's u32 depth).
#[derive(Clone, Debug)]
pub struct Bdp2<W: MdtsWord = u32> {
    plan: Plan,
    buckets: u32,
    _word: PhantomData<W>,
}

impl<W: MdtsWord> Bdp2<W> {
    /// BDP2 with `buckets` pairs per pixel in each of its two arrays, within `memory_cap` bytes.
    ///
    /// # Errors
    /// No buckets, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, buckets: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        positive("BDP2's bucket count", buckets)?;
        let plan = Plan::new::<W>(
            Self::name_of(buckets),
            Promise::All(Capacity::Unbounded),
            viewport,
            RANGE_WORDS,
            4 * buckets as usize,
            memory_cap,
        )?;
        Ok(Self {
            plan,
            buckets,
            _word: PhantomData,
        })
    }

    /// The paper's form, 16 pairs per array, with the default memory cap.
    ///
    /// # Errors
    /// As [`Bdp2::new`].
    pub fn paper(viewport: Viewport) -> Result<Self, CaptureError> {
        Self::new(viewport, 16, MEMORY_CAP_DEFAULT)
    }

    fn name_of(buckets: u32) -> String {
        let form = if buckets == 16 {
            String::new()
        } else {
            format!("-pairs{buckets}")
        };
        format!("bdp2{form}{}", word_suffix::<W>())
    }

    /// Bucket words of pair `k` of `pixel` in the first and the second array.
    fn pair_words(&self, pixel: usize, k: usize) -> (usize, usize) {
        let first = self.plan.bucket(pixel, 2 * k);
        (first, first + 2 * self.buckets as usize)
    }
}

impl<W: MdtsWord> Scheme for Bdp2<W> {
    type State = Walk<W, Bdp2Stage<W>>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.plan.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Self::State {
        self.plan.begin(0, fragment)
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Self::State> {
        (pass < 3).then(|| self.plan.begin(pass, fragment))
    }

    fn step<M: Memory>(&self, walk: &mut Self::State, memory: &M) -> Step {
        let words = W::words(memory);
        let stage = match &mut walk.stage {
            Stage::Own(stage) => stage,
            _ => {
                return self.plan.range_step(walk, memory, |walk| {
                    let k = Plan::route(walk, self.buckets) as usize;
                    let (first, second) = self.pair_words(walk.fragment.pixel as usize, k);
                    if walk.pass == 1 {
                        Bdp2Stage::Blend(Blend::PairMin { word: first })
                    } else {
                        Bdp2Stage::LoadMin { first, second }
                    }
                })
            }
        };
        match *stage {
            Bdp2Stage::Blend(ref mut blend) => blend.step(walk.value, memory),
            Bdp2Stage::LoadMin { first, second } => {
                *stage = Bdp2Stage::LoadMax {
                    first,
                    second,
                    min: W::MAX.wrapping_sub(words.load(first)),
                };
                Step::Continue
            }
            Bdp2Stage::LoadMax { first, second, min } => {
                let max = words.load(first + 1);
                if walk.value <= min || walk.value >= max {
                    Step::Discarded
                } else {
                    *stage = Bdp2Stage::Blend(Blend::PairMin { word: second });
                    Step::Continue
                }
            }
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, _memory: &M) -> bool {
        pass < 2
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        for k in 0..self.buckets as usize {
            let (first, second) = self.pair_words(pixel, k);
            if let Some((min1, max1)) = read_pair::<W, M>(memory, first) {
                match read_pair::<W, M>(memory, second) {
                    Some((min2, max2)) => push_distinct(out, [min1, min2, max2, max1]),
                    None => push_distinct(out, [min1, max1]),
                }
            }
        }
        0
    }
}
