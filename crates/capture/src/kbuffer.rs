//! The k-buffer: Bavoil, Callahan, Lefohn, Comba and Silva, "Multi-fragment effects on the GPU
//! using the k-buffer" (I3D 2007), §3, as FreePipe (Liu et al., I3D 2010, §2 and Table 3) and
//! bucket depth peeling (Liu et al., HPG 2009, Table 2, "k-buffer of 32 layers without
//! modifications") run it.
//!
//! **Algorithm.** Each pixel owns `K` slots, initially empty (`u64::MAX`). A fragment's shader
//! *reads* the pixel's `K` slots, inserts itself into the `K + 1` values in registers, and *writes*
//! the `K` nearest back; on the GPU the read is a texture fetch of the render targets being drawn
//! and the write is the MRT output. Here the read is `K` plain `load`s and the write `K` plain
//! `store`s, one step each, slot 0 first ([`Insert`]). When the fragment is farther than all `K`
//! values read, it writes nothing (a shader `discard`) and its walk ends `Dropped`; when it evicts
//! the `K`-th value, its walk ends `Dropped` after the stores (one value fell off, as MDTS counts).
//!
//! **Guarantee.** On the serial executor each walk runs alone, so each pixel ends with exactly its
//! `K` nearest fragments in canonical order: [`Promise::Nearest`]`(K)`, exact up to `K`. Under any
//! other interleaving it is **not** safe: between a fragment's reads and its writes another
//! fragment may write the same slots, and the stale write-back then erases that fragment (lost),
//! or copies one fragment into two slots (a duplicate), or leaves the slots out of order. This is
//! the read–modify–write hazard the papers name; nothing here hides it: the post pass reports the
//! slots as they are, and `Oracle::diff` counts the lost, extra and misordered fragments
//! (`tests/kbuffer.rs` drives each case by hand; `docs/baselines/kbuffer.md` writes them out).
//!
//! **Cost.** One geometry pass; `2 K` memory operations per fragment (`K` when it is discarded);
//! memory `8 K` bytes per pixel.
//!
//! Unlike the paper, which keeps a depth and a colour per slot in RGBA render targets, a slot is
//! one `u64` `depth_key << 32 | prim`, so the capture is compared fragment for fragment with the
//! oracle (FreePipe's Table 3 counts 4 bytes a slot: 20 MB for `K` = 20 at 512×512; here 40 MiB).
//! Unlike the GPU, whose hazard window is the time between the texture fetch and the ROP's write,
//! the window here is whatever the executor puts between the first load and the last store; the
//! serial executor puts nothing, the scheduled executor anything its policy picks.

use fragsim_raster::{Fragment, Viewport};

use crate::capture::Identity;
use crate::guarantee::Guarantee;
use crate::memory::{Memory, WordMemory};
use crate::scheme::{check_cap, CaptureError, Layout, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// The value of an empty slot: larger than every packed fragment.
pub const EMPTY: u64 = u64::MAX;

/// The single-pass k-buffer over `u64` slots.
#[derive(Clone, Debug)]
pub struct KBuffer {
    pixels: usize,
    slots: Slots,
}

/// Where a fragment's read–insert–write is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Slot `i` is loaded next.
    Read(u32),
    /// Slot `i` is stored next.
    Write(u32),
}

/// A fragment's read–insert–write, one slot per step.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Insert {
    /// First word of the pixel's `K` slots.
    pub base: usize,
    /// The fragment, packed `depth_key << 32 | prim`.
    pub value: u64,
    /// The next memory operation.
    pub phase: Phase,
    /// While reading, the slots read so far; from the first write on, the `K` words to write.
    pub local: Vec<u64>,
    /// Whether the insertion pushed a value off the end.
    pub evicted: bool,
}

/// How a step of [`Slots::step`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// More loads or stores follow.
    Continue,
    /// The last store is done; nothing fell off.
    Stored,
    /// The last store is done; the value that was `K`-th fell off.
    Evicted,
    /// The fragment was farther than all `K` values read: it writes nothing.
    FellOff,
}

/// `K` slots per pixel and the read–insert–write on them, shared by the single-pass k-buffer and
/// the multi-pass one (`kbuffer_multipass`), which peels with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Slots {
    /// Slots per pixel.
    pub k: u32,
}

impl Slots {
    /// Fails on `k == 0`, naming `scheme`.
    pub fn new(scheme: &str, k: u32) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(format!(
                "{scheme} needs K ≥ 1 slots per pixel, got K = 0"
            )));
        }
        Ok(Self { k })
    }

    /// Words of `pixels` pixels' slots.
    pub fn words(self, pixels: usize) -> usize {
        pixels * self.k as usize
    }

    /// A fragment's walk before its first read.
    pub fn begin(self, fragment: Fragment) -> Insert {
        Insert {
            base: fragment.pixel as usize * self.k as usize,
            value: fragment.packed(),
            phase: Phase::Read(0),
            local: Vec::with_capacity(self.k as usize + 1),
            evicted: false,
        }
    }

    /// One load or one store of the walk.
    pub fn step(self, insert: &mut Insert, slots: &impl WordMemory<u64>) -> Outcome {
        let k = self.k;
        match insert.phase {
            Phase::Read(i) => {
                insert.local.push(slots.load(insert.base + i as usize));
                if i + 1 < k {
                    insert.phase = Phase::Read(i + 1);
                    return Outcome::Continue;
                }
                // The insertion, in registers: no memory operation. Under a hazard the values
                // read may hold gaps, duplicates or be out of order; they are sorted as they are,
                // as a shader sorting its K + 1 registers would.
                insert.local.retain(|&v| v != EMPTY);
                let full = insert.local.len() == k as usize;
                if full && insert.local.iter().all(|&v| v < insert.value) {
                    return Outcome::FellOff;
                }
                insert.local.push(insert.value);
                insert.local.sort_unstable();
                insert.evicted = insert.local.len() > k as usize;
                insert.local.resize(k as usize, EMPTY);
                insert.phase = Phase::Write(0);
                Outcome::Continue
            }
            Phase::Write(i) => {
                slots.store(insert.base + i as usize, insert.local[i as usize]);
                if i + 1 < k {
                    insert.phase = Phase::Write(i + 1);
                    Outcome::Continue
                } else if insert.evicted {
                    Outcome::Evicted
                } else {
                    Outcome::Stored
                }
            }
        }
    }

    /// The non-empty slots of `pixel`, in slot order: gaps, duplicates and disorder left by a
    /// hazard are kept, for the diff to see.
    pub fn occupied(
        self,
        slots: &impl WordMemory<u64>,
        pixel: usize,
    ) -> impl Iterator<Item = u64> + '_ {
        let base = pixel * self.k as usize;
        (0..self.k as usize)
            .map(move |i| slots.load(base + i))
            .filter(|&v| v != EMPTY)
    }
}

impl KBuffer {
    /// The k-buffer with `k` slots per pixel, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, k: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        let scheme = Self {
            pixels: viewport.pixels(),
            slots: Slots::new("the k-buffer", k)?,
        };
        check_cap(&scheme.name(), &scheme.layout(), memory_cap)?;
        Ok(scheme)
    }

    /// Like [`KBuffer::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`KBuffer::new`].
    pub fn with_k(viewport: Viewport, k: u32) -> Result<Self, CaptureError> {
        Self::new(viewport, k, MEMORY_CAP_DEFAULT)
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.slots.k
    }
}

impl Scheme for KBuffer {
    type State = Insert;

    fn name(&self) -> String {
        "kbuffer".into()
    }

    fn layout(&self) -> Layout {
        Layout {
            words32: 0,
            init32: 0,
            words64: self.slots.words(self.pixels),
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
        Promise::Nearest(self.slots.k)
    }

    fn begin(&self, fragment: Fragment) -> Insert {
        self.slots.begin(fragment)
    }

    fn step<M: Memory>(&self, insert: &mut Insert, memory: &M) -> Step {
        match self.slots.step(insert, memory) {
            Outcome::Continue => Step::Continue,
            Outcome::Stored => Step::Stored,
            Outcome::Evicted | Outcome::FellOff => Step::Dropped,
        }
    }

    fn pixels(&self) -> usize {
        self.pixels
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // No sort: the slots are reported as the hazards left them.
        out.extend(self.slots.occupied(memory, pixel));
        // What fell off is not in memory: the executors count it from the walks.
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::SerialMemory;

    fn fragment(depth_key: u32, prim: u32) -> Fragment {
        Fragment {
            pixel: 0,
            depth_key,
            prim,
        }
    }

    #[test]
    fn a_walk_is_k_loads_then_k_stores_or_k_loads_and_a_discard() {
        let scheme = KBuffer::with_k(Viewport::new(1, 1).unwrap(), 2).unwrap();
        let memory: SerialMemory = scheme.layout().allocate();
        let mut steps = 0;
        for (key, end) in [(5, Step::Stored), (3, Step::Stored), (9, Step::Dropped)] {
            let before = steps;
            assert_eq!(scheme.insert(fragment(key, 0), &memory, &mut steps), end);
            // A fragment farther than both held values only reads.
            assert_eq!(steps - before, if key == 9 { 2 } else { 4 });
        }
        assert_eq!(
            scheme.insert(fragment(1, 0), &memory, &mut steps),
            Step::Dropped,
            "inserting 1 into [3, 5] pushes 5 off"
        );
        let mut out = Vec::new();
        scheme.resolve_pixel(&memory, 0, &mut out);
        assert_eq!(out, vec![1 << 32, 3 << 32]);
    }
}
