//! The k-buffer's read–modify–write hazard rate over a whole scene: for one machine, one policy
//! of the scheduled executor and one number `W` of threads in flight, the fraction of covered
//! pixels whose list differs from the oracle's `K` nearest, over seeds, with the failure classes
//! counted apart and the rate bucketed by depth complexity.
//!
//! Why: the paper's claim is that the hazard grows with `W` (with `W = 1` each walk runs alone,
//! so the rate is 0) and with depth complexity. Render targets can only lose fragments (stale
//! reads); separate stores also tear write-backs, which leaves duplicates and slots out of order.
//! `fragsim hazard` prints these rows (`docs/rmw-hazard.md`).

use fragsim_capture::executors::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim_oracle::Oracle;
use fragsim_raster::View;
use fragsim_schemes::kbuffer::{KBuffer, WriteBack};
use serde::Serialize;

use crate::baselines::BaselineRow;

/// Depth-complexity buckets: inclusive upper bounds and labels.
pub const BUCKETS: [(u32, &str); 6] = [
    (1, "1"),
    (2, "2"),
    (4, "3–4"),
    (8, "5–8"),
    (16, "9–16"),
    (u32::MAX, "17+"),
];

/// The scheduled executor's policies the rates are measured under, with their names in rows.
pub const POLICIES: [(Policy, &str); 2] = [(Policy::Random, "random"), (Policy::Warps, "warps")];

/// One (machine, policy, threads in flight) measurement, over seeds.
#[derive(Debug, Clone, Serialize)]
pub struct HazardRow {
    /// `render-target` or `separate-stores`.
    pub write_back: String,
    /// `random` or `warps`.
    pub policy: String,
    /// Threads in flight, `W` (JSON `threads_in_flight`, as `--threads-in-flight` names it).
    pub threads_in_flight: usize,
    /// Fraction of covered pixels that differ from the oracle, per seed (JSON
    /// `mismatched_pixel_rate_per_seed`, as the JSON Lines record names it).
    #[serde(rename = "mismatched_pixel_rate_per_seed")]
    pub rate_per_seed: Vec<f64>,
    /// Its mean (JSON `mismatched_pixel_rate`).
    #[serde(rename = "mismatched_pixel_rate")]
    pub rate: f64,
    /// Fragments lost, summed over seeds.
    pub lost: u64,
    /// Extra fragments (duplicates, or fragments beyond the K nearest), summed over seeds.
    pub extra: u64,
    /// Second and later copies of a fragment in one pixel's slots, summed over seeds.
    pub duplicates: u64,
    /// Pixels whose slots are out of order, summed over seeds.
    pub misordered_pixels: u64,
    /// Per depth-complexity bucket: fraction of that bucket's pixels that differ (over seeds;
    /// JSON `mismatched_pixel_rate_by_depth_complexity`).
    #[serde(rename = "mismatched_pixel_rate_by_depth_complexity")]
    pub rate_by_depth_complexity: Vec<f64>,
}

/// The whole measurement.
#[derive(Debug, Clone, Serialize)]
pub struct HazardReport {
    /// Scene and size.
    pub scene: String,
    /// Viewport width in pixels.
    pub width: u32,
    /// Viewport height in pixels.
    pub height: u32,
    /// Slots per pixel.
    pub k: u32,
    /// Covered pixels.
    pub covered: usize,
    /// Fragments.
    pub fragments: usize,
    /// Bucket labels and the covered pixels in each.
    pub buckets: Vec<(String, usize)>,
    /// The measurements (empty with `--baselines`).
    pub rows: Vec<HazardRow>,
    /// The `--baselines` table (empty without it).
    pub baselines: Vec<BaselineRow>,
}

/// The bucket of depth complexity `dc`.
#[must_use]
pub fn bucket(dc: u32) -> usize {
    BUCKETS
        .iter()
        .position(|&(hi, _)| dc <= hi)
        .unwrap_or(BUCKETS.len() - 1)
}

/// Covered pixels in each of [`BUCKETS`].
#[must_use]
pub fn covered_by_bucket(oracle: &Oracle) -> Vec<usize> {
    let mut in_bucket = vec![0_usize; BUCKETS.len()];
    for &d in oracle.depth_complexity().iter().filter(|&&d| d > 0) {
        in_bucket[bucket(d)] += 1;
    }
    in_bucket
}

/// How rows and reports name a machine (the command line's spelling).
#[must_use]
pub fn machine_name(write_back: WriteBack) -> &'static str {
    match write_back {
        WriteBack::RenderTarget => "render-target",
        WriteBack::SeparateStores => "separate-stores",
    }
}

/// The rate of `scheme` (a k-buffer on `machine`) on `view` under `policy` (named `policy_name`)
/// with `threads_in_flight` fragments in flight, over seeds `0..seeds`, against `oracle`.
#[must_use]
pub fn rate(
    view: &View<'_>,
    oracle: &Oracle,
    scheme: &KBuffer,
    machine: WriteBack,
    (policy, policy_name): (Policy, &str),
    threads_in_flight: usize,
    seeds: u64,
) -> HazardRow {
    let dc = oracle.depth_complexity();
    let in_bucket = covered_by_bucket(oracle);
    let covered: usize = in_bucket.iter().sum();
    let k = scheme.k() as usize;
    let mut row = HazardRow {
        write_back: machine_name(machine).into(),
        policy: policy_name.into(),
        threads_in_flight,
        rate_per_seed: Vec::new(),
        rate: 0.0,
        lost: 0,
        extra: 0,
        duplicates: 0,
        misordered_pixels: 0,
        rate_by_depth_complexity: Vec::new(),
    };
    let mut bad_in_bucket = vec![0_usize; BUCKETS.len()];
    for seed in 0..seeds {
        let schedule = Schedule {
            policy,
            in_flight: threads_in_flight,
            granularity: Granularity::Fragment,
            seed,
        };
        let capture = run_scheduled(view, scheme, &schedule, false).run.capture;
        let diff = oracle.diff(&capture);
        row.rate_per_seed
            .push(diff.mismatched_pixels as f64 / covered.max(1) as f64);
        row.lost += diff.lost;
        row.extra += diff.extra;
        row.misordered_pixels += diff.misordered_pixels;
        row.duplicates += capture.duplicates();
        for (p, &d) in dc.iter().enumerate().filter(|&(_, &d)| d > 0) {
            let expected = oracle.pixel(p);
            let expected = &expected[..expected.len().min(k)];
            if capture.pixel(p) != expected {
                bad_in_bucket[bucket(d)] += 1;
            }
        }
    }
    let seeds = seeds as f64;
    row.rate = row.rate_per_seed.iter().sum::<f64>() / seeds;
    row.rate_by_depth_complexity = bad_in_bucket
        .iter()
        .zip(&in_bucket)
        .map(|(&b, &n)| {
            if n == 0 {
                0.0
            } else {
                b as f64 / (n as f64 * seeds)
            }
        })
        .collect();
    row
}

#[cfg(test)]
mod tests {
    use super::*;
    use fragsim_raster::{OrbitCamera, Scene, Viewport};

    #[test]
    fn buckets_are_inclusive_upper_bounds() {
        let at: Vec<usize> = [1, 2, 3, 4, 5, 16, 17, 1000].map(bucket).to_vec();
        assert_eq!(at, vec![0, 1, 2, 2, 3, 4, 5, 5]);
    }

    #[test]
    fn one_walk_at_a_time_loses_nothing_and_many_lose_on_render_targets_only_by_loss() {
        let scene = Scene::procedural("quads:6").unwrap();
        let view = scene
            .view(Viewport::new(24, 24).unwrap(), &OrbitCamera::default())
            .unwrap();
        let oracle = Oracle::build(&view);
        let machine = WriteBack::RenderTarget;
        let scheme = KBuffer::with_write_back(
            view.viewport(),
            8,
            machine,
            fragsim_capture::MEMORY_CAP_DEFAULT,
        )
        .unwrap();
        let alone = rate(&view, &oracle, &scheme, machine, POLICIES[0], 1, 2);
        assert_eq!((alone.rate, alone.lost), (0.0, 0));
        assert_eq!(alone.rate_per_seed.len(), 2);
        let wide = rate(&view, &oracle, &scheme, machine, POLICIES[0], 4096, 2);
        assert!(wide.rate > 0.0 && wide.lost > 0, "{wide:?}");
        // Stale reads lose; only torn write-backs duplicate.
        assert_eq!(wide.duplicates, 0);
        assert!(wide.rate_by_depth_complexity[0] == 0.0, "{wide:?}");
    }
}
