//! The frame loop, written once: begin pass, steps, end pass, resolve, stats.
//!
//! A frame runs geometry passes, each followed by the scheme's between-pass kernel
//! ([`Scheme::end_pass`]), until the scheme asks for no more, then the post pass
//! ([`Scheme::resolve`]), and reports what it measured ([`RunStats`]). Executors differ only in
//! who runs which fragment's walk within a pass: they hand [`run`] (or [`passes`], when the
//! caller keeps the memory and wants no post pass) a closure that runs one geometry pass and
//! returns its [`Counters`]. The pieces such a closure is made of are here too:
//! - [`walk`]: one fragment's walk of one pass to its end (what serial, parallel and tiled
//!   executors do for every fragment they rasterize);
//! - [`walks`]: a caller's list of fragments, one walk after the other, in the caller's order;
//! - [`interleaved`]: every walk of a pass in flight at once, the caller choosing which one takes
//!   the next step (tests that script an interleaving; the scheduled executor does the same under
//!   a simulated GPU scheduler, with traces).

use std::time::{Duration, Instant};

use fragsim_memory::{AtomicMemory, Layout, Memory, SerialMemory};
use fragsim_raster::{PixelRect, View};

use crate::capture::Capture;
use crate::scheme::{Scheme, Step};
use crate::walk_input::WalkInput;

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
    /// Counts one walk that ended with `end`.
    ///
    /// # Panics
    /// If `end` is [`Step::Continue`]: a walk that did not end is not counted.
    #[inline]
    pub fn record(&mut self, end: Step) {
        self.fragments += 1;
        match end {
            Step::Stored => self.stored += 1,
            Step::Dropped => self.dropped += 1,
            Step::Discarded => self.discarded += 1,
            Step::Continue => unreachable!("a walk ends with Stored, Dropped or Discarded"),
        }
    }

    /// The sum of two counts.
    #[must_use]
    pub fn merge(self, other: Self) -> Self {
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
    /// Bytes of per-pixel storage the scheme addresses (its [`Layout`], words and tables).
    pub memory_bytes: u64,
    /// Bytes of per-pixel storage allocated: the tables and the pages of words that writes
    /// reached (`fragsim_memory`'s `pages.rs`), at most [`RunStats::memory_bytes`] and the page tables.
    pub allocated_bytes: u64,
    /// Whether a write found no storage within the memory cap: the capture is not to be used
    /// (`SchemeRunner::run` reports the run as over the cap).
    pub over_cap: bool,
    /// Threads that ran the pass.
    pub threads: usize,
    /// Read-modify-write (locked) operations, when the run counted them
    /// ([`count_locked_ops`](super::count_locked_ops)).
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
    pub fn after_count_pass(self, count: &Self) -> Self {
        let counted = count.stats.pass_time + count.stats.resolve_time;
        Self {
            stats: RunStats {
                counters: count.stats.counters.merge(self.stats.counters),
                passes: count.stats.passes + self.stats.passes,
                pass_time: counted + self.stats.pass_time,
                memory_bytes: count.stats.memory_bytes.max(self.stats.memory_bytes),
                allocated_bytes: count.stats.allocated_bytes.max(self.stats.allocated_bytes),
                over_cap: count.stats.over_cap || self.stats.over_cap,
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

/// One whole frame of `scheme` on `memory`: every geometry pass ([`passes`]), the post pass
/// `resolve`, and the stats, the passes timed from `start` (so that what the executor did before,
/// re-initialising the storage or binning triangles, counts as pass time) and the post pass apart.
pub fn run<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    start: Instant,
    threads: usize,
    geometry_pass: impl FnMut(u32) -> Counters,
    resolve: impl FnOnce(&M) -> Capture,
) -> Run {
    let (counters, passes) = passes(scheme, memory, geometry_pass);
    let pass_time = start.elapsed();
    let resolve_start = Instant::now();
    let capture = resolve(memory);
    let layout = scheme.layout();
    let stats = RunStats {
        counters,
        passes,
        pass_time,
        resolve_time: resolve_start.elapsed(),
        memory_bytes: layout.bytes(),
        allocated_bytes: allocated_bytes(&layout, memory),
        over_cap: memory.over_cap(),
        threads,
        locked_ops: None,
        count_pass_time: None,
    };
    Run { capture, stats }
}

/// The bytes of `layout` that `memory` allocated: its tables and the words allocated, every word
/// where the memory holds them all.
pub(crate) fn allocated_bytes<M: Memory>(layout: &Layout, memory: &M) -> u64 {
    memory
        .allocated_bytes()
        .map_or(layout.bytes(), |words| words + layout.table_bytes as u64)
}

/// Every geometry pass of a frame on `memory`, kept by the caller: `geometry_pass(pass)` runs
/// pass `pass` (from 0) and returns its counters, then the scheme's between-pass kernel runs,
/// until it asks for no more passes. Returns the summed counters and the number of passes.
pub fn passes<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    mut geometry_pass: impl FnMut(u32) -> Counters,
) -> (Counters, u32) {
    let mut counters = Counters::default();
    let mut pass = 0;
    loop {
        let (done, more) = self::pass(scheme, memory, pass, &mut geometry_pass);
        counters = counters.merge(done);
        pass += 1;
        if !more {
            return (counters, pass);
        }
    }
}

/// Geometry pass `pass` alone, `geometry_pass(pass)`, and the between-pass kernel after it: for a
/// caller that looks at the memory between passes. Returns the pass's counters and whether the
/// scheme asks for another pass.
pub fn pass<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    pass: u32,
    geometry_pass: impl FnOnce(u32) -> Counters,
) -> (Counters, bool) {
    let counters = geometry_pass(pass);
    (counters, scheme.end_pass(pass, memory))
}

/// Runs `fragment`'s walk of geometry pass `pass` to its end, counting it into `counters`; a
/// fragment the pass ignores ([`Scheme::begin_pass`] gives `None`) is not counted.
pub fn walk<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    pass: u32,
    fragment: S::Input,
    counters: &mut Counters,
) {
    if let Some(state) = scheme.begin_pass(pass, fragment) {
        let end = scheme.insert_state(state, memory, &mut counters.steps);
        counters.record(end);
    }
}

/// The walks of geometry pass `pass` of `fragments`, one after the other in the order given:
/// the serial executor's behaviour on a fragment list of the caller's order.
pub fn walks<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    pass: u32,
    fragments: &[S::Input],
) -> Counters {
    let mut counters = Counters::default();
    for &fragment in fragments {
        walk(scheme, memory, pass, fragment, &mut counters);
    }
    counters
}

/// The walks of geometry pass `pass` of `fragments`, all in flight at once: before each step,
/// `pick` is given the indices into `fragments` of the unfinished walks, in the order of
/// `fragments`, and returns the position in that list of the walk that takes the step. A pick of
/// 0 every time runs the walks one after the other in the order given.
///
/// # Panics
/// If `pick` returns a position past the list it was given.
pub fn interleaved<S: Scheme, M: Memory>(
    scheme: &S,
    memory: &M,
    pass: u32,
    fragments: &[S::Input],
    mut pick: impl FnMut(&[usize]) -> usize,
) -> Counters {
    let mut counters = Counters::default();
    let (mut indices, mut states): (Vec<usize>, Vec<S::State>) = fragments
        .iter()
        .enumerate()
        .filter_map(|(i, &f)| scheme.begin_pass(pass, f).map(|state| (i, state)))
        .unzip();
    while !indices.is_empty() {
        let position = pick(&indices);
        counters.steps += 1;
        let end = scheme.step(&mut states[position], memory);
        if end != Step::Continue {
            counters.record(end);
            // `remove`, not `swap_remove`: the unfinished walks stay in the order given.
            indices.remove(position);
            states.remove(position);
        }
    }
    counters
}

/// Fragments rasterized ahead of their walks: each fragment's first words are loaded as it is
/// rasterized ([`Scheme::prefetch`]) and its walk runs this many fragments later. A walk's
/// read-modify-write waits for its pixel's line, and so does everything after it on that
/// thread: walked as they came, the 2048² dragon's fragments missed the last-level cache 1.6
/// times each, one after the other (callgrind's cache simulation). Loaded ahead, those misses
/// overlap one another and the rasterization in between.
const FRAGMENTS_AHEAD: usize = 32;

/// Rasterizes the pixels of `rect` that the triangles `prims` cover, triangle after triangle in
/// the order given ([`View::rasterize_each_in`]), gathers the fragments into the scheme's walk
/// inputs ([`WalkInput::gather`]: the fragments themselves, for every scheme that walks
/// fragments), and runs each input's walk of geometry pass `pass` to its end, in that order,
/// [`FRAGMENTS_AHEAD`] inputs after it is gathered (the first pass's inputs loaded ahead).
pub(crate) fn rasterize_into<S: Scheme, M: Memory>(
    view: &View<'_>,
    scheme: &S,
    memory: &M,
    pass: u32,
    prims: impl IntoIterator<Item = u32>,
    rect: PixelRect,
    counters: &mut Counters,
) {
    let mut ahead = Ahead::new(scheme, memory, pass);
    let mut gathering = scheme.gathering();
    view.rasterize_each_in(prims, rect, &mut |fragment| {
        S::Input::gather(&mut gathering, fragment, &mut |input| {
            ahead.push(input, counters);
        });
    });
    S::Input::flush(&mut gathering, &mut |input| ahead.push(input, counters));
    ahead.finish(counters);
}

/// The walks of one thread's stream of inputs, each run [`FRAGMENTS_AHEAD`] inputs after it
/// came, its first words loaded as it came (in the first pass).
pub(crate) struct Ahead<'a, S: Scheme, M> {
    scheme: &'a S,
    memory: &'a M,
    pass: u32,
    ring: [Option<S::Input>; FRAGMENTS_AHEAD],
    next: usize,
}

impl<'a, S: Scheme, M: Memory> Ahead<'a, S, M> {
    /// No input yet, for geometry pass `pass` of `scheme` on `memory`.
    pub(crate) fn new(scheme: &'a S, memory: &'a M, pass: u32) -> Self {
        Self {
            scheme,
            memory,
            pass,
            ring: [None; FRAGMENTS_AHEAD],
            next: 0,
        }
    }

    /// Takes `input`, loading its first words ahead, and runs the walk of the input that came
    /// [`FRAGMENTS_AHEAD`] before it, counting it into `counters`.
    #[inline]
    pub(crate) fn push(&mut self, input: S::Input, counters: &mut Counters) {
        if self.pass == 0 {
            self.scheme.prefetch(input, self.memory);
        }
        if let Some(earlier) = self.ring[self.next].replace(input) {
            walk(self.scheme, self.memory, self.pass, earlier, counters);
        }
        self.next = (self.next + 1) % FRAGMENTS_AHEAD;
    }

    /// Runs the walks still waiting, in the order they came.
    pub(crate) fn finish(self, counters: &mut Counters) {
        let (later, earlier) = self.ring.split_at(self.next);
        for input in earlier.iter().chain(later).flatten() {
            walk(self.scheme, self.memory, self.pass, *input, counters);
        }
    }
}

/// Storage that a frame loop re-initialises rather than allocates again.
pub(crate) trait ReusableStorage: Memory + Sized {
    /// Whether this storage has exactly the words `layout` asks for.
    fn fits(&self, layout: &Layout) -> bool;
    /// Re-initialises every word to `layout`'s initial values, with `cap` bytes for the words
    /// allocated from now on.
    fn reset(&mut self, layout: &Layout, cap: u64);
}

impl ReusableStorage for SerialMemory {
    fn fits(&self, layout: &Layout) -> bool {
        Self::fits(self, layout)
    }
    fn reset(&mut self, layout: &Layout, cap: u64) {
        Self::reset(self, layout, cap);
    }
}

impl ReusableStorage for AtomicMemory {
    fn fits(&self, layout: &Layout) -> bool {
        Self::fits(self, layout)
    }
    fn reset(&mut self, layout: &Layout, cap: u64) {
        Self::reset(self, layout, cap);
    }
}

/// The storage of `scheme`'s frame: `kept` re-initialised when it fits the scheme's layout, else
/// newly allocated; kept again for the next frame. The pages of words allocated as the frame
/// writes them may take `memory_cap` bytes less what is allocated before any
/// ([`Layout::least_bytes`]).
pub(crate) fn reuse_storage<'a, S: Scheme, M: ReusableStorage>(
    kept: &'a mut Option<M>,
    scheme: &S,
    memory_cap: u64,
) -> &'a mut M {
    let layout = scheme.layout();
    let mut memory = match kept.take() {
        Some(memory) if memory.fits(&layout) => memory,
        _ => layout.allocate(),
    };
    memory.reset(&layout, memory_cap.saturating_sub(layout.least_bytes()));
    kept.insert(memory)
}
