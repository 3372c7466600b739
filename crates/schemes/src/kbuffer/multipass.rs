//! The multi-pass k-buffer: Liu, Wei and Xu, "Multi-layer depth peeling via fragment sort"
//! (MSR-TR-2006-81), as bucket depth peeling (Liu et al., HPG 2009, §2 and Table 2, "[Liu 2006]")
//! and FreePipe (Liu et al., I3D 2010, Table 3, "Liu") describe and measure it.
//!
//! **Algorithm.** Depth peeling `K` layers at a time with the k-buffer's read–insert–write
//! (`kbuffer/slots.rs`, shared code, on either [`WriteBack`] machine). Each pixel has a *boundary*
//! `c` (every fragment below it is in the output list) and may have a *tentative* list: the `K`
//! or fewer fragments the previous pass captured, waiting to be checked, which span `[c, t)`.
//! In pass `p` a fragment first `load`s `c` and `t` (pass 0 has neither: `c = t = 0`), then:
//! - below `c`: `Discarded` (already output);
//! - in `[c, t)`: it counts itself into the pixel's *window count* (`fetch_add`) and its depth
//!   into the window's nearest (`fetch_min`, the depth test), then `Discarded`;
//! - at or beyond `t`: it counts itself into the pixel's *passed count* (`fetch_add`: what the
//!   occlusion query counts, per pixel) and runs the k-buffer walk. A fragment farther than the
//!   `K` values it read is `Discarded` (deferred to a later pass).
//!
//! Between passes a per-pixel kernel (`end_pass`):
//! 1. checks the tentative list against the window count. The list holds distinct fragments of
//!    `[c, t)`, so if as many fragments lie in `[c, t)` as the list holds, it holds all of them: it
//!    goes to the output and `c = t`. Otherwise a hazard erased one of them: only the window's
//!    nearest (exact: an atomic minimum) goes to the output, `c` moves just past it, and this
//!    pass's slots are thrown away (they lie beyond an unchecked gap): an **extra pass**.
//! 2. sorts this pass's slots (dropping duplicates a torn write-back left) and compares their
//!    number with the passed count: the fragments that passed the boundary test but were **not
//!    kept**. None: the slots are every remaining fragment, they go to the output and the pixel is
//!    complete. Some: the slots become the tentative list, `t` = just past the last, and another
//!    pass is needed.
//!
//! Passes repeat while some pixel is incomplete. So a pass is run while any fragment of a pixel
//! lies beyond its output, never because of where an empty slot is, and nothing is output that a
//! count has not confirmed.
//!
//! **Guarantee: exact under any interleaving** ([`Promise::All`]; fragments beyond the caller's
//! output capacity counted as overflow). Every fragment output is confirmed by an exact atomic
//! count (or is the window's atomic minimum), so a hazard can cost passes but never a fragment,
//! and the output is in canonical order. *Passes*, serially: `max(1, ⌈D / K⌉)` for a maximum depth
//! complexity `D` (a pixel of `n` fragments is complete after `⌈n / K⌉` passes: each pass confirms
//! the previous pass's `K` and the last one its own). Under hazards **at least as many** (no pass
//! confirms more than `K` fragments of a pixel) and at most `2 D + 1` (each pass confirms at least
//! one fragment, except the pass after a failed check, which starts afresh). The extra passes are
//! in `RunStats::passes`.
//!
//! **Memory per pixel:** `8 K` (slots) + `8 K` (tentative list) + 24 (`c`, `t`, the window's
//! nearest) + `8 D` (output) + 12 (output, passed and window counts) bytes, plus 12 on the
//! render-target machine (its lock and two tickets).
//!
//! Unlike the paper, whose passes composite each pass's layers into the frame and keep only the
//! `K` render targets (FreePipe's Table 3: 20 MB at 512×512, as the k-buffer), the layers are kept
//! in an output list so that the oracle can check them. Unlike the paper, whose peeling compares
//! depths, the boundary is on `(depth key, primitive id)`, so fragments of equal depth are all
//! peeled rather than merged. The per-pixel counts stand for the GPU's occlusion query (a global
//! count of fragments passing the boundary test) resolved per pixel, as a stencil count would;
//! the technical report's own rule for its robustness against "the unreliable parallel
//! read-after-write behavior" is not described by the citing papers, so this check is ours.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::kbuffer::{Insert, Outcome, Slots, WriteBack, EMPTY};
use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step};

/// The boundary of a pixel that needs no more passes: every fragment is below it.
const COMPLETE: u64 = u64::MAX;

/// The multi-pass k-buffer over `u64` words.
#[derive(Clone, Debug)]
pub struct KBufferMultipass {
    descriptor: Descriptor,
    slots: Slots,
    capacity: u32,
}

/// Where a fragment's walk of one pass is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The boundary `c` is loaded next.
    Boundary,
    /// The tentative list's end `t` is loaded next.
    TentativeEnd,
    /// In the tentative window: the window count is incremented next.
    CountWindow,
    /// In the tentative window: the window's nearest is lowered next, then the walk ends.
    WindowNearest,
    /// Beyond the window: the passed count is incremented next.
    CountPassed,
    /// The k-buffer walk.
    Walk,
}

/// A fragment's walk in one pass: the boundary tests and counts, then the k-buffer's
/// read–insert–write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Peel {
    /// The next memory operation.
    pub stage: Stage,
    /// The fragment's pixel.
    pub pixel: u32,
    /// The read–insert–write.
    pub insert: Insert,
}

/// Per-pixel `u32` words after the render-target bookkeeping: the output count (may pass the
/// capacity), the passed count and the window count.
const COUNTERS: usize = 3;
/// Per-pixel `u64` words between the tentative lists and the output: `c`, `t`, the window's nearest.
const BOUNDS: usize = 3;

impl KBufferMultipass {
    /// `k` slots per pixel on render targets and room for `layers` captured fragments per pixel
    /// (a pixel's fragments past it are counted as overflow), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        layers: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        Self::with_write_back(viewport, k, layers, WriteBack::RenderTarget, memory_cap)
    }

    /// As [`KBufferMultipass::new`], on the machine `write_back`.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn with_write_back(
        viewport: Viewport,
        k: u32,
        layers: u32,
        write_back: WriteBack,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let slots = Slots::new("the multi-pass k-buffer", k, write_back)?;
        let pixels = viewport.pixels();
        let descriptor = Descriptor {
            name: format!("kbuffer-multipass{}", write_back.suffix()),
            layout: Layout {
                words32: slots.sync_words(pixels) + pixels * COUNTERS,
                init32: 0,
                words64: 2 * slots.words(pixels) + pixels * (BOUNDS + layers as usize),
                init64: EMPTY,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            // Every output fragment is confirmed by an atomic count: hazards cost passes only.
            guarantee: Guarantee::Exact,
            promise: Promise::All(Capacity::PerPixel(layers)),
            pixels,
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            slots,
            capacity: layers,
        })
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.slots.k
    }

    /// The machine modelled.
    #[must_use]
    pub fn write_back(&self) -> WriteBack {
        self.slots.write_back
    }

    /// `u32` word `i` (of [`COUNTERS`]) of `pixel`: 0 output count, 1 passed, 2 window.
    fn counter(&self, pixel: usize, i: usize) -> usize {
        self.slots.sync_words(self.descriptor.pixels) + pixel * COUNTERS + i
    }

    /// The first word of `pixel`'s tentative list.
    fn tentative(&self, pixel: usize) -> usize {
        self.slots.words(self.descriptor.pixels) + pixel * self.slots.k as usize
    }

    /// `u64` word `i` (of [`BOUNDS`]) of `pixel`: 0 the boundary `c`, 1 the tentative end `t`,
    /// 2 the window's nearest.
    fn bound(&self, pixel: usize, i: usize) -> usize {
        2 * self.slots.words(self.descriptor.pixels) + pixel * BOUNDS + i
    }

    /// The first word of `pixel`'s output list.
    fn output(&self, pixel: usize) -> usize {
        2 * self.slots.words(self.descriptor.pixels)
            + self.descriptor.pixels * BOUNDS
            + pixel * self.capacity as usize
    }

    /// Appends `values` to `pixel`'s output list, counting those past its capacity.
    fn emit<M: Memory>(&self, memory: &M, pixel: usize, values: &[u64]) {
        let count_word = self.counter(pixel, 0);
        let mut count = WordMemory::<u32>::load(memory, count_word) as usize;
        for &value in values {
            if count < self.capacity as usize {
                WordMemory::<u64>::store(memory, self.output(pixel) + count, value);
            }
            count += 1;
        }
        #[expect(
            clippy::cast_possible_truncation,
            reason = "count is of one pixel's fragments, at most one per triangle, and triangle ids are u32"
        )]
        WordMemory::<u32>::store(memory, count_word, count as u32);
    }

    /// The non-empty words `base .. base + K`, sorted, without duplicates.
    fn distinct_sorted<M: Memory>(&self, memory: &M, base: usize) -> Vec<u64> {
        let mut values: Vec<u64> = (base..base + self.slots.k as usize)
            .map(|w| WordMemory::<u64>::load(memory, w))
            .filter(|&v| v != EMPTY)
            .collect();
        values.sort_unstable();
        values.dedup();
        values
    }

    /// The between-pass kernel for one pixel not yet complete; returns whether it needs another
    /// pass. Leaves the pass's slots and counts cleared.
    fn end_pass_pixel<M: Memory>(&self, pass: u32, memory: &M, pixel: usize) -> bool {
        let (mut c, mut t) = if pass == 0 {
            (0, 0)
        } else {
            (
                WordMemory::<u64>::load(memory, self.bound(pixel, 0)),
                WordMemory::<u64>::load(memory, self.bound(pixel, 1)),
            )
        };
        // 1. The tentative list against the window count.
        let mut checked = true;
        if t > c {
            let tentative = self.distinct_sorted(memory, self.tentative(pixel));
            let window = WordMemory::<u32>::load(memory, self.counter(pixel, 2)) as usize;
            if window == tentative.len() {
                self.emit(memory, pixel, &tentative);
                c = t;
            } else {
                // More fragments in [c, t) than the list holds: keep only the exact nearest.
                let nearest = WordMemory::<u64>::load(memory, self.bound(pixel, 2));
                self.emit(memory, pixel, &[nearest]);
                // Packed fragments stop at key 0x3F80_0000, so `nearest + 1` cannot reach
                // COMPLETE.
                c = nearest + 1;
                checked = false;
            }
        }
        // 2. This pass's slots against the passed count.
        let mut more = !checked;
        if checked {
            let captured = self.distinct_sorted(memory, pixel * self.slots.k as usize);
            let passed = WordMemory::<u32>::load(memory, self.counter(pixel, 1)) as usize;
            if passed == captured.len() {
                self.emit(memory, pixel, &captured);
                c = COMPLETE;
            } else {
                // All K words: a shorter list must not leave the last one's tail behind.
                for i in 0..self.slots.k as usize {
                    let v = captured.get(i).copied().unwrap_or(EMPTY);
                    WordMemory::<u64>::store(memory, self.tentative(pixel) + i, v);
                }
                more = true;
            }
            t = captured.last().map_or(c, |&last| last + 1);
        }
        if !checked || c == COMPLETE {
            t = c;
        }
        if t == c {
            for i in 0..self.slots.k as usize {
                WordMemory::<u64>::store(memory, self.tentative(pixel) + i, EMPTY);
            }
        }
        WordMemory::<u64>::store(memory, self.bound(pixel, 0), c);
        WordMemory::<u64>::store(memory, self.bound(pixel, 1), t);
        WordMemory::<u64>::store(memory, self.bound(pixel, 2), EMPTY);
        WordMemory::<u32>::store(memory, self.counter(pixel, 1), 0);
        WordMemory::<u32>::store(memory, self.counter(pixel, 2), 0);
        self.slots.clear(memory, pixel);
        more
    }
}

impl Scheme for KBufferMultipass {
    type State = Peel;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Peel {
        Peel {
            // The first pass takes every fragment: there is no boundary to load.
            stage: Stage::CountPassed,
            pixel: fragment.pixel,
            insert: self.slots.begin(fragment),
        }
    }

    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<Peel> {
        let mut peel = self.begin(fragment);
        if pass > 0 {
            peel.stage = Stage::Boundary;
        }
        Some(peel)
    }

    fn step<M: Memory>(&self, peel: &mut Peel, memory: &M) -> Step {
        let pixel = peel.pixel as usize;
        let value = peel.insert.value;
        match peel.stage {
            Stage::Boundary => {
                let c: u64 = memory.load(self.bound(pixel, 0));
                if value < c {
                    return Step::Discarded;
                }
                peel.stage = Stage::TentativeEnd;
            }
            Stage::TentativeEnd => {
                let t: u64 = memory.load(self.bound(pixel, 1));
                peel.stage = if value < t {
                    Stage::CountWindow
                } else {
                    Stage::CountPassed
                };
            }
            Stage::CountWindow => {
                WordMemory::<u32>::fetch_add(memory, self.counter(pixel, 2), 1);
                peel.stage = Stage::WindowNearest;
            }
            Stage::WindowNearest => {
                WordMemory::<u64>::fetch_min(memory, self.bound(pixel, 2), value);
                return Step::Discarded;
            }
            Stage::CountPassed => {
                WordMemory::<u32>::fetch_add(memory, self.counter(pixel, 1), 1);
                peel.stage = Stage::Walk;
            }
            Stage::Walk => {
                return match self.slots.step(&mut peel.insert, memory) {
                    Outcome::Continue => Step::Continue,
                    // An evicted value is beyond this pass's slots, an overtaken write-back lost
                    // to a stale read: the counts notice both, and a later pass takes them.
                    Outcome::Stored | Outcome::Evicted | Outcome::Overtaken => Step::Stored,
                    Outcome::FellOff => Step::Discarded,
                };
            }
        }
        Step::Continue
    }

    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let mut more = false;
        for pixel in 0..self.descriptor.pixels {
            // Before the first pass the boundary words hold nothing meaningful.
            if pass > 0 && WordMemory::<u64>::load(memory, self.bound(pixel, 0)) == COMPLETE {
                continue;
            }
            more |= self.end_pass_pixel(pass, memory, pixel);
        }
        more
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "count is the pixel's u32 counter word"
    )]
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let count = WordMemory::<u32>::load(memory, self.counter(pixel, 0)) as usize;
        let stored = count.min(self.capacity as usize);
        let output = self.output(pixel);
        // No sort: the output's order is the passes' order.
        out.extend((0..stored).map(|i| WordMemory::<u64>::load(memory, output + i)));
        (count - stored) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_memory::SerialMemory;

    /// One pass over `fragments` with the walks interleaved as `order` says (`order[i]` is the walk
    /// that takes step `i`; unfinished walks then run in order), then the kernel.
    fn pass_in_order(
        scheme: &KBufferMultipass,
        memory: &SerialMemory,
        pass: u32,
        fragments: &[Fragment],
        order: &[usize],
    ) -> bool {
        let mut walks: Vec<Option<Peel>> = fragments
            .iter()
            .map(|&f| scheme.begin_pass(pass, f))
            .collect();
        let rest: Vec<usize> = (0..fragments.len()).flat_map(|w| [w; 64]).collect();
        for &w in order.iter().chain(&rest) {
            if let Some(peel) = walks[w].as_mut() {
                if scheme.step(peel, memory) != Step::Continue {
                    walks[w] = None;
                }
            }
        }
        assert!(walks.iter().all(Option::is_none));
        scheme.end_pass(pass, memory)
    }

    #[test]
    fn a_failed_window_check_outputs_only_the_exact_nearest_and_costs_a_pass() {
        let frag = |depth_key, prim| Fragment {
            pixel: 0,
            depth_key,
            prim,
        };
        // K = 2, three fragments. Pass 0 (render targets): near and mid read the empty pixel,
        // near commits, then mid (a later primitive) commits [mid]: near is erased; far then reads
        // [mid] and writes [mid, far]. Passed 3, kept 2: tentative [mid, far].
        let fragments = [frag(10, 0), frag(20, 1), frag(30, 2)];
        let scheme = KBufferMultipass::new(Viewport::new(1, 1).unwrap(), 2, 3, u64::MAX).unwrap();
        let memory: SerialMemory = scheme.layout().allocate();
        // Steps per walk in pass 0: count, read, write.
        assert!(pass_in_order(
            &scheme,
            &memory,
            0,
            &fragments,
            &[0, 1, 0, 1, 0, 1]
        ));
        // Pass 1: the window [mid, far] holds near too (3 fragments, list of 2): only near, the
        // exact nearest, is output.
        assert!(pass_in_order(&scheme, &memory, 1, &fragments, &[]));
        let mut out = Vec::new();
        scheme.resolve_pixel(&memory, 0, &mut out);
        assert_eq!(out, vec![fragments[0].packed()]);
        // Pass 2 starts afresh past near and captures mid and far: complete.
        assert!(!pass_in_order(&scheme, &memory, 2, &fragments, &[]));
        out.clear();
        scheme.resolve_pixel(&memory, 0, &mut out);
        let all: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
        assert_eq!(out, all);
    }
}
