//! `hazard`: the k-buffer's read–modify–write hazard rate as the parallelism `W` grows and as
//! depth complexity grows, measured with the scheduled executor on the machines the k-buffer
//! runs on; and the baselines table of `docs/baselines/kbuffer.md` (passes and losses of the
//! catalog's k-buffer schemes and the stencil-routed A-buffer on every executor).
//!
//! For each machine, each policy (uniform random, lockstep warps), each `W` and each seed, the
//! k-buffer runs the scene one fragment per thread under the scheduled executor, and
//! `Oracle::diff` counts the covered pixels whose list differs from the oracle's `K` nearest. A
//! row is `fragsim_explain::hazard::rate`'s and a baseline `fragsim_explain::baselines`'s; this
//! module walks the campaign and gathers the report.

use fragsim_capture::MEMORY_CAP_DEFAULT;
use fragsim_explain::baselines;
use fragsim_explain::hazard::{covered_by_bucket, machine_name, rate, BUCKETS, POLICIES};
pub use fragsim_explain::{
    baselines::BaselineRow,
    hazard::{HazardReport, HazardRow},
};
use fragsim_oracle::Oracle;
use fragsim_raster::{SceneSpec, View, Viewport};
use fragsim_schemes::kbuffer::{KBuffer, WriteBack};

use crate::Progress;

pub mod report;

/// What `hazard` measures.
#[derive(Debug, Clone)]
pub struct HazardParams {
    /// The scene and its camera.
    pub scene: SceneSpec,
    /// The viewport.
    pub viewport: Viewport,
    /// The k-buffer's machines.
    pub write_back: Vec<WriteBack>,
    /// What is measured on them.
    pub campaign: Campaign,
}

/// The hazard rates, or the baselines table.
#[derive(Debug, Clone)]
pub enum Campaign {
    /// The k-buffer's hazard rate with `k` slots per pixel, for each number of threads in
    /// flight, over `seeds` seeds per (machine, policy, threads in flight).
    Rates {
        /// Slots per pixel.
        k: u32,
        /// Threads in flight `W` (each at least 1).
        threads_in_flight: Vec<usize>,
        /// Seeds per row (at least 1).
        seeds: u64,
    },
    /// Passes and losses of the k-buffer schemes for each K of `ks` and of the stencil-routed
    /// A-buffer, on every executor.
    Baselines {
        /// Slots per pixel of the k-buffer rows.
        ks: Vec<u32>,
    },
}

/// Runs the campaign of `params`: a report with its rows (`Rates`) or its baselines
/// (`Baselines`).
///
/// # Errors
/// No machine, no seed or zero threads in flight; scene, memory or scheme errors.
pub fn hazard(params: &HazardParams, progress: &dyn Progress) -> Result<HazardReport, String> {
    let spec = &params.scene;
    let scene = spec.load(None).map_err(|e| e.to_string())?;
    let view = spec
        .view(&scene, params.viewport)
        .map_err(|e| e.to_string())?;
    hazard_in_view(
        &view,
        crate::scene_name(spec),
        &params.write_back,
        &params.campaign,
        progress,
    )
}

/// [`hazard`] in a view already made (a scene given as arrays, which no spec loads), the scene
/// named `scene` in the report.
///
/// # Errors
/// No machine, no seed or zero threads in flight; memory or scheme errors.
pub fn hazard_in_view(
    view: &View<'_>,
    scene: String,
    write_back: &[WriteBack],
    campaign: &Campaign,
    progress: &dyn Progress,
) -> Result<HazardReport, String> {
    let nothing_to_run = match campaign {
        Campaign::Rates {
            threads_in_flight,
            seeds,
            ..
        } => threads_in_flight.contains(&0) || *seeds == 0,
        Campaign::Baselines { .. } => false,
    };
    if write_back.is_empty() || nothing_to_run {
        return Err("hazard needs threads in flight ≥ 1, at least one seed and one machine".into());
    }
    fragsim_oracle::memory_cap::check(view, MEMORY_CAP_DEFAULT).map_err(|e| e.to_string())?;
    let oracle = Oracle::build(view);
    let in_bucket = covered_by_bucket(&oracle);
    let viewport = view.viewport();
    let mut report = HazardReport {
        scene,
        width: viewport.width,
        height: viewport.height,
        k: 0,
        covered: in_bucket.iter().sum(),
        fragments: oracle.fragments(),
        buckets: BUCKETS
            .iter()
            .zip(&in_bucket)
            .map(|(&(_, label), &n)| (label.to_string(), n))
            .collect(),
        rows: Vec::new(),
        baselines: Vec::new(),
    };
    match campaign {
        Campaign::Rates {
            k,
            threads_in_flight,
            seeds,
        } => {
            report.k = *k;
            report.rows = rates(
                write_back,
                (view, &oracle),
                (*k, threads_in_flight, *seeds),
                progress,
            )?;
        }
        Campaign::Baselines { ks } => {
            // The output lists hold every layer (as `render` sizes them).
            let layers = oracle.max_depth_complexity().max(1);
            let table = baselines::table(viewport, ks, write_back, layers)?;
            progress.begin(table.len() as u64, "hazard --baselines");
            for baseline in table {
                progress.message(&format!("{} K = {}", baseline.scheme, baseline.k));
                report
                    .baselines
                    .extend(baselines::rows(&baseline, view, &oracle)?);
                progress.step();
            }
            progress.end();
        }
    }
    Ok(report)
}

/// The rows of a `Rates` campaign of `k` slots, `threads_in_flight` and `seeds` on `view`
/// and its oracle: every machine of `write_back`, policy and number of threads in flight.
fn rates(
    write_back: &[WriteBack],
    (view, oracle): (&View<'_>, &Oracle),
    (k, threads_in_flight, seeds): (u32, &[usize], u64),
    progress: &dyn Progress,
) -> Result<Vec<HazardRow>, String> {
    progress.begin(
        (write_back.len() * POLICIES.len() * threads_in_flight.len()) as u64,
        "hazard",
    );
    let mut rows = Vec::new();
    for &machine in write_back {
        let scheme = KBuffer::with_write_back(view.viewport(), k, machine, MEMORY_CAP_DEFAULT)
            .map_err(|e| e.to_string())?;
        for policy in POLICIES {
            for &in_flight in threads_in_flight {
                progress.message(&format!(
                    "{} {} W = {in_flight}",
                    machine_name(machine),
                    policy.1
                ));
                rows.push(rate(
                    view, oracle, &scheme, machine, policy, in_flight, seeds,
                ));
                progress.step();
            }
        }
    }
    progress.end();
    Ok(rows)
}

/// The machine that rows and reports name `name` (`render-target`, `separate-stores`), if any.
#[must_use]
pub fn machine_named(name: &str) -> Option<WriteBack> {
    [WriteBack::RenderTarget, WriteBack::SeparateStores]
        .into_iter()
        .find(|&machine| machine_name(machine) == name)
}
