//! The memory seam: the only place that knows which atomic type is underneath.
//!
//! Schemes see per-pixel storage as two flat arrays of words, one of `u32` and one of `u64`,
//! through [`WordMemory`]'s seven operations: the atomics CUDA offers on global memory (`atomicMin`,
//! `atomicMax`, `atomicAdd`, `atomicOr`, `atomicExch`) plus plain loads and stores. Every
//! operation is one step.
//!
//! Unlike the GPU, the atomic implementation uses `Relaxed` ordering: the schemes' guarantees need
//! only per-location atomicity (a total order of the read-modify-writes on each word), and the end
//! of a pass, a thread join, publishes everything (the proof is in `docs/proof.md`, loom checks it).
//!
//! [`AtomicMemory`] also remembers which blocks of [`BLOCK_WORDS`] words any write touched since
//! its last reset, so that the next frame's reset re-initialises only those (a 2048² MDTS frame
//! touches a fifth of its 671 MB), and a post pass may skip what no fragment reached
//! ([`WordMemory::untouched`]). That bookkeeping is no memory operation of the simulated GPU: it
//! costs a plain load (and once per block a store) beside each write, and the reset it shortens is
//! still timed as pass time.

use std::cell::Cell;
use std::fmt::Debug;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering::Relaxed};

mod counting;
mod layout;

pub use counting::CountingMemory;
pub use layout::Layout;

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
    const MAX: Self = u32::MAX;
    const ONE: Self = 1;
    fn wrapping_add(self, other: Self) -> Self {
        u32::wrapping_add(self, other)
    }
    fn wrapping_sub(self, other: Self) -> Self {
        u32::wrapping_sub(self, other)
    }
}

impl Word for u64 {
    const ZERO: Self = 0;
    const MAX: Self = u64::MAX;
    const ONE: Self = 1;
    fn wrapping_add(self, other: Self) -> Self {
        u64::wrapping_add(self, other)
    }
    fn wrapping_sub(self, other: Self) -> Self {
        u64::wrapping_sub(self, other)
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
    /// block since the storage was allocated or reset: a hint for post passes, which may skip
    /// such words. `false` is always a correct answer, and the default; it is no memory
    /// operation and no step.
    fn untouched(&self, index: usize) -> bool {
        let _ = index;
        false
    }
}

/// Per-pixel storage: a `u32` array and a `u64` array.
pub trait Memory: WordMemory<u32> + WordMemory<u64> {
    /// Storage with `len32` words of `init32` and `len64` words of `init64`.
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self
    where
        Self: Sized;

    /// Takes the spin lock held in `u32` word `index` (0 free, 1 held), waiting while another
    /// thread holds it; everything the previous holder did before its [`Memory::unlock`] is
    /// visible after this returns.
    ///
    /// A scheme uses it to make one step of several words indivisible: a render target's read or
    /// write of a pixel's `K` slots, which the GPU's ROP performs as one operation
    /// (`crate::schemes::kbuffer::WriteBack::RenderTarget`). The words themselves stay `Relaxed`: the
    /// ordering comes from the fences around the lock word's `swap` and `store` (C++ fence–fence
    /// synchronisation: a release fence before the store that frees the lock synchronises with the
    /// acquire fence after the `swap` that reads it free). Memories whose threads are not OS
    /// threads (loom's) must override both methods with their own fences and a yielding spin.
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

/// Plain cells for one thread: the fastest memory and the reference behaviour of a scheme.
#[derive(Clone, Debug)]
pub struct SerialMemory {
    words32: Vec<Cell<u32>>,
    words64: Vec<Cell<u64>>,
}

/// Std atomics with `Relaxed` ordering, shared by the threads of the parallel executor, with a
/// flag per block of 64 words (`BLOCK_WORDS`) set by the first write to the block (see the module
/// documentation): what [`AtomicMemory::reset`] re-initialises.
#[derive(Debug)]
pub struct AtomicMemory {
    words32: Vec<AtomicU32>,
    words64: Vec<AtomicU64>,
    touched32: Vec<AtomicBool>,
    touched64: Vec<AtomicBool>,
    /// The initial values the words were last set to: a reset to other values writes every word.
    init: (u32, u64),
}

/// Words per block of [`AtomicMemory`]'s touched flags: 64 words, four or eight cache lines,
/// small enough that a sparse frame's blocks are mostly untouched, large enough that the flags
/// (a byte per block) stay in cache beside the words.
const BLOCK_WORDS: usize = 64;

/// One flag per block of `len` words, every one clear.
fn untouched_blocks(len: usize) -> Vec<AtomicBool> {
    (0..len.div_ceil(BLOCK_WORDS))
        .map(|_| AtomicBool::new(false))
        .collect()
}

/// Marks word `index`'s block touched. The flag is loaded first, so that after the first write
/// to a block its cache line is only read, never bounced between threads.
#[inline]
fn touch(flags: &[AtomicBool], index: usize) {
    let flag = &flags[index / BLOCK_WORDS];
    if !flag.load(Relaxed) {
        flag.store(true, Relaxed);
    }
}

/// Sets every word of the touched blocks of `words` to `init` (every block when `all`), in
/// parallel, and clears the flags.
fn reset_touched<A: Send>(
    words: &mut [A],
    flags: &mut [AtomicBool],
    all: bool,
    set: impl Fn(&mut A) + Sync,
) {
    use rayon::prelude::*;
    words
        .par_chunks_mut(BLOCK_WORDS)
        .zip(flags.par_iter_mut())
        .with_min_len(1024)
        .for_each(|(block, flag)| {
            if all || *flag.get_mut() {
                block.iter_mut().for_each(&set);
                *flag.get_mut() = false;
            }
        });
}

macro_rules! serial_words {
    ($word:ty, $field:ident) => {
        impl WordMemory<$word> for SerialMemory {
            #[inline]
            fn len(&self) -> usize {
                self.$field.len()
            }
            #[inline]
            fn load(&self, i: usize) -> $word {
                self.$field[i].get()
            }
            #[inline]
            fn store(&self, i: usize, v: $word) {
                self.$field[i].set(v);
            }
            #[inline]
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.min(v));
                old
            }
            #[inline]
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.max(v));
                old
            }
            #[inline]
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.wrapping_add(v));
                old
            }
            #[inline]
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old | v);
                old
            }
            #[inline]
            fn swap(&self, i: usize, v: $word) -> $word {
                self.$field[i].replace(v)
            }
        }
    };
}

macro_rules! atomic_words {
    ($word:ty, $field:ident, $touched:ident) => {
        impl WordMemory<$word> for AtomicMemory {
            #[inline]
            fn len(&self) -> usize {
                self.$field.len()
            }
            #[inline]
            fn load(&self, i: usize) -> $word {
                self.$field[i].load(Relaxed)
            }
            #[inline]
            fn store(&self, i: usize, v: $word) {
                self.$field[i].store(v, Relaxed);
                touch(&self.$touched, i);
            }
            #[inline]
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].fetch_min(v, Relaxed);
                touch(&self.$touched, i);
                old
            }
            #[inline]
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].fetch_max(v, Relaxed);
                touch(&self.$touched, i);
                old
            }
            #[inline]
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].fetch_add(v, Relaxed);
                touch(&self.$touched, i);
                old
            }
            #[inline]
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].fetch_or(v, Relaxed);
                touch(&self.$touched, i);
                old
            }
            #[inline]
            fn swap(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].swap(v, Relaxed);
                touch(&self.$touched, i);
                old
            }
            #[inline]
            fn untouched(&self, i: usize) -> bool {
                !self.$touched[i / BLOCK_WORDS].load(Relaxed)
            }
        }
    };
}

serial_words!(u32, words32);
serial_words!(u64, words64);
atomic_words!(u32, words32, touched32);
atomic_words!(u64, words64, touched64);

impl SerialMemory {
    /// Whether this storage has exactly the words `layout` asks for.
    #[must_use]
    pub fn fits(&self, layout: &Layout) -> bool {
        self.words32.len() == layout.words32 && self.words64.len() == layout.words64
    }

    /// Re-initialises every word to `layout`'s initial values.
    pub fn reset(&mut self, layout: &Layout) {
        self.words32
            .iter_mut()
            .for_each(|w| *w.get_mut() = layout.init32);
        self.words64
            .iter_mut()
            .for_each(|w| *w.get_mut() = layout.init64);
    }
}

impl AtomicMemory {
    /// Whether this storage has exactly the words `layout` asks for.
    #[must_use]
    pub fn fits(&self, layout: &Layout) -> bool {
        self.words32.len() == layout.words32 && self.words64.len() == layout.words64
    }

    /// Re-initialises every word to `layout`'s initial values, in parallel (FreePipe's
    /// initialisation kernel: one GPU thread per word): the blocks a write touched since the last
    /// reset, the others holding them already; every block when the initial values change.
    pub fn reset(&mut self, layout: &Layout) {
        let (init32, init64) = (layout.init32, layout.init64);
        let all = self.init != (init32, init64);
        reset_touched(&mut self.words32, &mut self.touched32, all, |w| {
            *w.get_mut() = init32;
        });
        reset_touched(&mut self.words64, &mut self.touched64, all, |w| {
            *w.get_mut() = init64;
        });
        self.init = (init32, init64);
    }
}

impl Memory for SerialMemory {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        Self {
            words32: vec![Cell::new(init32); len32],
            words64: vec![Cell::new(init64); len64],
        }
    }
}

impl Memory for AtomicMemory {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        // FreePipe initialises with one GPU thread per word; here rayon fills in parallel chunks.
        use rayon::prelude::*;
        let words32 = (0..len32)
            .into_par_iter()
            .map(|_| AtomicU32::new(init32))
            .collect();
        let words64 = (0..len64)
            .into_par_iter()
            .map(|_| AtomicU64::new(init64))
            .collect();
        Self {
            words32,
            words64,
            touched32: untouched_blocks(len32),
            touched64: untouched_blocks(len64),
            init: (init32, init64),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every word of `memory`: the `u32` array widened, then the `u64` array.
    fn words(memory: &AtomicMemory) -> Vec<u64> {
        let narrow = (0..WordMemory::<u32>::len(memory))
            .map(|i| u64::from(WordMemory::<u32>::load(memory, i)));
        let wide = (0..WordMemory::<u64>::len(memory)).map(|i| WordMemory::<u64>::load(memory, i));
        narrow.chain(wide).collect()
    }

    #[test]
    fn a_reset_re_initialises_every_word_a_write_reached_and_only_their_blocks_read_touched() {
        let layout = Layout::counters_and_slots(5 * BLOCK_WORDS + 3, 7 * BLOCK_WORDS + 1);
        let mut memory: AtomicMemory = layout.allocate();
        let fresh = words(&memory);
        // One write of each kind, in blocks apart, the last words of both arrays included.
        WordMemory::<u32>::fetch_add(&memory, 0, 1);
        WordMemory::<u32>::store(&memory, 5 * BLOCK_WORDS + 2, 9);
        WordMemory::<u32>::swap(&memory, 2 * BLOCK_WORDS, 4);
        WordMemory::<u64>::fetch_min(&memory, BLOCK_WORDS + 1, 3);
        WordMemory::<u64>::fetch_max(&memory, 3 * BLOCK_WORDS, 8);
        WordMemory::<u64>::fetch_or(&memory, 7 * BLOCK_WORDS, 2);
        assert!(
            !WordMemory::<u32>::untouched(&memory, 1),
            "block 0 was written"
        );
        assert!(WordMemory::<u32>::untouched(&memory, BLOCK_WORDS));
        assert!(!WordMemory::<u64>::untouched(&memory, 2 * BLOCK_WORDS - 1));
        assert!(WordMemory::<u64>::untouched(&memory, 0));
        assert_ne!(words(&memory), fresh);
        memory.reset(&layout);
        assert_eq!(words(&memory), fresh);
        assert!((0..7 * BLOCK_WORDS + 1).all(|i| WordMemory::<u64>::untouched(&memory, i)));
    }

    #[test]
    fn a_reset_to_other_initial_values_writes_every_word() {
        let layout = Layout::counters_and_slots(3 * BLOCK_WORDS, 2 * BLOCK_WORDS);
        let mut memory: AtomicMemory = layout.allocate();
        let other = Layout {
            init32: 7,
            init64: 0,
            ..layout
        };
        memory.reset(&other);
        assert!((0..3 * BLOCK_WORDS).all(|i| WordMemory::<u32>::load(&memory, i) == 7));
        assert!((0..2 * BLOCK_WORDS).all(|i| WordMemory::<u64>::load(&memory, i) == 0));
        memory.reset(&layout);
        assert_eq!(words(&memory), words(&layout.allocate()));
    }
}
