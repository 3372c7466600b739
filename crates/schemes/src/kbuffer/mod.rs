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
//! `K` nearest fragments in canonical order: [`Promise::Nearest`](fragsim_capture::Promise::Nearest)`(K)`, exact up to `K`, on both
//! machines. Under any other interleaving it is **not** safe: this is the read–modify–write hazard
//! the papers name. Nothing here hides it: the post pass reports the slots as they are, and
//! `Oracle::diff` counts the lost, extra and misordered fragments (`tests/suite/kbuffer/` drives each
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
//!
//! **The family.** This folder holds the k-buffer (this module) and the schemes built on its
//! slots: [`interlock`] and [`interlock_ordered`] (the read–insert–write as one critical section),
//! [`spinlock`] (the section under a spinlock) and [`multipass`] (peeling `K` layers a pass);
//! `slots.rs` holds what they share, the `K` slots of a pixel and one fragment's insertion.

pub mod interlock;
pub mod interlock_ordered;
pub mod multipass;
mod slots;
pub mod spinlock;

pub use slots::{Insert, Phase, WriteBack, EMPTY};
pub(crate) use slots::{Outcome, Slots};

use fragsim_memory::Memory;
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::{CaptureError, Descriptor, Scheme, Step, MEMORY_CAP_DEFAULT};

/// The single-pass k-buffer over `u64` slots.
#[derive(Clone, Debug)]
pub struct KBuffer {
    descriptor: Descriptor,
    slots: Slots,
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
    type Input = Fragment;

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
        self.slots.resolve_pixel(memory, pixel, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::one_pixel::fragment;
    use fragsim_memory::SerialMemory;

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
