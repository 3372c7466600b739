//! BDP, bucket depth peeling in one capture pass: HPG 2009 §3.2 and GPU Pro §1.3.
//!
//! **Algorithm.** After the shared depth-range pass (see [`crate::bucket`]), the capture pass
//! routes each fragment to bucket `floor(B · (d − zNear) / (zFar − zNear))` of its pixel (HPG
//! eq. 2, clamped to the last bucket) and MAX-blends it there:
//! - [`Buckets::Pairs`] (the paper's depth form, `B = 16`): bucket `k` is a pair of words,
//!   updated with `(1 − d, d)` in the paper and here with `(!value, value)` by two `fetch_max`,
//!   so it ends holding its minimum and maximum (HPG eq. 3). Buckets in order, each min then max,
//!   are sorted (eq. 4); an empty pair is skipped, a pair with min = max is one value.
//! - [`Buckets::Singles`] (the paper's attribute form, `B = 32`, where the packed colour of each
//!   fragment is what MAX blending keeps): one word per bucket, one `fetch_max` of the value; the
//!   largest value of the bucket survives.
//!
//! **Guarantee.** Approximate: exact for a pixel whose buckets each receive at most 2 fragments
//! (pairs) or at most 1 (singles), with distinct values; from a bucket with more, everything but
//! its minimum and maximum (its maximum) is lost, and the oracle's diff counts it as `lost`. The
//! result is independent of the order of the fragments (MAX is commutative), so every executor
//! and schedule gives the same capture. Promise: all, overflow 0.
//!
//! **Passes.** 2 geometry passes: the range pass and the capture pass (the paper counts 1: its
//! range pass renders a bounding box, not the model). Per fragment: 2 operations in the range
//! pass, then 2 loads and 2 (pairs) or 1 (singles) `fetch_max`.
//!
//! **Memory per pixel.** 2 u32 range words plus `2B` (pairs) or `B` (singles) bucket words: with
//! the paper's 32 channels and u32 words 8 + 128 = 136 bytes (34 MiB at 512 × 512; FreePipe's
//! Table 3 lists 32 MB for BDP, the bucket array alone), 8 + 256 with u64 words.
//!
//! Unlike the paper, whose attribute form routes packed colours, the singles store the depth key
//! (or `key << 32 | prim`), so the capture can be diffed with the oracle; and a bucket stores
//! value + 1 so that depth 0.0 is not mistaken for an empty bucket.

use std::marker::PhantomData;

use fragsim_memory::Memory;
use fragsim_raster::{Fragment, Viewport};

use super::{
    positive, push_distinct, read_pair, read_single, word_suffix, Blend, Plan, Stage, Walk,
    RANGE_WORDS,
};
use crate::common::MdtsWord;
use fragsim_capture::Capacity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// How a pixel's bucket words are used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Buckets {
    /// This many buckets of two words (min and max); the paper uses 16.
    Pairs(u32),
    /// This many buckets of one word (max); the paper's attribute form uses 32.
    Singles(u32),
}

impl Buckets {
    /// The paper's depth form: 16 pairs in 32 channels.
    pub const PAPER_PAIRS: Self = Self::Pairs(16);
    /// The paper's attribute form: 32 single buckets.
    pub const PAPER_SINGLES: Self = Self::Singles(32);

    /// Number of buckets (subintervals).
    #[must_use]
    pub fn count(self) -> u32 {
        match self {
            Self::Pairs(n) | Self::Singles(n) => n,
        }
    }

    /// Words per bucket.
    fn width(self) -> usize {
        match self {
            Self::Pairs(_) => 2,
            Self::Singles(_) => 1,
        }
    }
}

/// Bucket depth peeling in one capture pass (after the range pass), over bucket words of type
/// `W` (default: the paper's u32 depth).
#[derive(Clone, Debug)]
pub struct Bdp<W: MdtsWord = u32> {
    plan: Plan,
    buckets: Buckets,
    _word: PhantomData<W>,
}

impl<W: MdtsWord> Bdp<W> {
    /// BDP with `buckets` per pixel within `memory_cap` bytes.
    ///
    /// # Errors
    /// No buckets, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        buckets: Buckets,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        positive("BDP's bucket count", buckets.count())?;
        let words = buckets.count() as usize * buckets.width();
        let promise = Promise::All(Capacity::Unbounded);
        let plan = Plan::new::<W>(
            Self::name_of(buckets),
            promise,
            viewport,
            RANGE_WORDS,
            words,
            memory_cap,
        )?;
        Ok(Self {
            plan,
            buckets,
            _word: PhantomData,
        })
    }

    /// The paper's depth form, 16 pairs, with the default memory cap.
    ///
    /// # Errors
    /// As [`Bdp::new`].
    pub fn pairs(viewport: Viewport) -> Result<Self, CaptureError> {
        Self::new(viewport, Buckets::PAPER_PAIRS, MEMORY_CAP_DEFAULT)
    }

    /// The paper's attribute form, 32 single buckets, with the default memory cap.
    ///
    /// # Errors
    /// As [`Bdp::new`].
    pub fn singles(viewport: Viewport) -> Result<Self, CaptureError> {
        Self::new(viewport, Buckets::PAPER_SINGLES, MEMORY_CAP_DEFAULT)
    }

    /// The bucket configuration.
    #[must_use]
    pub fn buckets(&self) -> Buckets {
        self.buckets
    }

    fn name_of(buckets: Buckets) -> String {
        let form = match buckets {
            Buckets::Pairs(16) => String::new(),
            Buckets::Singles(32) => "-single".into(),
            Buckets::Pairs(n) => format!("-pairs{n}"),
            Buckets::Singles(n) => format!("-single{n}"),
        };
        format!("bdp{form}{}", word_suffix::<W>())
    }
}

impl<W: MdtsWord> Scheme for Bdp<W> {
    type State = Walk<W, Blend>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.plan.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Self::State {
        self.plan.begin(0, fragment)
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Self::State> {
        (pass < 2).then(|| self.plan.begin(pass, fragment))
    }

    fn step<M: Memory>(&self, walk: &mut Self::State, memory: &M) -> Step {
        match &mut walk.stage {
            Stage::Own(blend) => blend.step(walk.value, memory),
            _ => self.plan.range_step(walk, memory, |walk| {
                let k = Plan::route(walk, self.buckets.count()) as usize;
                let word = self
                    .plan
                    .bucket(walk.fragment.pixel as usize, k * self.buckets.width());
                match self.buckets {
                    Buckets::Pairs(_) => Blend::PairMin { word },
                    Buckets::Singles(_) => Blend::Single { word },
                }
            }),
        }
    }

    fn end_pass<M: Memory>(&self, pass: u32, _memory: &M) -> bool {
        pass == 0
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        for k in 0..self.buckets.count() as usize {
            let word = self.plan.bucket(pixel, k * self.buckets.width());
            match self.buckets {
                Buckets::Pairs(_) => {
                    if let Some((min, max)) = read_pair::<W, M>(memory, word) {
                        push_distinct(out, [min, max]);
                    }
                }
                Buckets::Singles(_) => {
                    if let Some(value) = read_single::<W, M>(memory, word) {
                        out.push(value.decode());
                    }
                }
            }
        }
        0
    }
}
