//! The registry of schemes the command line can run: one name, one constructor.

use clap::ValueEnum;
use fragsim_capture::abuffer::{ABuffer, PostSort};
use fragsim_capture::bucket::{Adp, Bdp, Bdp2, Buckets};
use fragsim_capture::dual_peeling::DualDepthPeeling;
use fragsim_capture::executor::{self, ParallelExecutor, Run, SerialExecutor};
use fragsim_capture::kbuffer::{KBuffer, WriteBack};
use fragsim_capture::kbuffer_multipass::KBufferMultipass;
use fragsim_capture::layer_counter::LayerCounter;
use fragsim_capture::linked_list::{LinkedList, Resolve};
use fragsim_capture::loop32::Loop32;
use fragsim_capture::mdts::{Direction, Mdts};
use fragsim_capture::mdts_packed::{Colours, MdtsPacked};
use fragsim_capture::peeling::DepthPeeling;
use fragsim_capture::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_capture::stencil_routed::StencilRouted;
use fragsim_capture::tiled::TiledExecutor;
use fragsim_capture::zbuffer::ZBuffer;
use fragsim_capture::{CaptureError, Scheme};
use fragsim_raster::{View, Viewport};

use crate::args::Count;

/// The schemes the command line can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SchemeName {
    /// MDTS, 64-bit words (depth key and primitive id), ascending.
    Mdts,
    /// MDTS, 32-bit depth keys as in FreePipe's Table 1.
    Mdts32,
    /// MDTS with `atomicMax`, descending.
    MdtsDesc,
    /// MDTS (64-bit words) with the probing walk: a load first, `atomicMin` only where it would
    /// change the slot (same lists, fewer locked operations).
    MdtsProbe,
    /// A-buffer, storage sized exactly by a counting pass, insertion-sorted.
    Abuffer,
    /// A-buffer as above, bitonic-sorted.
    AbufferBitonic,
    /// A-buffer with a fixed capacity per pixel (`--capacity`, or the maximum depth complexity).
    AbufferFixed,
    /// Classical depth peeling, 64-bit words (ties ordered by primitive id): one pass per layer.
    Peeling,
    /// Classical depth peeling on 32-bit depth keys: equal depths merge.
    Peeling32,
    /// Dual depth peeling (nearest and farthest layer per pass), 64-bit words.
    DualPeeling,
    /// Dual depth peeling on 32-bit depth keys.
    DualPeeling32,
    /// The opaque z-buffer via `atomicMin`: the nearest fragment only.
    Zbuffer,
    /// Bucket depth peeling, one pass, 16 bucket pairs (HPG 2009 §3.2).
    Bdp,
    /// Bucket depth peeling, 32 single-value buckets.
    BdpSingle,
    /// Two-pass bucket depth peeling (§3.2).
    Bdp2,
    /// Adaptive bucket depth peeling (§3.3).
    Adp,
    /// The k-buffer: read–insert–write of K slots, exact only without concurrent hazards;
    /// render-target write-backs (one step each, committed in primitive order).
    Kbuffer,
    /// The k-buffer with K separate loads and stores (CUDA's): torn write-backs too.
    KbufferStores,
    /// The multi-pass k-buffer: k-buffer passes beyond the confirmed boundary until every
    /// fragment is confirmed by a count (render-target write-backs).
    KbufferMultipass,
    /// The multi-pass k-buffer with K separate loads and stores.
    KbufferMultipassStores,
    /// The stencil-routed A-buffer: 8 samples per pixel and pass, 2 passes.
    Srab,
    /// MDTS with depth and colour packed into two 32-bit arrays (FreePipe §4.1.2).
    MdtsPacked,
    /// nvpro-samples' loop32: MDTS's `atomicMin` loop stopping on an equal depth (equal depths
    /// merge), then a colour pass; K = `--k`.
    Loop32,
    /// Bevy 0.15's OIT: `atomicAdd` on a per-pixel layer counter, `--k` layers, the rest discarded.
    LayerCounter,
    /// Per-pixel linked lists (node counter, head exchange), the resolve keeping the first `--k`
    /// nodes (the most recent: Vulkan-Samples); node pool `--capacity` per pixel, `exact` = the
    /// scene's fragments.
    LinkedList,
    /// Per-pixel linked lists, the resolve keeping the `--k` nearest (nvpro-samples).
    LinkedListNearest,
    /// Every scheme above.
    All,
}

impl SchemeName {
    /// Every concrete scheme, in the order tables list them.
    pub const EVERY: [SchemeName; 26] = [
        SchemeName::Mdts,
        SchemeName::Mdts32,
        SchemeName::MdtsDesc,
        SchemeName::MdtsProbe,
        SchemeName::Abuffer,
        SchemeName::AbufferBitonic,
        SchemeName::AbufferFixed,
        SchemeName::Peeling,
        SchemeName::Peeling32,
        SchemeName::DualPeeling,
        SchemeName::DualPeeling32,
        SchemeName::Zbuffer,
        SchemeName::Bdp,
        SchemeName::BdpSingle,
        SchemeName::Bdp2,
        SchemeName::Adp,
        SchemeName::Kbuffer,
        SchemeName::KbufferStores,
        SchemeName::KbufferMultipass,
        SchemeName::KbufferMultipassStores,
        SchemeName::Srab,
        SchemeName::MdtsPacked,
        SchemeName::Loop32,
        SchemeName::LayerCounter,
        SchemeName::LinkedList,
        SchemeName::LinkedListNearest,
    ];

    /// What the scheme promises against the oracle: `exact` (fragment for fragment, up to K where
    /// it has K slots), `exact-distinct-depths` (32-bit depth peeling merges equal depths),
    /// `exact-without-hazards` (read–modify–write schemes: exact serially), `exact-in-arrival-order`
    /// (multi-pass routing), `exact-within-capacity` (shipping OIT storage: exact while the scene
    /// fits it, silently lossy beyond), or `approximate` (loses fragments in situations its paper
    /// describes, and reports them). Only `exact` schemes fail `render` when they differ from the oracle.
    #[must_use]
    pub fn guarantee(self) -> &'static str {
        match self {
            SchemeName::Peeling32 | SchemeName::DualPeeling32 => "exact-distinct-depths",
            SchemeName::Bdp | SchemeName::BdpSingle | SchemeName::Bdp2 | SchemeName::Adp => {
                "approximate"
            }
            // Exact on the serial executor; concurrent read–modify–write hazards lose fragments.
            SchemeName::Kbuffer | SchemeName::KbufferStores => "exact-without-hazards",
            // Exact up to 8 samples per pass (the rest counted as overflow); its passes must see
            // one arrival order, which the parallel executor does not promise.
            SchemeName::Srab => "exact-in-arrival-order",
            // 20 bits of depth: fragments closer than 2^-20 may swap colours.
            SchemeName::MdtsPacked => "approximate",
            // Equal depths merge into one slot (docs/baselines/shipping.md).
            SchemeName::Loop32 => "exact-distinct-depths",
            // Exact while every pixel's fragments fit its layers (or its list fits `--k` and the
            // node pool); past that, fragments are lost silently.
            SchemeName::LayerCounter | SchemeName::LinkedList | SchemeName::LinkedListNearest => {
                "exact-within-capacity"
            }
            _ => "exact",
        }
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

    /// `names` with `all` expanded and duplicates removed, in the order given.
    #[must_use]
    pub fn expand(names: &[SchemeName]) -> Vec<SchemeName> {
        if names.contains(&SchemeName::All) {
            return Self::EVERY.to_vec();
        }
        let mut unique = Vec::new();
        for &n in names {
            if !unique.contains(&n) {
                unique.push(n);
            }
        }
        unique
    }
}

/// What sizing a scheme may need from the scene and the user.
#[derive(Debug, Clone, Copy)]
pub struct Sizing<'a> {
    /// `--k`.
    pub k: Count,
    /// `--capacity`.
    pub capacity: Count,
    /// The scene's per-pixel depth complexity (from the oracle's counting pass).
    pub depth_complexity: &'a [u32],
    /// Its maximum.
    pub max_depth_complexity: u32,
    /// `--memory-cap`.
    pub memory_cap: u64,
}

/// A finished run of a named scheme.
#[derive(Debug, Clone)]
pub struct NamedRun {
    /// The run.
    pub run: Run,
    /// The scheme's own name (`Scheme::name`).
    pub name: String,
    /// Slots per pixel, where the scheme has a fixed number.
    pub slots: Option<u32>,
}

/// Executors that keep their storage between frames of the same scheme.
#[derive(Debug, Default)]
pub struct Executors {
    serial: SerialExecutor,
    parallel: ParallelExecutor,
    tiled: TiledExecutor,
    /// Run the next frames on fresh storage that counts read-modify-write operations
    /// ([`RunStats::locked_ops`](fragsim_capture::executor::RunStats)), untimed.
    pub count_locked_ops: bool,
}

impl Executors {
    /// Builds scheme `name` sized by `sizing` and runs one frame of it on `executor`
    /// (`serial`, or `parallel` or `tiled` on the current rayon pool).
    ///
    /// # Errors
    /// A parameter the scheme rejects, or storage beyond the memory cap.
    pub fn run(
        &mut self,
        name: SchemeName,
        executor: &str,
        view: &View<'_>,
        sizing: &Sizing<'_>,
    ) -> Result<NamedRun, String> {
        let mut go = |scheme: &dyn ErasedScheme, slots: Option<u32>| NamedRun {
            run: scheme.run(self, executor, view),
            name: scheme.name(),
            slots,
        };
        let viewport = view.viewport();
        let cap = sizing.memory_cap;
        let k = sizing.k.resolve(sizing.max_depth_complexity);
        // Multi-pass schemes store every layer: sized to the scene, as the A-buffer's storage.
        let layers = sizing.max_depth_complexity.max(1);
        let err = |e: CaptureError| e.to_string();
        let exact_or_fixed =
            |sort: PostSort, capacity: Count| -> Result<(ABuffer, Option<u32>), String> {
                Ok(match capacity {
                    Count::Auto => (
                        ABuffer::exact(sizing.depth_complexity, sort, cap).map_err(err)?,
                        None,
                    ),
                    Count::Fixed(c) => (
                        ABuffer::fixed(viewport, c, sort, cap).map_err(err)?,
                        Some(c),
                    ),
                })
            };
        Ok(match name {
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
            SchemeName::Abuffer => {
                let (scheme, slots) = exact_or_fixed(PostSort::Insertion, sizing.capacity)?;
                go(&scheme, slots)
            }
            SchemeName::AbufferBitonic => {
                let (scheme, slots) = exact_or_fixed(PostSort::Bitonic, sizing.capacity)?;
                go(&scheme, slots)
            }
            SchemeName::AbufferFixed => {
                let capacity = Count::Fixed(sizing.capacity.resolve(sizing.max_depth_complexity));
                let (scheme, slots) = exact_or_fixed(PostSort::Insertion, capacity)?;
                go(&scheme, slots)
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
                let pool = match sizing.capacity {
                    Count::Auto => sizing
                        .depth_complexity
                        .iter()
                        .map(|&c| c as usize)
                        .sum::<usize>()
                        .max(1),
                    Count::Fixed(c) => viewport.pixels() * c as usize,
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
            SchemeName::All => return Err("`all` names a list of schemes, not one".into()),
        })
    }
}

/// Refuses, before the oracle's counting pass, any scheme of `names` whose storage on `viewport`
/// would exceed `memory_cap` even at its smallest.
///
/// With `--k auto` or `--capacity exact` storage is sized from the scene's depth complexity, known
/// only after the counting pass, and that pass alone needs 24 bytes a pixel (6 GiB at
/// 16384 × 16384): a refusal must not wait for it. The smallest storage is one slot per pixel for
/// MDTS and the fixed A-buffer, and for the exact A-buffer its counters and offsets with no
/// fragment (4 + 4 bytes a pixel, as `ABuffer::exact` counts them). Schemes not listed here are
/// checked when they are built, after the count.
///
/// # Errors
/// The first scheme refused, with the bytes it would need at least.
pub fn check_memory_cap_early(
    names: &[SchemeName],
    viewport: Viewport,
    k: Count,
    capacity: Count,
    memory_cap: u64,
) -> Result<(), String> {
    let smallest = |count: Count| match count {
        Count::Auto => 1,
        Count::Fixed(n) => n,
    };
    let (k_least, capacity_least) = (smallest(k), smallest(capacity));
    for name in SchemeName::expand(names) {
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
            SchemeName::Abuffer | SchemeName::AbufferBitonic if capacity == Count::Auto => {
                let pixels = viewport.pixels() as u64;
                let needed = pixels * 4 + (pixels + 1) * 4;
                if needed > memory_cap {
                    Err(CaptureError::TooMuchMemory {
                        scheme: if name == SchemeName::Abuffer {
                            "abuffer"
                        } else {
                            "abuffer-bitonic"
                        }
                        .into(),
                        needed,
                        cap: memory_cap,
                    })
                } else {
                    Ok(())
                }
            }
            SchemeName::Abuffer | SchemeName::AbufferBitonic | SchemeName::AbufferFixed => {
                ABuffer::fixed(viewport, capacity_least, PostSort::Insertion, memory_cap).map(drop)
            }
            _ => Ok(()),
        };
        if let Err(error) = result {
            let sized_by_scene = match name {
                SchemeName::Mdts
                | SchemeName::Mdts32
                | SchemeName::MdtsDesc
                | SchemeName::MdtsProbe => k == Count::Auto,
                _ => capacity == Count::Auto,
            };
            return Err(if sized_by_scene {
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
    fn run(&self, executors: &mut Executors, executor: &str, view: &View<'_>) -> Run;
}

impl<S: Scheme> ErasedScheme for S {
    fn name(&self) -> String {
        Scheme::name(self)
    }

    fn run(&self, executors: &mut Executors, executor: &str, view: &View<'_>) -> Run {
        if executors.count_locked_ops {
            executor::count_locked_ops(view, self, executor != "serial")
        } else {
            match executor {
                "serial" => executors.serial.run(view, self),
                "tiled" => executors.tiled.run(view, self),
                "scheduled" => run_scheduled(view, self, &SCHEDULE, false).run,
                _ => executors.parallel.run(view, self),
            }
        }
    }
}
