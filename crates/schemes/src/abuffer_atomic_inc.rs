//! The A-buffer as GPU code often writes it, with CUDA's wrapping `atomicInc(addr, bound)` for
//! the slot counter: a model of what goes wrong when storage overflows, next to
//! [`ABuffer`], which uses `fetch_add` and counts every drop.
//!
//! **CUDA's `atomicInc(addr, bound)`** reads `old = *addr`, stores `old >= bound ? 0 : old + 1`
//! and returns `old`, in one atomic operation. Started from 0 and applied only with one `bound`
//! (as on an A-buffer's counter), the values it returns, in the word's atomic order, are
//! `0, 1, …, bound, 0, 1, …`: exactly `fetch_add(1)`'s returned values modulo `bound + 1`, and
//! the word holds the count modulo `bound + 1`. So one step here is one `fetch_add` whose result
//! is reduced modulo `bound + 1` — still one atomic operation, under any interleaving.
//!
//! **What it does on overflow.** With `bound = capacity − 1`, the common way to keep the index in
//! bounds, the `capacity + 1`-th fragment of a pixel gets slot 0 again and its plain store
//! overwrites the first one: no fragment is ever dropped, none is counted, and the counter the
//! post pass reads holds `n mod capacity`, so it even reads fewer slots than were written. A pixel
//! of depth complexity `n > capacity` keeps `n mod capacity` fragments, silently: the
//! overflow it reports is 0. With `bound ≥ n − 1` it never wraps and behaves as the fixed
//! A-buffer, dropping and counting what does not fit.
//!
//! Not in the CLI's scheme registry on purpose: it exists to be compared with the A-buffer in
//! tests (`tests/suite/extremes/`, counters) and in `docs/extremes.md`, not to be used.
//!
//! Unlike the GPU, the counter word holds the unwrapped count (there is no wrapping RMW in
//! [`Memory`]); every reader reduces it modulo `bound + 1`, which is what `atomicInc` would have
//! left in the word.

use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::abuffer::{ABuffer, Claim, PostSort};
use crate::common::sort::insertion_sort;
use fragsim_capture::{CaptureError, Descriptor, Scheme, Step};

/// An A-buffer with `capacity` slots per pixel whose slot counter is CUDA's wrapping `atomicInc`.
#[derive(Clone, Debug)]
pub struct ABufferAtomicInc {
    descriptor: Descriptor,
    capacity: usize,
    bound: u32,
}

/// CUDA's `atomicInc` as seen through `fetch_add`: the value `atomicInc(addr, bound)` returns
/// (and leaves) when `fetch_add` on the same word returns (or leaves) `count`.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the remainder is at most bound, a u32"
)]
pub fn wrap(count: u32, bound: u32) -> u32 {
    (u64::from(count) % (u64::from(bound) + 1)) as u32
}

impl ABufferAtomicInc {
    /// `capacity` slots per pixel; the counter wraps to 0 past `bound`.
    ///
    /// # Errors
    /// `capacity == 0`, or storage beyond `memory_cap` bytes.
    pub fn new(
        viewport: Viewport,
        capacity: u32,
        bound: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        // The fixed A-buffer's storage, identity, guarantee and promise (its parameter check
        // too); only the name and the drops differ: a wrapped counter overwrites a slot, and no
        // walk counts what it overwrote.
        let abuffer = ABuffer::fixed(viewport, capacity, PostSort::Insertion, u64::MAX)?;
        let descriptor = Descriptor {
            name: format!("abuffer-atomicinc-{bound}"),
            counts_every_drop: false,
            ..abuffer.descriptor().clone()
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            capacity: capacity as usize,
            bound,
        })
    }

    /// The usual GPU choice: `bound = capacity − 1`, so that the slot index never leaves the
    /// pixel's storage (and wraps onto its first slots instead).
    ///
    /// # Errors
    /// As [`ABufferAtomicInc::new`].
    pub fn wrapping(
        viewport: Viewport,
        capacity: u32,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        Self::new(viewport, capacity, capacity.saturating_sub(1), memory_cap)
    }
}

impl Scheme for ABufferAtomicInc {
    type State = Claim;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Claim {
        Claim::Count {
            pixel: fragment.pixel,
            value: fragment.packed(),
        }
    }

    fn step<M: Memory>(&self, claim: &mut Claim, memory: &M) -> Step {
        match *claim {
            Claim::Count { pixel, value } => {
                // `slot = atomicInc(&counter[pixel], bound)`.
                let counted = WordMemory::<u32>::fetch_add(memory, pixel as usize, 1);
                let slot = wrap(counted, self.bound) as usize;
                if slot < self.capacity {
                    *claim = Claim::Write {
                        slot: pixel as usize * self.capacity + slot,
                        value,
                    };
                    Step::Continue
                } else {
                    Step::Dropped
                }
            }
            Claim::Write { slot, value } => {
                WordMemory::<u64>::store(memory, slot, value);
                Step::Stored
            }
        }
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "count is the pixel's u32 counter word"
    )]
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // What the GPU's post pass reads: the wrapped counter.
        let count = wrap(WordMemory::<u32>::load(memory, pixel), self.bound) as usize;
        let stored = count.min(self.capacity);
        let first = pixel * self.capacity;
        let start = out.len();
        out.extend((0..stored).map(|i| WordMemory::<u64>::load(memory, first + i)));
        insertion_sort(&mut out[start..]);
        (count - stored) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::abuffer::{ABuffer, PostSort};
    use fragsim_capture::{Keeps, MEMORY_CAP_DEFAULT};
    use fragsim_memory::SerialMemory;

    /// `n` fragments on one pixel, depths ascending, inserted in order; the kept list, the
    /// reported overflow and the walks that ended in a drop.
    fn one_pixel<S: Scheme<Input = Fragment>>(scheme: &S, n: u32) -> (Vec<u64>, u32, u32) {
        let memory: SerialMemory = scheme.layout().allocate();
        let (mut steps, mut dropped) = (0, 0);
        for prim in 0..n {
            let fragment = Fragment {
                pixel: 0,
                depth_key: prim,
                prim,
            };
            if scheme.insert(fragment, &memory, &mut steps) == Step::Dropped {
                dropped += 1;
            }
        }
        let capture = scheme.resolve(&memory);
        let Keeps::All { overflow, .. } = &capture.keeps else {
            unreachable!("both promise every fragment")
        };
        (capture.pixel(0).to_vec(), overflow[0], dropped)
    }

    #[test]
    fn wrap_is_atomic_inc_from_zero() {
        let mut word = 0_u32;
        for count in 0..50 {
            // CUDA: old = *addr; *addr = old >= bound ? 0 : old + 1.
            assert_eq!(wrap(count, 7), word);
            word = if word >= 7 { 0 } else { word + 1 };
        }
        assert_eq!(wrap(u32::MAX, u32::MAX), u32::MAX);
        assert_eq!(wrap(5, 0), 0);
    }

    #[test]
    fn within_capacity_atomic_inc_and_fetch_add_agree() {
        let viewport = Viewport::new(1, 1).unwrap();
        let inc = ABufferAtomicInc::wrapping(viewport, 8, MEMORY_CAP_DEFAULT).unwrap();
        let add = ABuffer::fixed(viewport, 8, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        assert_eq!(one_pixel(&inc, 7), one_pixel(&add, 7));
        assert_eq!(one_pixel(&inc, 7).0.len(), 7);
    }

    #[test]
    #[expect(
        clippy::cast_possible_truncation,
        clippy::shadow_unrelated,
        reason = "the test reads back the low word, a primitive id, of each kept slot; each `one_pixel` call's results are its own case's"
    )]
    fn past_capacity_atomic_inc_overwrites_silently_and_fetch_add_counts_the_drop() {
        let viewport = Viewport::new(1, 1).unwrap();
        let inc = ABufferAtomicInc::wrapping(viewport, 8, MEMORY_CAP_DEFAULT).unwrap();
        let add = ABuffer::fixed(viewport, 8, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        // 8 + 3 fragments: atomicInc hands out slots 0..7, then 0, 1, 2 again.
        let (kept, overflow, dropped) = one_pixel(&inc, 11);
        assert_eq!((kept.len(), overflow, dropped), (3, 0, 0), "{kept:x?}");
        // The three it reads are the overwriting fragments 8, 9, 10; 0..8 are gone unreported.
        assert_eq!(
            kept.iter().map(|w| *w as u32).collect::<Vec<_>>(),
            [8, 9, 10]
        );
        let (kept, overflow, dropped) = one_pixel(&add, 11);
        assert_eq!((kept.len(), overflow, dropped), (8, 3, 3));
        // A multiple of the capacity wraps the counter to 0: nothing is read at all.
        assert_eq!(one_pixel(&inc, 16), (Vec::new(), 0, 0));
    }

    #[test]
    fn a_bound_above_the_depth_complexity_never_wraps_and_drops_as_fetch_add() {
        let viewport = Viewport::new(1, 1).unwrap();
        let inc = ABufferAtomicInc::new(viewport, 8, u32::MAX, MEMORY_CAP_DEFAULT).unwrap();
        let add = ABuffer::fixed(viewport, 8, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
        assert_eq!(one_pixel(&inc, 20), one_pixel(&add, 20));
        assert!(ABufferAtomicInc::wrapping(viewport, 0, MEMORY_CAP_DEFAULT).is_err());
        let least = inc.layout().least_bytes();
        assert!(ABufferAtomicInc::wrapping(viewport, 8, least - 1).is_err());
        assert!(ABufferAtomicInc::wrapping(viewport, 8, least).is_ok());
    }
}
