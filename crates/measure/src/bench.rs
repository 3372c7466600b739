//! `fragsim bench`: the speed/accuracy trade of every scheme on one scene, measured the way the
//! papers do (FreePipe Tables 2–3, bucket depth peeling Table 2): passes, memory, fragments
//! captured and lost, error-pixel rate of an effect against the oracle's image, and time per
//! frame (median, min, max over `--frames`), with the split between vertex stage, rasterization
//! and capture.

use std::time::Duration;

use fragsim_capture::executors::Executor;
use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_catalog::{check_memory_cap_early, SchemeName, SchemeRunner};
use fragsim_oracle::verdict::{judge_run, RunVerdict};
use fragsim_oracle::{Oracle, Ties};
use fragsim_raster::{SamplePattern, SceneSpec, Viewport};
use serde::Serialize;

use crate::approximate::{ApproximateName, ApproximateRow};
use crate::colour_by_depth::ColourByDepth;
use crate::colour_judge::{AttributePass, ColourColumns, ColourJudge, EffectName, JudgedImage};
use crate::frame_timing::{median, ms, time_frames, time_raster_alone};
use crate::images::Images;
use crate::multisampled::MsaaReport;
use crate::{Progress, SchemeSetup, Shard};

pub mod report;

/// What `bench` measures, and how.
#[derive(Debug, Clone)]
pub struct BenchParams {
    /// The scene and its camera.
    pub scene: SceneSpec,
    /// The viewport.
    pub viewport: Viewport,
    /// The catalog schemes measured, in order.
    pub schemes: Vec<SchemeName>,
    /// Their sizes, executors, threads and submission order.
    pub setup: SchemeSetup,
    /// Frames timed per scheme and executor (the median, min and max are reported).
    pub frames: u32,
    /// The effect whose image is compared with the oracle's.
    pub effect: EffectName,
    /// Also measure multisampling at this many samples a pixel (the standard patterns).
    pub samples: Option<u32>,
    /// Approximate OIT schemes measured beside the catalog's.
    pub approximate: Vec<ApproximateName>,
    /// The rows measured: of the (scheme, executor) rows, then the approximate ones, row `k`
    /// when the shard takes `k`.
    pub shard: Shard,
    /// Where the effect images and their differences go (`None`: no images).
    pub images: Option<Images>,
}

/// One row of the bench.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// Scheme name.
    pub scheme: String,
    /// `exact`, `exact-distinct-depths` or `approximate`.
    pub guarantee: String,
    /// Whether the first frame kept the guarantee (judged by the oracle, on this executor).
    pub keeps_guarantee: bool,
    /// `serial`, `parallel`, `tiled` or `scheduled` (a record's context carries it).
    #[serde(skip)]
    pub executor: String,
    /// Threads (a record's context carries them).
    #[serde(skip)]
    pub threads: usize,
    /// Geometry passes per frame.
    pub passes: u32,
    /// The counting pass that sized the storage (inside `passes_ms`), where one ran.
    pub count_pass_ms: Option<f64>,
    /// Bytes of per-pixel storage.
    pub memory_bytes: u64,
    /// Bytes per pixel.
    pub bytes_per_pixel: f64,
    /// Fragments rasterized per frame, over all passes.
    pub fragments: u64,
    /// Fragments captured.
    pub captured: u64,
    /// Fragments the scheme had no room for (counted by design).
    pub overflowed: u64,
    /// Fragments it should have kept but did not.
    pub lost: u64,
    /// Pixels that differ from the oracle's lists.
    pub mismatched_pixels: u64,
    /// Pixels whose 8-bit colour differs from the oracle's image for the effect (`None` when the
    /// scheme's words cannot resolve the effect).
    pub error_pixels: Option<u64>,
    /// `error_pixels` over the pixels the oracle covers.
    pub error_pixel_rate: Option<f64>,
    /// The colour error of the effect's image against the oracle's (`mean_abs_error`,
    /// `max_abs_error`, `psnr_db`; all `null` when the words cannot resolve the effect).
    #[serde(flatten)]
    pub colour: ColourColumns,
    /// The same colour error per depth-complexity bucket (`pixels_dc_1`, …, all `null` when
    /// the words cannot resolve the effect).
    #[serde(flatten)]
    pub colour_by_depth: ColourByDepth,
    /// What the image judge completed from the oracle or recomputed (the deferred attribute
    /// pass), with its count and time; `None` when the image is the scheme's words alone.
    pub attribute_pass: Option<AttributePass>,
    /// Memory operations per fragment, of the untimed frame that counts locked operations.
    pub ops_per_fragment: f64,
    /// Read-modify-write operations (`lock`-prefixed instructions on x86) per fragment, counted
    /// in one extra, untimed frame: the frame `ops_per_fragment` counts too, so that the two
    /// describe one interleaving (a spinlock's spins vary from frame to frame).
    pub locked_ops_per_fragment: f64,
    /// Median frame time in milliseconds: vertex stage, geometry passes and post pass.
    pub time_ms: f64,
    /// Fastest frame.
    pub min_ms: f64,
    /// Slowest frame.
    pub max_ms: f64,
    /// Frames per second at the median.
    pub fps: f64,
    /// Triangles per second at the median (per geometry pass).
    pub triangles_per_second: f64,
    /// Fragments per second at the median.
    pub fragments_per_second: f64,
    /// Median time of the vertex stage (transform, outcodes, snapping of every vertex).
    pub vertex_ms: f64,
    /// Median time of the geometry passes: storage initialisation, rasterization and capture.
    pub passes_ms: f64,
    /// Median time of the post pass.
    pub resolve_ms: f64,
    /// The vertex stage's median over the mesh's vertices, in nanoseconds.
    pub ns_per_vertex: f64,
    /// The geometry passes' median over the triangles they ran (triangles × passes), in
    /// nanoseconds: set-up, scan and capture of a triangle's fragments, storage initialisation
    /// included.
    pub ns_per_triangle: f64,
    /// The geometry passes' and the post pass's medians over the fragments rasterized, in
    /// nanoseconds: what a fragment costs from rasterization to its resolved list.
    pub ns_per_fragment: f64,
    /// Shares of the frame: vertex stage, geometry passes and post pass, each median over the
    /// sum of the three medians (they add up to 1).
    pub shares: StageShares,
    /// Depth peeling's median time over this one, when depth peeling ran.
    pub speedup_vs_depth_peeling: Option<f64>,
}

/// Each stage's share of a frame ([`BenchRow::shares`]).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StageShares {
    /// The vertex stage.
    pub vertex: f64,
    /// The geometry passes.
    pub passes: f64,
    /// The post pass.
    pub resolve: f64,
}

impl StageShares {
    /// The shares of three stage times.
    fn of(vertex: Duration, passes: Duration, resolve: Duration) -> Self {
        let total = (vertex + passes + resolve).as_secs_f64().max(1e-12);
        Self {
            vertex: vertex.as_secs_f64() / total,
            passes: passes.as_secs_f64() / total,
            resolve: resolve.as_secs_f64() / total,
        }
    }
}

/// Nanoseconds per item of a stage that took `time` over `items` items (0 items: 0).
fn ns_per(time: Duration, items: u64) -> f64 {
    if items == 0 {
        0.0
    } else {
        time.as_secs_f64() * 1e9 / items as f64
    }
}

/// What the whole bench measured.
#[derive(Debug, Clone, Serialize)]
pub struct BenchReport {
    /// Scene name, as tables and titles print it (a mesh by its file name).
    #[serde(skip)]
    pub scene: String,
    /// Triangles.
    pub triangles: u32,
    /// Viewport.
    #[serde(skip)]
    pub width: u32,
    /// Viewport.
    #[serde(skip)]
    pub height: u32,
    /// Oracle fragments.
    pub oracle_fragments: usize,
    /// Largest depth complexity.
    pub max_depth_complexity: u32,
    /// Pixels with at least one fragment.
    pub covered_pixels: usize,
    /// Median rasterization alone (every triangle set up and scanned, fragments discarded) on the
    /// pool, ms: what every scheme pays per geometry pass before its first memory operation.
    pub raster_ms: f64,
    /// The effect compared.
    pub effect: String,
    /// Frames per row.
    pub frames: u32,
    /// The multisampled oracle image against the single-sample one, and the multisampled rows
    /// (`--samples`).
    pub msaa: Option<MsaaReport>,
    /// One row per scheme and executor.
    #[serde(skip)]
    pub rows: Vec<BenchRow>,
    /// One row per approximate scheme (`--approximate`).
    #[serde(skip)]
    pub approximate: Vec<ApproximateRow>,
}

/// Runs `bench`.
///
/// # Errors
/// Scene, parameter or output errors.
pub fn bench(params: &BenchParams, progress: &dyn Progress) -> Result<BenchReport, String> {
    let pattern = params
        .samples
        .map(|count| {
            if params.effect != EffectName::Transparency {
                return Err(format!(
                    "--samples resolves the transparency image only, not {}",
                    params.effect.label()
                ));
            }
            SamplePattern::standard(count).map_err(|e| format!("--samples {count}: {e}"))
        })
        .transpose()?;
    let pool = params.setup.pool()?;
    let spec = &params.scene;
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let viewport = params.viewport;
    let orbit = spec.orbit();
    let frames = params.frames as usize;
    // The camera depends on the model's bounds, a per-scene constant (a GPU application computes
    // it at load); the vertex stage proper is timed per frame, on the pool.
    let camera = spec.camera(&scene, viewport).map_err(|e| e.to_string())?;
    let serial_pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    let mut view = params
        .setup
        .submission(spec.view(&scene, viewport).map_err(|e| e.to_string())?);
    if let Some(warning) = scene.empty_view_warning(&view) {
        progress.warn(&warning);
    }
    let sizing = params.setup.sizing;
    let schemes = &params.schemes;
    check_memory_cap_early(schemes, viewport, &sizing).map_err(|e| e.to_string())?;
    if let Some(pattern) = pattern {
        crate::multisampled::check_early(&view, pattern, schemes, &sizing)?;
    }
    let raster_times: Vec<Duration> = (0..frames)
        .map(|_| pool.install(|| time_raster_alone(&view)))
        .collect();
    fragsim_oracle::memory_cap::check(&view, sizing.memory_cap).map_err(|e| e.to_string())?;
    let oracle = Oracle::build(&view);
    let judge = ColourJudge::new(params.effect, &scene, &view, orbit, &oracle);
    crate::approximate::check_effect(&judge, &params.approximate)?;
    let covered = judge.covered;
    let depth_complexity = oracle.depth_complexity();
    let executors = &params.setup.executors;
    // One step a frame, plus the untimed frame that counts locked operations.
    let shard = params.shard;
    progress.begin(
        ((0..schemes.len() * executors.len())
            .filter(|&k| shard.takes(k))
            .count()
            * (frames + 1)) as u64,
        "bench",
    );
    let images = &params.images;
    if let (Some(image), Some(images)) = (judge.reference(), &images) {
        images.save(
            image,
            &format!("bench-oracle-{}.png", params.effect.label()),
        )?;
    }
    // Row `k` of the campaign: the (scheme, executor) rows in order, then the approximate ones.
    let mut row_number = 0..;
    let mut rows = Vec::new();
    for &name in schemes {
        for &executor in executors {
            if !row_number.next().is_some_and(|k| shard.takes(k)) {
                continue;
            }
            progress.message(&format!("{name} on the {executor} executor"));
            let mut runner = SchemeRunner::default();
            // A frame is the vertex stage, the geometry passes and the post pass; the serial
            // executor's vertex stage runs on one thread too.
            let frame_pool = if executor == Executor::Serial {
                &serial_pool
            } else {
                &pool
            };
            let (named, times) =
                time_frames(&mut view, &camera, frame_pool, frames, progress, |view| {
                    let named = pool
                        .install(|| runner.run(name, executor, view, &sizing))
                        .map_err(|e| e.to_string())?;
                    let stats = &named.run.stats;
                    let (pass_time, resolve_time) = (stats.pass_time, stats.resolve_time);
                    Ok((named, pass_time, resolve_time))
                })?;
            runner.count_locked_ops = true;
            let counted = pool
                .install(|| runner.run(name, executor, &view, &sizing))
                .map_err(|e| e.to_string())?;
            progress.step();
            let locked_ops = counted.run.stats.locked_ops.unwrap_or(0);
            let RunVerdict { diff, kept, .. } = judge_run(
                &oracle,
                &named.run.capture,
                named.guarantee,
                executor.serialises_pixels(),
                Ties::ByPrimitive,
            );
            let judged = judge.judge(&named.run.capture);
            let error_pixels = judged.as_ref().map(|j| j.errors);
            let colour = ColourColumns::of(judged.as_ref().map(|j| j.colour));
            let colour_by_depth = ColourByDepth::of(
                judged.as_ref().map(|j| (j.reference, &j.image)),
                &depth_complexity,
            )?;
            if let (
                Some(JudgedImage {
                    image, reference, ..
                }),
                Some(images),
            ) = (judged.as_ref(), &images)
            {
                images.save_with_difference(
                    image,
                    reference,
                    &format!("bench-{}-{executor}", named.name),
                    &format!(
                        "{} of {} on the {executor} executor",
                        params.effect.label(),
                        named.name
                    ),
                )?;
            }
            let median_time = times.median();
            let stats = &named.run.stats;
            let (vertex_median, pass_median, resolve_median) =
                (times.vertex, times.passes, times.resolve);
            let triangles_run = u64::from(view.triangle_count()) * u64::from(stats.passes);
            let seconds = median_time.as_secs_f64().max(1e-12);
            rows.push(BenchRow {
                scheme: named.name.clone(),
                guarantee: named.guarantee.to_string(),
                keeps_guarantee: kept,
                executor: executor.name().into(),
                threads: stats.threads,
                passes: stats.passes,
                count_pass_ms: stats.count_pass_time.map(ms),
                memory_bytes: stats.memory_bytes,
                bytes_per_pixel: stats.memory_bytes as f64 / viewport.pixels() as f64,
                fragments: stats.counters.fragments,
                captured: diff.captured,
                overflowed: diff.overflowed,
                lost: diff.lost,
                mismatched_pixels: diff.mismatched_pixels,
                error_pixels,
                error_pixel_rate: error_pixels.map(|e| e as f64 / covered.max(1) as f64),
                colour,
                colour_by_depth,
                attribute_pass: judged.and_then(|j| j.pass),
                ops_per_fragment: counted.run.stats.counters.steps as f64
                    / counted.run.stats.counters.fragments.max(1) as f64,
                locked_ops_per_fragment: locked_ops as f64
                    / counted.run.stats.counters.fragments.max(1) as f64,
                time_ms: ms(median_time),
                min_ms: ms(times.frames[0]),
                max_ms: ms(times.frames[times.frames.len() - 1]),
                fps: 1.0 / seconds,
                triangles_per_second: f64::from(view.triangle_count()) * f64::from(stats.passes)
                    / seconds,
                fragments_per_second: stats.counters.fragments as f64 / seconds,
                vertex_ms: ms(vertex_median),
                passes_ms: ms(pass_median),
                resolve_ms: ms(resolve_median),
                ns_per_vertex: ns_per(vertex_median, view.mesh().positions.len() as u64),
                ns_per_triangle: ns_per(pass_median, triangles_run),
                ns_per_fragment: ns_per(pass_median + resolve_median, stats.counters.fragments),
                shares: StageShares::of(vertex_median, pass_median, resolve_median),
                speedup_vs_depth_peeling: None,
            });
        }
    }
    progress.end();
    set_speedups(&mut rows);
    let msaa = pattern
        .map(|pattern| {
            let bench = crate::multisampled::Bench {
                view: &view,
                scene: &scene,
                orbit,
                camera: &camera,
                judge: &judge,
                schemes,
                executors,
                sizing,
                frames,
                pool: &pool,
                serial_pool: &serial_pool,
                images: images.as_ref(),
                progress,
            };
            crate::multisampled::measure(&bench, pattern)
        })
        .transpose()?;
    let raster_ms = ms(median(&mut raster_times.clone()));
    let order = (!params.approximate.is_empty()).then(|| PrimitiveOrder::of_view(&view));
    let mut approximate = Vec::new();
    if let Some(order) = &order {
        let nodes = crate::approximate::nodes(sizing.k, &oracle);
        for &scheme in &params.approximate {
            if !row_number.next().is_some_and(|k| shard.takes(k)) {
                continue;
            }
            let (row, image) = pool.install(|| {
                crate::approximate::measure(
                    scheme, nodes, &judge, &oracle, order, frames, raster_ms,
                )
            })?;
            if let (Some(reference), Some(images)) = (judge.reference(), &images) {
                images.save_with_difference(
                    &image,
                    reference,
                    &format!("bench-{}", row.scheme),
                    &format!("{} of {}", params.effect.label(), row.label()),
                )?;
            }
            approximate.push(row);
        }
    }
    let report = BenchReport {
        scene: crate::scene_name(spec),
        triangles: view.triangle_count(),
        width: viewport.width,
        height: viewport.height,
        oracle_fragments: oracle.fragments(),
        max_depth_complexity: oracle.max_depth_complexity(),
        covered_pixels: covered,
        raster_ms,
        effect: params.effect.label().into(),
        frames: params.frames,
        msaa,
        rows,
        approximate,
    };
    Ok(report)
}

/// Classical depth peeling (64- or 32-bit words) is the papers' baseline: every row gets the
/// ratio of its time to it.
fn set_speedups(rows: &mut [BenchRow]) {
    let is_baseline = |scheme: &str| {
        matches!(
            SchemeName::from_name(scheme),
            Some(SchemeName::Peeling | SchemeName::Peeling32)
        )
    };
    let baselines: Vec<(String, f64)> = rows
        .iter()
        .filter(|r| is_baseline(&r.scheme))
        .map(|r| (r.executor.clone(), r.time_ms))
        .collect();
    for row in rows.iter_mut() {
        if let Some((_, base)) = baselines
            .iter()
            .find(|(executor, _)| *executor == row.executor)
        {
            row.speedup_vs_depth_peeling = Some(base / row.time_ms.max(1e-9));
        }
    }
}
