//! Memory that records every operation ([`RecordingMemory`]): the serial memory plus a log of
//! [`TraceEvent`]s, each stamped with the step, thread, fragment, pixel and pass the scheduled
//! executor sets before the step runs.

use std::cell::{Cell, RefCell};

use super::{Memory, SerialMemory, WordMemory};
use crate::executors::scheduled::{Op, TraceEvent};

/// Storage that can record every operation: plain memory plus a log.
pub(crate) struct RecordingMemory {
    pub(crate) inner: SerialMemory,
    pub(crate) log: Option<RefCell<Vec<TraceEvent>>>,
    /// (step, thread, fragment, pixel, pass) of the step being run.
    pub(crate) context: Cell<(u64, u32, u64, u32, u32)>,
}

impl RecordingMemory {
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
