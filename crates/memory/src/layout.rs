//! [`Layout`]: how many words of each width a scheme's storage has, and their initial values.
//!
//! It lives beside the memories rather than beside the `Scheme` trait because the memories are
//! re-initialised from it ([`crate::SerialMemory::reset`]): the memory crate then needs nothing
//! of the schemes, and the schemes import the memory, one way.

use super::Memory;

/// The storage a scheme needs: how many words of each width and their initial value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Number of `u32` words.
    pub words32: usize,
    /// Initial value of every `u32` word.
    pub init32: u32,
    /// Number of `u64` words.
    pub words64: usize,
    /// Initial value of every `u64` word.
    pub init64: u64,
    /// Read-only tables the scheme keeps beside the words (e.g. the A-buffer's offsets), in bytes.
    pub table_bytes: usize,
}

impl Layout {
    /// The layout of the counting schemes: `counters` `u32` words starting at 0 beside `slots`
    /// `u64` slots starting empty (`u64::MAX`), no tables.
    #[must_use]
    pub fn counters_and_slots(counters: usize, slots: usize) -> Self {
        Self {
            words32: counters,
            init32: 0,
            words64: slots,
            init64: u64::MAX,
            table_bytes: 0,
        }
    }

    /// Total bytes: words and tables.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        self.words32 as u64 * 4 + self.words64 as u64 * 8 + self.table_bytes as u64
    }

    /// The bytes a frame allocates before any fragment: the tables and the page tables of the
    /// words, whose pages are allocated as writes reach them (`pages.rs`). What the memory
    /// cap is checked against when a scheme is built; the pages are checked as they are
    /// allocated.
    #[must_use]
    pub fn least_bytes(&self) -> u64 {
        self.table_bytes as u64
            + super::pages::page_table_bytes(self.words32)
            + super::pages::page_table_bytes(self.words64)
    }

    /// Fresh storage for this layout.
    #[must_use]
    pub fn allocate<M: Memory>(&self) -> M {
        M::new(self.words32, self.init32, self.words64, self.init64)
    }
}
