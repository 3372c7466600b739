//! `bench --approximate` and `sweep --approximate`: the approximate OIT schemes (weighted blended
//! OIT, multi-layer alpha blending, tail blending; [`fragsim_shade::approximate`]) measured beside
//! the catalog's, by their image alone.
//!
//! **What is measured.** These schemes hold colour, not fragment lists, so there is no list for
//! the oracle to diff: each is judged by its transparency image against the oracle's
//! ([`ColourJudge::judge_image`]): error pixels, mean and maximum absolute error, PSNR, over the image
//! and per depth-complexity bucket ([`ColourByDepth`], where its error lives). Its fragments
//! reach it in primitive order, as a GPU's blending and ordered interlock deliver them
//! ([`PrimitiveOrder::of_view`]), so its image is the same whatever executor the catalog's
//! schemes ran on. Its time is the scene's rasterization alone (the bench's `raster_ms`: one
//! geometry pass, fragments discarded) plus the median time of its blend over every pixel's
//! fragments on the pool: a CPU model's cost, comparable with the other rows' only as the
//! schemes' shares of one machine are.
//!
//! **Sizes.** MLAB and tail blending take `--k` nodes a pixel (`auto`: the scene's maximum depth
//! complexity, where both are exact); WBOIT has none. Their storage is what the papers lay out
//! on a GPU ([`Approximation::bytes_per_pixel`]).

use std::time::{Duration, Instant};

use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_catalog::Count;
use fragsim_oracle::Oracle;
use fragsim_shade::approximate::{in_submission_order, Approximation};
use fragsim_shade::effects::Effect;
use image::RgbImage;
use serde::Serialize;

use crate::colour_by_depth::ColourByDepth;
use crate::colour_judge::{ColourColumns, ColourJudge};

/// An approximate OIT scheme, as `--approximate` spells it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "args", derive(clap::ValueEnum))]
pub enum ApproximateName {
    /// Weighted blended OIT (McGuire & Bavoil 2013, the weight of their eq. 10).
    Wboit,
    /// Multi-layer alpha blending with `--k` nodes (Salvi & Vaidyanathan 2014).
    Mlab,
    /// The `--k` nearest sorted, the rest blended into a tail (nvpro-samples).
    TailBlend,
}

impl ApproximateName {
    /// The scheme with `k` nodes where it takes a number.
    pub fn with_k(self, k: u32) -> Approximation {
        match self {
            Self::Wboit => Approximation::Wboit,
            Self::Mlab => Approximation::Mlab { k },
            Self::TailBlend => Approximation::TailBlend { k },
        }
    }
}

/// One approximate scheme's image of one scene against the oracle's.
#[derive(Debug, Clone, Serialize)]
pub struct ApproximateRow {
    /// `wboit`, `mlab` or `tail-blend`.
    pub scheme: String,
    /// Always `approximate`: judged by its colour error, never held to the oracle's lists.
    pub guarantee: &'static str,
    /// Nodes per pixel (`None`: WBOIT has none).
    pub nodes: Option<u32>,
    /// Bytes of per-pixel storage on a GPU, as the paper lays it out.
    pub memory_bytes: u64,
    /// Bytes per pixel.
    pub bytes_per_pixel: f64,
    /// Pixels with more fragments than `nodes`: the only ones MLAB and tail blending may get
    /// wrong (WBOIT: pixels with more than one fragment).
    pub pixels_beyond_nodes: u64,
    /// Pixels whose 8-bit colour differs from the oracle's image.
    pub error_pixels: u64,
    /// `error_pixels` over the pixels the oracle covers.
    pub error_pixel_rate: f64,
    /// The colour error against the oracle's image.
    #[serde(flatten)]
    pub colour: ColourColumns,
    /// Median time of the blend over every pixel's fragments, ms.
    pub blend_ms: f64,
    /// The rasterization alone plus `blend_ms`: the row's frame time, ms.
    pub time_ms: f64,
    /// Threads of the pool that blended (a record's context carries them).
    #[serde(skip)]
    pub threads: usize,
    /// The colour error per depth-complexity bucket (`pixels_dc_1`, …; bench.md's per-bucket
    /// table).
    #[serde(flatten)]
    pub colour_by_depth: ColourByDepth,
}

impl ApproximateRow {
    /// Its name in charts and tables: `mlab (blend, K = 8)`, told apart from the catalog's
    /// `mlab` row (its node depths, labelled by executor) by "blend".
    pub fn label(&self) -> String {
        match self.nodes {
            Some(k) => format!("{} (blend, K = {k})", self.scheme),
            None => format!("{} (blend)", self.scheme),
        }
    }
}

/// `--k` resolved for the approximate schemes: `auto` is the scene's maximum depth complexity.
pub fn nodes(k: Count, oracle: &Oracle) -> u32 {
    match k {
        Count::Fixed(n) => n,
        Count::Auto => oracle.max_depth_complexity().max(1),
    }
}

/// Refuses `--approximate` with an effect other than transparency, by name.
///
/// # Errors
/// The judge's effect is not transparency.
pub fn check_effect(
    judge: &ColourJudge<'_>,
    approximate: &[ApproximateName],
) -> Result<(), String> {
    if approximate.is_empty() || judge.effect() == Effect::Transparency {
        return Ok(());
    }
    let name = approximate[0].with_k(1).name();
    Err(format!(
        "--approximate {name} blends transparency only: run it with --effect transparency"
    ))
}

/// Measures `scheme` with `k` nodes on the judge's scene, blending `frames` times on the current
/// rayon pool (the median is reported); `order` is the view's primitive order and `raster_ms`
/// its rasterization alone.
/// Returns the row and the image.
///
/// # Errors
/// The image is not the judge's size (a bug).
pub fn measure(
    scheme: ApproximateName,
    k: u32,
    judge: &ColourJudge<'_>,
    oracle: &Oracle,
    order: &PrimitiveOrder,
    frames: usize,
    raster_ms: f64,
) -> Result<(ApproximateRow, RgbImage), String> {
    let approximation = scheme.with_k(k);
    // The order is the rasterizer's, free on a GPU: arranged once, outside the timed blend.
    let arrivals: Vec<Vec<u64>> = (0..oracle.pixels())
        .map(|p| in_submission_order(order, p, oracle.pixel(p)))
        .collect();
    let mut times: Vec<Duration> = Vec::with_capacity(frames.max(1));
    let mut image = RgbImage::new(0, 0);
    for _ in 0..frames.max(1) {
        let start = Instant::now();
        image = approximation.render(judge.material(), judge.size(), |p| &arrivals[p]);
        times.push(start.elapsed());
    }
    times.sort_unstable();
    let blend_ms = times[times.len() / 2].as_secs_f64() * 1e3;
    let limit = approximation.k().unwrap_or(1);
    let depth_complexity = oracle.depth_complexity();
    let pixels_beyond_nodes = depth_complexity.iter().filter(|&&n| n > limit).count() as u64;
    let judged = judge.judge_image(image, None)?;
    let colour_by_depth =
        ColourByDepth::of(Some((judged.reference, &judged.image)), &depth_complexity)?;
    let pixels = oracle.pixels() as u64;
    let memory_bytes = approximation.bytes_per_pixel() * pixels;
    let row = ApproximateRow {
        scheme: approximation.name().into(),
        guarantee: "approximate",
        nodes: approximation.k(),
        memory_bytes,
        bytes_per_pixel: memory_bytes as f64 / pixels.max(1) as f64,
        pixels_beyond_nodes,
        error_pixels: judged.errors,
        error_pixel_rate: judged.errors as f64 / judge.covered.max(1) as f64,
        colour: ColourColumns::of(Some(judged.colour)),
        blend_ms,
        time_ms: raster_ms + blend_ms,
        threads: rayon::current_num_threads(),
        colour_by_depth,
    };
    Ok((row, judged.image))
}
