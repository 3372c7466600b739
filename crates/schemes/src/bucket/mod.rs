//! Bucket depth peeling: Liu, Huang, Liu and Wu, "Efficient Depth Peeling via Bucket Sort"
//! (HPG 2009, §3), and its GPU Pro chapter, Huang, Liu, Liu and Wu, "Multi-Fragment Effects on the
//! GPU Using Bucket Sort" (§1.3–1.5).
//!
//! Each pixel's depth range `[zNear, zFar]` is cut into subintervals, and a fragment is routed to
//! the bucket of its subinterval, where MAX blending keeps the largest value that arrived. A bucket
//! holds what MAX blending can hold, so when more fragments fall into one bucket than it can keep
//! (a *collision*) the others are lost. Three schemes, one submodule each:
//!
//! - [`Bdp`] (HPG §3.2, GPU Pro §1.3): 16 uniform subintervals, each bucket a pair of words
//!   keeping the bucket's minimum and maximum (exact with at most 2 fragments per bucket); or the
//!   paper's attribute variant, 32 uniform subintervals of one word each (exact with at most 1).
//! - [`Bdp2`] (HPG §3.2, GPU Pro §1.4): BDP plus a second geometry pass that keeps the second
//!   minimum and maximum of every bucket (exact with at most 4 fragments per bucket).
//! - [`Adp`] (HPG §3.3, GPU Pro §1.5): a 1024-bit occupancy histogram per pixel, equalised into
//!   one subinterval per occupied bit, then a routing pass (exact when no two fragments share one
//!   of the 1024 uniform subintervals); batches of 32 layers for deeper scenes.
//!
//! None of them is exact in general: each promises [`Promise::All`] and
//! reports no overflow, so the oracle's diff counts every fragment lost to a collision as `lost`.
//! (ADP's storage, sized to the scene's depth complexity, can also be too small when the caller
//! under-states it: those fragments are counted as overflow, see [`Adp`].) A walk ends `Dropped`
//! when its own MAX-blend steps already show it kept nowhere; a fragment displaced later by
//! another one still ended `Stored`, so the executors' `dropped` count is a lower bound of the
//! losses and the diff is the measure. In the range and histogram passes a walk ends `Stored`
//! (its value went into the range or the histogram), so `stored` counts walks, not fragments.
//!
//! **The depth-range pass (shared).** The paper renders a bounding box or a coarse visual hull
//! first, with MAX blending of `(1 − z, z)`, to get an approximate per-pixel range (HPG §3.2;
//! Table 1, "Initialization"). Unlike the paper, the range pass here rasterises the scene itself
//! (the executors have no other geometry), which gives the *precise* range the paper mentions as
//! the costlier option: the best case for uniform routing, and one more geometry pass than the
//! paper counts. Two words per pixel, each fragment one `fetch_max` on each: the far word takes
//! the depth key, the near word takes the *complement* of the key (`!key`).
//!
//! **Why the complement and not `1 − d`.** MAX blending of `1 − d` keeps `1 − min d`: an
//! order-reversing code of the depth, so that MAX finds a minimum on buffers that start at 0. The
//! bitwise complement of the depth key is another order-reversing code, and `fetch_max(!key)`
//! keeps `!min key`: the same operation. The difference is rounding: in f32, `1 − d` is exact
//! only for `d ≥ 0.5` (Sterbenz), below that distinct depths can share one `1 − d` and
//! `1 − (1 − d) ≠ d` (`d = 0.1` comes back 3 ulps larger), whereas the complement is a bijection, so the
//! minimum comes back bit for bit. An empty word stays recognisable: `!key ≥ 0xC07F_FFFF > 0`.
//! `tests/suite/bucket/` measures how many of the bunny's depths `1 − d` would have altered.
//!
//! **Routing arithmetic.** [`subinterval`] computes `floor(count · (d − zNear) / (zFar − zNear))`
//! (HPG eq. 2) in f64 from the f32 depths, clamped to the last subinterval; every pass of a
//! scheme routes with this one function, so a fragment lands in the subinterval its earlier pass
//! saw. Unlike a shader, whose f32 arithmetic (with a division that is not correctly rounded) can
//! move a fragment at a subinterval boundary, the f64 form is reproducible by a GPU backend with
//! IEEE double arithmetic.
//!
//! **Words.** Generic over [`MdtsWord`]: `u32` words hold the depth key (the paper's 32-bit float
//! channels; [`Identity::KeyOnly`], so two equal depths in one bucket are one value and one of
//! them is lost) and are the default; `u64` words hold `key << 32 | prim`
//! ([`Identity::KeyAndPrim`]: every fragment distinct, compared fragment for fragment). Every
//! buffer starts at 0, as the paper's MRTs do (Layout has one initial value per word width): a
//! pair's min channel stores the complement (never 0), a single bucket stores value + 1.

mod adp;
mod bdp;
mod bdp2;

pub use adp::{Adp, AdpStage, ADP_BATCH, ADP_SUBINTERVALS};
pub use bdp::{Bdp, Buckets};
pub use bdp2::{Bdp2, Bdp2Stage};

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::MdtsWord;
use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{CaptureError, Descriptor, Promise, Step};

/// u32 words of the depth-range pass per pixel: the near word (complemented key) and the far word.
const RANGE_WORDS: usize = 2;

/// The subinterval of depth key `key` when the range `[near, far]` (keys) is cut into `count`
/// equal parts: `floor(count · (d − zNear) / (zFar − zNear))` in f64, clamped to `0..count`
/// (HPG eq. 2). A degenerate range (`far ≤ near`) has one subinterval, 0.
///
/// # Panics
/// If `count` is 0.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "k is floored, at least 0 and at most count - 1 after min; `as` saturates past u32"
)]
pub fn subinterval(key: u32, near: u32, far: u32, count: u32) -> u32 {
    assert!(count > 0, "a depth range needs at least one subinterval");
    let depth = |k: u32| f64::from(f32::from_bits(k));
    let (d, lo, hi) = (depth(key), depth(near), depth(far));
    if hi <= lo {
        return 0;
    }
    let k = (f64::from(count) * (d - lo) / (hi - lo)).floor();
    // The exact range puts its farthest fragment at `count`: the last subinterval is closed.
    (k.max(0.0) as u32).min(count - 1)
}

/// Where a bucket scheme's words are: per pixel, `aux` u32 words (the range, and ADP's histogram
/// and bounds) and `buckets` words of the bucket type, which share the u32 array when the buckets
/// are u32 and fill the u64 array otherwise. Every word starts at 0. It holds the scheme's
/// descriptor: every bucket scheme is approximate, on the words `W` identify.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Plan {
    descriptor: Descriptor,
    aux: usize,
    buckets: usize,
    wide: bool,
    bucket_base: usize,
}

impl Plan {
    /// The plan of the scheme `scheme` keeping `promise`, or the error when its storage exceeds
    /// `cap` bytes.
    fn new<W: MdtsWord>(
        scheme: String,
        promise: Promise,
        viewport: Viewport,
        aux: usize,
        buckets: usize,
        cap: u64,
    ) -> Result<Self, CaptureError> {
        let pixels = viewport.pixels();
        let wide = W::IDENTITY == Identity::KeyAndPrim;
        let bucket_bytes = if wide { 8 } else { 4 };
        // In u128 so that absurd bucket counts are refused, never overflowed: storage no
        // address space holds is refused whatever the cap.
        let needed = pixels as u128 * (aux as u128 * 4 + buckets as u128 * bucket_bytes);
        if needed > u128::from(cap) && needed > isize::MAX as u128 {
            return Err(CaptureError::TooMuchMemory {
                scheme,
                needed: u64::try_from(needed).unwrap_or(u64::MAX),
                cap,
            });
        }
        let (words32, words64) = if wide {
            (pixels * aux, pixels * buckets)
        } else {
            (pixels * (aux + buckets), 0)
        };
        let descriptor = Descriptor {
            name: scheme,
            layout: Layout {
                words32,
                init32: 0,
                words64,
                init64: 0,
                table_bytes: 0,
            },
            identity: W::IDENTITY,
            guarantee: Guarantee::Approximate,
            promise,
            pixels,
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(cap)?,
            aux,
            buckets,
            wide,
            bucket_base: if wide { 0 } else { pixels * aux },
        })
    }

    /// Index of aux word `i` of `pixel` in the u32 array.
    fn aux(&self, pixel: usize, i: usize) -> usize {
        pixel * self.aux + i
    }

    /// Index of bucket word `i` of `pixel` in the bucket type's array.
    fn bucket(&self, pixel: usize, i: usize) -> usize {
        self.bucket_base + pixel * self.buckets + i
    }

    /// A fragment's walk in geometry pass `pass`: pass 0 is the range pass, later passes start by
    /// loading the range.
    fn begin<W: MdtsWord, S>(&self, pass: u32, fragment: Fragment) -> Walk<W, S> {
        Walk {
            fragment,
            value: W::encode(fragment),
            pass,
            range: (0, 0),
            stage: if pass == 0 {
                Stage::RangeNear
            } else {
                Stage::LoadNear
            },
        }
    }

    /// One step of the stages every bucket scheme shares; `route` picks the scheme's first own
    /// stage once the pixel's range is loaded (pure computation, no memory operation).
    fn range_step<M: Memory, W: MdtsWord, S>(
        &self,
        walk: &mut Walk<W, S>,
        memory: &M,
        route: impl FnOnce(&Walk<W, S>) -> S,
    ) -> Step {
        let pixel = walk.fragment.pixel as usize;
        let key = walk.fragment.depth_key;
        match walk.stage {
            Stage::RangeNear => {
                WordMemory::<u32>::fetch_max(memory, self.aux(pixel, 0), !key);
                walk.stage = Stage::RangeFar;
                Step::Continue
            }
            Stage::RangeFar => {
                WordMemory::<u32>::fetch_max(memory, self.aux(pixel, 1), key);
                Step::Stored
            }
            Stage::LoadNear => {
                walk.range.0 = !WordMemory::<u32>::load(memory, self.aux(pixel, 0));
                walk.stage = Stage::LoadFar;
                Step::Continue
            }
            Stage::LoadFar => {
                walk.range.1 = WordMemory::<u32>::load(memory, self.aux(pixel, 1));
                walk.stage = Stage::Own(route(walk));
                Step::Continue
            }
            Stage::Own(_) => unreachable!("a scheme runs its own stages itself"),
        }
    }

    /// The subinterval of the walk's fragment among `count`, in its pixel's loaded range.
    fn route<W, S>(walk: &Walk<W, S>, count: u32) -> u32 {
        subinterval(walk.fragment.depth_key, walk.range.0, walk.range.1, count)
    }
}

/// A fragment's progress through one geometry pass of a bucket scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Walk<W, S> {
    /// The fragment.
    pub fragment: Fragment,
    /// What the buckets store for it: its depth key (u32) or `key << 32 | prim` (u64).
    pub value: W,
    /// The geometry pass.
    pub pass: u32,
    /// The pixel's depth range `(zNear, zFar)` as keys, once loaded.
    pub range: (u32, u32),
    /// What comes next.
    pub stage: Stage<S>,
}

/// The stages of a walk: the shared range stages, then the scheme's own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage<S> {
    /// Range pass: `fetch_max` of the complemented key into the near word.
    RangeNear,
    /// Range pass: `fetch_max` of the key into the far word.
    RangeFar,
    /// Later passes: load the near word.
    LoadNear,
    /// Later passes: load the far word, then route.
    LoadFar,
    /// The scheme's own stages.
    Own(S),
}

/// MAX-blend writes into buckets: a pair keeps its bucket's minimum (in the complemented min
/// channel) and maximum; a single bucket keeps its maximum (stored + 1, so that 0 is empty).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blend {
    /// `fetch_max` of the complemented value into the pair's min channel (bucket word `word`).
    PairMin {
        /// Bucket word of the min channel; the max channel is the next word.
        word: usize,
    },
    /// `fetch_max` of the value into the pair's max channel.
    PairMax {
        /// Bucket word of the max channel.
        word: usize,
        /// Whether the min channel took the value.
        kept: bool,
    },
    /// `fetch_max` of value + 1 into a single bucket.
    Single {
        /// Bucket word.
        word: usize,
    },
}

impl Blend {
    /// One MAX-blend write. Ends `Stored` when the value is in a word it wrote, `Dropped` when
    /// both (or the only) MAX tests already held a value at least as large: then no later
    /// fragment can bring it back, it is lost to a collision. (With u32 keys an equal depth is
    /// such a loss: the bucket holds the value once.)
    fn step<W: MdtsWord, M: Memory>(&mut self, value: W, memory: &M) -> Step {
        let words = W::words(memory);
        match *self {
            Self::PairMin { word } => {
                let code = W::MAX.wrapping_sub(value);
                let kept = words.fetch_max(word, code) < code;
                *self = Self::PairMax {
                    word: word + 1,
                    kept,
                };
                Step::Continue
            }
            Self::PairMax { word, kept } => {
                if words.fetch_max(word, value) < value || kept {
                    Step::Stored
                } else {
                    Step::Dropped
                }
            }
            Self::Single { word } => {
                let code = value.wrapping_add(W::ONE);
                if words.fetch_max(word, code) < code {
                    Step::Stored
                } else {
                    Step::Dropped
                }
            }
        }
    }
}

/// The `(min, max)` a pair of bucket words at `word` holds, or `None` when it is empty.
fn read_pair<W: MdtsWord, M: Memory>(memory: &M, word: usize) -> Option<(W, W)> {
    let words = W::words(memory);
    let code = words.load(word);
    (code != W::ZERO).then(|| (W::MAX.wrapping_sub(code), words.load(word + 1)))
}

/// The value a single bucket at `word` holds, or `None` when it is empty.
fn read_single<W: MdtsWord, M: Memory>(memory: &M, word: usize) -> Option<W> {
    let code = W::words(memory).load(word);
    (code != W::ZERO).then(|| code.wrapping_sub(W::ONE))
}

/// Appends the packed form of `values` (ascending) to `out`, each distinct value once: a pair
/// holding one fragment has min = max.
fn push_distinct<W: MdtsWord>(out: &mut Vec<u64>, values: impl IntoIterator<Item = W>) {
    let mut last = None;
    for value in values {
        if last != Some(value) {
            out.push(value.decode());
            last = Some(value);
        }
    }
}

/// The name suffix of the word type: none for the paper's u32, `-64` for u64.
fn word_suffix<W: MdtsWord>() -> &'static str {
    if W::IDENTITY == Identity::KeyAndPrim {
        "-64"
    } else {
        ""
    }
}

/// Fails with [`CaptureError::BadParameter`] when `count` is 0.
fn positive(what: &str, count: u32) -> Result<(), CaptureError> {
    if count == 0 {
        return Err(CaptureError::BadParameter(format!(
            "{what} must be at least 1, got 0"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[expect(
        clippy::shadow_unrelated,
        reason = "each loop's `d` is its own case's depth"
    )]
    fn one_minus_d_does_not_round_trip_but_the_complement_does() {
        let d = 0.1_f32;
        assert_ne!(1.0 - (1.0 - d), d, "1 − d rounds below 0.5");
        // Two depths one ulp apart share one 1 − d, so MAX blending could not tell them apart.
        let next = f32::from_bits(d.to_bits() + 1);
        assert_eq!(1.0 - d, 1.0 - next);
        assert!(!d.to_bits() > !next.to_bits());
        for d in [0.0_f32, 1e-30, 0.1, 0.499, 0.5, 0.75, 1.0] {
            assert_eq!(!!d.to_bits(), d.to_bits());
            assert!(!d.to_bits() > 0);
        }
    }

    #[test]
    fn subinterval_is_monotone_and_closes_the_last_interval() {
        let key = |d: f32| d.to_bits();
        let (near, far) = (key(0.25), key(0.75));
        assert_eq!(subinterval(near, near, far, 16), 0);
        assert_eq!(subinterval(far, near, far, 16), 15);
        assert_eq!(subinterval(key(0.5), near, far, 16), 8);
        assert_eq!(subinterval(key(0.5), key(0.5), key(0.5), 16), 0);
        let mut last = 0;
        for i in 0..=1000 {
            let k = subinterval(key(0.25 + 0.5 * i as f32 / 1000.0), near, far, 1024);
            assert!(k >= last && k < 1024);
            last = k;
        }
        assert_eq!(last, 1023);
    }
}
