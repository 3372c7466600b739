//! The k-buffer inside an **ordered** fragment-shader-interlock critical section: Vulkan's
//! `VK_EXT_fragment_shader_interlock` in its ordered mode (`PixelInterlockOrderedEXT`), Direct3D's
//! rasterizer-ordered views (ROVs), Metal's raster order groups: a pixel's critical sections run
//! one at a time **in primitive order**.
//!
//! **Algorithm.** As the unordered interlock
//! ([`kbuffer::interlock`](crate::kbuffer::interlock)): each pixel owns `K` slots; a
//! fragment's critical section reads them, inserts itself in registers and writes them back, one
//! step. What is added is the order: a fragment enters only once every fragment of its pixel
//! submitted before it has left its section. Each pixel counts the sections that have left
//! (`done`); a fragment of rank `r` (the number of its pixel's fragments submitted before it,
//! [`PrimitiveOrder::rank`]) takes the pixel's lock, reads `done`, and if `done ≠ r` frees the
//! lock and tries again later (a spin: one step, no progress, [`Simt::spinning`]); if `done = r`
//! it runs the section and stores `done = r + 1` before freeing the lock. Two policies
//! ([`Keep`]): the `K` nearest (the k-buffer's insertion), and keep-first (a full pixel drops the
//! newcomer, the policy of the layer counter and of keep-first linked lists).
//!
//! **Guarantee.** [`Keep::Nearest`]: exact under any interleaving, [`Guarantee::Exact`],
//! [`Promise::Nearest`]`(K)`, for the unordered interlock's reason (every section is one
//! fragment's sorted insertion into the slots, the lock making it indivisible). [`Keep::First`]:
//! each pixel keeps the first `K` of its fragments **in submission order**, sorted, and drops the
//! rest, on every executor and under every interleaving: the sections run in rank order, so the
//! slots after section `r` depend on ranks `0..=r` only. The catalog judges it as the layer
//! counter is judged ([`Guarantee::ExactWithinCapacity`]`(K)`, [`Capacity::PerPixelUncounted`]:
//! exact while a pixel has at most `K` fragments, exactly `max(0, n − K)` missing beyond), and
//! `tests/suite/interlock_ordered.rs` checks the stronger claim, that the lists are the first `K`
//! submitted, identical on every executor and schedule, where the same policy without the order
//! (an unordered interlock) keeps whichever `K` arrived first. A different submission order
//! (`--shuffle`) keeps different fragments: keep-first is deterministic, not order independent.
//!
//! **Why no executor deadlocks.** A fragment waits only for fragments of its pixel submitted
//! before it. The serial and tiled executors run a pixel's fragments in submission order, so
//! none ever waits. The scheduled executor starts fragments in submission order, so the earliest
//! unfinished fragment is in flight and can always enter. The parallel executor hands rayon
//! triangles by submission index; each task runs its range in increasing order, and a thread
//! blocked in a spin holds in its deque only ranges after the fragment it spins on, so the
//! earliest unfinished fragment is always being run by a thread that is not blocked. A spin
//! holds the lock for one load only, never across steps.
//!
//! **Cost.** One geometry pass; 1 step per fragment when it need not wait (the critical
//! section), plus 1 per failed attempt; 1 locked operation per attempt. Memory: `8 K + 8` bytes
//! per pixel (the slots, the lock and `done`). A GPU's ordered interlock costs no memory; it
//! stalls a fragment until its predecessors leave, the waiting counted here as spins.
//!
//! **Sources.** The `VK_EXT_fragment_shader_interlock` specification (Khronos, 2019): "ordered"
//! critical sections execute "in primitive order" per pixel; D3D12 rasterizer-ordered views
//! (Microsoft, 2015); nvpro-samples' `vk_order_independent_transparency` (NVIDIA, 2020), whose
//! interlock mode this is with the ordered execution mode.
//!
//! **Departures.** The hardware knows each fragment's place in primitive order because it
//! rasterizes in order; the executors here may not, so the order is recorded before the frame
//! ([`PrimitiveOrder::of_view`], the catalog does it) and handed to the scheme. A scheme built
//! without one (a dump being read back, a bare fragment stream), or a fragment the order does not
//! hold, enters as soon as the lock is free: the unordered interlock. Primitive order is
//! submission order ([`View::submitted`](fragsim_raster::View::submitted)), which is primitive id
//! order unless the view is shuffled. As in the k-buffer, a slot is one `u64`
//! `depth_key << 32 | prim`.

use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{Fragment, Viewport};

use crate::kbuffer::interlock::section;
pub use crate::kbuffer::interlock::Keep;
use crate::kbuffer::{Insert, Slots, WriteBack};
use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_capture::Capacity;
use fragsim_capture::Guarantee;
use fragsim_capture::Simt;
use fragsim_capture::{CaptureError, Descriptor, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};

/// The k-buffer whose critical sections run one at a time per pixel, in primitive order.
#[derive(Clone, Debug)]
pub struct KBufferInterlockOrdered<'o> {
    descriptor: Descriptor,
    slots: Slots,
    keep: Keep,
    order: Option<&'o PrimitiveOrder>,
}

/// A fragment's walk: its insertion and its place in its pixel's order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Ordered {
    /// The k-buffer's read–insert–write state.
    pub insert: Insert,
    /// The sections of the pixel that must leave before this one enters; `None`: it enters as
    /// soon as the lock is free.
    pub rank: Option<u32>,
    /// The last attempt found an earlier fragment still to come: the next step retries.
    pub waiting: bool,
}

impl<'o> KBufferInterlockOrdered<'o> {
    /// The ordered interlock with `k` slots per pixel keeping `keep`, its sections in `order`
    /// (`None`: arrival order, the unordered interlock), within `memory_cap` bytes.
    ///
    /// # Errors
    /// `k == 0`, or storage beyond `memory_cap`.
    pub fn new(
        viewport: Viewport,
        k: u32,
        keep: Keep,
        order: Option<&'o PrimitiveOrder>,
        memory_cap: u64,
    ) -> Result<Self, CaptureError> {
        let slots = Slots::new(Self::name_of(keep), k, WriteBack::RenderTarget)?;
        let pixels = viewport.pixels();
        let (guarantee, promise) = match keep {
            Keep::Nearest => (Guarantee::Exact, Promise::Nearest(k)),
            // What is dropped is not in memory: the oracle supplies the count.
            Keep::First => (
                Guarantee::ExactWithinCapacity(k),
                Promise::All(Capacity::PerPixelUncounted(k)),
            ),
        };
        let descriptor = Descriptor {
            promise,
            // `u32` words `2 p` (pixel `p`'s lock) and `2 p + 1` (its sections done).
            ..slots.descriptor(Self::name_of(keep).into(), pixels, 2 * pixels, guarantee)
        };
        Ok(Self {
            descriptor: descriptor.within(memory_cap)?,
            slots,
            keep,
            order,
        })
    }

    /// Like [`KBufferInterlockOrdered::new`] with the default memory cap.
    ///
    /// # Errors
    /// As [`KBufferInterlockOrdered::new`].
    pub fn with_k(
        viewport: Viewport,
        k: u32,
        keep: Keep,
        order: Option<&'o PrimitiveOrder>,
    ) -> Result<Self, CaptureError> {
        Self::new(viewport, k, keep, order, MEMORY_CAP_DEFAULT)
    }

    /// The catalog's name of the policy.
    fn name_of(keep: Keep) -> &'static str {
        match keep {
            Keep::Nearest => "kbuffer-interlock-ordered",
            Keep::First => "kbuffer-interlock-ordered-first",
        }
    }
}

impl Scheme for KBufferInterlockOrdered<'_> {
    type State = Ordered;
    type Input = Fragment;

    fn descriptor(&self) -> &Descriptor {
        &self.descriptor
    }

    fn begin(&self, fragment: Fragment) -> Ordered {
        Ordered {
            insert: self.slots.begin(fragment),
            rank: self.order.and_then(|order| order.rank(fragment)),
            waiting: false,
        }
    }

    /// One attempt: lock, and either (an earlier fragment still to come) unlock, or the whole
    /// critical section, `done` advanced, unlock.
    fn step<M: Memory>(&self, walk: &mut Ordered, memory: &M) -> Step {
        let pixel = walk.insert.base / self.slots.k as usize;
        let (lock, done) = (2 * pixel, 2 * pixel + 1);
        memory.lock(lock);
        if let Some(rank) = walk.rank {
            walk.waiting = WordMemory::<u32>::load(memory, done) != rank;
            if walk.waiting {
                memory.unlock(lock);
                return Step::Continue;
            }
            WordMemory::<u32>::store(memory, done, rank + 1);
        }
        let end = section(self.slots, self.keep, &mut walk.insert, memory);
        memory.unlock(lock);
        end
    }

    fn simt(&self, walk: &Ordered) -> Simt {
        Simt {
            spinning: walk.waiting,
            reconverging: false,
        }
    }

    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        // Already in canonical order: every section leaves the slots sorted.
        self.slots.resolve_pixel(memory, pixel, out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::common::one_pixel::{fragment, one_pixel};
    use fragsim_capture::executors::scheduled::run_fragments_in_order;
    use fragsim_memory::SerialMemory;

    /// A later fragment that arrives first waits (one step each attempt, nothing written) until
    /// the earlier one has left; then it enters.
    #[test]
    fn a_fragment_waits_for_the_fragments_submitted_before_it() {
        let stream = [fragment(5, 0), fragment(3, 1)];
        let order = PrimitiveOrder::of_fragments(1, &stream);
        let scheme =
            KBufferInterlockOrdered::with_k(one_pixel(), 1, Keep::First, Some(&order)).unwrap();
        let memory: SerialMemory = scheme.layout().allocate();
        let mut late = scheme.begin(stream[1]);
        assert_eq!(scheme.step(&mut late, &memory), Step::Continue);
        assert!(scheme.simt(&late).spinning);
        assert_eq!(scheme.resolve(&memory).pixel(0), &[] as &[u64]);
        let mut early = scheme.begin(stream[0]);
        assert_eq!(scheme.step(&mut early, &memory), Step::Stored);
        // Keep-first, K = 1: the earlier one is kept although the later is nearer.
        assert_eq!(scheme.step(&mut late, &memory), Step::Dropped);
        assert!(!scheme.simt(&late).spinning);
        assert_eq!(scheme.resolve(&memory).pixel(0), &[stream[0].packed()]);
        // Both locks free, two sections done.
        assert_eq!(WordMemory::<u32>::load(&memory, 0), 0);
        assert_eq!(WordMemory::<u32>::load(&memory, 1), 2);
    }

    /// Every order of three fragments' attempts: keep-first with the order keeps the first two
    /// submitted; without it, the first two to arrive.
    #[test]
    fn keep_first_keeps_the_first_submitted_in_every_arrival_order_only_with_the_order() {
        let stream = [fragment(7, 0), fragment(2, 1), fragment(9, 2)];
        let order = PrimitiveOrder::of_fragments(1, &stream);
        let ordered =
            KBufferInterlockOrdered::with_k(one_pixel(), 2, Keep::First, Some(&order)).unwrap();
        let unordered = KBufferInterlockOrdered::with_k(one_pixel(), 2, Keep::First, None).unwrap();
        let first_two = [stream[1].packed(), stream[0].packed()];
        let mut differ = 0;
        for arrival in [[0, 1, 2], [2, 1, 0], [1, 2, 0], [2, 0, 1]] {
            // Attempts in `arrival` order, repeated until every walk is done (a waiting walk's
            // failed attempt leaves it in place).
            let schedule: Vec<u32> = arrival.iter().copied().cycle().take(9).collect();
            let run = run_fragments_in_order(&ordered, &stream, &schedule, false);
            assert_eq!(
                run.run.capture.pixel(0),
                first_two.as_slice(),
                "{arrival:?}"
            );
            assert_eq!(run.run.stats.counters.dropped, 1, "{arrival:?}");
            #[expect(clippy::shadow_unrelated, reason = "the next run of the same test")]
            let run = run_fragments_in_order(&unordered, &stream, &arrival, false);
            differ += usize::from(run.run.capture.pixel(0) != first_two.as_slice());
        }
        assert!(
            differ > 0,
            "the unordered control kept the first submitted too"
        );
    }

    #[test]
    fn k_zero_and_storage_beyond_the_cap_are_refused_by_name() {
        let zero = KBufferInterlockOrdered::with_k(one_pixel(), 0, Keep::First, None).unwrap_err();
        assert!(
            zero.to_string().contains("kbuffer-interlock-ordered-first"),
            "{zero}"
        );
        // What is allocated before any fragment (the page tables of its words) is checked
        // when the scheme is built; its pages as a frame writes them.
        let least = KBufferInterlockOrdered::new(one_pixel(), 4, Keep::Nearest, None, u64::MAX)
            .unwrap()
            .layout()
            .least_bytes();
        let capped = KBufferInterlockOrdered::new(one_pixel(), 4, Keep::Nearest, None, least - 1)
            .unwrap_err();
        assert!(
            matches!(capped, CaptureError::TooMuchMemory { needed, .. } if needed == least),
            "{capped:?}"
        );
    }
}
