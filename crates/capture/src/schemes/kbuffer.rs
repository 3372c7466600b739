//! The k-buffer: Bavoil, Callahan, Lefohn, Comba and Silva, "Multi-fragment effects on the GPU
//! using the k-buffer" (I3D 2007), §3, as FreePipe (Liu et al., I3D 2010, §2 and Table 3) and
//! bucket depth peeling (Liu et al., HPG 2009, Table 2, "k-buffer of 32 layers without
//! modifications") run it.
//!
//! **Algorithm.** Each pixel owns `K` slots, initially empty (`u64::MAX`). A fragment's shader
//! *reads* the pixel's `K` slots, inserts itself into the `K + 1` values in registers, and *writes*
//! the `K` nearest back. When the fragment is farther than all `K` values read, it writes nothing
//! (a shader `discard`) and its walk ends `Dropped`; when it evicts the `K`-th value, its walk ends
//! `Dropped` after the write (one value fell off, as MDTS counts).
//!
//! **Two machines** ([`WriteBack`]), which differ in what one step is:
//! - [`WriteBack::RenderTarget`] (the default; the papers' GPUs): the read is a texture fetch of
//!   the render targets being drawn and the write-back is the MRT output through the ROP. The read
//!   of the `K` slots is **one** step (a consistent snapshot of the pixel), the write-back **one**
//!   step (all `K` slots at once), and write-backs to a pixel commit in primitive order (the ROP.s
//!   API order). Only the read can be stale: it may miss a write-back that commits before this
//!   one. The only failure is a **lost** fragment: the slots always hold a sorted list of distinct
//!   fragments, because every write-back is one fragment's sorted insertion into one snapshot.
//! - [`WriteBack::SeparateStores`] (what CUDA code does, `backends/cuda`): `K` plain `load`s, then
//!   `K` plain `store`s, slot 0 first, one step each. Two write-backs can interleave store by
//!   store, so besides losses the slots can hold **duplicates** and be **out of order** (torn
//!   write-backs), which the render-target machine cannot produce.
//!
//! **Guarantee.** On the serial executor each walk runs alone, so each pixel ends with exactly its
//! `K` nearest fragments in canonical order: [`Promise::Nearest`]`(K)`, exact up to `K`, on both
//! machines. Under any other interleaving it is **not** safe: this is the read–modify–write hazard
//! the papers name. Nothing here hides it: the post pass reports the slots as they are, and
//! `Oracle::diff` counts the lost, extra and misordered fragments (`tests/suite/kbuffer.rs` drives each
//! case by hand; `docs/baselines/kbuffer.md` and `docs/rmw-hazard.md` write them out).
//!
//! **How the render-target step is made indivisible.** On the serial and scheduled executors a
//! step runs alone anyway. On the parallel executor several threads may read and write one pixel's
//! `K` words at once, so each pixel has a lock word, taken and freed around the step with
//! [`Memory::lock`] / [`Memory::unlock`] (acquire and release fences around a `swap`: the slot
//! words stay `Relaxed`); a step holds it only for its own `K` loads or stores, never across
//! steps, so no executor can deadlock on it. The lock is the CPU's stand-in for the ROP and costs
//! a locked operation per step, which `count_locked_ops` reports; a GPU pays nothing for it.
//!
//! **How "commit in primitive order" is modelled.** The ROP commits a pixel's write-backs in the
//! order its fragments arrived (primitive order: rasterization is in order), holding a write-back
//! until the earlier ones have committed. An executor that runs triangles out of order (parallel,
//! scheduled) cannot wait for a fragment that is not rasterized yet, or it would deadlock. So each
//! fragment takes a *ticket* with its read (a per-pixel counter, inside the read's step): the
//! commit order is the order of the reads. Each pixel keeps the last committed ticket, and a
//! write-back whose ticket is older is dropped inside its step (Thomas's write rule): in commit
//! order it came first and the newer one, whose read missed it, overwrote it whole, so dropping it
//! gives the same slots. The walk still ends `Stored` (the ROP did write it). Departure: the ticket
//! order is the reads' order, which is primitive order wherever an executor starts a pixel's reads
//! in primitive order (serial, tiled) but not always within the scheduled executor's window or
//! across the parallel executor's threads. There a stale pair loses the earlier *reader* where a GPU
//! would lose the earlier *primitive*: one fragment either way. Walks run one after another in any
//! order are exact, as on the serial executor, and every final state is one a GPU reaches with
//! fragments that read in primitive order: the surviving write-back chain is in increasing ticket
//! order, each link reading the previous link's write-back, which a stale read can see.
//!
//! **The shortest losing interleaving** under render-target writes is **4 steps**: two fragments,
//! both reads before either write-back (read A, read B, write A, write B). A loss needs a
//! write-back computed from a read that missed another fragment's write-back, so two fragments that
//! both write, each one read and one write; one alone, or one that only reads (discards), cannot
//! erase anything; and the only 2-fragment orders in which neither read misses the other's write
//! are the two serial ones. With separate stores the same loss takes `4 K` steps (both walks
//! complete, `K` loads and `K` stores each: 12 for `K` = 3).
//!
//! **Cost.** One geometry pass. Render targets: 2 steps per fragment (1 when it is discarded);
//! separate stores: `2 K` memory operations (`K` when it is discarded). Memory: `8 K` bytes per
//! pixel, plus 12 for the render-target machine (the lock, the next ticket, the last committed one).
//!
//! Unlike the paper, which keeps a depth and a colour per slot in RGBA render targets, a slot is
//! one `u64` `depth_key << 32 | prim`, so the capture is compared fragment for fragment with the
//! oracle (FreePipe's Table 3 counts 4 bytes a slot: 20 MB for `K` = 20 at 512×512; here 40 MiB).
//! Unlike the GPU, whose hazard window is the time between the texture fetch and the ROP's write,
//! the window here is whatever the executor puts between the read and the write-back; the serial
//! executor puts nothing, the scheduled executor anything its policy picks.

use fragsim_raster::{Fragment, Viewport};

use crate::capture::Identity;
use crate::guarantee::Guarantee;
use crate::memory::{Layout, Memory, WordMemory};
use crate::scheme::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// The value of an empty slot: larger than every packed fragment.
pub const EMPTY: u64 = u64::MAX;

/// How a fragment's read and write-back reach the pixel's `K` slots: the machine modelled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WriteBack {
    /// Render targets, as on the papers' GPUs: the read of the `K` slots is one step, the
    /// write-back one step, and write-backs to a pixel commit in order. Only the read
    /// can be stale, so the only failure is a lost fragment.
    #[default]
    RenderTarget,
    /// `K` loads, then `K` stores, one step each, as CUDA code does: write-backs can tear, so the
    /// slots can also hold duplicates and be out of order.
    SeparateStores,
}

impl WriteBack {
    /// The suffix of a scheme's name on this machine: none for render targets (the default).
    #[must_use]
    pub fn suffix(self) -> &'static str {
        match self {
            WriteBack::RenderTarget => "",
            WriteBack::SeparateStores => "-stores",
        }
    }
}

/// The single-pass k-buffer over `u64` slots.
#[derive(Clone, Debug)]
pub struct KBuffer {
    descriptor: Descriptor,
    slots: Slots,
}

/// Where a fragment's read–insert–write is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Slot `i` is loaded next (with render targets, `Read(0)`: all `K` slots in one step).
    Read(u32),
    /// Slot `i` is stored next (with render targets, `Write(0)`: all `K` slots in one step).
    Write(u32),
}

/// A fragment's read–insert–write.
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
    /// Render targets: the fragment's place in the pixel's commit order, taken with its read.
    pub ticket: u32,
}

/// How a step of [`Slots::step`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// More steps follow.
    Continue,
    /// The write-back is done; nothing fell off.
    Stored,
    /// The write-back is done; the value that was `K`-th fell off.
    Evicted,
    /// The fragment was farther than all `K` values read: it writes nothing.
    FellOff,
    /// Render targets only: the write-back of a fragment that read later had already committed,
    /// so in commit order this one came first and was overwritten; nothing was written.
    Overtaken,
}

/// `K` slots per pixel and the read–insert–write on them, shared by the single-pass k-buffer and
/// the multi-pass one (`kbuffer_multipass`), which peels with it.
///
/// The slots of pixel `p` are `u64` words `p K .. (p + 1) K`; with render targets, `u32` words
/// `3 p` (the lock), `3 p + 1` (the next ticket) and `3 p + 2` (the last committed ticket + 1) are
/// the pixel's too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Slots {
    /// Slots per pixel.
    pub k: u32,
    /// The machine.
    pub write_back: WriteBack,
}

impl Slots {
    /// Fails on `k == 0`, naming `scheme`.
    pub fn new(scheme: &str, k: u32, write_back: WriteBack) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(format!(
                "{scheme} needs K ≥ 1 slots per pixel, got K = 0"
            )));
        }
        Ok(Self { k, write_back })
    }

    /// The descriptor of a scheme keeping these slots for `pixels` pixels, its `u32` words
    /// (locks, tickets) `words32`: whole fragments in `u64` slots, all empty at first, the `K`
    /// nearest promised, and every fragment that falls off a walk's end counted as dropped.
    pub fn descriptor(
        self,
        name: String,
        pixels: usize,
        words32: usize,
        guarantee: Guarantee,
    ) -> Descriptor {
        Descriptor {
            name,
            layout: Layout {
                words32,
                init32: 0,
                words64: self.words(pixels),
                init64: EMPTY,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee,
            promise: Promise::Nearest(self.k),
            pixels,
            counts_every_drop: true,
        }
    }

    /// `u64` words of `pixels` pixels' slots.
    pub fn words(self, pixels: usize) -> usize {
        pixels * self.k as usize
    }

    /// `u32` words of `pixels` pixels' render-target bookkeeping (none for separate stores):
    /// the lock, the next ticket, the last committed ticket + 1.
    pub fn sync_words(self, pixels: usize) -> usize {
        match self.write_back {
            WriteBack::RenderTarget => 3 * pixels,
            WriteBack::SeparateStores => 0,
        }
    }

    /// A fragment's walk before its first read.
    pub fn begin(self, fragment: Fragment) -> Insert {
        Insert {
            base: fragment.pixel as usize * self.k as usize,
            value: fragment.packed(),
            phase: Phase::Read(0),
            local: Vec::with_capacity(self.k as usize + 1),
            evicted: false,
            ticket: 0,
        }
    }

    /// One step of the walk: one load or one store with separate stores; the whole read or the
    /// whole write-back with render targets.
    pub fn step<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        match self.write_back {
            WriteBack::SeparateStores => self.step_separate(insert, memory),
            WriteBack::RenderTarget => self.step_render_target(insert, memory),
        }
    }

    fn step_separate<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        let k = self.k;
        match insert.phase {
            Phase::Read(i) => {
                insert
                    .local
                    .push(WordMemory::<u64>::load(memory, insert.base + i as usize));
                if i + 1 < k {
                    insert.phase = Phase::Read(i + 1);
                    return Outcome::Continue;
                }
                self.insert_in_registers(insert)
            }
            Phase::Write(i) => {
                WordMemory::<u64>::store(
                    memory,
                    insert.base + i as usize,
                    insert.local[i as usize],
                );
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

    fn step_render_target<M: Memory>(self, insert: &mut Insert, memory: &M) -> Outcome {
        let k = self.k as usize;
        let pixel = insert.base / k;
        let (lock, next_ticket, last_writer) = (3 * pixel, 3 * pixel + 1, 3 * pixel + 2);
        match insert.phase {
            Phase::Read(_) => {
                memory.lock(lock);
                insert.ticket = WordMemory::<u32>::load(memory, next_ticket);
                WordMemory::<u32>::store(memory, next_ticket, insert.ticket.wrapping_add(1));
                insert.local.extend(
                    (insert.base..insert.base + k).map(|w| WordMemory::<u64>::load(memory, w)),
                );
                memory.unlock(lock);
                self.insert_in_registers(insert)
            }
            Phase::Write(_) => {
                // `ticket + 1`, so that 0 means "no write-back yet".
                let mine = insert.ticket.saturating_add(1);
                memory.lock(lock);
                let commits = mine > WordMemory::<u32>::load(memory, last_writer);
                if commits {
                    for (i, &v) in insert.local.iter().enumerate() {
                        WordMemory::<u64>::store(memory, insert.base + i, v);
                    }
                    WordMemory::<u32>::store(memory, last_writer, mine);
                }
                memory.unlock(lock);
                if !commits {
                    Outcome::Overtaken
                } else if insert.evicted {
                    Outcome::Evicted
                } else {
                    Outcome::Stored
                }
            }
        }
    }

    /// The insertion, in registers, after the last read: no memory operation. Under a hazard the
    /// values read may hold gaps, duplicates or be out of order (separate stores only); they are
    /// sorted as they are, as a shader sorting its `K + 1` registers would.
    pub(crate) fn insert_in_registers(self, insert: &mut Insert) -> Outcome {
        let k = self.k as usize;
        insert.local.retain(|&v| v != EMPTY);
        let full = insert.local.len() == k;
        if full && insert.local.iter().all(|&v| v < insert.value) {
            return Outcome::FellOff;
        }
        insert.local.push(insert.value);
        insert.local.sort_unstable();
        insert.evicted = insert.local.len() > k;
        insert.local.resize(k, EMPTY);
        insert.phase = Phase::Write(0);
        Outcome::Continue
    }

    /// Empties `pixel`'s slots and forgets its last writer (between geometry passes).
    pub fn clear<M: Memory>(self, memory: &M, pixel: usize) {
        let base = pixel * self.k as usize;
        for w in base..base + self.k as usize {
            WordMemory::<u64>::store(memory, w, EMPTY);
        }
        if self.write_back == WriteBack::RenderTarget {
            WordMemory::<u32>::store(memory, 3 * pixel + 1, 0);
            WordMemory::<u32>::store(memory, 3 * pixel + 2, 0);
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
    /// The k-buffer with `k` slots per pixel on render targets (the papers' machine), within
    /// `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(viewport: Viewport, k: u32, memory_cap: u64) -> Result<Self, CaptureError> {
        Self::with_write_back(viewport, k, WriteBack::RenderTarget, memory_cap)
    }

    /// The k-buffer with `k` slots per pixel on the machine `write_back`, within `memory_cap`
    /// bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn with_write_back(
        viewport: Viewport,
        k: u32,
        write_back: WriteBack,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let slots = Slots::new("the k-buffer", k, write_back)?;
        let pixels = viewport.pixels();
        let descriptor = slots.descriptor(
            format!("kbuffer{}", write_back.suffix()),
            pixels,
            slots.sync_words(pixels),
            Guarantee::ExactWithoutHazards,
        );
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            slots,
        })
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

    /// The machine modelled.
    #[must_use]
    pub fn write_back(&self) -> WriteBack {
        self.slots.write_back
    }
}

impl Scheme for KBuffer {
    type State = Insert;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Insert {
        self.slots.begin(fragment)
    }

    fn step<M: Memory>(&self, insert: &mut Insert, memory: &M) -> Step {
        match self.slots.step(insert, memory) {
            Outcome::Continue => Step::Continue,
            // An overtaken write-back did reach the pixel, in commit order before the one that
            // overwrote it: stored, then lost to that one's stale read.
            Outcome::Stored | Outcome::Overtaken => Step::Stored,
            Outcome::Evicted | Outcome::FellOff => Step::Dropped,
        }
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
    use crate::schemes::common::one_pixel::fragment;

    #[test]
    fn a_walk_is_k_loads_then_k_stores_or_one_read_and_one_write_back() {
        for (write_back, read, write) in [
            (WriteBack::SeparateStores, 2, 2),
            (WriteBack::RenderTarget, 1, 1),
        ] {
            let scheme = KBuffer::with_write_back(
                Viewport::new(1, 1).unwrap(),
                2,
                write_back,
                MEMORY_CAP_DEFAULT,
            )
            .unwrap();
            let memory: SerialMemory = scheme.layout().allocate();
            let mut steps = 0;
            for (key, end) in [(5, Step::Stored), (3, Step::Stored), (9, Step::Dropped)] {
                let before = steps;
                assert_eq!(scheme.insert(fragment(key, 0), &memory, &mut steps), end);
                // A fragment farther than both held values only reads.
                let expected = if key == 9 { read } else { read + write };
                assert_eq!(steps - before, expected, "{write_back:?}, key {key}");
            }
            assert_eq!(
                scheme.insert(fragment(1, 0), &memory, &mut steps),
                Step::Dropped,
                "inserting 1 into [3, 5] pushes 5 off"
            );
            let mut out = Vec::new();
            scheme.resolve_pixel(&memory, 0, &mut out);
            assert_eq!(out, vec![1 << 32, 3 << 32], "{write_back:?}");
        }
    }

    #[test]
    fn a_render_target_write_back_that_read_before_the_last_committed_one_is_dropped() {
        let scheme = KBuffer::with_k(Viewport::new(1, 1).unwrap(), 2).unwrap();
        let memory: SerialMemory = scheme.layout().allocate();
        let (mut early, mut late) = (scheme.begin(fragment(3, 1)), scheme.begin(fragment(5, 2)));
        // Both read the empty pixel, early first; the later reader commits first.
        assert_eq!(scheme.step(&mut early, &memory), Step::Continue);
        assert_eq!(scheme.step(&mut late, &memory), Step::Continue);
        assert_eq!(scheme.step(&mut late, &memory), Step::Stored);
        assert_eq!(scheme.step(&mut early, &memory), Step::Stored);
        let mut out = Vec::new();
        scheme.resolve_pixel(&memory, 0, &mut out);
        // In commit order the early write-back came first and the late one, read before it
        // committed, overwrote it.
        assert_eq!(out, vec![5 << 32 | 2]);
    }
}
