//! What `bench` writes: its JSON Lines records, the terminal table, the Markdown report and the
//! speed/accuracy chart.

use serde::Serialize;

use super::{BenchArgs, BenchReport, BenchRow};
use crate::approximate::ApproximateRow;
use crate::multisampled::SampledRow;
use crate::record::{bucket_cells, mean_of_channels, percent};
use crate::schemes::family;

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

/// Writes the report's records, Markdown and chart into `--out` and prints its table.
///
/// # Errors
/// A file that cannot be written.
pub(super) fn write_outputs(report: &BenchReport, args: &BenchArgs) -> Result<(), String> {
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let mut lines = String::new();
    for row in &report.rows {
        let context = report.context.on(&row.executor, row.threads);
        let record = BenchRecord { row, bench: report };
        lines.push_str(&crate::record::line("bench", &context, &record)?);
        lines.push('\n');
    }
    for row in &report.approximate {
        let context = report.context.on("primitive-order", row.threads);
        let record = ApproximateRecord { row, bench: report };
        lines.push_str(&crate::record::line(
            "bench-approximate",
            &context,
            &record,
        )?);
        lines.push('\n');
    }
    for row in report.msaa.iter().flat_map(|m| &m.rows) {
        let context = report.context.on(&row.executor, row.threads);
        let record = SampledRecord { row, bench: report };
        lines.push_str(&crate::record::line("bench-msaa", &context, &record)?);
        lines.push('\n');
    }
    let json_path = args.out.join("bench.jsonl");
    std::fs::write(&json_path, &lines)
        .map_err(|e| format!("cannot write {}: {e}", json_path.display()))?;
    let markdown = markdown(report);
    let md_path = args.out.join("bench.md");
    std::fs::write(&md_path, &markdown)
        .map_err(|e| format!("cannot write {}: {e}", md_path.display()))?;
    let wrote = if args.no_images {
        format!("wrote {}: bench.jsonl, bench.md", args.out.display())
    } else {
        speed_accuracy_chart(report, &args.out.join("bench-speed-accuracy.png"))?;
        format!(
            "wrote {}: bench.jsonl, bench.md, bench-speed-accuracy.png and the effect and \
             difference images",
            args.out.display()
        )
    };
    // Under `--json` stdout stays JSON Lines: where the files went goes to stderr.
    if args.json {
        out!("{lines}");
        eprintln!("{wrote}");
    } else {
        out!("{}", terminal_table(report));
        if let Some(msaa) = &report.msaa {
            out!("\n{}", crate::multisampled::terminal_table(msaa));
        }
        let tables = if report.msaa.is_some() {
            "every column, with their key, the per-depth tables and the multisampled table"
        } else {
            "every column, with their key, and the per-depth tables"
        };
        outln!("{wrote} (bench.md: {tables})");
    }
    Ok(())
}

/// The bench's own speed/accuracy chart: one point per scheme and executor.
fn speed_accuracy_chart(report: &BenchReport, path: &std::path::Path) -> Result<(), String> {
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

/// What bench prints on a terminal: the scene line of bench.md and the columns a reader scans
/// first, aligned, in about 120 characters (bench.md holds all 26).
fn terminal_table(report: &BenchReport) -> String {
    let columns: [crate::record::Column<BenchRow>; 10] = [
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
    text.push_str(&crate::record::aligned_table(&columns, &report.rows, 2));
    text.push_str(
        "Columns: passes geometry passes a frame; B/px storage bytes a pixel; lost fragments it \
         should have kept; mismatched px pixels whose list differs from the oracle's; EPR % \
         pixels whose 8-bit colour of the effect differs, in % of the covered pixels; PSNR dB of \
         that image; frame ms the median frame; vs DP speed-up over depth peeling.\n",
    );
    text
}

fn markdown(report: &BenchReport) -> String {
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
        text.push_str(&crate::approximate::markdown(&report.approximate));
    }
    text.push_str(&depth_markdown(report));
    if let Some(msaa) = &report.msaa {
        text.push_str(&crate::multisampled::markdown(msaa));
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
