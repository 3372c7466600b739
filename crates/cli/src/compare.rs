//! `fragsim compare REFERENCE CANDIDATE`: a GPU backend's dump (or fragsim's own) against the
//! oracle or another dump, pixel by pixel (`docs/dump-format.md`).
//!
//! Either side is a dump directory or the word `oracle`: fragsim's serial oracle on the scene
//! the other side's header names. The verdict is the oracle's
//! ([`fragsim_oracle::verdict::judge_sides`]: the candidate's lists decoded by the scheme's own
//! post pass and judged under its promise, every word of its storage checked against its layout);
//! this module holds the arguments and prints the verdict as text, JSON Lines and a difference
//! image. Exit code 0 only when every pixel is equal.

use std::path::{Path, PathBuf};

use clap::Args;
use fragsim_oracle::compare::flags;
use fragsim_oracle::verdict::{judge_sides, Entry, Options, Side, SidesOptions, Summary, Verdict};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::VertexPrecision;

use crate::args::parse_bytes;
use crate::record::{Context, Slots};
use fragsim_capture::MEMORY_CAP_DEFAULT;

/// Options of `fragsim compare`.
#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    /// The reference: a dump directory (or its dump.json), or `oracle`.
    #[arg(value_name = "REFERENCE")]
    pub reference: String,
    /// The candidate: a dump directory (or its dump.json), or `oracle`.
    #[arg(value_name = "CANDIDATE")]
    pub candidate: String,
    /// Print JSON Lines instead of the report: one `compare` record, then one `difference`
    /// record per differing pixel shown (`--show`; `docs/json-schema.md`).
    #[arg(long)]
    pub json: bool,
    /// Accept a candidate depth key within N f32 ulps of the reference's (same primitive), for
    /// backends that interpolate depth in f32.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub depth_ulps: u32,
    /// How many differing pixels to show, both lists side by side.
    #[arg(long, value_name = "N", default_value_t = 8)]
    pub show: usize,
    /// The difference image (PNG).
    #[arg(long, value_name = "PATH", default_value = "out/compare-diff.png")]
    pub image: PathBuf,
    /// Write no difference image (`--no-images`, as every command spells it; the older
    /// `--no-image` still works).
    #[arg(long = "no-images", alias = "no-image", conflicts_with = "image")]
    pub no_image: bool,
    /// The mesh file to rebuild the oracle from instead of the one the dump names (a dump that
    /// travelled); its bytes must still hash as the dump says.
    #[arg(long, value_name = "PATH")]
    pub mesh: Option<PathBuf>,
    /// How the candidate's vertex stage is judged when the reference is the oracle: by default
    /// (and `f64`) every bit is owed to the oracle rebuilt under the dump's declared conventions
    /// (`scene.conventions`, its vertex stage included: fragsim's own dumps, a replay of its
    /// screen triangles); `f32` (a vertex shader) judges it within the bounds derived for an f32
    /// vertex stage against the exact f64 one (`docs/semantics.md`, "Precision of a conforming
    /// implementation").
    #[arg(long, value_name = "f64|f32", value_parser = ["f64", "f32"])]
    pub vertex_precision: Option<String>,
    /// Compare two dumps that name different scenes (refused otherwise, exit 2).
    #[arg(long)]
    pub allow_different_scenes: bool,
    /// `--mesh` replaces the named scene (`bunny`, `quads:8`, …) a dump's header gives; without
    /// it, `--mesh` on a dump of a named scene is refused.
    #[arg(long, requires = "mesh")]
    pub mesh_replaces_scene: bool,
    /// Refuse dumps whose arrays, and scenes whose mesh and oracle, could exceed this many
    /// bytes, before reading or making them (as `render --memory-cap`).
    #[arg(long, default_value_t = MEMORY_CAP_DEFAULT, allow_negative_numbers = true,
          value_parser = parse_bytes)]
    pub memory_cap: u64,
}

/// What the report prints: the verdict's totals, its scene, and the difference image written.
struct Report<'a> {
    summary: Summary<'a>,
    scene: &'a SceneSpec,
    width: u32,
    height: u32,
    image: Option<String>,
    /// The difference image's legend, entry by entry (`missing: 1`), as the image shows it.
    legend: Vec<String>,
}

/// Runs `compare`; returns whether the sides are equal.
///
/// # Errors
/// Unreadable or inconsistent dumps, a scene that cannot be rebuilt, an image that cannot be
/// written.
pub fn compare(args: &CompareArgs) -> Result<bool, String> {
    let reference = Side::open_within(&args.reference, args.memory_cap)?;
    let candidate = Side::open_within(&args.candidate, args.memory_cap)?;
    check_mesh_replaces(args, [&reference, &candidate])?;
    let options = SidesOptions {
        options: Options {
            depth_ulps: args.depth_ulps,
            examples: args.show,
        },
        vertex_precision: match args.vertex_precision.as_deref() {
            Some("f32") => VertexPrecision::F32,
            _ => VertexPrecision::F64,
        },
        mesh: args.mesh.as_deref(),
        allow_different_scenes: args.allow_different_scenes,
        memory_cap: Some(args.memory_cap),
    };
    let verdict = judge_sides(&reference, &candidate, &options)?;
    let (image, legend) = if args.no_image {
        (None, Vec::new())
    } else {
        let legend = legend(&verdict);
        write_image(&verdict, &legend, &args.image)?;
        (Some(args.image.display().to_string()), legend)
    };
    let report = Report {
        summary: verdict.summary(reference.describe(), candidate.describe()),
        scene: verdict.scene.as_ref().ok_or("the verdict names no scene")?,
        width: verdict.width,
        height: verdict.height,
        image,
        legend: legend.into_iter().map(|(_, entry)| entry).collect(),
    };
    if args.json {
        print_json(&report)?;
    } else {
        print_report(&report);
    }
    Ok(verdict.equal)
}

/// Refuses `--mesh` on a dump of a named scene unless `--mesh-replaces-scene` says so: the file
/// would silently replace the scene the dump was made of.
fn check_mesh_replaces(args: &CompareArgs, sides: [&Side; 2]) -> Result<(), String> {
    let (Some(mesh), false) = (&args.mesh, args.mesh_replaces_scene) else {
        return Ok(());
    };
    for side in sides {
        if let Side::Dump(dump, path) = side {
            if let Some(name) = &dump.header.scene.name {
                return Err(format!(
                    "--mesh {}: {} is a dump of the named scene {name:?}, not of a mesh file; \
                     pass --mesh-replaces-scene to judge it against the file instead",
                    mesh.display(),
                    path.display()
                ));
            }
        }
    }
    Ok(())
}

/// Colour of a pixel's verdict in the difference image.
fn colour(flags: u8, fragments: usize) -> [u8; 3] {
    let wrong = flags & (flags::MISSING | flags::EXTRA);
    match () {
        () if flags & flags::CORRUPT != 0 => [40, 220, 40],
        () if wrong == flags::MISSING | flags::EXTRA => [220, 50, 220],
        () if wrong == flags::MISSING => [230, 40, 40],
        () if wrong == flags::EXTRA => [60, 90, 255],
        () if flags & flags::MISORDERED != 0 => [250, 220, 0],
        () if flags & flags::MISCOUNTED != 0 => [255, 140, 0],
        () if flags & flags::OVERFLOWED != 0 => [0, 90, 90],
        () if fragments > 0 => [70, 70, 70],
        () => [0, 0, 0],
    }
}

/// The legend of the difference image: every colour [`colour`] gives, what it means, and how
/// many pixels have it. A verdict's count is the report's (every pixel with that flag), though a
/// pixel of several verdicts is drawn in the colour of the one listed first: the entry says how
/// many of its pixels are drawn above, so that the legend and the text agree ("missing 1" in
/// both where the one missing pixel is also corrupt).
fn legend(v: &Verdict) -> Vec<(image::Rgb<u8>, String)> {
    // (the flags a pixel must all have, the fragments its reference holds, the meaning): the
    // verdicts in the order their colours win, then the equal pixels, covered or not.
    let meanings: [(u8, usize, &str); 9] = [
        (flags::CORRUPT, 0, "corrupt word"),
        (flags::MISSING | flags::EXTRA, 0, "missing and extra"),
        (flags::MISSING, 0, "missing"),
        (flags::EXTRA, 0, "extra"),
        (flags::MISORDERED, 0, "misordered"),
        (flags::MISCOUNTED, 0, "overflow miscounted"),
        (flags::OVERFLOWED, 0, "overflowed (by design)"),
        (0, 1, "equal, covered"),
        (0, 0, "no fragment"),
    ];
    let mut counts = [(0_u64, 0_u64); 9];
    for (&flags, &n) in v.comparison.verdicts.iter().zip(&v.reference_fragments) {
        let drawn = colour(flags, n as usize);
        for (&(wanted, covered, _), (has, drawn_above)) in meanings.iter().zip(&mut counts) {
            let own = colour(wanted, covered);
            let counted = if wanted == 0 {
                // The equal pixels are counted as drawn.
                drawn == own
            } else {
                flags & wanted == wanted
            };
            if counted {
                *has += 1;
                *drawn_above += u64::from(drawn != own);
            }
        }
    }
    meanings
        .iter()
        .zip(counts)
        .map(|(&(f, n, meaning), (count, drawn_above))| {
            let above = if drawn_above > 0 {
                format!(" ({drawn_above} drawn above)")
            } else {
                String::new()
            };
            (
                image::Rgb(colour(f, n)),
                format!("{meaning}: {count}{above}"),
            )
        })
        .collect()
}

/// The difference image of `v`, one column per list (a per-sample layout's samples side by
/// side), with its `legend`.
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
)]
fn write_image(
    v: &Verdict,
    legend: &[(image::Rgb<u8>, String)],
    path: &Path,
) -> Result<(), String> {
    let width = v.width * v.lists_per_pixel;
    let image = image::RgbImage::from_fn(width, v.height, |x, y| {
        let p = (y * width + x) as usize;
        image::Rgb(colour(
            v.comparison.verdicts[p],
            v.reference_fragments[p] as usize,
        ))
    });
    let differing = v
        .comparison
        .verdicts
        .iter()
        .enumerate()
        .filter(|&(_, &v)| v & flags::DIFFERS != 0)
        .map(|(p, _)| ((p % width as usize) as u32, (p / width as usize) as u32));
    // Rings only where differences are sparse: dense ones show alone, and rings would hide some.
    let ring = differing.clone().count() <= fragsim_shade::legend::MARKS;
    let marks: Vec<(u32, u32)> = differing.take(fragsim_shade::legend::MARKS).collect();
    let figure = fragsim_shade::legend::difference_figure(&image, legend, &marks, ring)
        .map_err(|e| e.to_string())?;
    fragsim_shade::save_png(&figure, path).map_err(|e| e.to_string())
}

/// The report as JSON Lines: the report's fields flattened into one `compare` record (a group's
/// fields named as everywhere else: `missing_pixels`, `lost`, `reported_overflow`,
/// `corrupt_words`, `candidate_k`, `precision_…`), then one `difference` record per example.
fn print_json(report: &Report<'_>) -> Result<(), String> {
    let r = &report.summary;
    let mut context = Context::new("compare", report.scene, report.width, report.height);
    context.k = r.candidate.k.map(Slots::Fixed);
    context.capacity = r.candidate.capacity.map(Slots::Fixed);
    let serde_json::Value::Object(whole) = serde_json::to_value(r).map_err(|e| e.to_string())?
    else {
        return Err("the compare report is not a JSON object".into());
    };
    let mut flat = serde_json::Map::new();
    for (key, value) in whole {
        match (key.as_str(), value) {
            // The examples are records of their own.
            ("first_differences", _) => {}
            (group, serde_json::Value::Object(fields)) => {
                for (k, v) in fields {
                    flat.insert(flat_name(group, &k), v);
                }
            }
            (_, value) => {
                flat.insert(key, value);
            }
        }
    }
    flat.insert(
        "image".into(),
        serde_json::to_value(&report.image).map_err(|e| e.to_string())?,
    );
    crate::record::emit("compare", &context, &flat)?;
    for example in r.first_differences {
        crate::record::emit("difference", &context, example)?;
    }
    Ok(())
}

/// The record's name of field `key` of the report's group `group`.
fn flat_name(group: &str, key: &str) -> String {
    let key = key.replace('-', "_");
    match (group, key.as_str()) {
        ("verdicts", _) => format!("{key}_pixels"),
        ("fragments", "reference") => "reference_fragments".into(),
        ("fragments", "overflow_claimed") => "reported_overflow".into(),
        ("fragments", _) => key,
        ("words", "checked") => "words_checked".into(),
        ("words", _) => format!("{key}_words"),
        _ => format!("{group}_{key}"),
    }
}

fn print_report(report: &Report<'_>) {
    let r = &report.summary;
    outln!(
        "reference {}\ncandidate {}\nscene {} at {}x{}",
        r.reference.describe(),
        r.candidate.describe(),
        report.scene.describe(),
        report.width,
        report.height
    );
    outln!("compared: {}", r.compared);
    let v = &r.verdicts;
    outln!(
        "pixels {}: equal {}, missing {}, extra {}, misordered {}, overflowed {}, \
         overflow-miscounted {}, corrupt {}",
        r.pixels,
        v.equal,
        v.missing,
        v.extra,
        v.misordered,
        v.overflowed,
        v.miscounted,
        v.corrupt
    );
    if let Some(s) = &r.per_sample {
        outln!(
            "per sample ({} a pixel): {} of {} samples differ, in {} of {} pixels",
            s.samples,
            s.differing_samples,
            s.compared,
            s.differing_pixels,
            s.compared / u64::from(s.samples)
        );
    }
    if let Some(wrong) = r.wrong_masks {
        outln!("masked nodes: {wrong} stored with another coverage mask than the reference's");
    }
    if let Some(b) = &r.precision {
        outln!(
            "precision ({}): vertex error up to {:.3} subpixels (snapped radius {}), \
             depth intervals up to {} ulps, {} ambiguous (pixel, triangle) pairs ({} may be \
             present, {} covered with coverage undecided, {} covered with depth leaving [0, 1], \
             {} of clipped triangles not analysed), {} clipped triangles analysed piece by \
             piece, {} not analysed, {} judged by the edge bound",
            match (r.vertex_precision, r.stored_depth) {
                ("f32", "f32") => "f32 vertex stage".to_string(),
                ("f32", stored) => format!("f32 vertex stage, {stored} depth"),
                (_, stored) => format!("{stored} depth"),
            },
            b.max_vertex_error_subpixels,
            b.max_snap_radius_subpixels,
            b.max_depth_interval_ulps,
            b.ambiguous_pairs,
            b.may_be_present_pairs,
            b.coverage_undecided_pairs,
            b.depth_undecided_pairs,
            b.clipped_pairs,
            b.clipped_triangles,
            b.unanalysed_triangles,
            b.bounded_triangles
        );
        let why = r.ambiguous_by_cause.unwrap_or_default();
        outln!(
            "pixels within precision {}, ambiguous {} (counted, never errors; by cause: coverage \
             {}, depth {}, order {}, clipped {})",
            v.within_precision,
            v.ambiguous,
            why.coverage,
            why.depth,
            why.order,
            why.clipped
        );
        let s = r.snaps.unwrap_or_default();
        outln!(
            "one snap per vertex: {} vertices may snap to more than one grid point where a \
             centre's coverage hangs on it, {} pinned by the capture; {} pixels judged jointly, \
             {} of them decided by the pins, {} decided but for which triangle a key-only word \
             came from (the dump names none), {} contradicting every snap (errors), {} past the \
             enumeration",
            s.undecided_vertices,
            s.pinned_vertices,
            s.joint_pixels,
            s.decided_pixels,
            s.unnamed_pixels,
            s.contradicting_pixels,
            s.unjoined_pixels
        );
    }
    let f = &r.fragments;
    let claimed = if f.overflow_claimed == f.overflowed {
        String::new()
    } else {
        format!(" (counters claim {})", f.overflow_claimed)
    };
    outln!(
        "fragments: reference {}, captured {}, lost {}, extra {}, overflowed by design {}{claimed}",
        f.reference,
        f.captured,
        f.lost,
        f.extra,
        f.overflowed
    );
    if r.words.checked {
        outln!(
            "words: corrupt {}, not checked {}, spare room not read {}, nodes no list reaches {}",
            r.words.corrupt,
            r.words.unchecked,
            r.words.spare,
            r.words.unreachable
        );
    }
    for note in r.notes {
        outln!("note: {note}");
    }
    for hint in r.hints {
        outln!("hint: {hint}");
    }
    for e in r.first_differences {
        let sample = e.sample.map_or(String::new(), |s| format!(", sample {s}"));
        outln!(
            "pixel {} (x {}, y {}{sample}): {}",
            e.pixel,
            e.x,
            e.y,
            e.verdict.join(", ")
        );
        outln!("  {:<36} {:<36}", "reference", "candidate");
        #[expect(clippy::shadow_unrelated, reason = "each row's entry, not an error")]
        let show = |e: Option<&Entry>| {
            e.map_or(String::new(), |e| match e.prim {
                Some(prim) => format!("{:.9} [{}] prim {prim}", e.depth, e.key),
                None => format!("{:.9} [{}]", e.depth, e.key),
            })
        };
        for (a, b) in aligned(&e.reference, &e.candidate) {
            let same = matches!((a, b), (Some(a), Some(b)) if same_fragment(a, b));
            outln!(
                "{} {:<36} {:<36}",
                if same { ' ' } else { '*' },
                show(a),
                show(b)
            );
        }
        for c in &e.corrupt_words {
            outln!("  slot {}: {} {}", c.slot, c.word, c.why);
        }
    }
    if let Some(image) = &report.image {
        outln!("difference image: {image}");
        outln!("  legend: {}", report.legend.join("; "));
    }
    outln!("verdict: {}", r.word());
}

/// Whether two shown entries are the same fragment: the same depth key and primitive.
fn same_fragment(a: &Entry, b: &Entry) -> bool {
    a.key == b.key && a.prim == b.prim
}

/// The most cells of the table [`aligned`] matches two lists with (16 MiB of them).
const ALIGNED_CELLS: usize = 1 << 22;

/// The rows of a differing pixel's two lists side by side, aligned by fragment rather than by
/// index, so that one missing fragment marks one row, not every row after it: the longest run
/// of fragments both lists hold in the same order is matched row for row; between two matched
/// rows the rest go in depth order, a reference and a candidate entry of the same primitive on
/// one row (a depth that moved), every other entry on a row of its own.
fn aligned<'e>(
    reference: &'e [Entry],
    candidate: &'e [Entry],
) -> Vec<(Option<&'e Entry>, Option<&'e Entry>)> {
    let (n, m) = (reference.len(), candidate.len());
    // Lists too long for the table below are merged in depth order alone.
    if (n + 1).saturating_mul(m + 1) > ALIGNED_CELLS {
        let (reference, candidate): (Vec<&Entry>, Vec<&Entry>) =
            (reference.iter().collect(), candidate.iter().collect());
        return unmatched_rows(&reference, &candidate);
    }
    // common[i][j]: the longest common subsequence of reference[i..] and candidate[j..].
    let mut common = vec![vec![0_u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            common[i][j] = if same_fragment(&reference[i], &candidate[j]) {
                common[i + 1][j + 1] + 1
            } else {
                common[i + 1][j].max(common[i][j + 1])
            };
        }
    }
    let mut rows = Vec::with_capacity(n.max(m));
    let (mut i, mut j) = (0, 0);
    let (mut gap_reference, mut gap_candidate) = (Vec::new(), Vec::new());
    while i < n || j < m {
        if i < n && j < m && same_fragment(&reference[i], &candidate[j]) {
            rows.extend(unmatched_rows(&gap_reference, &gap_candidate));
            gap_reference.clear();
            gap_candidate.clear();
            rows.push((Some(&reference[i]), Some(&candidate[j])));
            (i, j) = (i + 1, j + 1);
        } else if j == m || (i < n && common[i + 1][j] >= common[i][j + 1]) {
            gap_reference.push(&reference[i]);
            i += 1;
        } else {
            gap_candidate.push(&candidate[j]);
            j += 1;
        }
    }
    rows.extend(unmatched_rows(&gap_reference, &gap_candidate));
    rows
}

/// The rows of entries neither list matched between two matched rows, merged in depth order: a
/// reference and a candidate entry of the same primitive share a row.
fn unmatched_rows<'e>(
    reference: &[&'e Entry],
    candidate: &[&'e Entry],
) -> Vec<(Option<&'e Entry>, Option<&'e Entry>)> {
    let mut rows = Vec::with_capacity(reference.len() + candidate.len());
    let (mut r, mut c) = (reference.iter().peekable(), candidate.iter().peekable());
    loop {
        let row = match (r.peek(), c.peek()) {
            (None, None) => break,
            (Some(&&a), Some(&&b)) if a.prim.is_some() && a.prim == b.prim => {
                (r.next().copied(), c.next().copied())
            }
            (Some(&&a), Some(&&b)) if b.depth < a.depth => (None, c.next().copied()),
            (Some(_), _) => (r.next().copied(), None),
            (None, Some(_)) => (None, c.next().copied()),
        };
        rows.push(row);
    }
    rows
}
