//! What `hazard` reports: hazard.md (the rates, per seed and per depth-complexity bucket, with
//! their key), baselines.md, and the two charts (pixels wrong against threads in flight and
//! against depth complexity), and the JSON Lines records of the rows. Text and files, never
//! stdout: the command line prints them.

use std::fmt::Write as _;
use std::path::Path;

use fragsim_explain::hazard::POLICIES;
use fragsim_shade::plot::{chart, chart_with_ticks, Series};
use serde::Serialize;

use super::HazardReport;
use crate::record::{line, Context, Slots};

/// What hazard.md's tables mean, under them.
const KEY: &str = "
Key: **W** threads in flight: how many fragments the scheduled executor keeps walking at once, one \
thread each (W = 1 runs each walk alone: no hazard); **write-back** the k-buffer's machine \
(`render-target`: the K slots read in one step and written back in one, write-backs committed in \
order, so only a stale read loses; `separate-stores`: K loads and K stores, one step each, as CUDA \
code does, so write-backs also tear); **policy** how the scheduled executor picks the next step \
(`random`: any thread in flight, uniformly; `warps`: warps of 32 threads in round-robin, one step \
per lane in lane order); **pixels wrong %** covered pixels whose slots differ from the oracle's K \
nearest, in percent, mean over the seeds (JSON: the fraction, `mismatched_pixel_rate`); **per \
seed** the same for each seed, 0, 1, … (`mismatched_pixel_rate_per_seed`); **lost**, **extra**, \
**duplicates** fragments summed over the seeds; **misordered px** pixels whose slots are out of \
order; **dc** a pixel's depth complexity (its fragments), bucketed, with the covered pixels in \
each bucket.
";

/// `rate` (a fraction) as the tables print rates: a percentage.
fn percent(rate: f64) -> String {
    format!("{:.2}", 100.0 * rate)
}

/// hazard.md: the rates of `report`'s rows, per seed and per depth-complexity bucket, and what
/// the columns mean.
#[must_use]
pub fn markdown(report: &HazardReport) -> String {
    let seeds = report.rows.first().map_or(0, |r| r.rate_per_seed.len());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "k-buffer (K = {}) on `{}` at {}×{}: {} fragments, {} covered pixels; {} seeds per row.\n",
        report.k,
        report.scene,
        report.width,
        report.height,
        report.fragments,
        report.covered,
        seeds
    );
    let _ = writeln!(
        md,
        "| write-back | policy | W | pixels wrong % (mean) | per seed % | lost | extra | duplicates | misordered px |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---|---:|---:|---:|---:|");
    for r in &report.rows {
        let per_seed: Vec<String> = r.rate_per_seed.iter().map(|&x| percent(x)).collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.threads_in_flight,
            percent(r.rate),
            per_seed.join(" "),
            r.lost,
            r.extra,
            r.duplicates,
            r.misordered_pixels
        );
    }
    let _ = writeln!(
        md,
        "\nPixels wrong by depth complexity, % of the bucket's pixels:\n"
    );
    let labels: Vec<String> = report
        .buckets
        .iter()
        .map(|(l, n)| format!("dc {l} ({n} px)"))
        .collect();
    let _ = writeln!(md, "| write-back | policy | W | {} |", labels.join(" | "));
    let _ = writeln!(md, "|---|---|---:|{}", "---:|".repeat(labels.len()));
    for r in &report.rows {
        let cells: Vec<String> = r
            .rate_by_depth_complexity
            .iter()
            .zip(&report.buckets)
            .map(|(&x, (_, n))| if *n == 0 { "–".into() } else { percent(x) })
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            r.write_back,
            r.policy,
            r.threads_in_flight,
            cells.join(" | ")
        );
    }
    md.push_str(KEY);
    md
}

/// baselines.md: passes and losses of every baseline row of `report`.
#[must_use]
pub fn baselines_markdown(report: &HazardReport) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "`{}` at {}×{}: {} fragments, {} covered pixels; output lists sized to the maximum depth complexity.\n",
        report.scene, report.width, report.height, report.fragments, report.covered
    );
    let _ = writeln!(
        md,
        "| scheme | K | executor | passes | overflowed | lost | extra | duplicates | misordered px | error px (of covered) | memory MiB |"
    );
    let _ = writeln!(md, "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &report.baselines {
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} ({:.2} %) | {:.1} |",
            r.scheme,
            r.k,
            r.executor,
            r.passes,
            r.overflowed,
            r.lost,
            r.extra,
            r.duplicates,
            r.misordered_pixels,
            r.error_pixels,
            100.0 * r.error_pixels as f64 / report.covered.max(1) as f64,
            r.memory_bytes as f64 / f64::from(1 << 20),
        );
    }
    md
}

/// Draws the two charts of `report`'s rows into `dir` as `ext` (`png` or `svg`): pixels wrong
/// against threads in flight (a line per machine and policy) and against depth complexity (a line
/// per row with more than one thread in flight). Returns their file names.
///
/// # Errors
/// A chart that cannot be drawn or written.
pub fn charts(report: &HazardReport, dir: &Path, ext: &str) -> Result<[String; 2], String> {
    let mut by_width: Vec<Series> = Vec::new();
    let mut machines: Vec<&str> = Vec::new();
    for r in &report.rows {
        if !machines.contains(&r.write_back.as_str()) {
            machines.push(&r.write_back);
        }
    }
    for machine in machines {
        for (_, p) in POLICIES {
            let points = report
                .rows
                .iter()
                .filter(|r| r.policy == p && r.write_back == machine)
                .map(|r| ((r.threads_in_flight as f64).log2(), 100.0 * r.rate))
                .collect();
            by_width.push((format!("{machine} {p}"), points));
        }
    }
    let vs_width = format!("hazard-vs-width.{ext}");
    chart(
        &dir.join(&vs_width),
        &format!(
            "k-buffer (K = {}): pixels wrong vs threads in flight",
            report.k
        ),
        "log2 W (threads in flight)",
        "% of covered pixels wrong",
        &by_width,
        false,
    )
    .map_err(|e| e.to_string())?;
    let by_dc: Vec<Series> = report
        .rows
        .iter()
        .filter(|r| r.threads_in_flight > 1)
        .map(|r| {
            let points = r
                .rate_by_depth_complexity
                .iter()
                .enumerate()
                .filter(|&(i, _)| report.buckets[i].1 > 0)
                .map(|(i, &x)| (i as f64, 100.0 * x))
                .collect();
            (
                format!("{} {} W={}", r.write_back, r.policy, r.threads_in_flight),
                points,
            )
        })
        .collect();
    let ticks: Vec<String> = report
        .buckets
        .iter()
        .map(|(label, n)| format!("{label} ({n} px)"))
        .collect();
    let vs_dc = format!("hazard-vs-depth-complexity.{ext}");
    chart_with_ticks(
        &dir.join(&vs_dc),
        (
            &format!(
                "k-buffer (K = {}): pixels wrong vs depth complexity",
                report.k
            ),
            "depth complexity of the pixel (bucket, pixels in it)",
            "% of the bucket's pixels wrong",
        ),
        &by_dc,
        false,
        Some(&ticks),
    )
    .map_err(|e| e.to_string())?;
    Ok([vs_width, vs_dc])
}

/// One line of hazard's JSON Lines: a row of the rates (the context carries the scheduled
/// executor and the threads in flight).
#[derive(Serialize)]
struct HazardRecord<'a> {
    scheme: &'static str,
    write_back: &'a str,
    policy: &'a str,
    seeds: u64,
    /// Fraction of covered pixels whose list differs from the oracle's K nearest, mean over
    /// the seeds.
    mismatched_pixel_rate: f64,
    /// The same, per seed.
    mismatched_pixel_rate_per_seed: &'a [f64],
    lost: u64,
    extra: u64,
    duplicates: u64,
    misordered_pixels: u64,
    /// The rate among the pixels of each depth-complexity bucket (`dc_1`, `dc_2`, `dc_3_4`, …);
    /// `null` for a bucket without pixels.
    #[serde(flatten)]
    by_depth_complexity: std::collections::BTreeMap<String, Option<f64>>,
}

/// One line of `hazard --baselines`' JSON Lines (the context carries K and the executor).
#[derive(Serialize)]
struct BaselineRecord<'a> {
    scheme: &'a str,
    passes: u32,
    overflowed: u64,
    lost: u64,
    extra: u64,
    duplicates: u64,
    misordered_pixels: u64,
    error_pixels: u64,
    /// `error_pixels` over the covered pixels.
    error_pixel_rate: f64,
    memory_bytes: u64,
}

/// The rates' JSON Lines records (`docs/json-schema.md`), one `hazard` line per row, in
/// `context` (the scene's) with the report's K; `seeds`: the seeds each row ran.
///
/// # Errors
/// A record cannot be serialised (a bug).
pub fn records(
    report: &HazardReport,
    context: &Context,
    seeds: u64,
) -> Result<Vec<String>, String> {
    let mut context = context.clone();
    context.k = Some(Slots::Fixed(report.k));
    report
        .rows
        .iter()
        .map(|r| {
            let by_depth_complexity = report
                .buckets
                .iter()
                .zip(&r.rate_by_depth_complexity)
                .map(|((label, n), &rate)| {
                    let key = format!("mismatched_pixel_rate_dc_{}", label.replace('–', "_"));
                    (key, (*n > 0).then_some(rate))
                })
                .collect();
            let record = HazardRecord {
                scheme: "kbuffer",
                write_back: &r.write_back,
                policy: &r.policy,
                seeds,
                mismatched_pixel_rate: r.rate,
                mismatched_pixel_rate_per_seed: &r.rate_per_seed,
                lost: r.lost,
                extra: r.extra,
                duplicates: r.duplicates,
                misordered_pixels: r.misordered_pixels,
                by_depth_complexity,
            };
            line(
                "hazard",
                &context.on("scheduled", r.threads_in_flight),
                &record,
            )
        })
        .collect()
}

/// The baselines' JSON Lines records, one `baseline` line per row, in `context` (the scene's)
/// with each row's K and executor.
///
/// # Errors
/// A record cannot be serialised (a bug).
pub fn baseline_records(report: &HazardReport, context: &Context) -> Result<Vec<String>, String> {
    report
        .baselines
        .iter()
        .map(|r| {
            let mut context = context.on(&r.executor, 0);
            context.threads = None;
            context.k = Some(Slots::Fixed(r.k));
            let record = BaselineRecord {
                scheme: &r.scheme,
                passes: r.passes,
                overflowed: r.overflowed,
                lost: r.lost,
                extra: r.extra,
                duplicates: r.duplicates,
                misordered_pixels: r.misordered_pixels,
                error_pixels: r.error_pixels,
                error_pixel_rate: r.error_pixels as f64 / report.covered.max(1) as f64,
                memory_bytes: r.memory_bytes,
            };
            line("baseline", &context, &record)
        })
        .collect()
}
