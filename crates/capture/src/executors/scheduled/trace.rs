//! The scheduled executor's traces: every memory operation of a run as a [`TraceEvent`], in
//! execution order ([`Trace`]), grouped by step or filtered to one pixel.

#[cfg(doc)]
use super::run_fragments_in_order;

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

/// The recorded memory operations of a run, in execution order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Trace {
    /// Events in execution order.
    pub events: Vec<TraceEvent>,
}

impl Trace {
    /// The thread that ran each step, in order: one entry per step, however many memory
    /// operations the step did (what [`run_fragments_in_order`] replays).
    #[must_use]
    pub fn order(&self) -> Vec<u32> {
        self.steps().map(|events| events[0].thread).collect()
    }

    /// The events grouped by step (consecutive events with one `step` index), in order.
    pub fn steps(&self) -> impl Iterator<Item = &[TraceEvent]> + '_ {
        self.events.chunk_by(|a, b| a.step == b.step)
    }

    /// The events that touched `pixel`'s fragments.
    #[must_use]
    pub fn pixel(&self, pixel: u32) -> Trace {
        Trace {
            events: self
                .events
                .iter()
                .filter(|e| e.pixel == pixel)
                .copied()
                .collect(),
        }
    }
}
