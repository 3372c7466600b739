//! Executors: who runs which fragment's next step, and when.
//!
//! The third, [`crate::tiled`], bins triangles into screen tiles first.
//!
//! - [`run_serial`]: triangles in submission order on one thread, each fragment's walk run to the
//!   end before the next fragment starts, on [`SerialMemory`]: the reference behaviour of a scheme.
//! - [`run_parallel`]: FreePipe's model, one logical thread per triangle, on the current rayon pool
//!   with std atomics ([`AtomicMemory`]). Fragments are inserted as they are rasterized, never
//!   collected first. Triangles are handed to rayon in chunks, never a task per triangle.
//!
//! Multi-pass schemes run one geometry pass after another, with the scheme's between-pass kernel
//! in between, until the scheme asks for no more. Both executors time the passes (storage
//! initialisation, rasterization, capture) and the post pass (resolve) separately, and count
//! fragments, steps (= memory operations), drops and passes. The parallel executor runs the post
//! pass in parallel too (FreePipe's post-sort kernel: one GPU thread per pixel).

use std::time::{Duration, Instant};

use fragsim_raster::{PixelRect, View};
use rayon::prelude::*;

use crate::capture::Capture;
use crate::counting::CountingMemory;
use crate::memory::{AtomicMemory, Memory, SerialMemory};
use crate::scheme::{Layout, Scheme, Step};

/// Triangles per rayon work item by default: large enough to amortise scheduling (~100 ns a
/// task), small enough to balance the uneven cost of triangles. Scenes of fewer triangles than two
/// tasks run on one thread, so tests that want concurrency on small scenes set a smaller size
/// ([`ParallelExecutor::with_task_size`]).
pub const TRIANGLES_PER_TASK: usize = 1024;

/// The executors, by name: what the command line, the catalog and the tests iterate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Executor {
    /// Submission order on one thread: the reference behaviour.
    Serial,
    /// FreePipe's model: triangles in chunks on rayon, std atomics.
    Parallel,
    /// Triangles binned into screen tiles, one thread per tile at a time.
    Tiled,
    /// A replayable GPU-like interleaving on one thread ([`crate::scheduled`]).
    Scheduled,
}

impl Executor {
    /// Every executor.
    pub const EVERY: [Executor; 4] = [
        Executor::Serial,
        Executor::Parallel,
        Executor::Tiled,
        Executor::Scheduled,
    ];

    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Executor::Serial => "serial",
            Executor::Parallel => "parallel",
            Executor::Tiled => "tiled",
            Executor::Scheduled => "scheduled",
        }
    }

    /// Whether each pixel sees its fragments one walk at a time, in primitive order: then no
    /// read–modify–write hazard can happen, and the guarantees that exclude hazards are owed.
    #[must_use]
    pub fn serialises_pixels(self) -> bool {
        matches!(self, Executor::Serial | Executor::Tiled)
    }
}

impl std::fmt::Display for Executor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Counts of what a pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Fragments rasterized and inserted.
    pub fragments: u64,
    /// Steps run, each one memory operation.
    pub steps: u64,
    /// Walks that ended with a value stored.
    pub stored: u64,
    /// Walks that ended with a value dropped for lack of storage.
    pub dropped: u64,
    /// Walks rejected by the scheme's own test (e.g. not in this peeling pass's layer).
    pub discarded: u64,
}

impl Counters {
    pub(crate) fn record(&mut self, end: Step) {
        self.fragments += 1;
        match end {
            Step::Stored => self.stored += 1,
            Step::Dropped => self.dropped += 1,
            Step::Discarded => self.discarded += 1,
            Step::Continue => unreachable!("a walk ends with Stored or Dropped"),
        }
    }

    pub(crate) fn merge(self, other: Self) -> Self {
        Self {
            fragments: self.fragments + other.fragments,
            steps: self.steps + other.steps,
            stored: self.stored + other.stored,
            dropped: self.dropped + other.dropped,
            discarded: self.discarded + other.discarded,
        }
    }
}

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunStats {
    /// Counts, over all passes.
    pub counters: Counters,
    /// Geometry passes.
    pub passes: u32,
    /// Initialisation, rasterization and capture.
    pub pass_time: Duration,
    /// The post pass.
    pub resolve_time: Duration,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
    /// Threads that ran the pass.
    pub threads: usize,
    /// Read-modify-write (locked) operations, when the run counted them ([`count_locked_ops`]).
    pub locked_ops: Option<u64>,
    /// The counting pass that sized the storage, when one ran (its time is in `pass_time` and
    /// its geometry pass in `passes` too): see [`Run::after_count_pass`].
    pub count_pass_time: Option<Duration>,
}

/// A run's result.
#[derive(Clone, Debug)]
pub struct Run {
    /// The per-pixel lists.
    pub capture: Capture,
    /// What was measured.
    pub stats: RunStats,
}

impl Run {
    /// This run as the second half of a frame whose storage `count` sized: the counting pass's
    /// geometry pass, counters and time (its pass and its read-back) are added in, and the
    /// memory is the larger of the two (the counters are freed, or reused as the A-buffer's,
    /// before the sized storage is allocated).
    #[must_use]
    pub fn after_count_pass(self, count: &Run) -> Run {
        let counted = count.stats.pass_time + count.stats.resolve_time;
        Run {
            stats: RunStats {
                counters: count.stats.counters.merge(self.stats.counters),
                passes: count.stats.passes + self.stats.passes,
                pass_time: counted + self.stats.pass_time,
                memory_bytes: count.stats.memory_bytes.max(self.stats.memory_bytes),
                locked_ops: self
                    .stats
                    .locked_ops
                    .map(|ops| ops + count.stats.locked_ops.unwrap_or(0)),
                count_pass_time: Some(counted),
                ..self.stats
            },
            capture: self.capture,
        }
    }
}

/// Runs `scheme` over `view` serially, in submission order, on fresh storage.
pub fn run_serial<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    SerialExecutor::default().run(view, scheme)
}

/// Runs `scheme` over `view` on the current rayon pool, with std atomics, on fresh storage.
pub fn run_parallel<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    ParallelExecutor::default().run(view, scheme)
}

/// The serial executor, keeping its storage between frames: like a GPU application it allocates
/// once and re-initialises the words every frame (timed as part of the pass).
#[derive(Debug, Default)]
pub struct SerialExecutor {
    memory: Option<SerialMemory>,
}

impl SerialExecutor {
    /// Runs one frame of `scheme` over `view`.
    pub fn run<S: Scheme>(&mut self, view: &View<'_>, scheme: &S) -> Run {
        let start = Instant::now();
        let memory = reuse_storage(&mut self.memory, scheme);
        let passes = serial_passes(view, scheme, &*memory);
        finish(scheme, start, passes, 1, || scheme.resolve(&*memory))
    }
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
        let passes = parallel_passes(view, scheme, &*memory, self.triangles_per_task);
        finish(scheme, start, passes, rayon::current_num_threads(), || {
            resolve_parallel(scheme, &*memory)
        })
    }
}

/// Storage that a frame loop re-initialises rather than allocates again.
pub(crate) trait ReusableStorage: Memory + Sized {
    /// Whether this storage has exactly the words `layout` asks for.
    fn fits(&self, layout: &Layout) -> bool;
    /// Re-initialises every word to `layout`'s initial values.
    fn reset(&mut self, layout: &Layout);
}

impl ReusableStorage for SerialMemory {
    fn fits(&self, layout: &Layout) -> bool {
        SerialMemory::fits(self, layout)
    }
    fn reset(&mut self, layout: &Layout) {
        SerialMemory::reset(self, layout);
    }
}

impl ReusableStorage for AtomicMemory {
    fn fits(&self, layout: &Layout) -> bool {
        AtomicMemory::fits(self, layout)
    }
    fn reset(&mut self, layout: &Layout) {
        AtomicMemory::reset(self, layout);
    }
}

/// The storage of `scheme`'s frame: `kept` re-initialised when it fits the scheme's layout, else
/// newly allocated; kept again for the next frame.
pub(crate) fn reuse_storage<'a, S: Scheme, M: ReusableStorage>(
    kept: &'a mut Option<M>,
    scheme: &S,
) -> &'a mut M {
    let layout = scheme.layout();
    let memory = match kept.take() {
        Some(mut memory) if memory.fits(&layout) => {
            memory.reset(&layout);
            memory
        }
        _ => layout.allocate(),
    };
    kept.insert(memory)
}

/// Runs one frame of `scheme` over `view` on fresh storage that counts its read-modify-write
/// operations (on the current rayon pool when `parallel`, else serially): an untimed frame that
/// reports [`RunStats::locked_ops`]. Its lists are those of an ordinary run.
pub fn count_locked_ops<S: Scheme>(view: &View<'_>, scheme: &S, parallel: bool) -> Run {
    let start = Instant::now();
    let (run, locked_ops) = if parallel {
        let memory: CountingMemory<AtomicMemory> = scheme.layout().allocate();
        let passes = parallel_passes(view, scheme, &memory, TRIANGLES_PER_TASK);
        let run = finish(scheme, start, passes, rayon::current_num_threads(), || {
            resolve_parallel(scheme, &memory)
        });
        (run, memory.read_modify_writes())
    } else {
        let memory: CountingMemory<SerialMemory> = scheme.layout().allocate();
        let passes = serial_passes(view, scheme, &memory);
        let run = finish(scheme, start, passes, 1, || scheme.resolve(&memory));
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

/// Every geometry pass of a frame, triangles in submission order on this thread.
fn serial_passes<S: Scheme, M: Memory>(view: &View<'_>, scheme: &S, memory: &M) -> (Counters, u32) {
    run_passes(scheme, memory, |pass| {
        let mut counters = Counters::default();
        let rect = view.viewport().rect();
        for prim in 0..view.triangle_count() {
            rasterize_into(view, scheme, memory, pass, prim, rect, &mut counters);
        }
        counters
    })
}

/// Every geometry pass of a frame, triangles in chunks on the current rayon pool.
fn parallel_passes<S: Scheme, M: Memory + Sync>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    triangles_per_task: usize,
) -> (Counters, u32) {
    run_passes(scheme, memory, |pass| {
        (0..view.triangle_count())
            .into_par_iter()
            .with_min_len(triangles_per_task)
            .fold(Counters::default, |mut counters, prim| {
                let rect = view.viewport().rect();
                rasterize_into(view, scheme, memory, pass, prim, rect, &mut counters);
                counters
            })
            .reduce(Counters::default, Counters::merge)
    })
}

/// Rasterizes the pixels of `rect` that triangle `prim` covers and runs each fragment's walk of
/// geometry pass `pass` to its end.
pub(crate) fn rasterize_into<S: Scheme, M: Memory>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    pass: u32,
    prim: u32,
    rect: PixelRect,
    counters: &mut Counters,
) {
    view.rasterize_in(prim, rect, &mut |fragment| {
        if let Some(state) = scheme.begin_pass(pass, fragment) {
            let end = scheme.insert_state(state, memory, &mut counters.steps);
            counters.record(end);
        }
    });
}

/// Runs geometry passes until the scheme's between-pass kernel asks for no more; returns the
/// summed counters and the number of passes.
pub(crate) fn run_passes<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    mut geometry_pass: impl FnMut(u32) -> Counters,
) -> (Counters, u32) {
    let mut counters = Counters::default();
    let mut pass = 0;
    loop {
        counters = counters.merge(geometry_pass(pass));
        pass += 1;
        if !scheme.end_pass(pass - 1, memory) {
            return (counters, pass);
        }
    }
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
    let (mut rest, mut base) = (capture.entries.as_mut_slice(), 0);
    for (entries, _, _) in &chunks {
        let (slice, tail) = rest.split_at_mut(entries.len());
        entry_slices.push((slice, base));
        base += entries.len();
        rest = tail;
    }
    chunks
        .into_par_iter()
        .zip(entry_slices)
        .zip(capture.offsets[1..].par_chunks_mut(PIXELS_PER_TASK))
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

/// Ends a frame whose geometry passes ran since `start` and returned `(counters, passes)`: runs
/// the post pass `resolve`, timing the two apart.
pub(crate) fn finish<S: Scheme>(
    scheme: &S,
    start: Instant,
    (counters, passes): (Counters, u32),
    threads: usize,
    resolve: impl FnOnce() -> Capture,
) -> Run {
    let pass_time = start.elapsed();
    let resolve_start = Instant::now();
    let capture = resolve();
    let stats = RunStats {
        counters,
        passes,
        pass_time,
        resolve_time: resolve_start.elapsed(),
        memory_bytes: scheme.layout().bytes(),
        threads,
        locked_ops: None,
        count_pass_time: None,
    };
    Run { capture, stats }
}
