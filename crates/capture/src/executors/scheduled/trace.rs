//! The scheduled executor's traces: every memory operation of a run as a [`TraceEvent`] (recorded
//! by `fragsim_memory`'s [`RecordingMemory`](fragsim_memory::RecordingMemory)), in execution
//! order ([`Trace`]), grouped by step or filtered to one pixel.

use fragsim_memory::TraceEvent;

#[cfg(doc)]
use super::run_fragments_in_order;

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
    pub fn pixel(&self, pixel: u32) -> Self {
        Self {
            events: self
                .events
                .iter()
                .filter(|e| e.pixel == pixel)
                .copied()
                .collect(),
        }
    }
}
