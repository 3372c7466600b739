//! The simulated GPU's memory: the per-pixel words the capture schemes work on, the only place
//! that knows which atomic type is underneath.
//!
//! - **Words.** Schemes see per-pixel storage as two flat arrays of words, one of `u32` and one of
//!   `u64` ([`Word`]), sized and initialised by a [`Layout`] (how many words of each width, and
//!   their initial values).
//! - **Operations.** [`WordMemory`] has seven: the atomics CUDA offers on global memory
//!   (`atomicMin`, `atomicMax`, `atomicAdd`, `atomicOr`, `atomicExch`) plus plain loads and
//!   stores. Every operation is one step of a scheme's state machine. [`Memory`] is both arrays,
//!   with a spin lock on a `u32` word for the steps a GPU performs as one (a render target's
//!   read or write of a pixel's slots).
//! - **Orderings.** Unlike the GPU, the atomic implementation uses `Relaxed` ordering: the
//!   schemes' guarantees need only per-location atomicity (a total order of the
//!   read-modify-writes on each word), and the end of a pass, a thread join, publishes everything
//!   (the proof is in `docs/proof.md`, loom checks it). The lock alone fences: acquire after
//!   taking it, release before freeing it.
//! - **The memories.** [`SerialMemory`] (plain cells, one thread: the serial executor's),
//!   [`AtomicMemory`] (std atomics, shared by threads: the parallel and tiled executors'),
//!   [`CountingMemory`] (any memory, its read-modify-writes counted: the locked instructions
//!   `fragsim bench` reports) and [`RecordingMemory`] (the serial memory with a log of every
//!   operation as a [`TraceEvent`]: the scheduled executor's traces). The loom suite
//!   (`tests/loom/`) puts loom's atomics behind the same traits.
//! - **Pages and budget.** The serial and atomic memories allocate their words a page of
//!   [`PAGE_WORDS`] at a time, on the first write that reaches a page (`pages.rs`), within a
//!   byte cap set by the executor ([`SerialMemory::reset`]): storage, its reset and the post
//!   pass then follow the pixels the fragments reach, not viewport × K. A write the cap refuses
//!   goes to a scratch page and the frame is reported over the cap ([`Memory::over_cap`]). That
//!   bookkeeping is no memory operation of the simulated GPU: it costs a load of the page's entry
//!   and of its written flag beside each operation, and the first write to a page its allocation.
//!
//! The crate needs nothing of the schemes or the executors (`fragsim-capture`), which are built
//! on it: it sits below them as `crossbeam-utils` below `crossbeam`.

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

use std::fmt::Debug;

mod counting;
mod layout;
mod pages;
mod recording;
mod serial_atomic;

pub use counting::CountingMemory;
pub use layout::Layout;
pub use pages::PAGE_WORDS;
pub use recording::{Op, RecordingMemory, TraceEvent};
pub use serial_atomic::{AtomicMemory, SerialMemory};

/// A memory word: `u32` or `u64`.
pub trait Word: Copy + Eq + Ord + Debug + Send + Sync + 'static {
    /// The all-zero word.
    const ZERO: Self;
    /// The all-ones word.
    const MAX: Self;
    /// The word 1.
    const ONE: Self;
    /// Wrapping addition, as the hardware adds.
    fn wrapping_add(self, other: Self) -> Self;
    /// Wrapping subtraction.
    fn wrapping_sub(self, other: Self) -> Self;
}

impl Word for u32 {
    const ZERO: Self = 0;
    const MAX: Self = Self::MAX;
    const ONE: Self = 1;
    fn wrapping_add(self, other: Self) -> Self {
        Self::wrapping_add(self, other)
    }
    fn wrapping_sub(self, other: Self) -> Self {
        Self::wrapping_sub(self, other)
    }
}

impl Word for u64 {
    const ZERO: Self = 0;
    const MAX: Self = Self::MAX;
    const ONE: Self = 1;
    fn wrapping_add(self, other: Self) -> Self {
        Self::wrapping_add(self, other)
    }
    fn wrapping_sub(self, other: Self) -> Self {
        Self::wrapping_sub(self, other)
    }
}

/// The operations on one array of words. Each read-modify-write returns the old value.
pub trait WordMemory<W: Word> {
    /// Number of words.
    fn len(&self) -> usize;
    /// Whether there are no words.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Plain load.
    fn load(&self, index: usize) -> W;
    /// Plain store.
    fn store(&self, index: usize, value: W);
    /// `atomicMin`.
    fn fetch_min(&self, index: usize, value: W) -> W;
    /// `atomicMax`.
    fn fetch_max(&self, index: usize, value: W) -> W;
    /// `atomicAdd` (wrapping).
    fn fetch_add(&self, index: usize, value: W) -> W;
    /// `atomicOr`.
    fn fetch_or(&self, index: usize, value: W) -> W;
    /// `atomicExch` (`imageAtomicExchange`): stores `value`, returns the old value.
    fn swap(&self, index: usize, value: W) -> W;
    /// Whether word `index` is known to hold its initial value, no write having reached its
    /// page since the storage was allocated or reset: a hint for post passes, which may skip
    /// such words. `false` is always a correct answer, and the default; it is no memory
    /// operation and no step.
    fn untouched(&self, index: usize) -> bool {
        let _ = index;
        false
    }
    /// How many words from `index` on, up to `end`, are known to hold their initial value as
    /// [`WordMemory::untouched`] knows it, found in bulk (a page's written flags at a time): what
    /// lets a post pass skip the empty parts of a frame without visiting each pixel. 0 is always
    /// a correct answer, and the default; it is no memory operation and no step.
    fn untouched_run(&self, index: usize, end: usize) -> usize {
        let _ = (index, end);
        0
    }
    /// How many words from `index` on, up to `end`, lie in the run of blocks written since the
    /// storage was allocated or reset that holds `index`: words a post pass is to read, found in
    /// bulk, so that it asks again only after them. Every word up to `end`, the default, is
    /// always a correct answer; it is no memory operation and no step.
    fn written_run(&self, index: usize, end: usize) -> usize {
        end.saturating_sub(index)
    }
    /// Loads word `index` ahead of the walk that will operate on it, its value unused, so that
    /// its cache miss overlaps other work instead of stalling that walk's read-modify-write (a
    /// locked instruction waits for its line, and so does everything after it). Not a memory
    /// operation of the GPU: nothing is counted or recorded, no value changes, and doing nothing,
    /// the default, is always correct.
    fn prefetch(&self, index: usize) {
        let _ = index;
    }
    /// Runs `visitor` on words `start..start + len`, handing it either this memory or a view of
    /// the one page that holds those words, whose operations find no page each: the same
    /// operations on the same words, with the same results, found once (a fragment's walk of a
    /// pixel's slots, a pixel's list read back). Indices stay those of the whole array, and the
    /// visitor is to use no word outside the span. The default hands it this memory.
    fn with_span<V: SpanVisitor<W>>(&self, start: usize, len: usize, visitor: V) -> V::Output
    where
        Self: Sized,
    {
        let _ = (start, len);
        visitor.visit(self)
    }
    /// Appends words `start..start + len` to `out`, in order: `len` loads, their page found once
    /// where one page holds them ([`WordMemory::with_span`]).
    fn load_into(&self, start: usize, len: usize, out: &mut Vec<W>)
    where
        Self: Sized,
    {
        self.with_span(start, len, LoadInto { start, len, out });
    }
}

/// What runs on a span of words ([`WordMemory::with_span`]), generic over the words it is handed.
pub trait SpanVisitor<W: Word> {
    /// What the visit returns.
    type Output;
    /// Runs on `words`, using only the span's words.
    fn visit<A: WordMemory<W>>(self, words: &A) -> Self::Output;
}

/// [`WordMemory::load_into`]'s visit.
struct LoadInto<'a, W> {
    start: usize,
    len: usize,
    out: &'a mut Vec<W>,
}

impl<W: Word> SpanVisitor<W> for LoadInto<'_, W> {
    type Output = ();
    fn visit<A: WordMemory<W>>(self, words: &A) {
        self.out
            .extend((self.start..self.start + self.len).map(|i| words.load(i)));
    }
}

/// Per-pixel storage: a `u32` array and a `u64` array.
pub trait Memory: WordMemory<u32> + WordMemory<u64> {
    /// Storage with `len32` words of `init32` and `len64` words of `init64`.
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self
    where
        Self: Sized;

    /// Bytes of storage actually allocated, where the memory allocates as it is written
    /// (`pages.rs`); `None` for a memory that holds every word of its layout.
    fn allocated_bytes(&self) -> Option<u64> {
        None
    }

    /// Whether a write found no storage within the cap since the last reset: the frame is to be
    /// reported over the cap, its words not used.
    fn over_cap(&self) -> bool {
        false
    }

    /// Takes the spin lock held in `u32` word `index` (0 free, 1 held), waiting while another
    /// thread holds it; everything the previous holder did before its [`Memory::unlock`] is
    /// visible after this returns.
    ///
    /// A scheme uses it to make one step of several words indivisible: a render target's read or
    /// write of a pixel's `K` slots, which the GPU's ROP performs as one operation
    /// (the k-buffer's `WriteBack::RenderTarget`, in `fragsim-schemes`). The words themselves
    /// stay `Relaxed`: the ordering comes from the fences around the lock word's `swap` and
    /// `store` (C++ fence–fence synchronisation: a release fence before the store that frees the
    /// lock synchronises with the acquire fence after the `swap` that reads it free). Memories
    /// whose threads are not OS threads (loom's) must override both methods with their own
    /// fences and a yielding spin.
    fn lock(&self, index: usize) {
        while WordMemory::<u32>::swap(self, index, 1) != 0 {
            // Wait with plain loads, so that waiting threads do not bounce the line.
            while WordMemory::<u32>::load(self, index) != 0 {
                std::hint::spin_loop();
            }
        }
        std::sync::atomic::fence(std::sync::atomic::Ordering::Acquire);
    }

    /// One attempt at the lock of [`Memory::lock`] (GLSL's `atomicCompSwap(lock, 0, 1) == 0`):
    /// true when it was free and is now held, with the previous holder's writes visible. A scheme
    /// that holds a lock across steps (a spinlock) takes it with this, one attempt per step.
    fn try_lock(&self, index: usize) -> bool {
        let taken = WordMemory::<u32>::swap(self, index, 1) == 0;
        if taken {
            std::sync::atomic::fence(std::sync::atomic::Ordering::Acquire);
        }
        taken
    }

    /// Frees the lock taken by [`Memory::lock`] on `u32` word `index`.
    fn unlock(&self, index: usize) {
        std::sync::atomic::fence(std::sync::atomic::Ordering::Release);
        WordMemory::<u32>::store(self, index, 0);
    }
}

#[cfg(test)]
mod tests {
    use super::pages::PAGE_WORDS;
    use super::*;

    /// Every word of `memory`: the `u32` array widened, then the `u64` array.
    fn words<M: Memory>(memory: &M) -> Vec<u64> {
        let narrow = (0..WordMemory::<u32>::len(memory))
            .map(|i| u64::from(WordMemory::<u32>::load(memory, i)));
        let wide = (0..WordMemory::<u64>::len(memory)).map(|i| WordMemory::<u64>::load(memory, i));
        narrow.chain(wide).collect()
    }

    /// Writes of every kind to pages apart (the last, shorter pages of both arrays included);
    /// the pages of the `u64` array written, in order.
    fn write_pages_apart<M: Memory>(memory: &M) -> [usize; 3] {
        WordMemory::<u32>::fetch_add(memory, 0, 1);
        WordMemory::<u32>::fetch_max(memory, 1, 5);
        WordMemory::<u32>::store(memory, 5 * PAGE_WORDS + 2, 9);
        WordMemory::<u32>::swap(memory, 2 * PAGE_WORDS, 4);
        WordMemory::<u32>::fetch_or(memory, 2 * PAGE_WORDS + 1, 2);
        // The u64 words start at all ones: only a minimum, an add or a swap changes them.
        WordMemory::<u64>::fetch_min(memory, PAGE_WORDS + 1, 3);
        WordMemory::<u64>::fetch_add(memory, 3 * PAGE_WORDS, 8);
        WordMemory::<u64>::swap(memory, 7 * PAGE_WORDS, 2);
        [1, 3, 7]
    }

    /// `untouched_run` from words spread over the array (and to ends within it) counts the
    /// words from there on that `untouched` knows untouched, up to the end given.
    fn untouched_runs_are_runs_of_untouched_words<M: WordMemory<W>, W: Word>(memory: &M) {
        let len = memory.len();
        for start in (0..len).step_by(61).chain([len - 1, len]) {
            for end in [len, start + 100, start + 3 * PAGE_WORDS / 2] {
                let end = end.min(len);
                let expected = (start..end).take_while(|&i| memory.untouched(i)).count();
                assert_eq!(
                    memory.untouched_run(start, end),
                    expected,
                    "from {start} to {end}"
                );
                // A written run ends where a block is untouched (or at `end`), and holds no
                // untouched word.
                let written = memory.written_run(start, end);
                assert!((start..start + written).all(|i| !memory.untouched(i)));
                assert!(start + written == end || memory.untouched(start + written));
            }
        }
    }

    fn pages_are_allocated_on_first_write_and_reset_to_their_initial_values<
        M: Memory + WordMemory<u32> + WordMemory<u64>,
    >(
        mut reset: impl FnMut(&mut M, &Layout),
    ) {
        let layout = Layout::counters_and_slots(5 * PAGE_WORDS + 3, 7 * PAGE_WORDS + 1);
        let mut memory: M = layout.allocate();
        let fresh = words(&memory);
        assert_eq!(fresh, words(&layout.allocate::<M>()));
        // Reading every word allocated nothing: the page tables alone.
        let tables = memory.allocated_bytes().unwrap();
        assert_eq!(tables, layout.least_bytes());
        let written = write_pages_apart(&memory);
        // Three pages of each array, the last one of each 3 and 1 words long.
        let pages = 2 * PAGE_WORDS as u64 * 4 + 3 * 4 + 2 * PAGE_WORDS as u64 * 8 + 8;
        assert_eq!(memory.allocated_bytes(), Some(tables + pages));
        assert!(
            !WordMemory::<u32>::untouched(&memory, 1),
            "page 0 was written"
        );
        assert!(WordMemory::<u32>::untouched(&memory, PAGE_WORDS));
        for page in 0..8 {
            let index = page * PAGE_WORDS;
            assert_eq!(
                WordMemory::<u64>::untouched(&memory, index),
                !written.contains(&page),
                "page {page}"
            );
        }
        // Within a page written, only the block written.
        assert!(WordMemory::<u64>::untouched(
            &memory,
            PAGE_WORDS + pages::BLOCK_WORDS
        ));
        untouched_runs_are_runs_of_untouched_words::<M, u32>(&memory);
        untouched_runs_are_runs_of_untouched_words::<M, u64>(&memory);
        assert_ne!(words(&memory), fresh);
        reset(&mut memory, &layout);
        assert_eq!(words(&memory), fresh);
        // The pages stay allocated, none of them written since the reset.
        assert_eq!(memory.allocated_bytes(), Some(tables + pages));
        assert!((0..7 * PAGE_WORDS + 1).all(|i| WordMemory::<u64>::untouched(&memory, i)));
        // Other initial values reach every allocated page and every page not allocated.
        let other = Layout {
            init32: 7,
            init64: 0,
            ..layout
        };
        reset(&mut memory, &other);
        assert!((0..5 * PAGE_WORDS + 3).all(|i| WordMemory::<u32>::load(&memory, i) == 7));
        assert!((0..7 * PAGE_WORDS + 1).all(|i| WordMemory::<u64>::load(&memory, i) == 0));
        reset(&mut memory, &layout);
        assert_eq!(words(&memory), fresh);
    }

    #[test]
    fn atomic_pages_are_allocated_on_first_write_and_reset_to_their_initial_values() {
        pages_are_allocated_on_first_write_and_reset_to_their_initial_values::<AtomicMemory>(
            |memory, layout| memory.reset(layout, u64::MAX),
        );
    }

    #[test]
    fn serial_pages_are_allocated_on_first_write_and_reset_to_their_initial_values() {
        pages_are_allocated_on_first_write_and_reset_to_their_initial_values::<SerialMemory>(
            |memory, layout| memory.reset(layout, u64::MAX),
        );
    }

    /// A read-modify-write that cannot change its word is answered by a load: it returns the
    /// word's value and writes nothing, so the page stays unallocated (a write would allocate
    /// it); one that changes the word writes as before. The allocation is the control: the
    /// same operations with values that change the word allocate a page each.
    fn unchanging_read_modify_writes_write_nothing<M: Memory>() {
        let layout = Layout {
            init32: 0b0110,
            ..Layout::counters_and_slots(4 * PAGE_WORDS, 4 * PAGE_WORDS)
        };
        let memory: M = layout.allocate();
        let tables = memory.allocated_bytes();
        // Each on its own page: a minimum not below the word (equal, then above), a maximum not
        // above it, an or of bits already set.
        assert_eq!(WordMemory::<u64>::fetch_min(&memory, 0, u64::MAX), u64::MAX);
        assert_eq!(
            WordMemory::<u32>::fetch_max(&memory, PAGE_WORDS, 0b0110),
            0b0110
        );
        assert_eq!(WordMemory::<u32>::fetch_max(&memory, PAGE_WORDS, 3), 0b0110);
        assert_eq!(
            WordMemory::<u32>::fetch_or(&memory, 2 * PAGE_WORDS, 0b0100),
            0b0110
        );
        assert_eq!(
            WordMemory::<u32>::fetch_or(&memory, 2 * PAGE_WORDS, 0),
            0b0110
        );
        assert_eq!(memory.allocated_bytes(), tables, "nothing was written");
        assert!(WordMemory::<u64>::untouched(&memory, 0));
        // A written word, then a minimum above it: the word's value back, the word kept.
        assert_eq!(WordMemory::<u64>::fetch_min(&memory, 5, 40), u64::MAX);
        let one_page = memory.allocated_bytes();
        assert_ne!(one_page, tables, "a changing minimum writes");
        assert_eq!(WordMemory::<u64>::fetch_min(&memory, 5, 41), 40);
        assert_eq!(WordMemory::<u64>::fetch_min(&memory, 5, 40), 40);
        assert_eq!(WordMemory::<u64>::load(&memory, 5), 40);
        assert_eq!(WordMemory::<u64>::fetch_min(&memory, 5, 39), 40);
        assert_eq!(WordMemory::<u64>::load(&memory, 5), 39);
        // The control: values that change the words write, a page each.
        assert_eq!(WordMemory::<u32>::fetch_max(&memory, PAGE_WORDS, 7), 0b0110);
        assert_eq!(
            WordMemory::<u32>::fetch_or(&memory, 2 * PAGE_WORDS, 1),
            0b0110
        );
        assert_eq!(WordMemory::<u32>::load(&memory, PAGE_WORDS), 7);
        assert_eq!(WordMemory::<u32>::load(&memory, 2 * PAGE_WORDS), 0b0111);
        assert!(
            memory.allocated_bytes() > one_page,
            "changing operations write"
        );
    }

    #[test]
    fn atomic_read_modify_writes_that_change_nothing_write_nothing() {
        unchanging_read_modify_writes_write_nothing::<AtomicMemory>();
    }

    #[test]
    fn serial_read_modify_writes_that_change_nothing_write_nothing() {
        unchanging_read_modify_writes_write_nothing::<SerialMemory>();
    }

    #[test]
    fn an_empty_read_of_an_array_with_no_words_loads_nothing() {
        // A dump may declare no slots (fuzz corpus dump_layouts/01bb91ef): its resolve reads an
        // empty run at word 0 of an array with no page.
        let layout = Layout::counters_and_slots(4, 0);
        let memory: AtomicMemory = layout.allocate();
        let mut out = vec![7_u64];
        WordMemory::<u64>::load_into(&memory, 0, 0, &mut out);
        assert_eq!(out, [7], "nothing appended");
        let mut out32 = Vec::new();
        WordMemory::<u32>::load_into(&memory, 4, 0, &mut out32);
        assert!(out32.is_empty());
    }

    #[test]
    fn a_write_beyond_the_cap_is_reported_and_read_back_never_allocated() {
        let layout = Layout::counters_and_slots(0, 4 * PAGE_WORDS);
        let mut memory: AtomicMemory = layout.allocate();
        // Room for one page of u64 words and the page table.
        memory.reset(&layout, memory.allocated_bytes() + PAGE_WORDS as u64 * 8);
        WordMemory::<u64>::fetch_min(&memory, 0, 5);
        assert!(!memory.over_cap());
        let before = memory.allocated_bytes();
        WordMemory::<u64>::fetch_min(&memory, 2 * PAGE_WORDS + 3, 6);
        assert!(memory.over_cap(), "the second page is refused");
        assert_eq!(memory.allocated_bytes(), before);
        // Written to the scratch page, and read back: a scheme that checks its own write ends.
        assert_eq!(WordMemory::<u64>::load(&memory, 2 * PAGE_WORDS + 3), 6);
        assert_eq!(WordMemory::<u64>::load(&memory, 0), 5);
        // A reset with room clears the refusal.
        memory.reset(&layout, u64::MAX);
        assert!(!memory.over_cap());
        assert_eq!(
            WordMemory::<u64>::load(&memory, 2 * PAGE_WORDS + 3),
            u64::MAX
        );
    }
}
