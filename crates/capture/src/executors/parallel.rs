//! The parallel executor: FreePipe's model, one logical thread per triangle, on the current rayon
//! pool with std atomics ([`AtomicMemory`]). Fragments are inserted as they are rasterized, never
//! collected first. Triangles are handed to rayon in chunks, never a task per triangle. The post
//! pass runs in parallel too (FreePipe's post-sort kernel: one GPU thread per pixel).

use std::time::Instant;

use fragsim_memory::{AtomicMemory, Memory};
use fragsim_raster::View;
use rayon::prelude::*;

use super::frame::{self, rasterize_into, reuse_storage, Counters, Run};
use crate::post_pass::resolve_parallel;
use crate::scheme::{Scheme, MEMORY_CAP_DEFAULT};

/// Triangles per rayon work item by default: large enough to amortise scheduling (~100 ns a
/// task), small enough to balance the uneven cost of triangles. Scenes of fewer triangles than two
/// tasks run on one thread, so tests that want concurrency on small scenes set a smaller size
/// ([`ParallelExecutor::with_task_size`]).
pub const TRIANGLES_PER_TASK: usize = 1024;

/// Runs `scheme` over `view` on the current rayon pool, with std atomics, on fresh storage.
pub fn run_parallel<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    ParallelExecutor::default().run(view, scheme)
}

/// The parallel executor (rayon, std atomics), keeping its storage between frames.
#[derive(Debug)]
pub struct ParallelExecutor {
    memory: Option<AtomicMemory>,
    /// The cap on the bytes of storage a frame allocates (`None`: [`MEMORY_CAP_DEFAULT`]); a
    /// frame that needs more is reported [`RunStats::over_cap`](super::RunStats).
    pub memory_cap: Option<u64>,
    triangles_per_task: usize,
}

impl Default for ParallelExecutor {
    fn default() -> Self {
        Self::with_task_size(TRIANGLES_PER_TASK)
    }
}

impl ParallelExecutor {
    /// The executor handing rayon `triangles_per_task` triangles per work item (at least 1):
    /// small sizes make small scenes run on every thread, so their fragments really interleave.
    #[must_use]
    pub fn with_task_size(triangles_per_task: usize) -> Self {
        Self {
            memory: None,
            memory_cap: None,
            triangles_per_task: triangles_per_task.max(1),
        }
    }

    /// Runs one frame of `scheme` over `view` on the current rayon pool.
    pub fn run<S: Scheme>(&mut self, view: &View<'_>, scheme: &S) -> Run {
        let start = Instant::now();
        let memory = reuse_storage(
            &mut self.memory,
            scheme,
            self.memory_cap.unwrap_or(MEMORY_CAP_DEFAULT),
        );
        parallel_frame(view, scheme, &*memory, start, self.triangles_per_task)
    }
}

/// One frame on `memory` begun at `start`: every pass with triangles in chunks of
/// `triangles_per_task` on the current rayon pool, then the post pass in parallel.
pub(crate) fn parallel_frame<S: Scheme, M: Memory + Sync>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    start: Instant,
    triangles_per_task: usize,
) -> Run {
    let triangles = view.triangle_count() as usize;
    let rect = view.viewport().rect();
    // One work item per chunk of triangles, its counters local to a plain loop: a rayon `fold`
    // over single triangles moves the counters in and out of its closure for every triangle
    // (rayon's helper alone was 39 instructions per triangle in the 512² dragon's profile, most
    // of whose triangles cover no pixel centre).
    let geometry_pass = |pass| {
        (0..triangles.div_ceil(triangles_per_task))
            .into_par_iter()
            .map(|task| {
                let mut counters = Counters::default();
                let first = task * triangles_per_task;
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "triangle indices are below View::triangle_count, a u32"
                )]
                let prims = (first..(first + triangles_per_task).min(triangles))
                    .map(|index| view.submitted(index as u32));
                rasterize_into(view, scheme, memory, pass, prims, rect, &mut counters);
                counters
            })
            .reduce(Counters::default, Counters::merge)
    };
    rayon_frame(scheme, memory, start, geometry_pass)
}

/// A frame of the executors that run on the rayon pool (parallel and tiled): their geometry
/// passes, then the post pass in parallel (`crate::post_pass`).
pub(crate) fn rayon_frame<S: Scheme, M: Memory + Sync>(
    scheme: &S,
    memory: &M,
    start: Instant,
    geometry_pass: impl FnMut(u32) -> Counters,
) -> Run {
    frame::run(
        scheme,
        memory,
        start,
        rayon::current_num_threads(),
        geometry_pass,
        |memory| resolve_parallel(scheme, memory),
    )
}
