//! The counted frame: a frame on storage that counts its read-modify-write operations
//! ([`CountingMemory`]), for `fragsim bench`'s locked operations per fragment. Counting costs an
//! atomic increment per operation, so it is a separate, untimed frame; timed frames run on the
//! bare memory.

use std::time::Instant;

use fragsim_memory::{AtomicMemory, CountingMemory, SerialMemory};
use fragsim_raster::View;

use super::frame::{Run, RunStats};
use super::parallel::{parallel_frame, TRIANGLES_PER_TASK};
use super::serial::serial_frame;
use crate::scheme::Scheme;

/// Runs one frame of `scheme` over `view` on fresh storage that counts its read-modify-write
/// operations (on the current rayon pool when `parallel`, else serially): an untimed frame that
/// reports [`RunStats::locked_ops`]. Its lists are those of an ordinary run.
pub fn count_locked_ops<S: Scheme>(view: &View<'_>, scheme: &S, parallel: bool) -> Run {
    let start = Instant::now();
    let (run, locked_ops) = if parallel {
        let memory: CountingMemory<AtomicMemory> = scheme.layout().allocate();
        let run = parallel_frame(view, scheme, &memory, start, TRIANGLES_PER_TASK);
        (run, memory.read_modify_writes())
    } else {
        let memory: CountingMemory<SerialMemory> = scheme.layout().allocate();
        let run = serial_frame(view, scheme, &memory, start);
        (run, memory.read_modify_writes())
    };
    Run {
        stats: RunStats {
            locked_ops: Some(locked_ops),
            ..run.stats
        },
        ..run
    }
}
