//! `sweep`: the error-pixel rate of each scheme at many view angles around the model (the
//! bucket depth peeling paper's Figure 6), and the colour error over the image and per
//! depth-complexity bucket at each angle, with each angle's frame time; its tables and charts
//! are [`report`]'s.

use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_catalog::{SchemeName, SchemeRunner};
use fragsim_oracle::Oracle;
use fragsim_raster::{SceneSpec, Viewport};
use fragsim_shade::colour_error::{BucketDeviation, ColourDeviation, DEPTH_BUCKETS};
use serde::Serialize;

use crate::approximate::ApproximateName;
use crate::colour_by_depth::ColourByDepth;
use crate::colour_judge::{ColourColumns, ColourJudge, EffectName};
use crate::{Progress, SchemeSetup, Shard};

pub mod report;

/// What `sweep` measures, and how.
#[derive(Debug, Clone)]
pub struct SweepParams {
    /// The scene; its view angle is the sweep's, step by step.
    pub scene: SceneSpec,
    /// The viewport.
    pub viewport: Viewport,
    /// The catalog schemes swept, in order.
    pub schemes: Vec<SchemeName>,
    /// Their sizes, executor (the first of `executors` runs), threads and submission order.
    pub setup: SchemeSetup,
    /// View angles, evenly spaced over a full turn.
    pub angles: u32,
    /// The effect whose image is compared with the oracle's.
    pub effect: EffectName,
    /// The angle steps swept: step `k` when the shard takes `k`.
    pub shard: Shard,
    /// Approximate OIT schemes swept beside the catalog's.
    pub approximate: Vec<ApproximateName>,
}

/// What the sweep measured.
#[derive(Debug, Clone, Serialize)]
pub struct SweepReport {
    /// The angles swept, degrees, in order.
    pub angles: Vec<f64>,
    /// The executor the schemes ran on.
    pub executor: String,
    /// Its threads.
    pub threads: usize,
    /// One series per scheme: the catalog's in order, then the approximate ones.
    pub series: Vec<SweepSeries>,
}

/// One scheme's measurements over the sweep.
#[derive(Debug, Clone, Serialize)]
pub struct SweepSeries {
    /// Scheme name.
    pub scheme: String,
    /// Error-pixel rate (over covered pixels) per angle; `None` where the effect is unresolvable.
    pub error_pixel_rate: Vec<Option<f64>>,
    /// The colour error against the oracle's image per angle (`None` fields: unresolvable).
    pub colour: Vec<ColourColumns>,
    /// The same per depth-complexity bucket, per angle (no buckets: unresolvable).
    pub colour_by_depth: Vec<ColourByDepth>,
    /// Frame time per angle, ms.
    pub time_ms: Vec<f64>,
}

impl SweepSeries {
    fn named(scheme: &str) -> Self {
        Self {
            scheme: scheme.into(),
            error_pixel_rate: Vec::new(),
            colour: Vec::new(),
            colour_by_depth: Vec::new(),
            time_ms: Vec::new(),
        }
    }

    /// Its buckets over every angle: pixels and error pixels summed, the mean absolute
    /// error weighted by each angle's pixels (so it is the mean over every pixel of every angle in
    /// the bucket), the largest error, and the lowest PSNR of any angle; buckets without a pixel at
    /// any angle are left out.
    #[must_use]
    pub fn colour_by_depth_over_angles(&self) -> Vec<BucketDeviation> {
        let angles = &self.colour_by_depth;
        DEPTH_BUCKETS
            .iter()
            .enumerate()
            .filter_map(|(i, &(lo, hi))| {
                let at_angles: Vec<(u64, u64, ColourDeviation)> = angles
                    .iter()
                    .filter_map(|a| a.buckets.get(i))
                    .filter_map(|b| Some((b.pixels, b.error_pixels, b.error?)))
                    .collect();
                let pixels: u64 = at_angles.iter().map(|a| a.0).sum();
                (pixels > 0).then(|| {
                    let weighted = |c: usize| {
                        at_angles
                            .iter()
                            .map(|(n, _, e)| e.mean_abs[c] * *n as f64)
                            .sum::<f64>()
                            / pixels as f64
                    };
                    let largest = |c: usize| at_angles.iter().map(|(_, _, e)| e.max_abs[c]).max();
                    BucketDeviation {
                        lo,
                        hi,
                        pixels,
                        error_pixels: at_angles.iter().map(|a| a.1).sum(),
                        error: Some(ColourDeviation {
                            mean_abs: [0, 1, 2].map(weighted),
                            max_abs: [0, 1, 2].map(|c| largest(c).unwrap_or(0)),
                            psnr_db: at_angles
                                .iter()
                                .map(|(_, _, e)| e.psnr_db)
                                .fold(f64::INFINITY, f64::min),
                        }),
                    }
                })
            })
            .collect()
    }
}

/// Runs `sweep`.
///
/// # Errors
/// Scene, parameter or output errors.
pub fn sweep(params: &SweepParams, progress: &dyn Progress) -> Result<SweepReport, String> {
    let pool = params.setup.pool()?;
    let spec = &params.scene;
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let viewport = params.viewport;
    let executor = *params
        .setup
        .executors
        .first()
        .ok_or_else(|| "sweep needs an executor".to_string())?;
    let mut threads = 0;
    let schemes = &params.schemes;
    let mut series: Vec<SweepSeries> = Vec::new();
    let mut angles = Vec::new();
    let steps: Vec<u32> = (0..params.angles)
        .filter(|&step| params.shard.takes(step as usize))
        .collect();
    progress.begin(steps.len() as u64, "sweep");
    for step in steps {
        progress.message(&format!("angle {step}"));
        let angle = 360.0 * f64::from(step) / f64::from(params.angles);
        angles.push(angle);
        let at_angle = SceneSpec {
            view_degrees: angle,
            ..spec.clone()
        };
        let orbit = at_angle.orbit();
        let view = params
            .setup
            .submission(at_angle.view(&scene, viewport).map_err(|e| e.to_string())?);
        fragsim_oracle::memory_cap::check(&view, params.setup.sizing.memory_cap)
            .map_err(|e| e.to_string())?;
        let oracle = Oracle::build(&view);
        let judge = ColourJudge::new(params.effect, &scene, &view, orbit, &oracle);
        crate::approximate::check_effect(&judge, &params.approximate)?;
        let depth_complexity = oracle.depth_complexity();
        let sizing = params.setup.sizing;
        let mut runner = SchemeRunner::default();
        for (i, &name) in schemes.iter().enumerate() {
            let named = pool
                .install(|| runner.run(name, executor, &view, &sizing))
                .map_err(|e| e.to_string())?;
            if series.len() <= i {
                series.push(SweepSeries::named(&named.name));
            }
            let judged = judge.judge(&named.run.capture);
            let rate = judged
                .as_ref()
                .map(|judged| judged.errors as f64 / judge.covered.max(1) as f64);
            series[i].error_pixel_rate.push(rate);
            series[i]
                .colour
                .push(ColourColumns::of(judged.as_ref().map(|j| j.colour)));
            series[i].colour_by_depth.push(ColourByDepth::of(
                judged.as_ref().map(|j| (j.reference, &j.image)),
                &depth_complexity,
            )?);
            series[i].time_ms.push(
                (named.run.stats.pass_time + named.run.stats.resolve_time).as_secs_f64() * 1e3,
            );
            threads = named.run.stats.threads;
        }
        if !params.approximate.is_empty() {
            let order = PrimitiveOrder::of_view(&view);
            let raster_ms = pool
                .install(|| crate::frame_timing::time_raster_alone(&view))
                .as_secs_f64()
                * 1e3;
            let nodes = crate::approximate::nodes(sizing.k, &oracle);
            for (j, &scheme) in params.approximate.iter().enumerate() {
                let (row, _) = pool.install(|| {
                    crate::approximate::measure(
                        scheme, nodes, &judge, &oracle, &order, 1, raster_ms,
                    )
                })?;
                let i = schemes.len() + j;
                if series.len() <= i {
                    series.push(SweepSeries::named(&row.scheme));
                }
                series[i].error_pixel_rate.push(Some(row.error_pixel_rate));
                series[i].colour.push(row.colour);
                series[i].colour_by_depth.push(row.colour_by_depth);
                series[i].time_ms.push(row.time_ms);
            }
        }
        progress.step();
    }
    progress.end();
    Ok(SweepReport {
        angles,
        executor: executor.name().into(),
        threads,
        series,
    })
}
