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

use std::cell::Cell;
use std::fmt::Debug;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

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

/// Std atomics with `Relaxed` ordering, shared by the threads of the parallel executor.
#[derive(Debug)]
pub struct AtomicMemory {
    words32: Vec<AtomicU32>,
    words64: Vec<AtomicU64>,
}

macro_rules! serial_words {
    ($word:ty, $field:ident) => {
        impl WordMemory<$word> for SerialMemory {
            fn len(&self) -> usize {
                self.$field.len()
            }
            fn load(&self, i: usize) -> $word {
                self.$field[i].get()
            }
            fn store(&self, i: usize, v: $word) {
                self.$field[i].set(v);
            }
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.min(v));
                old
            }
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.max(v));
                old
            }
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old.wrapping_add(v));
                old
            }
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                let old = self.$field[i].get();
                self.$field[i].set(old | v);
                old
            }
            fn swap(&self, i: usize, v: $word) -> $word {
                self.$field[i].replace(v)
            }
        }
    };
}

macro_rules! atomic_words {
    ($word:ty, $field:ident) => {
        impl WordMemory<$word> for AtomicMemory {
            fn len(&self) -> usize {
                self.$field.len()
            }
            fn load(&self, i: usize) -> $word {
                self.$field[i].load(Relaxed)
            }
            fn store(&self, i: usize, v: $word) {
                self.$field[i].store(v, Relaxed);
            }
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_min(v, Relaxed)
            }
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_max(v, Relaxed)
            }
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_add(v, Relaxed)
            }
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                self.$field[i].fetch_or(v, Relaxed)
            }
            fn swap(&self, i: usize, v: $word) -> $word {
                self.$field[i].swap(v, Relaxed)
            }
        }
    };
}

serial_words!(u32, words32);
serial_words!(u64, words64);
atomic_words!(u32, words32);
atomic_words!(u64, words64);

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
    /// initialisation kernel: one GPU thread per word).
    pub fn reset(&mut self, layout: &Layout) {
        use rayon::prelude::*;
        self.words32
            .par_iter_mut()
            .for_each(|w| *w.get_mut() = layout.init32);
        self.words64
            .par_iter_mut()
            .for_each(|w| *w.get_mut() = layout.init64);
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
        Self { words32, words64 }
    }
}
