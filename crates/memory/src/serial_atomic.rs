//! The two memories of per-pixel words: [`SerialMemory`] (plain cells, one thread) and
//! [`AtomicMemory`] (std atomics, `Relaxed`, shared by threads), both paged (`pages.rs`). Each
//! operation of [`WordMemory`] is written once, by the macros below, for both word widths of both
//! memories and for the spans of their pages.

use std::cell::Cell;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering::Relaxed};

use super::pages::{Budget, Cells, Pages, Span, WordCell};
use super::{Layout, Memory, SpanVisitor, Word, WordMemory};

/// Plain cells for one thread: the fastest memory and the reference behaviour of a scheme.
#[derive(Clone, Debug)]
pub struct SerialMemory {
    words32: Pages<u32, Cell<u32>>,
    words64: Pages<u64, Cell<u64>>,
    budget: Budget,
}

/// Std atomics with `Relaxed` ordering, shared by the threads of the parallel executor.
#[derive(Debug)]
pub struct AtomicMemory {
    words32: Pages<u32, AtomicU32>,
    words64: Pages<u64, AtomicU64>,
    budget: Budget,
}

macro_rules! word_cells {
    ($word:ty, $cell:ty, $value:expr) => {
        impl WordCell<$word> for $cell {
            fn new(value: $word) -> Self {
                <$cell>::new(value)
            }
            fn set_mut(&mut self, value: $word) {
                *self.get_mut() = value;
            }
            fn value(&self) -> $word {
                $value(self)
            }
        }
    };
}

word_cells!(u32, Cell<u32>, Cell::get);
word_cells!(u64, Cell<u64>, Cell::get);
word_cells!(u32, AtomicU32, |cell: &AtomicU32| cell.load(Relaxed));
word_cells!(u64, AtomicU64, |cell: &AtomicU64| cell.load(Relaxed));

/// `Cells<$word, $cell>` for a memory whose `$field` pages hold its cells of `$word`.
macro_rules! memory_cells {
    ($memory:ty, $word:ty, $cell:ty, $field:ident) => {
        impl Cells<$word, $cell> for $memory {
            #[inline]
            fn len(&self) -> usize {
                self.$field.len()
            }
            #[inline]
            fn init(&self) -> $word {
                self.$field.init()
            }
            #[inline]
            fn read_cell(&self, i: usize) -> Option<&$cell> {
                self.$field.read(i, &self.budget)
            }
            #[inline]
            fn write_cell(&self, i: usize) -> &$cell {
                self.$field.write(i, &self.budget)
            }
        }
    };
}

/// `WordMemory<$word>` for `$words`, whose cells of type `$cell` it finds through [`Cells`]: `$get`
/// reads a cell, `$set` writes one, `$rmw!` applies a read-modify-write to one and returns the
/// old value; `$extra` are further methods (the memories' own).
///
/// `fetch_min`, `fetch_max` and `fetch_or` load the word first and return what they saw, writing
/// nothing, when the operation could not change it (a value at or above the word for a minimum,
/// at or below it for a maximum, bits all set already for an or): the read-modify-write that
/// reads that value writes it back unchanged and returns it, so the load *is* that operation,
/// linearised where the load read (`docs/proof.md`, "A read-modify-write decided by a load"). No
/// locked instruction runs, the cache line is only read, and a page is neither allocated nor
/// marked written. It is still one operation of the GPU algorithm: the counting memory
/// ([`super::CountingMemory`]) counts it above this, and the scheduled executor steps it.
macro_rules! word_ops {
    ($words:ty, $word:ty, $cell:ty, $get:expr, $set:expr, $rmw:ident { $($extra:item)* }) => {
        impl WordMemory<$word> for $words {
            #[inline]
            fn len(&self) -> usize {
                Cells::<$word, $cell>::len(self)
            }
            #[inline]
            fn load(&self, i: usize) -> $word {
                Cells::<$word, $cell>::read_cell(self, i)
                    .map_or(Cells::<$word, $cell>::init(self), $get)
            }
            #[inline]
            fn store(&self, i: usize, v: $word) {
                $set(Cells::<$word, $cell>::write_cell(self, i), v);
            }
            #[inline]
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                let seen = WordMemory::<$word>::load(self, i);
                if seen <= v {
                    return seen;
                }
                $rmw!(Cells::<$word, $cell>::write_cell(self, i), fetch_min, Ord::min, v)
            }
            #[inline]
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                let seen = WordMemory::<$word>::load(self, i);
                if seen >= v {
                    return seen;
                }
                $rmw!(Cells::<$word, $cell>::write_cell(self, i), fetch_max, Ord::max, v)
            }
            #[inline]
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                $rmw!(
                    Cells::<$word, $cell>::write_cell(self, i),
                    fetch_add,
                    Word::wrapping_add,
                    v
                )
            }
            #[inline]
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                let seen = WordMemory::<$word>::load(self, i);
                if seen | v == seen {
                    return seen;
                }
                $rmw!(
                    Cells::<$word, $cell>::write_cell(self, i),
                    fetch_or,
                    std::ops::BitOr::bitor,
                    v
                )
            }
            #[inline]
            fn swap(&self, i: usize, v: $word) -> $word {
                $rmw!(Cells::<$word, $cell>::write_cell(self, i), swap, |_, v| v, v)
            }
            $($extra)*
        }
    };
}

/// `WordMemory<$word>` for a memory whose `$field` pages hold its cells of type `$cell`, and for
/// the [`Span`]s of those pages (`$get`, `$set` and `$rmw` as in `word_ops!`).
macro_rules! paged_words {
    ($memory:ty, $word:ty, $cell:ty, $field:ident, $get:expr, $set:expr, $rmw:ident) => {
        memory_cells!($memory, $word, $cell, $field);
        word_ops!($memory, $word, $cell, $get, $set, $rmw {
            #[inline]
            fn untouched(&self, i: usize) -> bool {
                self.$field.untouched(i, &self.budget)
            }
            #[inline]
            fn untouched_run(&self, i: usize, end: usize) -> usize {
                self.$field.untouched_run(i, end, &self.budget)
            }
            #[inline]
            fn written_run(&self, i: usize, end: usize) -> usize {
                self.$field.written_run(i, end)
            }
            #[inline]
            fn prefetch(&self, i: usize) {
                if i < self.$field.len() {
                    std::hint::black_box(WordMemory::<$word>::load(self, i));
                }
            }
            #[inline]
            fn with_span<V: SpanVisitor<$word>>(&self, start: usize, len: usize, visitor: V) -> V::Output {
                match self.$field.span(start, len) {
                    Some(span) => visitor.visit(&span),
                    None => visitor.visit(self),
                }
            }
        });
        word_ops!(Span<'_, $word, $cell>, $word, $cell, $get, $set, $rmw {});
    };
}

/// A read-modify-write on a `Cell`: read, `$combine` the old value with `$value`, write; returns
/// the old value (`$op` names the atomic method it stands for).
macro_rules! cell_rmw {
    ($cell:expr, $op:ident, $combine:expr, $value:expr) => {{
        let cell = $cell;
        let old = cell.get();
        cell.set($combine(old, $value));
        old
    }};
}

/// A read-modify-write on an atomic: its `Relaxed` method `$op`; returns the old value.
macro_rules! atomic_rmw {
    ($cell:expr, $op:ident, $combine:expr, $value:expr) => {
        $cell.$op($value, Relaxed)
    };
}

paged_words!(
    SerialMemory,
    u32,
    Cell<u32>,
    words32,
    Cell::get,
    Cell::set,
    cell_rmw
);
paged_words!(
    SerialMemory,
    u64,
    Cell<u64>,
    words64,
    Cell::get,
    Cell::set,
    cell_rmw
);
paged_words!(
    AtomicMemory,
    u32,
    AtomicU32,
    words32,
    |c: &AtomicU32| c.load(Relaxed),
    |c: &AtomicU32, v| c.store(v, Relaxed),
    atomic_rmw
);
paged_words!(
    AtomicMemory,
    u64,
    AtomicU64,
    words64,
    |c: &AtomicU64| c.load(Relaxed),
    |c: &AtomicU64, v| c.store(v, Relaxed),
    atomic_rmw
);

/// The storage methods both memories share: fit, reset, cap and what is allocated.
macro_rules! paged_memory {
    ($memory:ty) => {
        impl $memory {
            /// Whether this storage has exactly the words `layout` asks for.
            #[must_use]
            pub fn fits(&self, layout: &Layout) -> bool {
                self.words32.len() == layout.words32 && self.words64.len() == layout.words64
            }

            /// Re-initialises every word to `layout`'s initial values (the blocks written since the
            /// last reset; every allocated page where the initial values change) and sets the cap
            /// on the bytes of pages allocated from now on (FreePipe's initialisation kernel, one
            /// GPU thread per word; rayon tasks of a few pages here).
            pub fn reset(&mut self, layout: &Layout, cap: u64) {
                self.words32.reset(layout.init32);
                self.words64.reset(layout.init64);
                self.budget.reset(cap);
            }

            /// Bytes allocated: the pages written so far (since allocation, resets included) and
            /// the page tables.
            #[must_use]
            pub fn allocated_bytes(&self) -> u64 {
                self.budget.allocated() + self.words32.table_bytes() + self.words64.table_bytes()
            }
        }

        impl Memory for $memory {
            fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
                Self {
                    words32: Pages::new(len32, init32),
                    words64: Pages::new(len64, init64),
                    budget: Budget::new(u64::MAX),
                }
            }
            fn allocated_bytes(&self) -> Option<u64> {
                Some(<$memory>::allocated_bytes(self))
            }
            fn over_cap(&self) -> bool {
                self.budget.refused()
            }
        }
    };
}

paged_memory!(SerialMemory);
paged_memory!(AtomicMemory);
