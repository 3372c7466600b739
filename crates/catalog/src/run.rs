//! Running a catalog entry: its constructor from a [`Sizing`], its counting pass where it needs
//! one, and one frame on an executor ([`SchemeRunner::run`]); the memory cap checked before any of it
//! ([`check_memory_cap_early`]).

use super::{Build, Count, SchemeName, SchemeVisitor, Sizing, Storage};

use fragsim_capture::depth_count::{DepthCount, DepthCounts};
use fragsim_capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::executors::tiled::TiledExecutor;
use fragsim_capture::executors::{self, Executor, ParallelExecutor, Run, SerialExecutor};
use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_capture::{CaptureError, Descriptor, Guarantee, Scheme, Step, WalkInput};
use fragsim_memory::{Memory, WordMemory};
use fragsim_raster::{View, Viewport};
use fragsim_schemes::masked_abuffer::MaskedABuffer;
use std::sync::Mutex;

/// Why a catalog scheme could not be run ([`SchemeRunner::run`]) or is refused before any run
/// ([`check_memory_cap_early`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RunError {
    /// The scheme cannot be built at its sizes (a parameter out of range, or its tables over
    /// the memory cap).
    #[error(transparent)]
    Build(#[from] CaptureError),
    /// Sized to the scene, the scheme is over the memory cap even at one slot a pixel, before
    /// any counting pass sizes it.
    #[error("{0} (at least: sized to the scene, it needs one slot per pixel or more)")]
    OverCapAtLeast(CaptureError),
    /// The frame's writes reached more pages of storage than the memory cap allows.
    #[error(
        "{scheme} needed more than the memory cap of {cap} bytes of per-pixel storage: its frame \
         allocated {allocated} bytes and its writes reached more pages (--memory-cap raises it)"
    )]
    FrameOverCap {
        /// The scheme.
        scheme: String,
        /// The cap.
        cap: u64,
        /// The bytes the frame allocated.
        allocated: u64,
    },
}

/// A finished run of a named scheme.
#[derive(Debug, Clone)]
pub struct NamedRun {
    /// The run (with its counting pass folded in, where one ran).
    pub run: Run,
    /// The scheme's own name (`Scheme::name`).
    pub name: String,
    /// What the scheme guarantees (`Scheme::guarantee`).
    pub guarantee: Guarantee,
    /// Slots per pixel, where the scheme has a fixed number.
    pub slots: Option<u32>,
    /// The per-pixel counts of the scheme's own counting pass, where one sized its storage.
    pub counts: Option<Vec<u32>>,
    /// The sizes the scheme was built with (their `counts` are [`NamedRun::counts`]): what a
    /// dump of its memory needs to rebuild it.
    pub sizes: Build<'static>,
    /// The run's own memory after its last pass, before the post pass, where
    /// [`SchemeRunner::keep_memory`] asked for it: what `render --dump` writes, so that a dump holds
    /// the words of the run it reports (a racy run's included).
    pub memory: Option<MemoryWords>,
}

/// Every word of a scheme's memory, in the order of its [`Layout`](fragsim_memory::Layout).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MemoryWords {
    /// The u32 words.
    pub words32: Vec<u32>,
    /// The u64 words.
    pub words64: Vec<u64>,
}

impl MemoryWords {
    /// A copy of every word of `memory`.
    pub fn read<M: Memory>(memory: &M) -> Self {
        Self {
            words32: (0..WordMemory::<u32>::len(memory))
                .map(|i| WordMemory::<u32>::load(memory, i))
                .collect(),
            words64: (0..WordMemory::<u64>::len(memory))
                .map(|i| WordMemory::<u64>::load(memory, i))
                .collect(),
        }
    }
}

/// Runs catalog schemes by name on any executor, keeping each executor's storage between frames
/// of the same scheme (the executors themselves are [`fragsim_capture::executors`]).
#[derive(Debug, Default)]
pub struct SchemeRunner {
    serial: SerialExecutor,
    parallel: ParallelExecutor,
    tiled: TiledExecutor,
    /// Run the next frames on fresh storage that counts read-modify-write operations
    /// ([`RunStats::locked_ops`](fragsim_capture::executors::RunStats)), untimed.
    pub count_locked_ops: bool,
    /// Copy each run's memory after its last pass into [`NamedRun::memory`].
    pub keep_memory: bool,
}

impl SchemeRunner {
    /// Builds scheme `name` sized by `sizing` and runs one frame of it on `executor` (on the
    /// current rayon pool where it is parallel): first its counting pass where it needs one,
    /// then its own passes.
    ///
    /// # Errors
    /// A parameter the scheme rejects, or storage beyond the memory cap: its tables when it is
    /// built, or the pages its frame's writes reach (`fragsim_memory`'s `pages.rs`).
    pub fn run(
        &mut self,
        name: SchemeName,
        executor: Executor,
        view: &View<'_>,
        sizing: &Sizing,
    ) -> Result<NamedRun, RunError> {
        let viewport = view.viewport();
        for cap in [
            &mut self.serial.memory_cap,
            &mut self.parallel.memory_cap,
            &mut self.tiled.memory_cap,
        ] {
            *cap = Some(sizing.memory_cap);
        }
        let samples = view.samples().map_or(1, |pattern| pattern.count());
        let counted = match name.needs_count_pass(sizing) {
            false => None,
            // Masked-node storage counts its nodes, not the per-sample fragments.
            true if name.entry().storage == Storage::Nodes => {
                let counter = MaskedABuffer::node_counter(view.pixel_viewport(), samples)?;
                let run = run_on(&counter, self, executor, view);
                let counts = counter.masked_frame(&run).lists.overflow;
                Some(DepthCounts { counts, run })
            }
            true => Some(DepthCounts::from_run(run_on(
                &DepthCount::new(viewport),
                self,
                executor,
                view,
            ))),
        };
        // What `auto` sizes resolve to: the count pass's maximum depth complexity (at least 1).
        let scene_max = counted.as_ref().map_or(1, |c| c.max().max(1));
        let resolve = |count: Count| match count {
            Count::Auto => scene_max,
            Count::Fixed(n) => n,
        };
        let capacity = resolve(sizing.capacity);
        // The rasterizer's order, recorded before the frame for the schemes that follow it.
        let order = name
            .entry()
            .primitive_order
            .then(|| PrimitiveOrder::of_view(view));
        let build = Build {
            viewport,
            samples,
            k: resolve(sizing.k),
            capacity,
            layers: scene_max,
            // An `auto` pool holds the scene's fragments; otherwise `capacity` nodes a pixel.
            pool: match (sizing.capacity, &counted) {
                (Count::Auto, Some(counted)) => counted.total().max(1),
                _ => viewport.pixels() * capacity as usize,
            },
            memory_cap: sizing.memory_cap,
            counts: counted.as_ref().map(|c| c.counts.as_slice()),
            order: order.as_ref(),
        };
        let mut named = name.build(
            &build,
            RunOn {
                runner: self,
                executor,
                view,
                sizes: Build {
                    counts: None,
                    order: None,
                    ..build
                },
            },
        )?;
        if let Some(counted) = counted {
            named.run = named.run.after_count_pass(&counted.run);
            named.counts = Some(counted.counts);
        }
        if named.run.stats.over_cap {
            return Err(RunError::FrameOverCap {
                scheme: named.name,
                cap: sizing.memory_cap,
                allocated: named.run.stats.allocated_bytes,
            });
        }
        Ok(named)
    }
}

/// Refuses, before the oracle and any counting pass, any scheme of `names` whose storage on
/// `viewport` would exceed `memory_cap` even at its smallest.
///
/// With `--k auto`, `--capacity auto` or a scheme sized to the scene, storage is known only after
/// a counting pass, and the oracle alone needs 24 bytes a pixel (6 GiB at 16384 × 16384): a
/// refusal must not wait for them. Every catalog entry is built at its smallest (one slot or
/// layer, the least pool, no fragments) and refused if even that exceeds the cap; what a build
/// checks is what is allocated before any fragment (tables and page tables,
/// [`Layout::least_bytes`](fragsim_memory::Layout::least_bytes): the exact A-buffer's offsets, 4 bytes a pixel), the pages of words
/// being checked as a frame writes them.
///
/// # Errors
/// The first scheme refused, with the bytes it would need at least.
pub fn check_memory_cap_early(
    names: &[SchemeName],
    viewport: Viewport,
    sizing: &Sizing,
) -> Result<(), RunError> {
    let smallest = |count: Count| match count {
        Count::Auto => 1,
        Count::Fixed(n) => n,
    };
    let capacity_least = smallest(sizing.capacity);
    let no_fragments = vec![0; viewport.pixels()];
    let least = Build {
        counts: Some(&no_fragments),
        pool: viewport.pixels().max(1),
        ..Build::fixed(
            viewport,
            smallest(sizing.k),
            capacity_least,
            1,
            sizing.memory_cap,
        )
    };
    for &name in names {
        let result = name.build(&least, Unused);
        if let Err(error) = result {
            return Err(if name.needs_count_pass(sizing) {
                RunError::OverCapAtLeast(error)
            } else {
                RunError::Build(error)
            });
        }
    }
    Ok(())
}

/// The visitor of a scheme built only to see whether it can be.
struct Unused;

impl SchemeVisitor for Unused {
    type Output = ();
    fn visit<S: Scheme>(self, _: &S, _: Option<u32>) {}
}

/// The interleaving `--executor scheduled` runs: the scheduled executor's random policy with 256
/// fragments in flight, seed 0 (replayable; `fragsim explain` and `fragsim hazard` search seeds).
const SCHEDULE: Schedule = Schedule {
    policy: Policy::Random,
    in_flight: 256,
    granularity: Granularity::Fragment,
    seed: 0,
};

/// The catalog visitor that runs one frame of the built scheme on an executor.
struct RunOn<'e, 'v, 'm> {
    runner: &'e mut SchemeRunner,
    executor: Executor,
    view: &'v View<'m>,
    sizes: Build<'static>,
}

impl SchemeVisitor for RunOn<'_, '_, '_> {
    type Output = NamedRun;
    fn visit<S: Scheme>(self, scheme: &S, slots: Option<u32>) -> NamedRun {
        let kept = self.runner.keep_memory.then(|| Mutex::new(None));
        let run = run_keeping(scheme, self.runner, self.executor, self.view, kept.as_ref());
        NamedRun {
            run,
            name: scheme.name(),
            guarantee: scheme.guarantee(),
            slots,
            counts: None,
            sizes: self.sizes,
            memory: kept.and_then(|kept| kept.into_inner().ok().flatten()),
        }
    }
}

/// One frame of `scheme` on `executor`, its memory after the last pass copied into `keep` where
/// given; the bare scheme runs where nothing is kept, so that a run without `--dump` pays nothing
/// for the copy and keeps its tile-local path.
fn run_keeping<S: Scheme>(
    scheme: &S,
    runner: &mut SchemeRunner,
    executor: Executor,
    view: &View<'_>,
    keep: Option<&Mutex<Option<MemoryWords>>>,
) -> Run {
    match keep {
        None => run_on(scheme, runner, executor, view),
        Some(keep) => run_on(&KeepingMemory { scheme, keep }, runner, executor, view),
    }
}

/// One frame of `scheme` on `executor`.
fn run_on<S: Scheme>(
    scheme: &S,
    runner: &mut SchemeRunner,
    executor: Executor,
    view: &View<'_>,
) -> Run {
    if runner.count_locked_ops {
        return executors::count_locked_ops(view, scheme, executor != Executor::Serial);
    }
    match executor {
        Executor::Serial => runner.serial.run(view, scheme),
        Executor::Parallel => runner.parallel.run(view, scheme),
        Executor::Tiled => runner.tiled.run(view, scheme),
        Executor::Scheduled => run_scheduled(view, scheme, &SCHEDULE, false).run,
    }
}

/// The scheme, its memory copied into `keep` after the last pass (where the between-pass kernel
/// asks for no more), before the post pass reads it: what `render --dump` writes. Every other
/// method is the scheme's own, so that the run kept is the run reported (its gathering,
/// prefetches, walks and post pass unchanged).
struct KeepingMemory<'a, S> {
    scheme: &'a S,
    keep: &'a Mutex<Option<MemoryWords>>,
}

impl<S: Scheme> Scheme for KeepingMemory<'_, S> {
    type State = S::State;
    type Input = S::Input;

    fn descriptor(&self) -> &Descriptor {
        self.scheme.descriptor()
    }
    fn tile_local(&self) -> bool {
        // The memory kept for a dump is read in the layout it declares, screen-ordered: the
        // tiled executor's own pixel numbering would scramble it.
        false
    }
    fn gathering(&self) -> <S::Input as WalkInput>::Gathering {
        self.scheme.gathering()
    }
    fn begin(&self, input: S::Input) -> S::State {
        self.scheme.begin(input)
    }
    fn begin_pass(&self, pass: u32, input: S::Input) -> Option<S::State> {
        self.scheme.begin_pass(pass, input)
    }
    fn step<M: Memory>(&self, state: &mut S::State, memory: &M) -> Step {
        self.scheme.step(state, memory)
    }
    fn prefetch<M: Memory>(&self, input: S::Input, memory: &M) {
        self.scheme.prefetch(input, memory);
    }
    fn insert_state<M: Memory>(&self, state: S::State, memory: &M, steps: &mut u64) -> Step {
        self.scheme.insert_state(state, memory, steps)
    }
    fn simt(&self, state: &S::State) -> fragsim_capture::Simt {
        self.scheme.simt(state)
    }
    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        let more = self.scheme.end_pass(pass, memory);
        if !more {
            if let Ok(mut kept) = self.keep.lock() {
                *kept = Some(MemoryWords::read(memory));
            }
        }
        more
    }
    fn pixel_run<M: Memory>(
        &self,
        memory: &M,
        pixel: usize,
        end: usize,
    ) -> fragsim_capture::PixelRun {
        self.scheme.pixel_run(memory, pixel, end)
    }
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        self.scheme.resolve_pixel(memory, pixel, out)
    }
}
