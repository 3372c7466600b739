//! The k-buffer inside a per-pixel spinlock: nvpro-samples' `vk_order_independent_transparency`
//! "spinlock" mode (and the spinlock of Godot's OIT proposal), in its two loop shapes: the naive
//! one, which deadlocks lanes of one warp under lockstep SIMT, and the classic fix.
//!
//! **Algorithm.** Each pixel owns a lock word (0 free, 1 held) and `K` slots, initially empty
//! (`u64::MAX`), as in the [`kbuffer`](crate::kbuffer) on separate stores. A fragment
//! takes its pixel's lock with one compare-and-swap per step ([`Memory::try_lock`]), retrying until
//! it gets it; then, holding it, loads the `K` slots (one step each), inserts itself in registers,
//! stores the `K` nearest back (one step each; none when it falls off) and frees the lock with a
//! store ([`Memory::unlock`]). The two loops ([`Loop`]):
//!
//! ```glsl
//! // Loop::Naive: the critical section after the spin loop.
//! while (atomicCompSwap(lock[p], 0u, 1u) != 0u) {}
//! insert(); atomicExchange(lock[p], 0u);
//! // Loop::Fixed: the holder's critical section and release inside the loop body.
//! bool done = false;
//! while (!done) {
//!     if (atomicCompSwap(lock[p], 0u, 1u) == 0u) { insert(); atomicExchange(lock[p], 0u); done = true; }
//! }
//! ```
//!
//! **Guarantee.** Under independent thread scheduling (every executor, and the scheduled one's
//! random, warps and PCT policies), [`Guarantee::Exact`], [`Promise::Nearest`](fragsim_capture::Promise::Nearest)`(K)`, in both
//! loops: the lock makes each fragment's `2 K` steps a critical section, so the slots after any
//! set of critical sections hold the `K` nearest of the fragments inserted (the `K` nearest of a set
//! do not depend on their order; packed values are distinct); each fragment beyond the `K` kept
//! ends one walk `Dropped`, its own or its evictor's.
//!
//! **Lockstep.** Under the scheduled executor's [`Policy::Lockstep`](fragsim_capture::executors::scheduled::Policy)
//! (a warp's lanes execute one instruction together, as on GPUs before Volta), two lanes of one
//! warp contending for one pixel deadlock the naive loop: the lane that took the lock leaves the
//! loop and waits at its exit (the reconvergence point) for the lanes still looping, which spin on
//! a lock its holder will never free. The executor detects it (no progress within its bound) and
//! reports a [`Deadlock`](fragsim_capture::executors::scheduled::Deadlock). The fixed loop cannot deadlock:
//! the holder's path (insert, release) is inside the loop body, so the lanes that failed wait at
//! the end of the body (the branch's reconvergence point) while the holder finishes and frees the
//! lock, and the next iteration gives it to one of them. [`Scheme::simt`] reports the shape:
//! naive: a lane that took the lock is `reconverging` until its first load, a lane that failed is
//! `spinning`; fixed: a lane that failed is `spinning` and `reconverging` until its retry.
//!
//! **Cost.** One geometry pass; uncontended, `2 K + 2` steps per fragment (`K + 2` when it falls
//! off: the compare-and-swap, `K` loads, `K` stores, the release), of which **1 locked operation**
//! (the lock's); each failed attempt is one step and one locked operation more. Memory: `8 K + 4`
//! bytes per pixel (the slots and the lock word). The interlock
//! ([`kbuffer::interlock`](crate::kbuffer::interlock)) does the same work in one step with
//! no spinning, because the hardware queues the waiting invocations.
//!
//! **Sources.** nvpro-samples' `vk_order_independent_transparency` (NVIDIA, 2020), its spinlock
//! mode (`oitSpinlock` / the `OIT_SPINLOCK` shaders: `imageAtomicCompSwap` on a per-pixel lock
//! image, the insertion sort of `oitCompositeColor`'s k-buffer inside); the pre-Volta deadlock and
//! its fix: NVIDIA's *CUDA C Programming Guide* (Independent Thread Scheduling, compute
//! capability 7.x: "starvation-free algorithms"), and the folklore spinlock pattern of the CUDA
//! forums.
//!
//! **Departures.** The compare-and-swap is [`Memory::try_lock`], an exchange of 1 (`atomicExch`):
//! on a word that is only ever 0 or 1 it writes and returns what `atomicCompSwap(lock, 0, 1)`
//! would (writing 1 over 1 changes nothing), and the memory seam has no compare-and-swap. The
//! release is a store (with a release fence), as nvpro-samples' `imageAtomicExchange(lock, 0)`
//! does without reading the old value. As in the k-buffer, a slot is one `u64`
//! `depth_key << 32 | prim` rather than the samples' packed depth and colour, so the capture is
//! compared fragment for fragment with the oracle.

use fragsim_memory::Memory;
use fragsim_raster::{Fragment, Viewport};

use crate::kbuffer::{Insert, Outcome, Slots, WriteBack};
use fragsim_capture::Guarantee;
use fragsim_capture::Simt;
use fragsim_capture::{CaptureError, Descriptor, Scheme, Step, MEMORY_CAP_DEFAULT};

/// Where the critical section sits in the lock loop (module doc: the GLSL of each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Loop {
    /// After the spin loop: deadlocks lanes of one warp under lockstep SIMT.
    Naive,
    /// Inside the loop body, with the release: terminates under every scheduling.
    Fixed,
}

impl Loop {
    /// The catalog's name of the scheme with this loop.
    #[must_use]
    pub fn scheme_name(self) -> &'static str {
        match self {
            Self::Naive => "kbuffer-spinlock",
            Self::Fixed => "kbuffer-spinlock-fixed",
        }
    }
}

/// The k-buffer whose read–insert–write-back runs under a per-pixel spinlock.
#[derive(Clone, Debug)]
pub struct KBufferSpinlock {
    descriptor: Descriptor,
    /// The k-buffer's slots and insertion on separate loads and stores (the critical section's
    /// `2 K` steps).
    slots: Slots,
    shape: Loop,
}

/// Where a fragment's walk is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lock {
    /// Its next step tries to take the lock; `failed`: the last attempt failed.
    Acquire {
        /// Whether an attempt has failed already (the walk is spinning).
        failed: bool,
    },
    /// Holding the lock: its next step is one of the critical section's loads or stores.
    /// `at_exit`: the naive loop's lane that has just left the spin loop (the first load next).
    Held {
        /// Whether the lane stands at the spin loop's exit (naive loop only).
        at_exit: bool,
    },
    /// The critical section is over: its next step frees the lock, and its walk ends with `then`.
    Release {
        /// How the walk ends after the release.
        then: Step,
    },
}

/// A fragment's walk: the lock and the k-buffer's insertion.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SpinInsert {
    /// Where the lock loop is.
    pub lock: Lock,
    /// The k-buffer's read–insert–write.
    pub insert: Insert,
}

impl KBufferSpinlock {
    /// The spinlocked k-buffer with `k` slots per pixel and the lock loop `shape`, within
    /// `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        shape: Loop,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let slots = Slots::new(shape.scheme_name(), k, WriteBack::SeparateStores)?;
        let pixels = viewport.pixels();
        let descriptor = Descriptor {
            // Not claimed: its frames' drops are not checked against what their capture lacks.
            counts_every_drop: false,
            // `u32` word `p`: pixel `p`'s lock.
            ..slots.descriptor(shape.scheme_name().into(), pixels, pixels, Guarantee::Exact)
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            slots,
            shape,
        })
    }

    /// Like [`KBufferSpinlock::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`KBufferSpinlock::new`].
    pub fn with_k(viewport: Viewport, k: u32, shape: Loop) -> Result<Self, CaptureError> {
        Self::new(viewport, k, shape, MEMORY_CAP_DEFAULT)
    }

    /// Slots per pixel.
    #[must_use]
    pub fn k(&self) -> u32 {
        self.slots.k
    }

    /// The lock loop.
    #[must_use]
    pub fn shape(&self) -> Loop {
        self.shape
    }
}

impl Scheme for KBufferSpinlock {
    type State = SpinInsert;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> SpinInsert {
        SpinInsert {
            lock: Lock::Acquire { failed: false },
            insert: self.slots.begin(fragment),
        }
    }

    /// One attempt at the lock, one load or store of the critical section, or the release.
    fn step<M: Memory>(&self, walk: &mut SpinInsert, memory: &M) -> Step {
        let lock = walk.insert.base / self.slots.k as usize;
        match walk.lock {
            Lock::Acquire { .. } => {
                walk.lock = if memory.try_lock(lock) {
                    Lock::Held {
                        at_exit: self.shape == Loop::Naive,
                    }
                } else {
                    Lock::Acquire { failed: true }
                };
                Step::Continue
            }
            Lock::Held { .. } => {
                walk.lock = match self.slots.step(&mut walk.insert, memory) {
                    Outcome::Continue => Lock::Held { at_exit: false },
                    Outcome::Stored => Lock::Release { then: Step::Stored },
                    // Separate stores never overtake (that is the render targets' commit order).
                    Outcome::Evicted | Outcome::FellOff | Outcome::Overtaken => Lock::Release {
                        then: Step::Dropped,
                    },
                };
                Step::Continue
            }
            Lock::Release { then } => {
                memory.unlock(lock);
                then
            }
        }
    }

    fn simt(&self, walk: &SpinInsert) -> Simt {
        match (self.shape, walk.lock) {
            // Naive: a failed lane loops on (runnable, spinning); the holder waits at the exit.
            (Loop::Naive, Lock::Acquire { failed }) => Simt {
                spinning: failed,
                reconverging: false,
            },
            (Loop::Naive, Lock::Held { at_exit }) => Simt {
                spinning: false,
                reconverging: at_exit,
            },
            // Fixed: a failed lane waits at the end of the loop body for the holder's branch.
            (Loop::Fixed, Lock::Acquire { failed }) => Simt {
                spinning: failed,
                reconverging: failed,
            },
            (_, Lock::Held { .. } | Lock::Release { .. }) => Simt::default(),
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // Already in canonical order: every critical section leaves the slots sorted.
        self.slots.resolve_pixel(memory, pixel, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_capture::executors::scheduled::{
        run_fragments, run_fragments_in_order, Granularity, Policy, Schedule,
    };
    use fragsim_memory::{Op, SerialMemory, WordMemory};

    fn fragment(pixel: u32, depth_key: u32, prim: u32) -> Fragment {
        Fragment {
            pixel,
            depth_key,
            prim,
        }
    }

    fn viewport(pixels: u32) -> Viewport {
        Viewport::new(pixels, 1).unwrap()
    }

    fn lockstep(in_flight: usize) -> Schedule {
        Schedule {
            policy: Policy::Lockstep,
            in_flight,
            granularity: Granularity::Fragment,
            seed: 0,
        }
    }

    #[test]
    fn an_uncontended_walk_is_the_lock_k_loads_k_stores_and_the_release() {
        for shape in [Loop::Naive, Loop::Fixed] {
            let scheme = KBufferSpinlock::with_k(viewport(1), 2, shape).unwrap();
            let memory: SerialMemory = scheme.layout().allocate();
            for (key, end, steps_taken) in [
                (5, Step::Stored, 6),
                (3, Step::Stored, 6),
                // Farther than both: the lock, 2 loads, the release.
                (9, Step::Dropped, 4),
                // Evicts 5.
                (1, Step::Dropped, 6),
            ] {
                let mut steps = 0;
                assert_eq!(scheme.insert(fragment(0, key, 0), &memory, &mut steps), end);
                assert_eq!(steps, steps_taken, "{shape:?}, key {key}");
                assert_eq!(WordMemory::<u32>::load(&memory, 0), 0, "the lock is freed");
            }
            let mut out = Vec::new();
            scheme.resolve_pixel(&memory, 0, &mut out);
            assert_eq!(out, vec![1 << 32, 3 << 32]);
        }
    }

    #[test]
    fn k_zero_and_storage_beyond_the_cap_are_refused_by_name() {
        let zero = KBufferSpinlock::with_k(viewport(1), 0, Loop::Fixed).unwrap_err();
        assert!(
            zero.to_string().contains("kbuffer-spinlock-fixed"),
            "{zero}"
        );
        // What is allocated before any fragment (the page tables of its words) is checked
        // when the scheme is built; its pages as a frame writes them.
        let least = KBufferSpinlock::new(viewport(1), 4, Loop::Naive, u64::MAX)
            .unwrap()
            .layout()
            .least_bytes();
        let capped = KBufferSpinlock::new(viewport(1), 4, Loop::Naive, least - 1).unwrap_err();
        assert!(
            matches!(capped, CaptureError::TooMuchMemory { needed, .. } if needed == least),
            "{capped:?}"
        );
    }

    /// The plain k-buffer's losing interleaving (both read, then both write): here the second
    /// fragment's first step fails to take the lock, spins until the holder releases, and both
    /// are kept.
    #[test]
    fn a_contender_spins_until_the_holder_releases_and_nothing_is_lost() {
        let fragments = [fragment(0, 3, 0), fragment(0, 5, 1)];
        for shape in [Loop::Naive, Loop::Fixed] {
            let scheme = KBufferSpinlock::with_k(viewport(1), 2, shape).unwrap();
            // A takes the lock; B tries twice (spins) while A is in its critical section.
            let run = run_fragments_in_order(&scheme, &fragments, &[0, 1, 0, 1, 0], true);
            let trace = run.trace.unwrap();
            let failed = trace
                .events
                .iter()
                .filter(|e| e.thread == 1 && e.op == Op::Swap && e.returned == 1)
                .count();
            assert_eq!(
                failed, 2,
                "{shape:?}: B's two attempts while A holds the lock"
            );
            let expected: Vec<u64> = fragments.iter().map(|f| f.packed()).collect();
            assert_eq!(run.run.capture.pixel(0), expected.as_slice(), "{shape:?}");
            assert!(run.deadlock.is_none());
        }
    }

    /// The minimal deadlock: two fragments of one pixel in one lockstep warp. Lane 0 takes the
    /// lock and waits at the loop's exit; lane 1 spins until the bound. Then and only then: on two
    /// pixels, or with the fixed loop, or under independent scheduling, no deadlock.
    #[test]
    fn two_lanes_of_one_warp_on_one_pixel_deadlock_the_naive_loop_and_only_it() {
        let same = [fragment(0, 3, 0), fragment(0, 5, 1)];
        let naive = KBufferSpinlock::with_k(viewport(2), 2, Loop::Naive).unwrap();
        let deadlock = run_fragments(&naive, &same, &lockstep(2), false)
            .checked()
            .unwrap_err();
        assert_eq!(
            deadlock.spins,
            2 * fragsim_capture::executors::scheduled::DEADLOCK_SPINS_PER_THREAD
        );
        let simts: Vec<(u32, Simt)> = deadlock.lanes.iter().map(|l| (l.thread, l.simt)).collect();
        assert_eq!(
            simts,
            vec![
                (
                    0,
                    Simt {
                        spinning: false,
                        reconverging: true
                    }
                ),
                (
                    1,
                    Simt {
                        spinning: true,
                        reconverging: false
                    }
                ),
            ]
        );
        assert!(
            deadlock.to_string().contains("spins on a lock"),
            "{deadlock}"
        );

        let apart = [fragment(0, 3, 0), fragment(1, 5, 1)];
        assert!(run_fragments(&naive, &apart, &lockstep(2), false)
            .deadlock
            .is_none());
        let fixed = KBufferSpinlock::with_k(viewport(2), 2, Loop::Fixed).unwrap();
        let run = run_fragments(&fixed, &same, &lockstep(2), false)
            .checked()
            .unwrap();
        let expected: Vec<u64> = same.iter().map(|f| f.packed()).collect();
        assert_eq!(run.run.capture.pixel(0), expected.as_slice());
        for policy in [Policy::Random, Policy::Warps, Policy::Pct { depth: 2 }] {
            let schedule = Schedule {
                policy,
                ..lockstep(2)
            };
            #[expect(clippy::shadow_unrelated, reason = "the next run of the same test")]
            let run = run_fragments(&naive, &same, &schedule, false)
                .checked()
                .unwrap();
            assert_eq!(run.run.capture.pixel(0), expected.as_slice(), "{policy:?}");
        }
    }
}
