//! The serial executor: triangles in submission order on one thread, each fragment's walk run to
//! the end before the next fragment starts, on [`SerialMemory`]: the reference behaviour of a
//! scheme.

use std::time::Instant;

use fragsim_memory::{Memory, SerialMemory};
use fragsim_raster::View;

use super::frame::{self, rasterize_into, reuse_storage, Counters, Run};
use crate::scheme::{Scheme, MEMORY_CAP_DEFAULT};

/// Runs `scheme` over `view` serially, in submission order, on fresh storage.
pub fn run_serial<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    SerialExecutor::default().run(view, scheme)
}

/// The serial executor, keeping its storage between frames: like a GPU application it allocates
/// once and re-initialises the words every frame (timed as part of the pass).
#[derive(Debug, Default)]
pub struct SerialExecutor {
    memory: Option<SerialMemory>,
    /// The cap on the bytes of storage a frame allocates (`None`: [`MEMORY_CAP_DEFAULT`]); a
    /// frame that needs more is reported [`RunStats::over_cap`](super::RunStats).
    pub memory_cap: Option<u64>,
}

impl SerialExecutor {
    /// Runs one frame of `scheme` over `view`.
    pub fn run<S: Scheme>(&mut self, view: &View<'_>, scheme: &S) -> Run {
        let start = Instant::now();
        let memory = reuse_storage(
            &mut self.memory,
            scheme,
            self.memory_cap.unwrap_or(MEMORY_CAP_DEFAULT),
        );
        serial_frame(view, scheme, &*memory, start)
    }
}

/// One frame on `memory` begun at `start`: every pass serially, then the post pass.
pub(crate) fn serial_frame<S: Scheme, M: Memory>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    start: Instant,
) -> Run {
    frame::run(
        scheme,
        memory,
        start,
        1,
        |pass| serial_pass(view, scheme, memory, pass),
        |memory| scheme.resolve(memory),
    )
}

/// Every geometry pass of a frame of `scheme` over `view`, triangles in submission order on this
/// thread, on `memory`, which the caller keeps and can read after the passes (the dump recorder
/// writes its words out); no post pass. Returns the summed counters and the number of passes.
pub fn serial_passes<S: Scheme, M: Memory>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
) -> (Counters, u32) {
    frame::passes(scheme, memory, |pass| {
        serial_pass(view, scheme, memory, pass)
    })
}

/// Geometry pass `pass`, triangles in submission order ([`View::submitted`]) on this thread.
fn serial_pass<S: Scheme, M: Memory>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    pass: u32,
) -> Counters {
    let mut counters = Counters::default();
    let prims = (0..view.triangle_count()).map(|index| view.submitted(index));
    let rect = view.viewport().rect();
    rasterize_into(view, scheme, memory, pass, prims, rect, &mut counters);
    counters
}
