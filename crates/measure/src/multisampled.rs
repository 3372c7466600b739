//! `bench --samples N`: the oracle's transparency image resolved from N samples a pixel against
//! the single-sample image, and the multisampled schemes side by side, each against the
//! per-sample oracle ([`SampleOracle`], `docs/semantics.md` §11).
//!
//! **The rows.** Storage at both granularities:
//! - *per sample*: every scheme of `--scheme` run on the view rasterizing per sample
//!   ([`View::with_samples`]), whose sample-expanded framebuffer makes it the per-sample scheme
//!   (MDTS, the A-buffer, …, their storage × samples), by the catalog's own runner and sizing;
//! - *masked*: per-pixel storage whose nodes carry a coverage mask, a primitive's samples in one
//!   pixel merged into one node ([`MaskedABuffer`]): the masked-node A-buffer, `--capacity`
//!   nodes a pixel, and the masked-node linked list, a pool of `--capacity` nodes a pixel shared
//!   by all (`auto`: their own counting pass of nodes, a second geometry pass, reported, sizes
//!   the A-buffer to the deepest pixel and the pool to every node). They run on the serial and
//!   parallel executors only (they have their own two loops, not the catalog's executors): with
//!   `--executor tiled` or `scheduled` they have no row.
//!
//! **The error** of every row is against the per-sample oracle, whatever the storage: the sample
//! fragments missing from the scheme's per-sample resolve, the samples whose list differs, and of
//! those the misordered ones ([`SampleDeviation`]); and the colour error of its transparency image,
//! shaded per sample and box-resolved per pixel, against the oracle's image resolved the same
//! way ([`ColourJudge::per_sample`]). Memory is what the scheme allocated, sized by `--k` and
//! `--capacity` or by its own counting pass, never by the oracle.

use fragsim_capture::executors::Executor;
use fragsim_capture::Scheme as _;
use fragsim_catalog::{check_memory_cap_early, Count, SchemeName, SchemeRunner, Sizing};
use fragsim_oracle::samples::{SampleDeviation, SampleOracle};
use fragsim_raster::{Camera, OrbitCamera, SamplePattern, Scene, View};
use fragsim_schemes::masked_abuffer::{MaskedABuffer, MaskedFrame, MaskedStorage};
use fragsim_shade::effects::error_pixels;
use serde::Serialize;

use crate::colour_judge::{ColourColumns, ColourJudge, JudgedImage};
use crate::frame_timing::{ms, time_frames, FrameTimes};
use crate::images::Images;
use crate::Progress;

/// The oracle's transparency image resolved from several samples a pixel, against the
/// single-sample image, and the multisampled schemes' rows (`--samples`).
#[derive(Debug, Clone, Serialize)]
pub struct MsaaReport {
    /// Samples a pixel.
    pub samples: u32,
    /// Fragments of the per-sample oracle (one per covered sample).
    pub sample_fragments: usize,
    /// Pixels whose samples do not all hold the same primitives in the same order: every edge
    /// multisampling sees, between two triangles of one surface too.
    pub mixed_pixels: usize,
    /// Of those, pixels whose samples hold different numbers of fragments: where a layer begins
    /// or ends inside the pixel (silhouettes and folds).
    pub layer_edge_pixels: usize,
    /// Pixels whose resolved 8-bit colour differs from the single-sample image's.
    pub differing_pixels: usize,
    /// The deepest pixel of the per-sample oracle's per-pixel view: the most nodes one pixel
    /// needs when a primitive's samples share a node (what masked storage must hold to lose
    /// nothing).
    pub max_nodes_per_pixel: u32,
    /// One row per multisampled scheme and executor (`bench-msaa` records).
    #[serde(skip)]
    pub rows: Vec<SampledRow>,
}

/// One multisampled scheme on one executor, against the per-sample oracle.
#[derive(Debug, Clone, Serialize)]
pub struct SampledRow {
    /// The catalog's name of a scheme run per sample, `abuffer-masked` or `linked-list-masked`.
    pub scheme: String,
    /// `per-sample` (a catalog scheme on the sample-expanded framebuffer) or `masked` (per-pixel
    /// nodes carrying a coverage mask).
    pub storage: &'static str,
    /// The executor (a record's context carries it).
    #[serde(skip)]
    pub executor: String,
    /// Threads (a record's context carries them).
    #[serde(skip)]
    pub threads: usize,
    /// Samples a pixel.
    pub samples: u32,
    /// Geometry passes per frame, the counting pass that sized the storage included.
    pub passes: u32,
    /// That counting pass, where one ran (inside `passes_ms`).
    pub count_pass_ms: Option<f64>,
    /// Slots a sample (per-sample storage with a fixed count), nodes a pixel (the masked
    /// A-buffer) or pool nodes a pixel (linked lists) the storage had; `None` where it was sized
    /// by counts beyond one number (a pool of the scene's nodes, per-pixel exact storage).
    pub slots: Option<u32>,
    /// Bytes the scheme allocated.
    pub memory_bytes: u64,
    /// Bytes per pixel of the render target (all its samples).
    pub bytes_per_pixel: f64,
    /// Walks per frame, over all passes: sample fragments for per-sample storage, nodes (one
    /// per pixel a primitive covers: the fragment-shader invocations) for masked storage.
    pub fragments: u64,
    /// What found no room: sample fragments for per-sample storage (beyond K or the capacity,
    /// the oracle's prediction, as `bench` rows count it), whole nodes for masked storage (as its
    /// pixels' counters counted them).
    pub overflowed: u64,
    /// The unit of `overflowed`: `fragments` or `nodes`.
    pub overflow_unit: &'static str,
    /// Sample fragments of the per-sample oracle.
    pub sample_fragments: u64,
    /// Of those, missing from the scheme's per-sample resolve, the overflow's included.
    pub missing: u64,
    /// Of the missing, those the scheme owed: per-sample storage, fragments beyond the oracle's
    /// predicted overflow (as `bench` rows count `lost`, so that a full K is not read as a bug);
    /// masked storage, every missing one (its overflow counts whole nodes, whose sample
    /// fragments cannot be told from losses).
    pub lost: u64,
    /// Samples whose list differs from the per-sample oracle's in any way.
    pub wrong_samples: u64,
    /// `wrong_samples` over every sample of the render target.
    pub wrong_sample_rate: f64,
    /// Of the wrong samples, those with every fragment present in another order.
    pub misordered_samples: u64,
    /// Pixels whose 8-bit colour of the resolved transparency image differs from the oracle's
    /// resolved image (`None` when the words cannot resolve it).
    pub error_pixels: Option<u64>,
    /// `error_pixels` over the pixels the per-sample oracle covers.
    pub error_pixel_rate: Option<f64>,
    /// The colour error of that image.
    #[serde(flatten)]
    pub colour: ColourColumns,
    /// Median frame time in milliseconds: vertex stage, geometry passes and post pass.
    pub time_ms: f64,
    /// Fastest frame.
    pub min_ms: f64,
    /// Slowest frame.
    pub max_ms: f64,
    /// Median time of the vertex stage.
    pub vertex_ms: f64,
    /// Median time of the geometry passes (storage initialisation, rasterization per sample,
    /// capture; the masked nodes' merging too).
    pub passes_ms: f64,
    /// Median time of the post pass.
    pub resolve_ms: f64,
}

/// What the multisampled measurement needs of the bench.
pub(crate) struct Bench<'b, 'v> {
    /// The single-sample view (its camera set per frame).
    pub view: &'b View<'v>,
    /// The scene.
    pub scene: &'b Scene,
    /// Its orbit.
    pub orbit: OrbitCamera,
    /// The camera set each frame.
    pub camera: &'b Camera,
    /// The single-sample judge of transparency.
    pub judge: &'b ColourJudge<'b>,
    /// The catalog schemes to run per sample.
    pub schemes: &'b [SchemeName],
    /// The executors.
    pub executors: &'b [Executor],
    /// Their sizes.
    pub sizing: Sizing,
    /// Frames timed per row.
    pub frames: usize,
    /// The pool of the parallel executors.
    pub pool: &'b rayon::ThreadPool,
    /// One thread: a serial row's vertex stage.
    pub serial_pool: &'b rayon::ThreadPool,
    /// Where images go (`None`: `--no-images`).
    pub images: Option<&'b Images>,
    /// Where the rows' progress goes.
    pub progress: &'b dyn Progress,
}

/// Refuses, before any pass, storage of the multisampled rows beyond the memory cap: every scheme
/// of `schemes` at its smallest over the sample-expanded framebuffer, and the masked-node
/// A-buffer and linked list at a fixed `--capacity`.
///
/// # Errors
/// The first refusal, by name.
pub(crate) fn check_early(
    view: &View<'_>,
    pattern: SamplePattern,
    schemes: &[SchemeName],
    sizing: &Sizing,
) -> Result<(), String> {
    check_memory_cap_early(
        schemes,
        pattern.expand(view.viewport()).map_err(|e| e.to_string())?,
        sizing,
    )
    .map_err(|e| format!("at {} samples a pixel: {e}", pattern.count()))?;
    if let Count::Fixed(capacity) = sizing.capacity {
        for linked in [false, true] {
            let storage = masked_storage(linked, capacity, view.viewport().pixels());
            MaskedABuffer::with_storage(
                view.viewport(),
                pattern.count(),
                storage,
                sizing.memory_cap,
            )
            .map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// The `--samples` report: the oracle's resolved image and the multisampled rows.
///
/// # Errors
/// Memory beyond the cap, a scheme's refusal, or an image that cannot be written.
pub(crate) fn measure(bench: &Bench<'_, '_>, pattern: SamplePattern) -> Result<MsaaReport, String> {
    let samples = pattern.count();
    let mut view = bench
        .view
        .clone()
        .with_samples(pattern)
        .map_err(|e| e.to_string())?;
    // The per-sample oracle is about `samples` single-sample oracles (one per sample index,
    // each on a shifted pixel grid): the single-sample bound against that share of the cap.
    fragsim_oracle::memory_cap::check(bench.view, bench.sizing.memory_cap / u64::from(samples))
        .map_err(|e| e.to_string())?;
    let oracle = SampleOracle::build(&view).map_err(|e| e.to_string())?;
    let lists = oracle.oracle();
    let judge = ColourJudge::per_sample(
        crate::colour_judge::EffectName::Transparency,
        bench.scene,
        &view,
        bench.orbit,
        lists,
    )?;
    let image = judge
        .reference()
        .expect("the judge shades the oracle's image");
    let single = bench
        .judge
        .reference()
        .expect("the judge shades the oracle's image");
    let n = samples as usize;
    #[expect(
        clippy::cast_possible_truncation,
        reason = "list entries hold primitive ids, u32s"
    )]
    let prims = |sample: usize| lists.pixel(sample).iter().map(|&e| e as u32);
    let (mut mixed_pixels, mut layer_edge_pixels) = (0, 0);
    for first in (0..lists.pixels()).step_by(n) {
        let others = || first + 1..first + n;
        let layers = lists.pixel(first).len();
        layer_edge_pixels += usize::from(others().any(|s| lists.pixel(s).len() != layers));
        mixed_pixels += usize::from(others().any(|s| !prims(s).eq(prims(first))));
    }
    if let Some(images) = bench.images {
        images.save_with_difference(
            image,
            single,
            &format!("bench-oracle-transparency-msaa{samples}"),
            &format!("the oracle's transparency at {samples} samples a pixel, resolved"),
        )?;
    }
    let per_pixel = oracle.per_pixel();
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a pixel holds at most one node per triangle, and triangle ids are u32"
    )]
    let max_nodes_per_pixel = (0..per_pixel.pixels())
        .map(|p| per_pixel.pixel(p).len() as u32)
        .max()
        .unwrap_or(0);
    let rows = rows(bench, &mut view, &oracle, &judge)?;
    Ok(MsaaReport {
        samples,
        sample_fragments: lists.fragments(),
        mixed_pixels,
        layer_edge_pixels,
        differing_pixels: error_pixels(single, image),
        max_nodes_per_pixel,
        rows,
    })
}

/// The rows: every scheme per sample on every executor, then the masked-node A-buffer and
/// linked list on the serial and parallel executors among them.
fn rows(
    bench: &Bench<'_, '_>,
    view: &mut View<'_>,
    oracle: &SampleOracle,
    judge: &ColourJudge<'_>,
) -> Result<Vec<SampledRow>, String> {
    let masked_executors: Vec<Executor> = bench
        .executors
        .iter()
        .copied()
        .filter(|&e| matches!(e, Executor::Serial | Executor::Parallel))
        .collect();
    let progress = bench.progress;
    progress.begin(
        ((bench.schemes.len() * bench.executors.len() + 2 * masked_executors.len()) * bench.frames)
            as u64,
        "bench --samples",
    );
    let pixels = view.pixel_viewport();
    let samples = oracle.pattern().count();
    let mut rows = Vec::new();
    // The row of a first frame's per-sample lists and its times; the image unless --no-images.
    let mut row = |common: Common, error: SampleDeviation, judged: Option<JudgedImage<'_>>| {
        let times = &common.times;
        if let (Some(images), Some(j)) = (bench.images, &judged) {
            images.save_with_difference(
                &j.image,
                j.reference,
                &format!("bench-{}-msaa{samples}-{}", common.scheme, common.executor),
                &format!(
                    "transparency of {} at {samples} samples on the {} executor",
                    common.scheme, common.executor
                ),
            )?;
        }
        let error_pixels = judged.as_ref().map(|j| j.errors);
        rows.push(SampledRow {
            scheme: common.scheme,
            storage: common.storage,
            executor: common.executor.name().into(),
            threads: common.threads,
            samples,
            passes: common.passes,
            count_pass_ms: common.count_pass_ms,
            slots: common.slots,
            memory_bytes: common.memory_bytes,
            bytes_per_pixel: common.memory_bytes as f64 / pixels.pixels() as f64,
            fragments: common.fragments,
            overflowed: common.overflowed,
            overflow_unit: common.overflow_unit,
            sample_fragments: error.fragments,
            missing: error.lost,
            lost: common.owed_lost.unwrap_or(error.lost),
            wrong_samples: error.wrong_samples,
            wrong_sample_rate: error.wrong_samples as f64 / error.samples.max(1) as f64,
            misordered_samples: error.misordered_samples,
            error_pixels,
            error_pixel_rate: error_pixels.map(|e| e as f64 / judge.covered.max(1) as f64),
            colour: ColourColumns::of(judged.map(|j| j.colour)),
            time_ms: ms(times.median()),
            min_ms: ms(times.frames[0]),
            max_ms: ms(times.frames[times.frames.len() - 1]),
            vertex_ms: ms(times.vertex),
            passes_ms: ms(times.passes),
            resolve_ms: ms(times.resolve),
        });
        Ok::<(), String>(())
    };
    // Copied out of `bench`, whose progress the pool's threads must not see.
    let sizing = bench.sizing;
    for &name in bench.schemes {
        for &executor in bench.executors {
            progress.message(&format!("{name} per sample on the {executor} executor"));
            let mut runner = SchemeRunner::default();
            let (named, times) = time_frames(
                view,
                bench.camera,
                bench.vertex_pool(executor),
                bench.frames,
                progress,
                |view| {
                    let named = bench
                        .pool
                        .install(|| runner.run(name, executor, view, &sizing))
                        .map_err(|e| e.to_string())?;
                    let stats = &named.run.stats;
                    let (pass_time, resolve_time) = (stats.pass_time, stats.resolve_time);
                    Ok((named, pass_time, resolve_time))
                },
            )?;
            let stats = &named.run.stats;
            let capture = &named.run.capture;
            let diff = oracle.oracle().diff(capture);
            row(
                Common {
                    scheme: named.name.clone(),
                    storage: "per-sample",
                    executor,
                    threads: stats.threads,
                    passes: stats.passes,
                    count_pass_ms: stats.count_pass_time.map(ms),
                    slots: named.slots,
                    memory_bytes: stats.memory_bytes,
                    fragments: stats.counters.fragments,
                    overflowed: diff.overflowed,
                    overflow_unit: "fragments",
                    owed_lost: Some(diff.lost),
                    times,
                },
                oracle.capture_error(capture),
                judge.judge(capture),
            )?;
        }
    }
    for linked in [false, true] {
        for &executor in &masked_executors {
            let parallel = executor == Executor::Parallel;
            let kind = if linked { "linked list" } else { "A-buffer" };
            progress.message(&format!("masked {kind} on the {executor} executor"));
            let (masked, times) = time_frames(
                view,
                bench.camera,
                bench.vertex_pool(executor),
                bench.frames,
                progress,
                |view| {
                    let masked = bench
                        .pool
                        .install(|| masked_frame(view, sizing, linked, parallel))?;
                    let (pass_time, resolve_time) = (masked.pass_time(), masked.frame.resolve_time);
                    Ok((masked, pass_time, resolve_time))
                },
            )?;
            let per_sample = masked.frame.lists.per_sample();
            row(
                Common {
                    scheme: masked.name.clone(),
                    storage: "masked",
                    executor,
                    threads: if parallel {
                        bench.pool.current_num_threads()
                    } else {
                        1
                    },
                    passes: if masked.count.is_some() { 2 } else { 1 },
                    count_pass_ms: masked
                        .count
                        .as_ref()
                        .map(|c| ms(c.pass_time + c.resolve_time)),
                    slots: masked.slots,
                    memory_bytes: masked.memory_bytes,
                    fragments: masked.nodes,
                    overflowed: masked.frame.dropped,
                    overflow_unit: "nodes",
                    owed_lost: None,
                    times,
                },
                oracle.sample_error(&per_sample),
                judge.judge_lists(&per_sample),
            )?;
        }
    }
    progress.end();
    Ok(rows)
}

/// What a row's two kinds of scheme both report.
struct Common {
    scheme: String,
    storage: &'static str,
    executor: Executor,
    threads: usize,
    passes: u32,
    count_pass_ms: Option<f64>,
    slots: Option<u32>,
    memory_bytes: u64,
    fragments: u64,
    overflowed: u64,
    overflow_unit: &'static str,
    /// Fragments lost beyond the predicted overflow, where the overflow is counted in fragments
    /// (`None`: in nodes, so every missing sample fragment counts as lost).
    owed_lost: Option<u64>,
    times: FrameTimes,
}

impl Bench<'_, '_> {
    /// The vertex stage of a serial row runs on one thread too.
    fn vertex_pool(&self, executor: Executor) -> &rayon::ThreadPool {
        if executor == Executor::Serial {
            self.serial_pool
        } else {
            self.pool
        }
    }
}

/// One frame of masked-node storage, with its counting pass where `--capacity auto`.
struct MaskedRun {
    /// `abuffer-masked` or `linked-list-masked`.
    name: String,
    /// The counting pass of nodes, where one sized the storage.
    count: Option<MaskedFrame>,
    /// The capture.
    frame: MaskedFrame,
    /// Nodes a pixel (the A-buffer) or pool nodes a pixel (the linked list, a fixed pool).
    slots: Option<u32>,
    /// Bytes of the capture's storage (the counting pass needs one counter a pixel, which a GPU
    /// clears and reuses as the capture's).
    memory_bytes: u64,
    /// Nodes walked (fragment-shader invocations, one per pixel a primitive covers), over both
    /// passes.
    nodes: u64,
}

impl MaskedRun {
    /// Both passes' geometry time, the counting pass's read-back of its counters included.
    fn pass_time(&self) -> std::time::Duration {
        self.frame.pass_time
            + self
                .count
                .as_ref()
                .map_or(Default::default(), |c| c.pass_time + c.resolve_time)
    }
}

/// The storage of `--capacity N`: `N` slots a pixel, or a pool of `N` nodes for each of `pixels`
/// (as the catalog's linked lists size theirs).
fn masked_storage(linked: bool, capacity: u32, pixels: usize) -> MaskedStorage {
    if linked {
        MaskedStorage::Pool(pixels * capacity as usize)
    } else {
        MaskedStorage::Slots(capacity)
    }
}

/// A frame of the masked-node A-buffer (`linked`: linked list) on `view` (rasterizing per
/// sample), sized by `sizing.capacity`; `auto`: by its counting pass, the A-buffer to the
/// deepest pixel's nodes, the pool to all of them.
fn masked_frame(
    view: &View<'_>,
    sizing: Sizing,
    linked: bool,
    parallel: bool,
) -> Result<MaskedRun, String> {
    let pixels = view.pixel_viewport();
    let samples = view.samples().map_or(1, |p| p.count());
    let (count, storage) = match sizing.capacity {
        Count::Fixed(capacity) => (None, masked_storage(linked, capacity, pixels.pixels())),
        Count::Auto => {
            let counted = MaskedABuffer::count_nodes(pixels, samples, view, parallel)
                .map_err(|e| e.to_string())?;
            let nodes = counted.lists.overflow.iter();
            let storage = if linked {
                MaskedStorage::Pool(nodes.map(|&n| n as usize).sum::<usize>().max(1))
            } else {
                MaskedStorage::Slots(nodes.copied().max().unwrap_or(0).max(1))
            };
            (Some(counted), storage)
        }
    };
    let scheme = MaskedABuffer::with_storage(pixels, samples, storage, sizing.memory_cap)
        .map_err(|e| e.to_string())?;
    let frame = scheme.frame(view, parallel).map_err(|e| e.to_string())?;
    let slots = match (storage, sizing.capacity) {
        (MaskedStorage::Slots(capacity), _) => Some(capacity),
        (MaskedStorage::Pool(_), Count::Fixed(capacity)) => Some(capacity),
        (MaskedStorage::Pool(_), Count::Auto) => None,
    };
    Ok(MaskedRun {
        name: scheme.name(),
        slots,
        memory_bytes: scheme.layout().bytes(),
        nodes: frame.nodes + count.as_ref().map_or(0, |c| c.nodes),
        count,
        frame,
    })
}
