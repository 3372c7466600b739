//! Running a catalog entry: its constructor from a [`Sizing`], its counting pass where it needs
//! one, and one frame on an executor ([`Executors::run`]); the memory cap checked before any of it
//! ([`check_memory_cap_early`]).

use super::{Count, SchemeName, Sizing};

use crate::abuffer::{ABuffer, PostSort};
use crate::bucket::{Adp, Bdp, Bdp2, Buckets};
use crate::depth_count::{DepthCount, DepthCounts};
use crate::dual_peeling::DualDepthPeeling;
use crate::executor::{self, Executor, ParallelExecutor, Run, SerialExecutor};
use crate::kbuffer::KBuffer;
use crate::kbuffer_multipass::KBufferMultipass;
use crate::layer_counter::LayerCounter;
use crate::linked_list::{LinkedList, Resolve};
use crate::loop32::Loop32;
use crate::mdts::{Direction, Mdts};
use crate::mdts_packed::{Colours, MdtsPacked};
use crate::peeling::DepthPeeling;
use crate::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use crate::stencil_routed::StencilRouted;
use crate::tiled::TiledExecutor;
use crate::zbuffer::ZBuffer;
use crate::{CaptureError, Guarantee, Identity, Layout, Memory, Promise, Scheme, Step};
use fragsim_raster::{Fragment, View, Viewport};

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
}

/// A deliberate fault, for the tests that show a verdict can fail (`render --inject-fault`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// Every scheme that counts its own overflow reports one fragment more at pixel 0.
    MiscountOverflow,
}

/// Executors that keep their storage between frames of the same scheme.
#[derive(Debug, Default)]
pub struct Executors {
    serial: SerialExecutor,
    parallel: ParallelExecutor,
    tiled: TiledExecutor,
    /// Run the next frames on fresh storage that counts read-modify-write operations
    /// ([`RunStats::locked_ops`](crate::executor::RunStats)), untimed.
    pub count_locked_ops: bool,
    /// A fault injected into every scheme run (tests only).
    pub fault: Option<Fault>,
}

impl Executors {
    /// Builds scheme `name` sized by `sizing` and runs one frame of it on `executor` (on the
    /// current rayon pool where it is parallel): first its counting pass where it needs one,
    /// then its own passes.
    ///
    /// # Errors
    /// A parameter the scheme rejects, or storage beyond the memory cap.
    pub fn run(
        &mut self,
        name: SchemeName,
        executor: Executor,
        view: &View<'_>,
        sizing: &Sizing,
    ) -> Result<NamedRun, String> {
        let viewport = view.viewport();
        let counted = name
            .needs_count_pass(sizing)
            .then(|| DepthCounts::from_run(DepthCount::new(viewport).run(self, executor, view)));
        // What `auto` sizes resolve to: the count pass's maximum depth complexity (at least 1).
        let scene_max = counted.as_ref().map_or(1, |c| c.max().max(1));
        let resolve = |count: Count| match count {
            Count::Auto => scene_max,
            Count::Fixed(n) => n,
        };
        let (k, capacity) = (resolve(sizing.k), resolve(sizing.capacity));
        let layers = scene_max;
        let cap = sizing.memory_cap;
        let err = |e: CaptureError| e.to_string();
        let mut go = |scheme: &dyn ErasedScheme, slots: Option<u32>| NamedRun {
            run: scheme.run(self, executor, view),
            name: scheme.name(),
            guarantee: scheme.guarantee(),
            slots,
            counts: None,
        };
        let mut named = match name {
            SchemeName::Mdts => go(
                &Mdts::<u64>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::Mdts32 => go(
                &Mdts::<u32>::new(viewport, k, Direction::Ascending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::MdtsProbe => go(
                &Mdts::<u64>::new(viewport, k, Direction::Ascending, cap)
                    .map_err(err)?
                    .probing(),
                Some(k),
            ),
            SchemeName::MdtsDesc => go(
                &Mdts::<u64>::new(viewport, k, Direction::Descending, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::Abuffer => go(
                &ABuffer::fixed(viewport, capacity, PostSort::Insertion, cap).map_err(err)?,
                Some(capacity),
            ),
            SchemeName::AbufferBitonic => go(
                &ABuffer::fixed(viewport, capacity, PostSort::Bitonic, cap).map_err(err)?,
                Some(capacity),
            ),
            SchemeName::AbufferExact => {
                let counts = &counted.as_ref().expect("sized by its count pass").counts;
                go(
                    &ABuffer::exact(counts, PostSort::Insertion, cap).map_err(err)?,
                    None,
                )
            }
            SchemeName::Peeling => go(
                &DepthPeeling::<u64>::new(viewport, layers, cap).map_err(err)?,
                None,
            ),
            SchemeName::Peeling32 => go(
                &DepthPeeling::<u32>::new(viewport, layers, cap).map_err(err)?,
                None,
            ),
            SchemeName::DualPeeling => go(
                &DualDepthPeeling::<u64>::new(viewport, layers, cap).map_err(err)?,
                None,
            ),
            SchemeName::DualPeeling32 => go(
                &DualDepthPeeling::<u32>::new(viewport, layers, cap).map_err(err)?,
                None,
            ),
            SchemeName::Zbuffer => go(&ZBuffer::new(viewport, cap).map_err(err)?, Some(1)),
            SchemeName::Bdp => go(
                &Bdp::<u32>::new(viewport, Buckets::Pairs(16), cap).map_err(err)?,
                Some(32),
            ),
            SchemeName::BdpSingle => go(
                &Bdp::<u32>::new(viewport, Buckets::Singles(32), cap).map_err(err)?,
                Some(32),
            ),
            SchemeName::Bdp2 => go(&Bdp2::<u32>::new(viewport, 16, cap).map_err(err)?, Some(64)),
            SchemeName::Adp => go(
                &Adp::<u32>::new(viewport, layers, cap).map_err(err)?,
                Some(layers),
            ),
            SchemeName::Kbuffer | SchemeName::KbufferStores => go(
                &KBuffer::with_write_back(viewport, k, name.write_back(), cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::KbufferMultipass | SchemeName::KbufferMultipassStores => go(
                &KBufferMultipass::with_write_back(viewport, k, layers, name.write_back(), cap)
                    .map_err(err)?,
                Some(k),
            ),
            SchemeName::Srab => go(
                &StencilRouted::new(viewport, 2, cap).map_err(err)?,
                Some(16),
            ),
            SchemeName::MdtsPacked => go(
                &MdtsPacked::new(viewport, k, Colours::Prim, cap).map_err(err)?,
                Some(k),
            ),
            SchemeName::Loop32 => go(&Loop32::new(viewport, k, cap).map_err(err)?, Some(k)),
            SchemeName::LayerCounter => {
                go(&LayerCounter::new(viewport, k, cap).map_err(err)?, Some(k))
            }
            SchemeName::LinkedList | SchemeName::LinkedListNearest => {
                let pool = match (sizing.capacity, &counted) {
                    (Count::Auto, Some(counted)) => counted.total().max(1),
                    _ => viewport.pixels() * capacity as usize,
                };
                let resolve = if name == SchemeName::LinkedList {
                    Resolve::KeepFirst
                } else {
                    Resolve::KeepNearest
                };
                go(
                    &LinkedList::new(viewport, pool, k, resolve, cap).map_err(err)?,
                    Some(k),
                )
            }
        };
        if let Some(counted) = counted {
            named.run = named.run.after_count_pass(&counted.run);
            named.counts = Some(counted.counts);
        }
        Ok(named)
    }
}

/// Refuses, before the oracle and any counting pass, any scheme of `names` whose storage on
/// `viewport` would exceed `memory_cap` even at its smallest.
///
/// With `--k auto`, `--capacity auto` or a scheme sized to the scene, storage is known only after
/// a counting pass, and the oracle alone needs 24 bytes a pixel (6 GiB at 16384 × 16384): a
/// refusal must not wait for them. The smallest storage is one slot per pixel for MDTS and the
/// fixed A-buffer, and for the exact A-buffer its counters and offsets with no fragment (4 + 4
/// bytes a pixel, as `ABuffer::exact` counts them). Schemes not listed here are checked when they
/// are built.
///
/// # Errors
/// The first scheme refused, with the bytes it would need at least.
pub fn check_memory_cap_early(
    names: &[SchemeName],
    viewport: Viewport,
    sizing: &Sizing,
) -> Result<(), String> {
    let smallest = |count: Count| match count {
        Count::Auto => 1,
        Count::Fixed(n) => n,
    };
    let (k_least, capacity_least) = (smallest(sizing.k), smallest(sizing.capacity));
    let memory_cap = sizing.memory_cap;
    for &name in names {
        let result = match name {
            SchemeName::Mdts | SchemeName::MdtsProbe => {
                Mdts::<u64>::new(viewport, k_least, Direction::Ascending, memory_cap).map(drop)
            }
            SchemeName::Mdts32 => {
                Mdts::<u32>::new(viewport, k_least, Direction::Ascending, memory_cap).map(drop)
            }
            SchemeName::MdtsDesc => {
                Mdts::<u64>::new(viewport, k_least, Direction::Descending, memory_cap).map(drop)
            }
            SchemeName::AbufferExact => {
                ABuffer::exact(&vec![0; viewport.pixels()], PostSort::Insertion, memory_cap)
                    .map(drop)
            }
            SchemeName::Abuffer | SchemeName::AbufferBitonic => {
                ABuffer::fixed(viewport, capacity_least, PostSort::Insertion, memory_cap).map(drop)
            }
            _ => Ok(()),
        };
        if let Err(error) = result {
            return Err(if name.needs_count_pass(sizing) {
                format!(
                    "{error} (at least: sized to the scene, it needs one slot per pixel or more)"
                )
            } else {
                error.to_string()
            });
        }
    }
    Ok(())
}

/// The interleaving `--executor scheduled` runs: the scheduled executor's random policy with 256
/// fragments in flight, seed 0 (replayable; `fragsim explain` and `fragsim hazard` search seeds).
const SCHEDULE: Schedule = Schedule {
    policy: Policy::Random,
    in_flight: 256,
    granularity: Granularity::Fragment,
    seed: 0,
};

/// A scheme behind a vtable, so the registry needs one call site per executor rather than one
/// per (scheme, executor) pair. The per-step code stays statically dispatched inside `run`.
trait ErasedScheme {
    fn name(&self) -> String;
    fn guarantee(&self) -> Guarantee;
    fn run(&self, executors: &mut Executors, executor: Executor, view: &View<'_>) -> Run;
}

impl<S: Scheme> ErasedScheme for S {
    fn name(&self) -> String {
        Scheme::name(self)
    }

    fn guarantee(&self) -> Guarantee {
        Scheme::guarantee(self)
    }

    fn run(&self, executors: &mut Executors, executor: Executor, view: &View<'_>) -> Run {
        match executors.fault {
            Some(Fault::MiscountOverflow) => {
                run_on(&MiscountOverflow(self), executors, executor, view)
            }
            None => run_on(self, executors, executor, view),
        }
    }
}

/// One frame of `scheme` on `executor`.
fn run_on<S: Scheme>(
    scheme: &S,
    executors: &mut Executors,
    executor: Executor,
    view: &View<'_>,
) -> Run {
    if executors.count_locked_ops {
        return executor::count_locked_ops(view, scheme, executor != Executor::Serial);
    }
    match executor {
        Executor::Serial => executors.serial.run(view, scheme),
        Executor::Parallel => executors.parallel.run(view, scheme),
        Executor::Tiled => executors.tiled.run(view, scheme),
        Executor::Scheduled => run_scheduled(view, scheme, &SCHEDULE, false).run,
    }
}

/// [`Fault::MiscountOverflow`]: the scheme, reporting one overflowing fragment more at pixel 0
/// than it counted.
struct MiscountOverflow<'a, S>(&'a S);

impl<S: Scheme> Scheme for MiscountOverflow<'_, S> {
    type State = S::State;

    fn name(&self) -> String {
        self.0.name()
    }
    fn layout(&self) -> Layout {
        self.0.layout()
    }
    fn identity(&self) -> Identity {
        self.0.identity()
    }
    fn promise(&self) -> Promise {
        self.0.promise()
    }
    fn guarantee(&self) -> Guarantee {
        self.0.guarantee()
    }
    fn begin(&self, fragment: Fragment) -> S::State {
        self.0.begin(fragment)
    }
    fn begin_pass(&self, pass: u32, fragment: Fragment) -> Option<S::State> {
        self.0.begin_pass(pass, fragment)
    }
    fn step<M: Memory>(&self, state: &mut S::State, memory: &M) -> Step {
        self.0.step(state, memory)
    }
    fn end_pass<M: Memory>(&self, pass: u32, memory: &M) -> bool {
        self.0.end_pass(pass, memory)
    }
    fn resolve_pixel<M: Memory>(&self, memory: &M, pixel: usize, out: &mut Vec<u64>) -> u32 {
        self.0.resolve_pixel(memory, pixel, out) + u32::from(pixel == 0)
    }
    fn pixels(&self) -> usize {
        self.0.pixels()
    }
}
