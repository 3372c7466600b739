//! Executors: who runs which fragment's next step, and when.
//!
//! - [`run_serial`]: triangles in submission order on one thread, each fragment's walk run to the
//!   end before the next fragment starts, on [`SerialMemory`]: the reference behaviour of a scheme.
//! - [`run_parallel`]: FreePipe's model, one logical thread per triangle, on the current rayon pool
//!   with std atomics ([`AtomicMemory`]). Fragments are inserted as they are rasterized, never
//!   collected first. Triangles are handed to rayon in chunks, never a task per triangle.
//!
//! Both time the pass (storage initialisation, rasterization and capture) and the post pass
//! (resolve) separately, and count fragments, steps (= memory operations) and drops.

use std::time::{Duration, Instant};

use fragsim_raster::View;
use rayon::prelude::*;

use crate::capture::Capture;
use crate::memory::{AtomicMemory, Memory, SerialMemory};
use crate::scheme::{Scheme, Step};

/// Triangles per rayon work item: large enough to amortise scheduling (~100 ns a task), small
/// enough to balance the uneven cost of triangles.
const TRIANGLES_PER_TASK: usize = 1024;

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
}

impl Counters {
    fn record(&mut self, end: Step) {
        self.fragments += 1;
        match end {
            Step::Stored => self.stored += 1,
            Step::Dropped => self.dropped += 1,
            Step::Continue => unreachable!("a walk ends with Stored or Dropped"),
        }
    }

    fn merge(self, other: Self) -> Self {
        Self {
            fragments: self.fragments + other.fragments,
            steps: self.steps + other.steps,
            stored: self.stored + other.stored,
            dropped: self.dropped + other.dropped,
        }
    }
}

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunStats {
    /// Counts.
    pub counters: Counters,
    /// Initialisation, rasterization and capture.
    pub pass_time: Duration,
    /// The post pass.
    pub resolve_time: Duration,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
    /// Threads that ran the pass.
    pub threads: usize,
}

/// A run's result.
#[derive(Clone, Debug)]
pub struct Run {
    /// The per-pixel lists.
    pub capture: Capture,
    /// What was measured.
    pub stats: RunStats,
}

/// Runs `scheme` over `view` serially, in submission order.
pub fn run_serial<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    let start = Instant::now();
    let memory: SerialMemory = scheme.layout().allocate();
    let mut counters = Counters::default();
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |fragment| {
            let end = scheme.insert(fragment, &memory, &mut counters.steps);
            counters.record(end);
        });
    }
    finish(scheme, &memory, counters, start, 1)
}

/// Runs `scheme` over `view` on the current rayon pool, with std atomics.
pub fn run_parallel<S: Scheme>(view: &View<'_>, scheme: &S) -> Run {
    let start = Instant::now();
    let memory: AtomicMemory = scheme.layout().allocate();
    let counters = (0..view.triangle_count())
        .into_par_iter()
        .with_min_len(TRIANGLES_PER_TASK)
        .fold(Counters::default, |mut counters, prim| {
            view.rasterize(prim, &mut |fragment| {
                let end = scheme.insert(fragment, &memory, &mut counters.steps);
                counters.record(end);
            });
            counters
        })
        .reduce(Counters::default, Counters::merge);
    finish(
        scheme,
        &memory,
        counters,
        start,
        rayon::current_num_threads(),
    )
}

fn finish<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    counters: Counters,
    start: Instant,
    threads: usize,
) -> Run {
    let pass_time = start.elapsed();
    let resolve_start = Instant::now();
    let capture = scheme.resolve(memory);
    let stats = RunStats {
        counters,
        pass_time,
        resolve_time: resolve_start.elapsed(),
        memory_bytes: scheme.layout().bytes(),
        threads,
    };
    Run { capture, stats }
}
