//! The A-buffer scheme (ABS): FreePipe (Liu et al., I3D 2010) §4.2, after Carpenter 1984.
//!
//! **Algorithm.** Each pixel owns a counter (initially 0) and a run of slots. A fragment takes a
//! slot with `k = atomicInc(&counter, …)` (here `fetch_add(1)`: CUDA's `atomicInc` is the same
//! until it wraps at its bound) and writes itself into slot `k` with a plain store: two steps, two
//! memory operations. A post pass, one pixel at a time, sorts each list by insertion sort or by a
//! bitonic network (the paper names both); both give the canonical order.
//!
//! **Guarantee.** Fetch-and-add hands out distinct slot numbers under any interleaving, so no two
//! fragments write one slot and no write is lost: every fragment is captured, exactly, as long as
//! storage suffices. A fragment whose slot number is past the pixel's capacity is dropped and
//! counted: the counter keeps counting, so `counter − capacity` is the pixel's overflow, read by
//! the post pass and reported (never a write out of bounds). One geometry pass; memory: one
//! counter per pixel plus the slots.
//!
//! **Storage.** Either a fixed capacity per pixel (`abuffer`: FreePipe's layout, "a fixed size
//! struct array per pixel", §4.2, 20 slots in Table 3; guarantee
//! [`Guarantee::ExactWithinCapacity`]) or *exact* (`abuffer-exact`): sized by the scheme's own
//! counting pass ([`fragsim_capture::depth_count`], one `fetch_add` per fragment) into one flat array indexed
//! by the prefix sum of the counts, with no padding. The exact variant is two geometry passes, and
//! its rows say so; FreePipe's scheme is one.
//!
//! Unlike CUDA's `atomicInc(addr, bound)`, which wraps to 0 past `bound` and so would overwrite
//! slot 0, the counter here never wraps: a pixel receives at most one fragment per triangle and a
//! view has fewer than 2^32 triangles.

use fragsim_memory::{Layout, Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::common::sort::{bitonic_sort, insertion_sort};
use fragsim_capture::Guarantee;
use fragsim_capture::{Capacity, Identity};
use fragsim_capture::{
    CaptureError, Descriptor, PixelRun, Promise, Scheme, Step, MEMORY_CAP_DEFAULT,
};

/// The post pass's sort.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PostSort {
    /// Insertion sort: quadratic, the best for the short lists of most pixels.
    #[default]
    Insertion,
    /// A bitonic sorting network over the list padded to a power of two.
    Bitonic,
}

/// The A-buffer scheme.
#[derive(Clone, Debug)]
pub struct ABuffer {
    descriptor: Descriptor,
    storage: Storage,
    sort: PostSort,
}

/// Where each pixel's slots are.
#[derive(Clone, Debug)]
enum Storage {
    /// `capacity` slots per pixel, pixel `p`'s starting at `p * capacity`.
    Fixed { capacity: usize },
    /// `offsets[p]..offsets[p + 1]` are pixel `p`'s slots.
    Exact { offsets: Vec<usize> },
}

/// A fragment's progress: take a slot, then write it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Claim {
    /// Before the `fetch_add` on the pixel's counter.
    Count {
        /// The pixel.
        pixel: u32,
        /// The value to store.
        value: u64,
    },
    /// Slot taken; the store is next.
    Write {
        /// The slot.
        slot: usize,
        /// The value to store.
        value: u64,
    },
}

impl ABuffer {
    /// `capacity` slots for every pixel.
    ///
    /// # Errors
    /// `capacity == 0`, or storage beyond `memory_cap` bytes.
    pub fn fixed(
        viewport: Viewport,
        capacity: u32,
        sort: PostSort,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        if capacity == 0 {
            return Err(CaptureError::BadParameter(
                "the A-buffer needs a capacity of at least 1 slot per pixel".into(),
            ));
        }
        let storage = Storage::Fixed {
            capacity: capacity as usize,
        };
        Self::on(storage, viewport.pixels(), sort, memory_cap)
    }

    /// Exactly `counts[p]` slots for pixel `p` (the counts of a counting pass), in one flat array.
    ///
    /// # Errors
    /// Storage beyond `memory_cap` bytes.
    pub fn exact(counts: &[u32], sort: PostSort, memory_cap: u64) -> Result<Self, CaptureError> {
        let mut offsets = Vec::with_capacity(counts.len() + 1);
        let mut total = 0_usize;
        offsets.push(0);
        for &c in counts {
            total += c as usize;
            offsets.push(total);
        }
        Self::on(Storage::Exact { offsets }, counts.len(), sort, memory_cap)
    }

    /// The A-buffer on `storage` for `pixels` pixels, sorted by `sort`, within `memory_cap`
    /// bytes.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a fixed capacity is given as a u32 (ABuffer::fixed)"
    )]
    fn on(
        storage: Storage,
        pixels: usize,
        sort: PostSort,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let sort_name = match sort {
            PostSort::Insertion => "",
            PostSort::Bitonic => "-bitonic",
        };
        // FreePipe's A-buffer is the fixed-array one; exact storage is the variant.
        let (storage_name, slots, table_bytes, guarantee, capacity) = match &storage {
            Storage::Fixed { capacity } => (
                "",
                pixels * capacity,
                0,
                Guarantee::ExactWithinCapacity(*capacity as u32),
                Capacity::PerPixel(*capacity as u32),
            ),
            // A GPU would keep 32-bit offsets: that is what is counted.
            Storage::Exact { offsets } => (
                "-exact",
                offsets[offsets.len() - 1],
                offsets.len() * 4,
                Guarantee::Exact,
                Capacity::Unbounded,
            ),
        };
        let descriptor = Descriptor {
            name: format!("abuffer{storage_name}{sort_name}"),
            layout: Layout {
                table_bytes,
                ..Layout::counters_and_slots(pixels, slots)
            },
            identity: Identity::KeyAndPrim,
            guarantee,
            promise: Promise::All(capacity),
            pixels,
            counts_every_drop: true,
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            storage,
            sort,
        })
    }

    /// Like [`ABuffer::exact`] with insertion sort and the default cap.
    ///
    /// # Errors
    /// As [`ABuffer::exact`].
    pub fn exact_default(counts: &[u32]) -> Result<Self, CaptureError> {
        Self::exact(counts, PostSort::Insertion, MEMORY_CAP_DEFAULT)
    }

    /// The first slot of `pixel` and how many it has.
    #[inline]
    fn slots(&self, pixel: usize) -> (usize, usize) {
        match &self.storage {
            Storage::Fixed { capacity, .. } => (pixel * capacity, *capacity),
            Storage::Exact { offsets } => (offsets[pixel], offsets[pixel + 1] - offsets[pixel]),
        }
    }
}

impl Scheme for ABuffer {
    type State = Claim;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn tile_local(&self) -> bool {
        // Fixed arrays: a counter at `pixel`, `capacity` slots at `pixel · capacity`. Storage
        // sized exactly finds a pixel's slots through offsets in screen order.
        matches!(self.storage, Storage::Fixed { .. })
    }

    fn begin(&self, fragment: Fragment) -> Claim {
        Claim::Count {
            pixel: fragment.pixel,
            value: fragment.packed(),
        }
    }

    fn prefetch<M: Memory>(&self, fragment: Fragment, memory: &M) {
        let pixel = fragment.pixel as usize;
        WordMemory::<u32>::prefetch(memory, pixel);
        WordMemory::<u64>::prefetch(memory, self.slots(pixel).0);
    }

    fn step<M: Memory>(&self, claim: &mut Claim, memory: &M) -> Step {
        match *claim {
            Claim::Count { pixel, value } => {
                let taken = WordMemory::<u32>::fetch_add(memory, pixel as usize, 1) as usize;
                let (first, capacity) = self.slots(pixel as usize);
                if taken < capacity {
                    *claim = Claim::Write {
                        slot: first + taken,
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

    fn pixel_run<M: Memory>(&self, memory: &M, pixel: usize, end: usize) -> PixelRun {
        // A counter no write reached is still 0: no list, no overflow.
        PixelRun::of_first_words::<u32, _>(memory, pixel, end, 1)
    }

    #[expect(
        clippy::cast_possible_truncation,
        reason = "count is the pixel's u32 counter word"
    )]
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        let count = WordMemory::<u32>::load(memory, pixel) as usize;
        if count == 0 {
            // Most pixels of a written block of counters (64 pixels) are empty: their slots'
            // pages are not looked up.
            return 0;
        }
        let (first, capacity) = self.slots(pixel);
        let stored = count.min(capacity);
        let start = out.len();
        WordMemory::<u64>::load_into(memory, first, stored, out);
        let list = &mut out[start..];
        match self.sort {
            PostSort::Insertion => insertion_sort(list),
            PostSort::Bitonic => bitonic_sort(list),
        }
        (count - stored) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_sorts_sort() {
        let mut rng = fragsim_raster::SplitMix64::new(7);
        for len in 0..40 {
            let list: Vec<u64> = (0..len).map(|_| rng.next_u64() % 50).collect();
            let mut expected = list.clone();
            expected.sort_unstable();
            let (mut a, mut b) = (list.clone(), list);
            insertion_sort(&mut a);
            bitonic_sort(&mut b);
            assert_eq!(a, expected);
            assert_eq!(b, expected);
        }
    }
}
