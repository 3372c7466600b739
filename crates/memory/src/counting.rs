//! A [`Memory`] decorator that counts read-modify-write operations: the locked instructions
//! (`lock cmpxchg`, `lock xadd`) a frame costs on x86, reported per fragment by `fragsim bench`.
//!
//! Counting costs an atomic increment per operation, so the executors use it only for a separate,
//! untimed frame (`fragsim_capture::executors::count_locked_ops`); timed frames run on the bare memory.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use super::{Memory, Word, WordMemory};

/// `M` with a count of its read-modify-write operations (loads and stores are not counted).
#[derive(Debug)]
pub struct CountingMemory<M> {
    inner: M,
    read_modify_writes: AtomicU64,
}

impl<M> CountingMemory<M> {
    /// Read-modify-write operations so far.
    #[must_use]
    pub fn read_modify_writes(&self) -> u64 {
        self.read_modify_writes.load(Relaxed)
    }

    fn counted(&self) -> &M {
        self.read_modify_writes.fetch_add(1, Relaxed);
        &self.inner
    }
}

impl<W: Word, M: WordMemory<W>> WordMemory<W> for CountingMemory<M> {
    fn len(&self) -> usize {
        self.inner.len()
    }
    fn load(&self, index: usize) -> W {
        self.inner.load(index)
    }
    fn store(&self, index: usize, value: W) {
        self.inner.store(index, value);
    }
    fn fetch_min(&self, index: usize, value: W) -> W {
        self.counted().fetch_min(index, value)
    }
    fn fetch_max(&self, index: usize, value: W) -> W {
        self.counted().fetch_max(index, value)
    }
    fn fetch_add(&self, index: usize, value: W) -> W {
        self.counted().fetch_add(index, value)
    }
    fn fetch_or(&self, index: usize, value: W) -> W {
        self.counted().fetch_or(index, value)
    }
    fn swap(&self, index: usize, value: W) -> W {
        // `atomicExch` is a locked instruction too (`xchg` with memory is implicitly locked).
        self.counted().swap(index, value)
    }
    fn untouched(&self, index: usize) -> bool {
        self.inner.untouched(index)
    }
    fn untouched_run(&self, index: usize, end: usize) -> usize {
        self.inner.untouched_run(index, end)
    }
    fn written_run(&self, index: usize, end: usize) -> usize {
        self.inner.written_run(index, end)
    }
}

impl<M: Memory> Memory for CountingMemory<M> {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        Self {
            inner: M::new(len32, init32, len64, init64),
            read_modify_writes: AtomicU64::new(0),
        }
    }
    fn allocated_bytes(&self) -> Option<u64> {
        self.inner.allocated_bytes()
    }
    fn over_cap(&self) -> bool {
        self.inner.over_cap()
    }
}
