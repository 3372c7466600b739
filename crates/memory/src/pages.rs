//! [`Pages`]: one array of words whose storage is allocated a page at a time, on the first write
//! that reaches the page, within a byte budget shared by a memory's arrays ([`Budget`]).
//!
//! A frame of a real scene covers a fraction of the viewport (the dragon a sixth of a 2048²
//! frame), so storage sized viewport × K is mostly never written. Here a page is allocated, filled
//! with the array's initial value, when a write first reaches it; a read of a page never written
//! returns the initial value without allocating. Memory, the reset and the post pass then grow
//! with the pixels the fragments reach.
//!
//! Pages stay allocated across frames (a GPU application allocates once, and freeing them would
//! only fault them in again next frame). Each block of [`BLOCK_WORDS`] words of a page carries a
//! flag set by the first write since the last reset, so that a reset re-initialises the blocks
//! written and a post pass skips the others: a page is a row of a few hundred pixels, most of
//! whose blocks the edge of a mesh leaves unwritten.
//!
//! Where the budget would be exceeded, the write is not lost silently: it goes to a scratch page
//! shared by every page refused, the budget records the refusal, and the frame is reported over
//! the cap ([`Budget::refused`]), never as a result.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::OnceLock;

use super::Word;

/// Words per page: 32 KiB of `u64` words, a few hundred pixels of K slots, large enough that the
/// page table (one entry a page) is a fraction of a percent of the storage, small enough that a
/// sparse frame leaves most pages unallocated.
pub const PAGE_WORDS: usize = 4096;

/// Words per block of a page's written flags: 64 words, four or eight cache lines, a few pixels
/// of K slots.
pub(crate) const BLOCK_WORDS: usize = 64;

/// Written flags per page: one bit of a page's `u64` mask each, so that a page's unwritten
/// blocks are found a mask at a time.
const BLOCKS: usize = PAGE_WORDS / BLOCK_WORDS;
const _: () = assert!(
    BLOCKS == u64::BITS as usize,
    "a page's written mask is one u64, a bit a block"
);

/// Bytes of the page table of an array of `words` words: one entry a page, allocated with the
/// array whether or not its pages are.
#[must_use]
pub(crate) fn page_table_bytes(words: usize) -> u64 {
    // An entry's size does not depend on the cell type (a pointer, a length, two flags).
    (words.div_ceil(PAGE_WORDS) * std::mem::size_of::<OnceLock<Page<AtomicU64>>>()) as u64
}

/// A cell of one word: `Cell` for one thread, an atomic for several.
pub(crate) trait WordCell<W: Word>: Send {
    /// A cell holding `value`.
    fn new(value: W) -> Self;
    /// Sets the value through exclusive access (a reset, no memory operation of the GPU).
    fn set_mut(&mut self, value: W);
    /// The value, for a copy of the storage (no memory operation of the GPU).
    fn value(&self) -> W;
}

/// One page: its words and, bit `b` of `written` for block `b` of them, whether a write reached
/// the block since the last reset.
#[derive(Debug)]
pub(crate) struct Page<C> {
    written: AtomicU64,
    words: Box<[C]>,
}

impl<C> Page<C> {
    fn filled<W: Word>(init: W, len: usize) -> Self
    where
        C: WordCell<W>,
    {
        Self {
            written: AtomicU64::new(0),
            words: (0..len).map(|_| C::new(init)).collect(),
        }
    }
}

impl<C> Page<C> {
    /// The cell of the page's word `offset` for a write, its block marked written.
    #[inline]
    fn write(&self, offset: usize) -> &C {
        // Loaded first, so that after the block's first write the mask's line is only read (the
        // `fetch_or`, a locked instruction, runs once a block a frame at most).
        let bit = 1 << (offset / BLOCK_WORDS);
        if self.written.load(Relaxed) & bit == 0 {
            self.written.fetch_or(bit, Relaxed);
        }
        &self.words[offset]
    }

    fn copy<W: Word>(&self) -> Self
    where
        C: WordCell<W>,
    {
        Self {
            written: AtomicU64::new(self.written.load(Relaxed)),
            words: self.words.iter().map(|word| C::new(word.value())).collect(),
        }
    }
}

/// The byte budget of a memory's pages, shared by its arrays: what is allocated, the cap, and
/// whether a page was refused for lack of budget since the last reset.
#[derive(Debug)]
pub(crate) struct Budget {
    allocated: AtomicU64,
    cap: u64,
    refused: AtomicBool,
}

impl Budget {
    /// A budget of `cap` bytes, nothing allocated.
    #[must_use]
    pub(crate) fn new(cap: u64) -> Self {
        Self {
            allocated: AtomicU64::new(0),
            cap,
            refused: AtomicBool::new(false),
        }
    }

    /// Bytes of pages allocated.
    #[must_use]
    pub(crate) fn allocated(&self) -> u64 {
        self.allocated.load(Relaxed)
    }

    /// Whether a page was refused since the last reset: the frame's results are not to be used.
    #[must_use]
    #[inline]
    pub(crate) fn refused(&self) -> bool {
        self.refused.load(Relaxed)
    }

    /// Sets the cap for the next frames (pages already allocated stay) and forgets refusals.
    pub(crate) fn reset(&mut self, cap: u64) {
        self.cap = cap;
        *self.refused.get_mut() = false;
    }

    /// Takes `bytes` from the budget, or records a refusal and returns false.
    fn take(&self, bytes: u64) -> bool {
        let before = self.allocated.fetch_add(bytes, Relaxed);
        if before + bytes <= self.cap {
            return true;
        }
        self.allocated.fetch_sub(bytes, Relaxed);
        self.refused.store(true, Relaxed);
        false
    }

    /// Gives back `bytes` taken for a page another thread allocated first.
    fn give_back(&self, bytes: u64) {
        self.allocated.fetch_sub(bytes, Relaxed);
    }
}

impl Clone for Budget {
    fn clone(&self) -> Self {
        Self {
            allocated: AtomicU64::new(self.allocated()),
            cap: self.cap,
            refused: AtomicBool::new(self.refused()),
        }
    }
}

/// The words of one allocated page, addressed by their index in the whole array: a memory's
/// operations on words that one page holds, without finding the page for each
/// ([`crate::WordMemory::with_span`]). A write marks its block written, as the array's does.
#[derive(Debug)]
pub(crate) struct Span<'a, W, C> {
    page: &'a Page<C>,
    /// The array's index of the page's first word.
    first: usize,
    /// The array's length.
    len: usize,
    init: W,
}

/// Where a memory's operations find the cell of a word: the memory's whole array (its
/// [`Pages`] within its [`Budget`]) or one page's [`Span`].
pub(crate) trait Cells<W, C> {
    /// The array's length.
    fn len(&self) -> usize;
    /// The array's initial value.
    fn init(&self) -> W;
    /// The cell of word `index` for a read, `None` where it holds the initial value.
    fn read_cell(&self, index: usize) -> Option<&C>;
    /// The cell of word `index` for a write, its block marked written.
    fn write_cell(&self, index: usize) -> &C;
}

impl<W: Word, C> Cells<W, C> for Span<'_, W, C> {
    #[inline]
    fn len(&self) -> usize {
        self.len
    }
    #[inline]
    fn init(&self) -> W {
        self.init
    }
    #[inline]
    fn read_cell(&self, index: usize) -> Option<&C> {
        Some(&self.page.words[index - self.first])
    }
    #[inline]
    fn write_cell(&self, index: usize) -> &C {
        self.page.write(index - self.first)
    }
}

/// An array of `len` words of initial value `init`, allocated a page at a time.
#[derive(Debug)]
pub(crate) struct Pages<W, C> {
    len: usize,
    init: W,
    pages: Vec<OnceLock<Page<C>>>,
    /// Where the writes to refused pages go (see the module documentation).
    scratch: OnceLock<Page<C>>,
}

impl<W: Word, C: WordCell<W>> Clone for Pages<W, C> {
    fn clone(&self) -> Self {
        let copy = |slot: &OnceLock<Page<C>>| {
            let copied = OnceLock::new();
            if let Some(page) = slot.get() {
                let _ = copied.set(page.copy());
            }
            copied
        };
        Self {
            len: self.len,
            init: self.init,
            pages: self.pages.iter().map(copy).collect(),
            scratch: copy(&self.scratch),
        }
    }
}

impl<W: Word, C: WordCell<W>> Pages<W, C> {
    /// `len` words of `init`, no page allocated.
    pub(crate) fn new(len: usize, init: W) -> Self {
        Self {
            len,
            init,
            pages: (0..len.div_ceil(PAGE_WORDS))
                .map(|_| OnceLock::new())
                .collect(),
            scratch: OnceLock::new(),
        }
    }

    /// Number of words.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The value of every word not written since the last reset.
    #[inline]
    pub(crate) fn init(&self) -> W {
        self.init
    }

    /// Bytes of the page table itself, allocated with the array.
    pub(crate) fn table_bytes(&self) -> u64 {
        page_table_bytes(self.len)
    }

    /// The cell of word `index` for a read, or `None` where its page holds the initial value
    /// (never written, and no page refused).
    #[inline]
    pub(crate) fn read(&self, index: usize, budget: &Budget) -> Option<&C> {
        debug_assert!(index < self.len, "word {index} of {}", self.len);
        match self.pages[index / PAGE_WORDS].get() {
            Some(page) => Some(&page.words[index % PAGE_WORDS]),
            None => self.absent(index, budget),
        }
    }

    /// A read of a page not allocated: its initial value, unless a page was refused, when the
    /// scratch page stands for every refused page (a write then read back is seen).
    #[cold]
    fn absent(&self, index: usize, budget: &Budget) -> Option<&C> {
        if budget.refused() {
            return Some(self.scratch(index));
        }
        None
    }

    /// The cell of word `index` for a write: its page allocated if it was not, and marked
    /// written.
    #[inline]
    pub(crate) fn write(&self, index: usize, budget: &Budget) -> &C {
        debug_assert!(index < self.len, "word {index} of {}", self.len);
        let page = match self.pages[index / PAGE_WORDS].get() {
            Some(page) => page,
            None => match self.allocate(index / PAGE_WORDS, budget) {
                Some(page) => page,
                None => return self.scratch(index),
            },
        };
        page.write(index % PAGE_WORDS)
    }

    /// Words `start..start + len` as a [`Span`] of their page, when one page already allocated
    /// holds them all; `None` where they reach past a page's edge or their page is not
    /// allocated (its first write allocates it, which the span leaves to the array), or start
    /// at or past the array's end (an empty array has no page to lend).
    #[inline]
    pub(crate) fn span(&self, start: usize, len: usize) -> Option<Span<'_, W, C>> {
        let page = self.pages.get(start / PAGE_WORDS)?.get()?;
        let first = start / PAGE_WORDS * PAGE_WORDS;
        (start - first + len <= page.words.len()).then_some(Span {
            page,
            first,
            len: self.len,
            init: self.init,
        })
    }

    /// Allocates page `page` (filled with the initial value) within the budget, or `None`.
    #[cold]
    fn allocate(&self, page: usize, budget: &Budget) -> Option<&Page<C>> {
        let words = PAGE_WORDS.min(self.len - page * PAGE_WORDS);
        let bytes = (words * std::mem::size_of::<C>()) as u64;
        if !budget.take(bytes) {
            return None;
        }
        let mut filled_here = false;
        let allocated = self.pages[page].get_or_init(|| {
            filled_here = true;
            Page::filled(self.init, words)
        });
        if !filled_here {
            budget.give_back(bytes);
        }
        Some(allocated)
    }

    /// The scratch page's cell for word `index`.
    fn scratch(&self, index: usize) -> &C {
        &self
            .scratch
            .get_or_init(|| Page::filled(self.init, PAGE_WORDS))
            .words[index % PAGE_WORDS]
    }

    /// Whether word `index` holds its initial value for certain: its block not written since
    /// the last reset (and no page refused).
    #[inline]
    pub(crate) fn untouched(&self, index: usize, budget: &Budget) -> bool {
        match self.pages[index / PAGE_WORDS].get() {
            Some(page) => page.written.load(Relaxed) >> (index % PAGE_WORDS / BLOCK_WORDS) & 1 == 0,
            None => !budget.refused(),
        }
    }

    /// How many words from `index` on, up to `end`, hold their initial value for certain: the
    /// run of blocks not written since the last reset (and pages never allocated, while no page
    /// was refused) that starts at `index`'s block, a page's mask at a time.
    pub(crate) fn untouched_run(&self, index: usize, end: usize, budget: &Budget) -> usize {
        let end = end.min(self.len);
        let mut at = index;
        while at < end {
            let page = at / PAGE_WORDS;
            match self.pages[page].get() {
                Some(allocated) => {
                    let block = at % PAGE_WORDS / BLOCK_WORDS;
                    let written = allocated.written.load(Relaxed) >> block;
                    if written & 1 != 0 {
                        break;
                    }
                    // The blocks before the next written one, or the rest of the page.
                    let blocks = (written.trailing_zeros() as usize).min(BLOCKS - block);
                    at = (at / BLOCK_WORDS + blocks) * BLOCK_WORDS;
                }
                None if budget.refused() => break,
                None => at = (page + 1) * PAGE_WORDS,
            }
        }
        at.min(end).saturating_sub(index)
    }

    /// How many words from `index` on, up to `end`, lie in blocks written since the last reset,
    /// from `index`'s block on, a page's mask at a time: where [`Pages::untouched_run`] is 0, the
    /// words a post pass reads before it need ask again.
    pub(crate) fn written_run(&self, index: usize, end: usize) -> usize {
        let end = end.min(self.len);
        let mut at = index;
        while at < end {
            let Some(page) = self.pages[at / PAGE_WORDS].get() else {
                break;
            };
            let block = at % PAGE_WORDS / BLOCK_WORDS;
            let written = (page.written.load(Relaxed) >> block).trailing_ones() as usize;
            if written == 0 {
                break;
            }
            at = (at / BLOCK_WORDS + written.min(BLOCKS - block)) * BLOCK_WORDS;
        }
        at.min(end).saturating_sub(index)
    }

    /// Sets every word to `init`: the blocks written since the last reset (every allocated page
    /// when the initial value changes), one rayon task a few pages; drops the scratch page.
    pub(crate) fn reset(&mut self, init: W) {
        use rayon::prelude::*;
        let all = init != self.init;
        self.pages
            .par_iter_mut()
            .with_min_len(8)
            .filter_map(OnceLock::get_mut)
            .for_each(|page| {
                let mut written = std::mem::take(page.written.get_mut());
                if all {
                    written = u64::MAX;
                }
                // The written blocks, a set bit at a time (every block of a last, shorter page
                // where all are).
                while written != 0 {
                    let start = written.trailing_zeros() as usize * BLOCK_WORDS;
                    written &= written - 1;
                    if start >= page.words.len() {
                        break;
                    }
                    let end = (start + BLOCK_WORDS).min(page.words.len());
                    page.words[start..end]
                        .iter_mut()
                        .for_each(|word| word.set_mut(init));
                }
            });
        self.init = init;
        self.scratch = OnceLock::new();
    }
}
