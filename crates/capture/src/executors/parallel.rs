//! The parallel executor: FreePipe's model, one logical thread per triangle, on the current rayon
//! pool with std atomics ([`AtomicMemory`]). Fragments are inserted as they are rasterized, never
//! collected first. Triangles are handed to rayon in chunks, never a task per triangle. The post
//! pass runs in parallel too (FreePipe's post-sort kernel: one GPU thread per pixel).

use std::time::Instant;

use fragsim_raster::View;
use rayon::prelude::*;

use super::frame::{self, rasterize_into, reuse_storage, Counters, Run};
use crate::capture::Capture;
use crate::memory::{AtomicMemory, Memory};
use crate::scheme::Scheme;

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
            triangles_per_task: triangles_per_task.max(1),
        }
    }

    /// Runs one frame of `scheme` over `view` on the current rayon pool.
    pub fn run<S: Scheme>(&mut self, view: &View<'_>, scheme: &S) -> Run {
        let start = Instant::now();
        let memory = reuse_storage(&mut self.memory, scheme);
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
    let geometry_pass = |pass| {
        (0..view.triangle_count())
            .into_par_iter()
            .with_min_len(triangles_per_task)
            .fold(Counters::default, |mut counters, index| {
                let rect = view.viewport().rect();
                let prim = view.submitted(index);
                rasterize_into(view, scheme, memory, pass, prim, rect, &mut counters);
                counters
            })
            .reduce(Counters::default, Counters::merge)
    };
    rayon_frame(scheme, memory, start, geometry_pass)
}

/// A frame of the executors that run on the rayon pool (parallel and tiled): their geometry
/// passes, then the post pass in parallel ([`resolve_parallel`]).
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

/// Pixels per rayon work item in the post pass.
const PIXELS_PER_TASK: usize = 4096;

/// The post pass on the rayon pool: pixel chunks resolved independently, then copied into the
/// capture in parallel (a serial concatenation of a megapixel's offsets would cost as much as the
/// resolve itself on many threads).
pub(crate) fn resolve_parallel<S: Scheme, M: Memory + Sync>(scheme: &S, memory: &M) -> Capture {
    let pixels = scheme.pixels();
    let chunks: Vec<(Vec<u64>, Vec<usize>, Vec<u32>)> = (0..pixels.div_ceil(PIXELS_PER_TASK))
        .into_par_iter()
        .map(|chunk| {
            let range = chunk * PIXELS_PER_TASK..((chunk + 1) * PIXELS_PER_TASK).min(pixels);
            let mut entries = Vec::new();
            let mut ends = Vec::with_capacity(range.len());
            let mut overflow = Vec::with_capacity(range.len());
            for pixel in range {
                overflow.push(scheme.resolve_pixel(memory, pixel, &mut entries));
                ends.push(entries.len());
            }
            (entries, ends, overflow)
        })
        .collect();
    let mut capture = Capture::with_pixels(pixels, scheme.identity(), scheme.keeps(Vec::new()));
    let total: usize = chunks.iter().map(|(entries, _, _)| entries.len()).sum();
    capture.entries.resize(total, 0);
    capture.offsets.resize(pixels + 1, 0);
    let mut all_overflow = vec![0; pixels];
    // Each chunk's share of the entries, cut in order; offsets and overflow cut evenly.
    let mut entry_slices = Vec::with_capacity(chunks.len());
    let (mut rest, mut base) = (capture.lists.entries.as_mut_slice(), 0);
    for (entries, _, _) in &chunks {
        let (slice, tail) = rest.split_at_mut(entries.len());
        entry_slices.push((slice, base));
        base += entries.len();
        rest = tail;
    }
    chunks
        .into_par_iter()
        .zip(entry_slices)
        .zip(capture.lists.offsets[1..].par_chunks_mut(PIXELS_PER_TASK))
        .zip(all_overflow.par_chunks_mut(PIXELS_PER_TASK))
        .for_each(
            |((((entries, ends, overflow), (entry_slice, base)), offsets), overflow_out)| {
                entry_slice.copy_from_slice(&entries);
                for (offset, end) in offsets.iter_mut().zip(ends) {
                    *offset = base + end;
                }
                overflow_out.copy_from_slice(&overflow);
            },
        );
    capture.keeps = scheme.keeps(all_overflow);
    capture
}
