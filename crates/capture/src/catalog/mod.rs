//! The catalog: every scheme the simulator can run by name, and how to build and run it.
//!
//! One entry per scheme ([`CATALOG`]): its name (the one spelling used on the command line, in
//! JSON, in file names and in dump headers, and the one its [`Scheme::name`] returns), its
//! geometry passes, how it sizes its storage, a one-line description, and — through
//! [`Executors::run`] — a constructor from a [`Sizing`] that builds it and runs one frame. What a
//! scheme guarantees is never listed here: it comes from the built scheme
//! ([`Scheme::guarantee`]). Front ends (the command line, the property tests) iterate this list,
//! so adding a scheme means its module plus one entry and one constructor arm here.

use crate::abuffer::{ABuffer, PostSort};
use crate::bucket::{Adp, Bdp, Bdp2, Buckets};
use crate::depth_count::{DepthCount, DepthCounts};
use crate::dual_peeling::DualDepthPeeling;
use crate::executor::{self, Executor, ParallelExecutor, Run, SerialExecutor};
use crate::kbuffer::{KBuffer, WriteBack};
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

/// A slot count: a number, or derived from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    /// Sized to the scene's depth complexity by a counting pass of the scheme's own.
    Auto,
    /// Exactly this many.
    Fixed(u32),
}

/// How the user sized the schemes. Nothing here comes from the oracle: where a size is `auto`
/// (or a scheme's storage is sized to the scene by design), the scheme runs its own counting pass
/// first ([`crate::depth_count`]), and its run reports that pass.
#[derive(Debug, Clone, Copy)]
pub struct Sizing {
    /// Slots per pixel of the K-sized schemes (`--k`).
    pub k: Count,
    /// Slots per pixel of the capacity-sized schemes (`--capacity`; linked lists: pool nodes).
    pub capacity: Count,
    /// Refuse storage beyond this many bytes (`--memory-cap`).
    pub memory_cap: u64,
}

/// How a scheme sizes its per-pixel storage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    /// This many slots per pixel, whatever the sizing.
    Slots(u32),
    /// [`Sizing::k`] slots per pixel (a counting pass first where it is `auto`).
    K,
    /// [`Sizing::capacity`] slots per pixel (a counting pass first where it is `auto`).
    Capacity,
    /// [`Sizing::k`] nodes kept by the resolve, from a pool of [`Sizing::capacity`] nodes per
    /// pixel (a counting pass first where either is `auto`; `auto` pools hold the scene's
    /// fragments).
    KAndPool,
    /// Sized to the scene by its own counting pass, always (storage for every fragment, or a
    /// record of every layer).
    Counted,
}

/// How many geometry passes a scheme runs (its counting pass, where one runs, not included).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Passes {
    /// Exactly this many.
    Fixed(u32),
    /// At most this many: a later pass runs only where an earlier one overflowed.
    UpTo(u32),
    /// `before` passes, then one per `per` layers of the scene's maximum depth complexity
    /// (rounded up), then `after` passes (peeling's last one, which finds nothing).
    PerLayers {
        /// Passes before the layers' (ADP's range and histogram).
        before: u32,
        /// Layers captured per pass.
        per: u32,
        /// Passes after the layers'.
        after: u32,
    },
    /// At least one, repeated until every fragment is confirmed by a count (hazards cost
    /// passes).
    UntilConfirmed,
}

impl Passes {
    /// The least and the most passes (`None`: unbounded) on a scene of maximum depth complexity
    /// `layers`.
    #[must_use]
    pub fn bounds(self, layers: u32) -> (u32, Option<u32>) {
        match self {
            Passes::Fixed(n) => (n, Some(n)),
            Passes::UpTo(n) => (1, Some(n)),
            Passes::PerLayers { before, per, after } => {
                let n = before + layers.div_ceil(per) + after;
                (n, Some(n))
            }
            Passes::UntilConfirmed => (1, None),
        }
    }
}

/// One scheme of the catalog.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Which scheme.
    pub scheme: SchemeName,
    /// Its one spelling: the command line's, JSON's, file names' and dump headers'.
    pub name: &'static str,
    /// Its geometry passes.
    pub passes: Passes,
    /// How it sizes its storage.
    pub storage: Storage,
    /// One line on what it is (the command line's help).
    pub description: &'static str,
}

macro_rules! catalog {
    ($($scheme:ident $name:literal $passes:expr, $storage:expr, $description:literal;)*) => {
        /// Every scheme the simulator runs by name.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum SchemeName {
            $(#[doc = $description] $scheme,)*
        }

        /// Every scheme, in the order tables list them.
        pub const CATALOG: &[Entry] = &[
            $(Entry {
                scheme: SchemeName::$scheme,
                name: $name,
                passes: $passes,
                storage: $storage,
                description: $description,
            },)*
        ];
    };
}

use Passes::{Fixed, PerLayers, UntilConfirmed, UpTo};
use Storage::{Capacity, Counted, KAndPool, Slots, K};

catalog! {
    Mdts "mdts" Fixed(1), K,
        "MDTS, 64-bit words (depth key and primitive id), ascending.";
    Mdts32 "mdts32" Fixed(1), K,
        "MDTS, 32-bit depth keys as in FreePipe's Table 1.";
    MdtsDesc "mdts-desc" Fixed(1), K,
        "MDTS with `atomicMax`, descending.";
    MdtsProbe "mdts-probe" Fixed(1), K,
        "MDTS (64-bit words) with the probing walk: a load first, `atomicMin` only where it would change the slot (same lists, fewer locked operations).";
    Abuffer "abuffer" Fixed(1), Capacity,
        "FreePipe's A-buffer: `--capacity` slots per pixel (fixed arrays, FreePipe §4.2), overflow counted; insertion-sorted.";
    AbufferBitonic "abuffer-bitonic" Fixed(1), Capacity,
        "The A-buffer as above, bitonic-sorted.";
    AbufferExact "abuffer-exact" Fixed(1), Counted,
        "The A-buffer with storage sized exactly by its own counting pass (`fetch_add` per fragment, then a prefix sum): two geometry passes.";
    Peeling "peeling" PerLayers { before: 0, per: 1, after: 1 }, Counted,
        "Classical depth peeling, 64-bit words (ties ordered by primitive id): one pass per layer.";
    Peeling32 "peeling32" PerLayers { before: 0, per: 1, after: 1 }, Counted,
        "Classical depth peeling on 32-bit depth keys: equal depths merge.";
    DualPeeling "dual-peeling" PerLayers { before: 0, per: 2, after: 1 }, Counted,
        "Dual depth peeling (nearest and farthest layer per pass), 64-bit words.";
    DualPeeling32 "dual-peeling32" PerLayers { before: 0, per: 2, after: 1 }, Counted,
        "Dual depth peeling on 32-bit depth keys.";
    Zbuffer "zbuffer" Fixed(1), Slots(1),
        "The opaque z-buffer via `atomicMin`: the nearest fragment only.";
    Bdp "bdp" Fixed(2), Slots(32),
        "Bucket depth peeling, one pass, 16 bucket pairs (HPG 2009 §3.2).";
    BdpSingle "bdp-single" Fixed(2), Slots(32),
        "Bucket depth peeling, 32 single-value buckets.";
    Bdp2 "bdp2" Fixed(3), Slots(64),
        "Two-pass bucket depth peeling (§3.2).";
    Adp "adp" PerLayers { before: 2, per: 32, after: 0 }, Counted,
        "Adaptive bucket depth peeling (§3.3).";
    Kbuffer "kbuffer" Fixed(1), K,
        "The k-buffer: read–insert–write of K slots, exact only without concurrent hazards; render-target write-backs (one step each, committed in primitive order).";
    KbufferStores "kbuffer-stores" Fixed(1), K,
        "The k-buffer with K separate loads and stores (CUDA's): torn write-backs too.";
    KbufferMultipass "kbuffer-multipass" UntilConfirmed, Counted,
        "The multi-pass k-buffer: k-buffer passes beyond the confirmed boundary until every fragment is confirmed by a count (render-target write-backs).";
    KbufferMultipassStores "kbuffer-multipass-stores" UntilConfirmed, Counted,
        "The multi-pass k-buffer with K separate loads and stores.";
    Srab "srab" UpTo(2), Slots(16),
        "The stencil-routed A-buffer: 8 samples per pixel and pass, 2 passes.";
    MdtsPacked "mdts-packed" Fixed(1), K,
        "MDTS with depth and colour packed into two 32-bit arrays (FreePipe §4.1.2).";
    Loop32 "loop32" Fixed(2), K,
        "nvpro-samples' loop32: MDTS's `atomicMin` loop stopping on an equal depth (equal depths merge), then a colour pass; K = `--k`.";
    LayerCounter "layer-counter" Fixed(1), K,
        "Bevy 0.15's OIT: `atomicAdd` on a per-pixel layer counter, `--k` layers, the rest discarded.";
    LinkedList "linked-list" Fixed(1), KAndPool,
        "Per-pixel linked lists (node counter, head exchange), the resolve keeping the first `--k` nodes (the most recent: Vulkan-Samples); node pool `--capacity` per pixel, `exact` = the scene's fragments.";
    LinkedListNearest "linked-list-nearest" Fixed(1), KAndPool,
        "Per-pixel linked lists, the resolve keeping the `--k` nearest (nvpro-samples).";
}

impl SchemeName {
    /// The scheme's catalog entry.
    #[must_use]
    pub fn entry(self) -> &'static Entry {
        // The catalog lists the variants in declaration order (one macro writes both).
        &CATALOG[self as usize]
    }

    /// The scheme's one spelling.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// The scheme spelled `name`, if the catalog has one.
    #[must_use]
    pub fn from_name(name: &str) -> Option<SchemeName> {
        CATALOG.iter().find(|e| e.name == name).map(|e| e.scheme)
    }

    /// The machine a k-buffer scheme runs on: separate stores for the `-stores` names, render
    /// targets otherwise.
    #[must_use]
    pub fn write_back(self) -> WriteBack {
        match self {
            SchemeName::KbufferStores | SchemeName::KbufferMultipassStores => {
                WriteBack::SeparateStores
            }
            _ => WriteBack::RenderTarget,
        }
    }

    /// Whether the scheme, sized by `sizing`, needs the scene's per-pixel depth complexity, and
    /// so a counting pass before its capture.
    #[must_use]
    pub fn needs_count_pass(self, sizing: &Sizing) -> bool {
        let k_auto = sizing.k == Count::Auto;
        let capacity_auto = sizing.capacity == Count::Auto;
        match self.entry().storage {
            Storage::Slots(_) => false,
            Storage::K => k_auto,
            Storage::Capacity => capacity_auto,
            Storage::KAndPool => k_auto || capacity_auto,
            Storage::Counted => true,
        }
    }
}

impl std::fmt::Display for SchemeName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
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
