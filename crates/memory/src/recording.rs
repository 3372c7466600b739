//! Memory that records every operation ([`RecordingMemory`]): the serial memory plus a log of
//! [`TraceEvent`]s, each stamped with the step, thread, fragment, pixel and pass the scheduled
//! executor sets before the step runs. The events are defined here, beside what records them, so
//! that the memory needs nothing of the executors; the scheduled executor's `Trace` is made of
//! them.

use std::cell::{Cell, RefCell};

use super::{Memory, SerialMemory, WordMemory};

/// A memory operation, as recorded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// Plain load.
    Load,
    /// Plain store.
    Store,
    /// `atomicMin`.
    FetchMin,
    /// `atomicMax`.
    FetchMax,
    /// `atomicAdd`.
    FetchAdd,
    /// `atomicOr`.
    FetchOr,
    /// `atomicExch`.
    Swap,
}

/// One recorded memory operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceEvent {
    /// Index of the step in the whole run.
    pub step: u64,
    /// The logical thread (slot) that ran it.
    pub thread: u32,
    /// Index of the fragment in the pass's stream.
    pub fragment: u64,
    /// The fragment's pixel.
    pub pixel: u32,
    /// Geometry pass.
    pub pass: u32,
    /// Word width in bits (32 or 64).
    pub width: u8,
    /// Word index in its array.
    pub word: usize,
    /// The operation.
    pub op: Op,
    /// The value passed in (0 for a load).
    pub operand: u64,
    /// The value returned (the old value of a read-modify-write, the value of a load; the value
    /// overwritten, for a store).
    pub returned: u64,
}

/// Storage that can record every operation: plain memory plus a log, kept once
/// [`RecordingMemory::record`] starts it.
#[derive(Debug)]
pub struct RecordingMemory {
    inner: SerialMemory,
    log: Option<RefCell<Vec<TraceEvent>>>,
    /// (step, thread, fragment, pixel, pass) of the step being run.
    context: Cell<(u64, u32, u64, u32, u32)>,
}

impl RecordingMemory {
    /// Starts the log: every operation from here on is recorded as a [`TraceEvent`].
    pub fn record(&mut self) {
        self.log = Some(RefCell::new(Vec::new()));
    }

    /// Stamps the operations that follow with the step about to run: its index in the run, the
    /// logical thread that runs it, its fragment's index in the pass's stream, that fragment's
    /// pixel and the geometry pass.
    pub fn set_context(&self, step: u64, thread: u32, fragment: u64, pixel: u32, pass: u32) {
        self.context.set((step, thread, fragment, pixel, pass));
    }

    /// The memory underneath, read without recording (the post pass's).
    #[must_use]
    pub fn serial(&self) -> &SerialMemory {
        &self.inner
    }

    /// The memory underneath, and the recorded events in execution order where
    /// [`RecordingMemory::record`] started a log.
    #[must_use]
    pub fn into_parts(self) -> (SerialMemory, Option<Vec<TraceEvent>>) {
        (self.inner, self.log.map(RefCell::into_inner))
    }

    fn note(&self, width: u8, word: usize, op: Op, operand: u64, returned: u64) {
        if let Some(log) = &self.log {
            let (step, thread, fragment, pixel, pass) = self.context.get();
            log.borrow_mut().push(TraceEvent {
                step,
                thread,
                fragment,
                pixel,
                pass,
                width,
                word,
                op,
                operand,
                returned,
            });
        }
    }
}

/// Forwards each operation to the inner memory and records it.
macro_rules! recording_words {
    ($word:ty, $bits:expr) => {
        impl WordMemory<$word> for RecordingMemory {
            fn len(&self) -> usize {
                WordMemory::<$word>::len(&self.inner)
            }
            fn load(&self, i: usize) -> $word {
                let v = WordMemory::<$word>::load(&self.inner, i);
                self.note($bits, i, Op::Load, 0, u64::from(v));
                v
            }
            fn store(&self, i: usize, v: $word) {
                let old = WordMemory::<$word>::load(&self.inner, i);
                WordMemory::<$word>::store(&self.inner, i, v);
                self.note($bits, i, Op::Store, u64::from(v), u64::from(old));
            }
            fn fetch_min(&self, i: usize, v: $word) -> $word {
                let old = WordMemory::<$word>::fetch_min(&self.inner, i, v);
                self.note($bits, i, Op::FetchMin, u64::from(v), u64::from(old));
                old
            }
            fn fetch_max(&self, i: usize, v: $word) -> $word {
                let old = WordMemory::<$word>::fetch_max(&self.inner, i, v);
                self.note($bits, i, Op::FetchMax, u64::from(v), u64::from(old));
                old
            }
            fn fetch_add(&self, i: usize, v: $word) -> $word {
                let old = WordMemory::<$word>::fetch_add(&self.inner, i, v);
                self.note($bits, i, Op::FetchAdd, u64::from(v), u64::from(old));
                old
            }
            fn fetch_or(&self, i: usize, v: $word) -> $word {
                let old = WordMemory::<$word>::fetch_or(&self.inner, i, v);
                self.note($bits, i, Op::FetchOr, u64::from(v), u64::from(old));
                old
            }
            fn swap(&self, i: usize, v: $word) -> $word {
                let old = WordMemory::<$word>::swap(&self.inner, i, v);
                self.note($bits, i, Op::Swap, u64::from(v), u64::from(old));
                old
            }
        }
    };
}

recording_words!(u32, 32);
recording_words!(u64, 64);

impl Memory for RecordingMemory {
    fn new(len32: usize, init32: u32, len64: usize, init64: u64) -> Self {
        Self {
            inner: SerialMemory::new(len32, init32, len64, init64),
            log: None,
            context: Cell::new((0, 0, 0, 0, 0)),
        }
    }
    fn allocated_bytes(&self) -> Option<u64> {
        Memory::allocated_bytes(&self.inner)
    }
    fn over_cap(&self) -> bool {
        self.inner.over_cap()
    }
}
