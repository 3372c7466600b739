//! The multi-depth test scheme (MDTS): FreePipe (Liu et al., I3D 2010) §4.1.1 and Table 1.
//!
//! **Algorithm.** Each pixel owns `K` words initialised to the empty sentinel. A fragment walks
//! them in order: `old = atomicMin(&A[i], new)`; if `old` is the sentinel the fragment has landed
//! and stops; otherwise it carries `new = max(new, old)` to slot `i + 1`. Past slot `K − 1` the
//! carried value is dropped. The descending variant (§4.1.1, last paragraph) uses `atomicMax`,
//! the empty value 0 and carries `min(new, old)`.
//!
//! **Guarantee.** Under any interleaving of the fragments' steps, when all are done each pixel's
//! array holds exactly the `K` smallest values in ascending order (the `K` largest, descending, for
//! the descending variant), each value once: the proof is in `docs/proof.md`, loom checks it
//! exhaustively for small cases (`tests/loom/`). Exact up to `K`; with `K` at least the depth
//! complexity it is exact. Memory: `K` words per pixel. One geometry pass; at most `K` atomic
//! operations per fragment.
//!
//! **Words.** With `u64` words a value is `depth_key << 32 | prim`, so every fragment is distinct
//! and the result is comparable fragment for fragment with the oracle; with `u32` words (as in the
//! paper) a value is the depth key alone and equal depths are all kept (no early exit on equality).
//!
//! **The probing walk** ([`Mdts::probing`], a CPU optimisation, not in the paper): a step first
//! *loads* the slot, and only when the slot holds a larger value (or is empty) does the next step
//! run the `atomicMin`. A slot only ever decreases, so a slot seen at or below the carried value
//! would have made the `atomicMin` a no-op returning that value: the load *is* that `atomicMin`,
//! linearised at the load. The lists are therefore those of the plain walk under some
//! interleaving (proof in `docs/proof.md`; loom checks it in `tests/loom/`), with fewer
//! read-modify-writes counted: `fragsim bench` reports both. The memories themselves answer an
//! `atomicMin` that cannot change its word with a load (`fragsim_memory`'s `serial_atomic.rs`), so on the CPU
//! the plain walk runs no more locked instructions than this one; the probing walk is the GPU
//! algorithm that does the same in its steps.
//!
//! Unlike the paper's Table 1, which initialises to `0xFFFFFFFF` but stops on `0x7FFFFFFF`, the
//! sentinel tested is the one stored (`u32::MAX` / `u64::MAX`); no depth key reaches it, since the
//! largest is `0x3F80_0000` (depth 1.0). Unlike the paper's descending variant, whose empty value 0
//! is also the key of depth 0.0, values are stored plus one so that no fragment equals empty.

use fragsim_memory::{Layout, Memory, SpanVisitor, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::{
    walk_to_end, CaptureError, Descriptor, PixelRun, Promise, Scheme, Step, MEMORY_CAP_DEFAULT,
};

pub use crate::common::MdtsWord;

/// Which way the array is sorted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// `atomicMin`, empty = all ones: keeps the `K` nearest.
    Ascending,
    /// `atomicMax`, empty = 0: keeps the `K` farthest.
    Descending,
}

/// The multi-depth test scheme over words of type `W` (default: `u64`, fragment identity kept).
#[derive(Clone, Debug)]
pub struct Mdts<W: MdtsWord = u64> {
    descriptor: Descriptor,
    k: u32,
    direction: Direction,
    probe: bool,
    _word: std::marker::PhantomData<W>,
}

/// A fragment's walk: the slot it tests next and the value it carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Walk<W> {
    /// First word of the pixel's array.
    pub base: usize,
    /// Slot tested next.
    pub slot: u32,
    /// The value carried onward.
    pub carried: W,
    /// The probing walk loaded this slot and found it larger than `carried`: the next step is
    /// the `atomicMin`.
    pub probed: bool,
}

impl<W: MdtsWord> Mdts<W> {
    /// MDTS with `k` slots per pixel, sorted in `direction`, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        direction: Direction,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(
                "MDTS needs K ≥ 1 slots per pixel, got K = 0".into(),
            ));
        }
        let pixels = viewport.pixels();
        let words = pixels * k as usize;
        let (words32, words64) = if W::IDENTITY == Identity::KeyOnly {
            (words, 0)
        } else {
            (0, words)
        };
        let empty = Self::empty_in(direction).decode();
        let descriptor = Descriptor {
            name: Self::name_of(direction, false),
            layout: Layout {
                words32,
                init32: (empty >> 32) as u32,
                words64,
                init64: empty,
                table_bytes: 0,
            },
            identity: W::IDENTITY,
            guarantee: Guarantee::Exact,
            promise: match direction {
                Direction::Ascending => Promise::Nearest(k),
                Direction::Descending => Promise::Farthest(k),
            },
            pixels,
            counts_every_drop: true,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            k,
            direction,
            probe: false,
            _word: std::marker::PhantomData,
        })
    }

    /// The catalog's name of MDTS on `W` words sorted in `direction`, probing or not.
    fn name_of(direction: Direction, probe: bool) -> String {
        let word = if W::IDENTITY == Identity::KeyOnly {
            "32"
        } else {
            "64"
        };
        let probe = if probe { "-probe" } else { "" };
        match direction {
            Direction::Ascending => format!("mdts{word}{probe}"),
            Direction::Descending => format!("mdts{word}-desc{probe}"),
        }
        .replace("mdts64", "mdts")
    }

    /// Ascending MDTS (the paper's main form) with the default memory cap.
    ///
    /// # Errors
    /// As [`Mdts::new`].
    pub fn ascending(viewport: Viewport, k: u32) -> Result<Self, CaptureError> {
        Self::new(viewport, k, Direction::Ascending, MEMORY_CAP_DEFAULT)
    }

    /// The same scheme with the probing walk (see the module documentation).
    #[must_use]
    pub fn probing(self) -> Self {
        Self {
            descriptor: Descriptor {
                name: Self::name_of(self.direction, true),
                ..self.descriptor
            },
            probe: true,
            ..self
        }
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.k
    }

    /// The empty value of a slot.
    fn empty(&self) -> W {
        Self::empty_in(self.direction)
    }

    /// The empty value of a slot of an array sorted in `direction`.
    fn empty_in(direction: Direction) -> W {
        match direction {
            Direction::Ascending => W::MAX,
            Direction::Descending => W::ZERO,
        }
    }

    /// The stored value of a fragment.
    fn stored(&self, fragment: Fragment) -> W {
        let word = W::encode(fragment);
        match self.direction {
            Direction::Ascending => word,
            // Keys never reach the top of the word, so the offset cannot wrap.
            Direction::Descending => word.wrapping_add(W::ONE),
        }
    }
}

impl<W: MdtsWord> Mdts<W> {
    /// Moves a walk on to its next slot, dropping the carried value past the last.
    fn next_slot(&self, walk: &mut Walk<W>) -> Step {
        walk.slot += 1;
        if walk.slot == self.k {
            Step::Dropped
        } else {
            Step::Continue
        }
    }

    /// One step of `walk` on `words` (the memory's array of `W`, or the span of its page that
    /// holds the pixel's slots).
    #[inline]
    fn step_on(&self, walk: &mut Walk<W>, words: &impl WordMemory<W>) -> Step {
        let index = walk.base + walk.slot as usize;
        if self.probe && !walk.probed {
            let seen = words.load(index);
            // `carried` is never empty, so a slot at or past it in sort order holds a value.
            let no_op = match self.direction {
                Direction::Ascending => seen <= walk.carried,
                Direction::Descending => seen >= walk.carried,
            };
            if !no_op {
                walk.probed = true;
                return Step::Continue;
            }
            return self.next_slot(walk);
        }
        walk.probed = false;
        let old = match self.direction {
            Direction::Ascending => words.fetch_min(index, walk.carried),
            Direction::Descending => words.fetch_max(index, walk.carried),
        };
        if old == self.empty() {
            return Step::Stored;
        }
        walk.carried = match self.direction {
            Direction::Ascending => walk.carried.max(old),
            Direction::Descending => walk.carried.min(old),
        };
        self.next_slot(walk)
    }

    /// Appends the stored values of the pixel whose slots begin at `base` to `out`, nearest first:
    /// each slot loaded once, up to the first empty one.
    fn read_list(&self, words: &impl WordMemory<W>, base: usize, out: &mut Vec<u64>) {
        let start = out.len();
        for slot in base..base + self.k as usize {
            let word = words.load(slot);
            if word == self.empty() {
                break;
            }
            out.push(match self.direction {
                Direction::Ascending => word.decode(),
                // Undo the +1 offset.
                Direction::Descending => word.wrapping_sub(W::ONE).decode(),
            });
        }
        if self.direction == Direction::Descending {
            // Nearest first, like every other scheme.
            out[start..].reverse();
        }
    }
}

/// A fragment's walk to its end on the words it is handed ([`WordMemory::with_span`]).
struct WalkOn<'a, W: MdtsWord> {
    scheme: &'a Mdts<W>,
    walk: Walk<W>,
    steps: &'a mut u64,
}

impl<W: MdtsWord> SpanVisitor<W> for WalkOn<'_, W> {
    type Output = Step;
    fn visit<A: WordMemory<W>>(mut self, words: &A) -> Step {
        walk_to_end(self.steps, || self.scheme.step_on(&mut self.walk, words))
    }
}

/// A pixel's list read back on the words it is handed ([`WordMemory::with_span`]).
struct ReadList<'a, W: MdtsWord> {
    scheme: &'a Mdts<W>,
    base: usize,
    out: &'a mut Vec<u64>,
}

impl<W: MdtsWord> SpanVisitor<W> for ReadList<'_, W> {
    type Output = ();
    fn visit<A: WordMemory<W>>(self, words: &A) {
        self.scheme.read_list(words, self.base, self.out);
    }
}

impl<W: MdtsWord> Scheme for Mdts<W> {
    type State = Walk<W>;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn tile_local(&self) -> bool {
        // One pass, K words a pixel at `pixel · K`, read back from there alone.
        true
    }

    fn begin(&self, fragment: Fragment) -> Walk<W> {
        Walk {
            base: fragment.pixel as usize * self.k as usize,
            slot: 0,
            carried: self.stored(fragment),
            probed: false,
        }
    }

    fn step<M: Memory>(&self, walk: &mut Walk<W>, memory: &M) -> Step {
        self.step_on(walk, W::words(memory))
    }

    fn prefetch<M: Memory>(&self, fragment: Fragment, memory: &M) {
        W::words(memory).prefetch(fragment.pixel as usize * self.k as usize);
    }

    fn insert_state<M: Memory>(&self, walk: Walk<W>, memory: &M, steps: &mut u64) -> Step {
        // The pixel's K slots share a page but at a page's edge: their page is found once for
        // the walk, not for each memory operation.
        let walk_on = WalkOn {
            scheme: self,
            walk,
            steps,
        };
        W::words(memory).with_span(walk.base, self.k as usize, walk_on)
    }

    fn pixel_run<M: Memory>(&self, memory: &M, pixel: usize, end: usize) -> PixelRun {
        // A pixel whose first slot no write reached holds an empty list.
        PixelRun::of_first_words(W::words(memory), pixel, end, self.k as usize)
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let (base, k) = (pixel * self.k as usize, self.k as usize);
        let read = ReadList {
            scheme: self,
            base,
            out,
        };
        W::words(memory).with_span(base, k, read);
        // What fell off the end is not in memory: the executors count it from the walks.
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_capture::executors::frame::{interleaved, walks};
    use fragsim_memory::{SerialMemory, PAGE_WORDS};

    /// Every word of the `u64` array.
    fn words(memory: &SerialMemory) -> Vec<u64> {
        (0..WordMemory::<u64>::len(memory))
            .map(|i| WordMemory::<u64>::load(memory, i))
            .collect()
    }

    /// A walk run to its end on its page's span (`insert_state`) leaves the words, the pages
    /// allocated and the lists that step after step on the whole array leaves, for pixels inside a
    /// page, across a page's edge and on pages not yet allocated, in both directions and probing.
    #[test]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a random u64 taken modulo 6 as an index"
    )]
    fn walks_on_a_span_are_walks_on_the_array_across_page_edges() {
        let k = 20;
        // 420 pixels of 20 slots: pixel 204's slots cross the first page's edge (word 4096).
        let viewport = Viewport::new(420, 1).unwrap();
        let mut rng = fragsim_raster::SplitMix64::new(35);
        let fragments: Vec<Fragment> = (0..4000)
            .map(|prim| Fragment {
                pixel: [0, 203, 204, 205, 300, 409][rng.next_u64() as usize % 6],
                depth_key: (rng.next_u64() % 64) as u32,
                prim,
            })
            .collect();
        assert_eq!(204 * k as usize / PAGE_WORDS, 0);
        assert_eq!((205 * k as usize - 1) / PAGE_WORDS, 1);
        for direction in [Direction::Ascending, Direction::Descending] {
            for probe in [false, true] {
                let mut mdts =
                    Mdts::<u64>::new(viewport, k, direction, MEMORY_CAP_DEFAULT).unwrap();
                if probe {
                    mdts = mdts.probing();
                }
                let on_spans: SerialMemory = mdts.layout().allocate();
                let on_array: SerialMemory = mdts.layout().allocate();
                let counted = walks(&mdts, &on_spans, 0, &fragments);
                let stepped = interleaved(&mdts, &on_array, 0, &fragments, |_| 0);
                assert_eq!(counted, stepped, "{direction:?}, probing {probe}");
                assert_eq!(words(&on_spans), words(&on_array));
                assert_eq!(on_spans.allocated_bytes(), on_array.allocated_bytes());
                assert_eq!(mdts.resolve(&on_spans), mdts.resolve(&on_array));
                for pixel in 0..viewport.pixels() {
                    let base = pixel * k as usize;
                    assert_eq!(
                        WordMemory::<u64>::untouched(&on_spans, base),
                        WordMemory::<u64>::untouched(&on_array, base)
                    );
                }
            }
        }
    }
}
