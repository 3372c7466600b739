//! MDTS on 64-bit words emulated with 32-bit memory, as code must where 64-bit atomics are
//! missing (WebGPU core has only 32-bit `atomicMin`): the torn emulation and a correct one.
//!
//! **Algorithm.** FreePipe's MDTS walk ([`mdts`](crate::mdts)): a fragment's packed value
//! `v = depth_key << 32 | prim` is offered to slots `0, 1, …` of its pixel; each slot keeps the
//! smaller of its value and `v` and the walk carries the larger on, until a slot was empty
//! (stored) or the `K` slots are passed (dropped). Each slot is two 32-bit words (high, low),
//! so the 64-bit `atomicMin` is emulated ([`Emulation`]):
//! - [`Emulation::Torn`] (`mdts-emulated64-torn`): load the high word, load the low word, and
//!   where `v` is smaller store the high word, then the low word: four plain operations, one step
//!   each. Two fragments interleaving on one slot can leave the high word of one and the low word
//!   of the other (a **torn** word, a value nobody wrote), or lose one of them.
//! - [`Emulation::Locked`] (`mdts-emulated64`): the same loads and stores inside a per-slot lock
//!   taken with compare-and-swap ([`Memory::try_lock`], retried) and freed with a store: the
//!   slot's read–min–write is a critical section, i.e. the 64-bit `atomicMin` it emulates, so
//!   MDTS's proof (per-location atomicity, `docs/proof.md`) applies unchanged.
//!
//! **Guarantee.** Locked: [`Guarantee::Exact`], [`Promise::Nearest`]`(K)` under any
//! interleaving. Torn: [`Guarantee::ExactWithoutHazards`]: exact where each pixel's fragments
//! run one walk at a time (serial, tiled executors), and it tears or loses under concurrent ones.
//!
//! **Cost.** Per slot visited: torn, 2 loads and (where `v` is smaller) 2 stores, no locked
//! operation; locked, the same plus 1 compare-and-swap (a locked operation, one more per failed
//! attempt) and the release store: 4 to 6 steps per slot where a 64-bit `atomicMin` is 1.
//! Memory: 8 bytes per slot, plus the lock's 4 when locked (`12 K` bytes per pixel against
//! MDTS's `8 K`).
//!
//! **Sources.** FreePipe (Liu et al. 2010) for MDTS; the WebGPU specification (W3C, 2024: WGSL
//! atomics are `atomic<u32>` and `atomic<i32>` only) for why the emulation exists; the lock is
//! the per-slot form of nvpro-samples' spinlock (`kbuffer::spinlock`).
//!
//! **Departures.** The words hold the halves complemented (`!hi`, `!lo`), so that the zeroed
//! buffer WebGPU allocates is every slot empty (`u64::MAX`) and every lock free; the lock's
//! compare-and-swap is [`Memory::try_lock`] (an exchange of 1, the same on a 0/1 word). The lock
//! loop has the fixed shape of `kbuffer::spinlock` (the section inside the loop body), so lockstep
//! warps do not deadlock on it.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use fragsim_capture::Guarantee;
use fragsim_capture::Identity;
use fragsim_capture::Simt;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// An empty slot's value.
const EMPTY: u64 = u64::MAX;

/// How the 64-bit `atomicMin` is emulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Emulation {
    /// Two loads and two stores on the halves, unlocked: tears under concurrency.
    Torn,
    /// The loads and stores inside a per-slot compare-and-swap lock.
    Locked,
}

impl Emulation {
    /// The catalog's name of the scheme with this emulation.
    #[must_use]
    pub fn scheme_name(self) -> &'static str {
        match self {
            Self::Torn => "mdts-emulated64-torn",
            Self::Locked => "mdts-emulated64",
        }
    }
}

/// MDTS with each slot's 64-bit `atomicMin` emulated on two 32-bit words.
#[derive(Clone, Debug)]
pub struct MdtsEmulated64 {
    descriptor: Descriptor,
    k: u32,
    emulation: Emulation,
}

/// The next operation on the current slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op64 {
    /// Take the slot's lock (locked only); `failed`: an attempt has failed already.
    Acquire {
        /// Whether the walk is spinning.
        failed: bool,
    },
    /// Load the high half.
    LoadHi,
    /// Load the low half; the high half read.
    LoadLo {
        /// The high half read.
        hi: u32,
    },
    /// Store the high half of the walk's value; the slot's old value.
    StoreHi {
        /// The slot's value read.
        old: u64,
    },
    /// Store the low half; the slot's old value.
    StoreLo {
        /// The slot's value read.
        old: u64,
    },
    /// Free the slot's lock (locked only); the slot's old value.
    Release {
        /// The slot's value read.
        old: u64,
    },
}

/// A fragment's walk over its pixel's slots.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Walk64 {
    /// The slot index (pixel × `K` + slot) being updated.
    pub slot: usize,
    /// Slots left after this one.
    pub left: u32,
    /// The value carried.
    pub value: u64,
    /// The next operation.
    pub op: Op64,
}

impl MdtsEmulated64 {
    /// The emulated MDTS with `k` slots per pixel, within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        emulation: Emulation,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        if k == 0 {
            return Err(CaptureError::BadParameter(format!(
                "{} needs K ≥ 1 slots per pixel, got K = 0",
                emulation.scheme_name()
            )));
        }
        let slots = viewport.pixels() * k as usize;
        let locks = match emulation {
            Emulation::Torn => 0,
            Emulation::Locked => slots,
        };
        let descriptor = Descriptor {
            name: emulation.scheme_name().into(),
            layout: Layout {
                // Words `2 s`, `2 s + 1`: slot `s`'s complemented halves; then slot `s`'s lock at
                // `2 slots + s` (locked only). All zero: empty and free.
                words32: 2 * slots + locks,
                init32: 0,
                words64: 0,
                init64: 0,
                table_bytes: 0,
            },
            identity: Identity::KeyAndPrim,
            guarantee: match emulation {
                Emulation::Torn => Guarantee::ExactWithoutHazards,
                Emulation::Locked => Guarantee::Exact,
            },
            promise: Promise::Nearest(k),
            pixels: viewport.pixels(),
            counts_every_drop: false,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            k,
            emulation,
        })
    }

    /// Like [`MdtsEmulated64::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`MdtsEmulated64::new`].
    pub fn with_k(viewport: Viewport, k: u32, emulation: Emulation) -> Result<Self, CaptureError> {
        Self::new(viewport, k, emulation, MEMORY_CAP_DEFAULT)
    }

    fn slots(&self) -> usize {
        self.descriptor.pixels * self.k as usize
    }

    /// The 64-bit value of slot `slot` (what the post pass reads; a torn slot reads as torn).
    pub fn slot_value<M: Memory>(&self, memory: &M, slot: usize) -> u64 {
        let hi = !WordMemory::<u32>::load(memory, 2 * slot);
        let lo = !WordMemory::<u32>::load(memory, 2 * slot + 1);
        u64::from(hi) << 32 | u64::from(lo)
    }

    /// The first operation on a slot.
    fn first_op(&self) -> Op64 {
        match self.emulation {
            Emulation::Torn => Op64::LoadHi,
            Emulation::Locked => Op64::Acquire { failed: false },
        }
    }

    /// The slot's update is over, having read `old`: the walk ends, or moves on carrying the
    /// larger value.
    fn next_slot(&self, walk: &mut Walk64, old: u64) -> Step {
        if old == EMPTY {
            return Step::Stored;
        }
        walk.value = walk.value.max(old);
        if walk.left == 0 {
            return Step::Dropped;
        }
        walk.left -= 1;
        walk.slot += 1;
        walk.op = self.first_op();
        Step::Continue
    }

    /// After the low store (or a read that stores nothing): the release, or the next slot.
    fn finish(&self, walk: &mut Walk64, old: u64) -> Step {
        match self.emulation {
            Emulation::Locked => {
                walk.op = Op64::Release { old };
                Step::Continue
            }
            Emulation::Torn => self.next_slot(walk, old),
        }
    }
}

impl Scheme for MdtsEmulated64 {
    type State = Walk64;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Walk64 {
        Walk64 {
            slot: fragment.pixel as usize * self.k as usize,
            left: self.k - 1,
            value: fragment.packed(),
            op: self.first_op(),
        }
    }

    /// One compare-and-swap, load, store or release.
    fn step<M: Memory>(&self, walk: &mut Walk64, memory: &M) -> Step {
        let (hi_word, lo_word) = (2 * walk.slot, 2 * walk.slot + 1);
        let lock = 2 * self.slots() + walk.slot;
        match walk.op {
            Op64::Acquire { .. } => {
                walk.op = if memory.try_lock(lock) {
                    Op64::LoadHi
                } else {
                    Op64::Acquire { failed: true }
                };
                Step::Continue
            }
            Op64::LoadHi => {
                let hi = !WordMemory::<u32>::load(memory, hi_word);
                walk.op = Op64::LoadLo { hi };
                Step::Continue
            }
            Op64::LoadLo { hi } => {
                let lo = !WordMemory::<u32>::load(memory, lo_word);
                let old = u64::from(hi) << 32 | u64::from(lo);
                if walk.value < old {
                    walk.op = Op64::StoreHi { old };
                    Step::Continue
                } else {
                    self.finish(walk, old)
                }
            }
            Op64::StoreHi { old } => {
                WordMemory::<u32>::store(memory, hi_word, !((walk.value >> 32) as u32));
                walk.op = Op64::StoreLo { old };
                Step::Continue
            }
            Op64::StoreLo { old } => {
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "the low word of the 64-bit value, by design"
                )]
                WordMemory::<u32>::store(memory, lo_word, !(walk.value as u32));
                self.finish(walk, old)
            }
            Op64::Release { old } => {
                memory.unlock(lock);
                self.next_slot(walk, old)
            }
        }
    }

    fn simt(&self, walk: &Walk64) -> Simt {
        // The fixed loop shape: a lane that failed waits at the end of the loop body.
        match walk.op {
            Op64::Acquire { failed: true } => Simt {
                spinning: true,
                reconverging: true,
            },
            _ => Simt::default(),
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let base = pixel * self.k as usize;
        // Up to the first empty slot, as MDTS reads back; torn values are kept for the diff.
        out.extend(
            (base..base + self.k as usize)
                .map(|slot| self.slot_value(memory, slot))
                .take_while(|&v| v != EMPTY),
        );
        // What fell off the end is not in memory: the executors count it from the walks.
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::one_pixel::{fragment, one_pixel};
    use fragsim_capture::executors::scheduled::run_fragments_in_order;
    use fragsim_memory::SerialMemory;

    #[test]
    fn serially_both_keep_the_k_nearest_in_order() {
        for emulation in [Emulation::Torn, Emulation::Locked] {
            let scheme = MdtsEmulated64::with_k(one_pixel(), 2, emulation).unwrap();
            let memory: SerialMemory = scheme.layout().allocate();
            let mut dropped = 0;
            for (key, prim) in [(5, 0), (3, 1), (9, 2), (1, 3)] {
                let end = scheme.insert(fragment(key, prim), &memory, &mut 0);
                dropped += u32::from(end == Step::Dropped);
            }
            assert_eq!(
                scheme.resolve(&memory).pixel(0),
                [1 << 32 | 3, 3 << 32 | 1].as_slice(),
                "{emulation:?}"
            );
            assert_eq!(dropped, 2, "{emulation:?}");
        }
    }

    /// The smallest torn schedule: A (key 3) and B (key 5) both read the empty slot, A stores its
    /// high half, B both halves, A its low half: the slot holds B's high and A's low half, a
    /// value neither wrote, and both walks end `Stored`. Under the lock the same order of walks
    /// keeps both.
    #[test]
    fn the_torn_emulation_tears_where_the_locked_one_keeps_both() {
        let (a, b) = (fragment(3, 7), fragment(5, 9));
        let torn = MdtsEmulated64::with_k(one_pixel(), 2, Emulation::Torn).unwrap();
        // A: load hi, load lo; B: load hi, load lo; A: store hi; B: store hi, store lo; A: store lo.
        let order = [0, 0, 1, 1, 0, 1, 1, 0];
        let run = run_fragments_in_order(&torn, &[a, b], &order, false);
        let slot0 = torn.slot_value(&run.memory, 0);
        assert_eq!(slot0, 5 << 32 | 7, "B's high half, A's low half");
        assert_ne!(slot0, a.packed());
        assert_ne!(slot0, b.packed());

        let locked = MdtsEmulated64::with_k(one_pixel(), 2, Emulation::Locked).unwrap();
        #[expect(clippy::shadow_unrelated, reason = "the next run of the same test")]
        let run = run_fragments_in_order(&locked, &[a, b], &order, false);
        assert_eq!(
            run.run.capture.pixel(0),
            [a.packed(), b.packed()].as_slice()
        );
    }

    #[test]
    fn k_zero_and_storage_beyond_the_cap_are_refused_by_name() {
        let zero = MdtsEmulated64::with_k(one_pixel(), 0, Emulation::Locked).unwrap_err();
        assert!(zero.to_string().contains("mdts-emulated64"), "{zero}");
        // What is allocated before any fragment (the page tables of its words) is checked
        // when the scheme is built; its pages as a frame writes them.
        let least = MdtsEmulated64::new(one_pixel(), 2, Emulation::Locked, u64::MAX)
            .unwrap()
            .layout()
            .least_bytes();
        let capped = MdtsEmulated64::new(one_pixel(), 2, Emulation::Locked, least - 1).unwrap_err();
        assert!(
            matches!(capped, CaptureError::TooMuchMemory { needed, .. } if needed == least),
            "{capped:?}"
        );
        let torn = MdtsEmulated64::new(one_pixel(), 2, Emulation::Torn, u64::MAX).unwrap();
        let torn_least = torn.layout().least_bytes();
        assert!(MdtsEmulated64::new(one_pixel(), 2, Emulation::Torn, torn_least).is_ok());
    }
}
