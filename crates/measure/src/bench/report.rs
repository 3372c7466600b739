//! What `bench` reports beside its rows: bench.md (every column of every row with their key,
//! the approximate rows, the colour error per depth-complexity bucket, the multisampled rows),
//! the terminal tables (the columns a reader scans first), the JSON Lines records and the
//! speed/accuracy chart. Text and files, never stdout: the command line prints them.

use std::path::Path;

use serde::Serialize;

use super::{BenchReport, BenchRow};
use crate::approximate::ApproximateRow;
use crate::cells::{bucket_cells, family, mean_of_channels, percent};
use crate::multisampled::{MsaaReport, SampledRow};
use crate::record::{line, Context};
use crate::table::{Column, Table};

/// The bench's own speed/accuracy chart: one point per scheme and executor.
///
/// # Errors
/// The chart cannot be drawn or written.
pub fn speed_accuracy_chart(report: &BenchReport, path: &Path) -> Result<(), String> {
    let points: Vec<fragsim_shade::plot::Point> = report
        .rows
        .iter()
        .filter_map(|r| {
            Some(fragsim_shade::plot::Point {
                label: format!("{} ({})", r.scheme, r.executor),
                family: family(&r.scheme),
                time_ms: r.time_ms,
                rate: r.error_pixel_rate?,
                mean_error: mean_of_channels(&r.colour),
            })
        })
        .chain(
            report
                .approximate
                .iter()
                .map(|r| fragsim_shade::plot::Point {
                    label: r.label(),
                    family: family(&r.scheme),
                    time_ms: r.time_ms,
                    rate: r.error_pixel_rate,
                    mean_error: mean_of_channels(&r.colour),
                }),
        )
        .collect();
    fragsim_shade::plot::speed_accuracy(
        path,
        &format!(
            "{}: speed against accuracy ({}, {}x{})",
            report.scene, report.effect, report.width, report.height
        ),
        "median frame time (ms, log scale)",
        &points,
    )
    .map_err(|e| e.to_string())
}

/// What bench.md's columns mean, printed under the table.
const COLUMNS: &str = "
Columns: **thr** threads; **passes** geometry passes per frame (with the counting pass that \
sized the storage, where one ran); **memory B**, **B/px** per-pixel storage in bytes, in all and \
per pixel; **captured** fragments kept; **overflow** fragments with no room by design (beyond K \
or a fixed capacity: the oracle's prediction); **lost** fragments it should have kept and did \
not; **mismatched px** pixels whose list differs from the oracle's; **EPR %** error-pixel rate: \
pixels whose 8-bit colour of the effect differs from the oracle's image, in percent of the \
covered pixels (JSON holds the fraction, `error_pixel_rate`; n/a: the words cannot resolve the \
effect); **mean err**, **max err**, **PSNR dB** the colour error of that image: the mean \
absolute error of its 8-bit channels (the mean of the three channels'; JSON holds each, \
`mean_abs_error`), the largest of any channel, and the peak signal-to-noise ratio (inf: equal \
images); **ops/frag** memory operations per fragment; **locked/frag** read-modify-write \
operations per fragment (counted in one extra, untimed frame); **vertex ms**, **passes ms**, \
**post ms** medians of the vertex stage, the geometry passes (storage initialisation, \
rasterization, capture) and the post pass (resolve, sort); **frame ms** their median sum \
(`time_ms`), **min**, **max** the fastest and slowest frame; **fps** frames per second at the \
median; **Mtri/s**, **Mfrag/s** millions of triangles (per pass) and fragments per second; \
**vs DP** depth peeling's median time over this row's (above 1: faster than depth peeling).
";

/// bench.md: the scene, the rows' table with its key, the approximate rows, the colour error
/// per depth-complexity bucket and the multisampled rows.
#[must_use]
pub fn markdown(report: &BenchReport) -> String {
    let mut text = format!(
        "scene {}: {} triangles, {}x{}, {} fragments, max depth complexity {}, {} covered pixels; \
         rasterization alone {:.2} ms (median of {} frames); effect {}\n\n",
        report.scene,
        report.triangles,
        report.width,
        report.height,
        report.oracle_fragments,
        report.max_depth_complexity,
        report.covered_pixels,
        report.raster_ms,
        report.frames,
        report.effect
    );
    if let Some(msaa) = &report.msaa {
        text.push_str(&format!(
            "The oracle's image at {n} samples a pixel (standard pattern), shaded per sample and \
             resolved per pixel (bench-oracle-{effect}-msaa{n}.png): {} sample fragments; {} \
             mixed pixels (samples holding different primitives), {} of them layer edges \
             (samples holding different numbers of fragments); {} pixels whose 8-bit colour \
             differs from the single-sample image (bench-oracle-{effect}-msaa{n}-diff.png).\n\n",
            msaa.sample_fragments,
            msaa.mixed_pixels,
            msaa.layer_edge_pixels,
            msaa.differing_pixels,
            n = msaa.samples,
            effect = report.effect,
        ));
    }
    text.push_str(
        "| scheme | executor | thr | passes | memory B | B/px | captured | overflow | lost | mismatched px | EPR % | mean err | max err | PSNR dB | ops/frag | locked/frag | vertex ms | passes ms | post ms | frame ms | min | max | fps | Mtri/s | Mfrag/s | vs DP |\n",
    );
    text.push_str(
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let option = |v: Option<f64>, digits: usize| {
        v.map_or_else(|| "n/a".to_string(), |v| format!("{v:.digits$}"))
    };
    for r in &report.rows {
        let [mean_error, max_error, psnr] = r.colour.cells();
        text.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} | {:.1} | {:.1} | {} |\n",
            r.scheme,
            r.executor,
            r.threads,
            r.passes,
            r.memory_bytes,
            r.bytes_per_pixel,
            r.captured,
            r.overflowed,
            r.lost,
            r.mismatched_pixels,
            r.error_pixel_rate.map_or_else(|| "n/a".to_string(), |e| percent(e, 3)),
            mean_error,
            max_error,
            psnr,
            r.ops_per_fragment,
            r.locked_ops_per_fragment,
            r.vertex_ms,
            r.passes_ms,
            r.resolve_ms,
            r.time_ms,
            r.min_ms,
            r.max_ms,
            r.fps,
            r.triangles_per_second / 1e6,
            r.fragments_per_second / 1e6,
            option(r.speedup_vs_depth_peeling, 2),
        ));
    }
    text.push_str(COLUMNS);
    if !report.approximate.is_empty() {
        text.push_str(&approximate_markdown(&report.approximate));
    }
    text.push_str(&depth_markdown(report));
    if let Some(msaa) = &report.msaa {
        text.push_str(&msaa_markdown(msaa));
    }
    text
}

/// bench.md's table of the colour error per depth-complexity bucket, of every approximate image
/// (as the chart labels them) and every catalog image that differs from the oracle's (by scheme
/// and executor); empty when there is none.
fn depth_markdown(report: &BenchReport) -> String {
    let differing = report
        .rows
        .iter()
        .filter(|r| r.error_pixels.is_some_and(|e| e > 0))
        .map(|r| (format!("{} ({})", r.scheme, r.executor), &r.colour_by_depth));
    let approximate = report
        .approximate
        .iter()
        .map(|r| (r.label(), &r.colour_by_depth));
    let mut lines = String::new();
    for (label, by_depth) in differing.chain(approximate) {
        for bucket in by_depth.covered() {
            lines.push_str(&format!(
                "| {label} | {} |\n",
                bucket_cells(bucket).join(" | ")
            ));
        }
    }
    if lines.is_empty() {
        return lines;
    }
    format!(
        "\nThe colour error per depth-complexity bucket (fragments per pixel), of the approximate \
         images and of every other image that differs from the oracle's\n\n\
         | row | fragments/px | pixels | EPR % | mean err | max err | PSNR dB |\n\
         |---|---|---|---|---|---|---|\n{lines}\n\
         Columns: **fragments/px** the bucket (the oracle's fragments per pixel; uncovered \
         pixels are in none); **pixels** the covered pixels in it; **EPR %** of them, those whose \
         8-bit colour differs; **mean err**, **max err**, **PSNR dB** the colour error over them \
         alone. JSON: `pixels_dc_5_8`, `error_pixels_dc_5_8`, `error_pixel_rate_dc_5_8`, \
         `mean_abs_error_dc_5_8`, … for every bucket, on every record.\n"
    )
}

/// bench.md's table of the approximate schemes, with what its columns mean.
fn approximate_markdown(rows: &[ApproximateRow]) -> String {
    let mut text = String::from(
        "\nApproximate OIT (judged by the image: their storage holds colour, not lists)\n\n\
         | scheme | nodes | memory B | B/px | px beyond nodes | EPR % | mean err | max err | PSNR dB | blend ms | frame ms |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let [mean, max, psnr] = r.colour.cells();
        text.push_str(&format!(
            "| {} | {} | {} | {:.1} | {} | {:.3} | {mean} | {max} | {psnr} | {:.2} | {:.2} |\n",
            r.scheme,
            r.nodes.map_or("-".into(), |k| k.to_string()),
            r.memory_bytes,
            r.bytes_per_pixel,
            r.pixels_beyond_nodes,
            r.error_pixel_rate * 100.0,
            r.blend_ms,
            r.time_ms,
        ));
    }
    text.push_str(
        "\nColumns: **nodes** per pixel (`--k`; WBOIT none); **memory B**, **B/px** the storage a \
         GPU needs as the paper lays it out; **px beyond nodes** pixels with more fragments than \
         nodes (WBOIT: more than one), the only pixels where the scheme may differ from the \
         exact image; **EPR %**, **mean err**, **max err**, **PSNR dB** as above, of its \
         transparency image; **blend ms** the median time of the blend over every pixel's \
         fragments in primitive order; **frame ms** the rasterization alone plus the blend.\n",
    );
    text
}

/// bench.md's table of the multisampled rows, with what its columns mean.
#[must_use]
pub fn msaa_markdown(msaa: &MsaaReport) -> String {
    let percent = |part: u64, whole: u64| 100.0 * part as f64 / whole.max(1) as f64;
    let mut text = format!(
        "\nMultisampled schemes at {n} samples a pixel, against the per-sample oracle ({} sample \
         fragments; its deepest pixel needs {} masked nodes)\n\n\
         | scheme | storage | executor | thr | passes | slots | memory B | B/px | overflow | missing | lost | wrong samples | misordered | EPR % | mean err | max err | PSNR dB | passes ms | post ms | frame ms |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        msaa.sample_fragments,
        msaa.max_nodes_per_pixel,
        n = msaa.samples,
    );
    for r in &msaa.rows {
        let [mean_error, max_error, psnr] = r.colour.cells();
        text.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {:.1} | {} {} | {} ({:.3} %) | {} | {} ({:.3} %) | {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} |\n",
            r.scheme,
            r.storage,
            r.executor,
            r.threads,
            r.passes,
            r.slots.map_or_else(|| "counted".to_string(), |s| s.to_string()),
            r.memory_bytes,
            r.bytes_per_pixel,
            r.overflowed,
            r.overflow_unit,
            r.missing,
            percent(r.missing, r.sample_fragments),
            r.lost,
            r.wrong_samples,
            100.0 * r.wrong_sample_rate,
            r.misordered_samples,
            r.error_pixel_rate
                .map_or_else(|| "n/a".to_string(), |e| format!("{:.3}", e * 100.0)),
            mean_error,
            max_error,
            psnr,
            r.passes_ms,
            r.resolve_ms,
            r.time_ms,
        ));
    }
    text.push_str(
        "
Columns: **storage** `per-sample`: the scheme run on the sample-expanded framebuffer (its storage \
× samples); `masked`: per-pixel nodes, one per primitive and pixel, each carrying the mask of the \
samples it covers and the nearest of their depths, in `--capacity` slots a pixel \
(`abuffer-masked`) or a pool of `--capacity` nodes a pixel shared by all (`linked-list-masked`); \
**passes** geometry passes, its own counting pass included; **slots** slots a sample \
(per-sample), nodes a pixel (masked A-buffer) or pool nodes a pixel (linked lists) the storage \
had (`--k`, `--capacity`, or its counting pass's deepest pixel under `auto`; counted: a pool of \
every node, storage sized per pixel); **memory B**, **B/px** \
bytes allocated, in all and per pixel (all its samples); **overflow** what found no room: sample \
fragments (per-sample storage, the oracle's prediction as above) or whole nodes (masked storage, \
its counters' count: per pixel, or the pool's one counter); **missing** sample fragments of the \
per-sample oracle missing from the scheme's per-sample resolve, the overflow's included, with \
their share; **lost** of those, the ones the scheme owed: beyond the predicted overflow for \
per-sample storage (as the single-sample table counts them: 0 for a correct scheme whatever K), \
every missing one for masked storage (its overflow counts nodes); **wrong samples** samples whose list differs from \
the per-sample oracle's, with their share of all samples; **misordered** of those, samples with \
every fragment present in another order (a masked node orders all its samples by its nearest \
depth); **EPR %**, **mean err**, **max err**, **PSNR dB** the transparency image shaded per \
sample and box-resolved per pixel against the oracle's resolved the same way; **passes ms**, \
**post ms**, **frame ms** medians of the geometry passes, the post pass and the frame (vertex \
stage included).
",
    );
    text
}

/// What bench prints on a terminal: the scene line of bench.md and the columns a reader scans
/// first, aligned, in about 120 characters (bench.md holds all 26).
#[must_use]
pub fn terminal_table(report: &BenchReport) -> String {
    let columns: [Column<BenchRow>; 10] = [
        ("scheme", |r| r.scheme.clone()),
        ("executor", |r| r.executor.clone()),
        ("passes", |r| r.passes.to_string()),
        ("B/px", |r| format!("{:.1}", r.bytes_per_pixel)),
        ("lost", |r| r.lost.to_string()),
        ("mismatched px", |r| r.mismatched_pixels.to_string()),
        ("EPR %", |r| {
            r.error_pixel_rate
                .map_or_else(|| "n/a".into(), |e| percent(e, 3))
        }),
        ("PSNR dB", |r| r.colour.cells()[2].clone()),
        ("frame ms", |r| format!("{:.2}", r.time_ms)),
        ("vs DP", |r| {
            r.speedup_vs_depth_peeling
                .map_or_else(|| "n/a".into(), |v| format!("{v:.2}"))
        }),
    ];
    let mut text = markdown(report)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    text.push_str("\n\n");
    text.push_str(&Table::of(&columns, &report.rows, 2).text(2));
    text.push_str(
        "Columns: passes geometry passes a frame; B/px storage bytes a pixel; lost fragments it \
         should have kept; mismatched px pixels whose list differs from the oracle's; EPR % \
         pixels whose 8-bit colour of the effect differs, in % of the covered pixels; PSNR dB of \
         that image; frame ms the median frame; vs DP speed-up over depth peeling.\n",
    );
    text
}

/// What `bench --samples` prints on a terminal under the single-sample table: the line of
/// bench.md that opens the multisampled table, and its columns a reader scans first, aligned
/// (bench.md holds every column and their key).
#[must_use]
pub fn msaa_terminal_table(msaa: &MsaaReport) -> String {
    let columns: [Column<SampledRow>; 10] = [
        ("scheme", |r| r.scheme.clone()),
        ("storage", |r| r.storage.to_string()),
        ("executor", |r| r.executor.clone()),
        ("passes", |r| r.passes.to_string()),
        ("B/px", |r| format!("{:.1}", r.bytes_per_pixel)),
        ("overflow", |r| {
            format!("{} {}", r.overflowed, r.overflow_unit)
        }),
        ("lost", |r| r.lost.to_string()),
        ("wrong samples", |r| r.wrong_samples.to_string()),
        ("EPR %", |r| {
            r.error_pixel_rate
                .map_or_else(|| "n/a".into(), |e| percent(e, 3))
        }),
        ("frame ms", |r| format!("{:.2}", r.time_ms)),
    ];
    let mut text = msaa_markdown(msaa)
        .lines()
        .find(|line| !line.is_empty())
        .unwrap_or_default()
        .to_string();
    text.push_str("\n\n");
    text.push_str(&Table::of(&columns, &msaa.rows, 3).text(2));
    text.push_str(
        "Columns: overflow what found no room (sample fragments, or whole masked nodes); lost \
         sample fragments the scheme owed and is missing (per-sample storage: beyond the \
         overflow); wrong samples samples whose list differs from the per-sample oracle's; the \
         rest as above.\n",
    );
    text
}

/// One line of bench's JSON Lines: a row with what the whole bench measured.
#[derive(Serialize)]
struct BenchRecord<'a> {
    #[serde(flatten)]
    row: &'a BenchRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// One line of bench's JSON Lines for an approximate scheme: its row with what the whole bench
/// measured.
#[derive(Serialize)]
struct ApproximateRecord<'a> {
    #[serde(flatten)]
    row: &'a ApproximateRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// One line of bench's JSON Lines for a multisampled scheme (`--samples`): its row with what the
/// whole bench measured.
#[derive(Serialize)]
struct SampledRecord<'a> {
    #[serde(flatten)]
    row: &'a SampledRow,
    #[serde(flatten)]
    bench: &'a BenchReport,
}

/// bench's JSON Lines (`docs/json-schema.md`; bench.jsonl holds the same): a `bench` line per
/// row, a `bench-approximate` line per approximate row, a `bench-msaa` line per multisampled
/// row, each in `context` (the scene's, sized) on the row's executor and threads.
///
/// # Errors
/// A record cannot be serialised (a bug).
pub fn records(report: &BenchReport, context: &Context) -> Result<String, String> {
    let mut lines = String::new();
    for row in &report.rows {
        let on = context.on(&row.executor, row.threads);
        let record = BenchRecord { row, bench: report };
        lines.push_str(&line("bench", &on, &record)?);
        lines.push('\n');
    }
    for row in &report.approximate {
        let on = context.on("primitive-order", row.threads);
        let record = ApproximateRecord { row, bench: report };
        lines.push_str(&line("bench-approximate", &on, &record)?);
        lines.push('\n');
    }
    for row in report.msaa.iter().flat_map(|m| &m.rows) {
        let on = context.on(&row.executor, row.threads);
        let record = SampledRecord { row, bench: report };
        lines.push_str(&line("bench-msaa", &on, &record)?);
        lines.push('\n');
    }
    Ok(lines)
}
