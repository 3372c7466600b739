//! `fragsim compare REFERENCE CANDIDATE`: a GPU backend's dump (or fragsim's own) against the
//! oracle or another dump, pixel by pixel (`docs/dump-format.md`).
//!
//! Either side is a dump directory or the word `oracle`: fragsim's serial oracle on the scene
//! the other side's header names. The verdict is the oracle's
//! ([`fragsim_oracle::verdict::judge_sides`]: the candidate's lists decoded by the scheme's own
//! post pass and judged under its promise, every word of its storage checked against its layout);
//! the difference image is `fragsim_shade::verdict_image`'s and the lists side by side
//! `fragsim_oracle::verdict::Example::rows`; this module holds the arguments and prints the
//! verdict as text and JSON Lines. Exit code 0 only when every pixel is equal.

use std::path::PathBuf;

use clap::Args;
use fragsim_oracle::verdict::{judge_sides, Entry, Options, Side, SidesOptions, Summary};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::VertexPrecision;
use fragsim_shade::verdict_image::write_difference_image;

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
        let legend = write_difference_image(&verdict, &args.image).map_err(|e| e.to_string())?;
        (Some(args.image.display().to_string()), legend)
    };
    let report = Report {
        summary: verdict.summary(reference.describe(), candidate.describe()),
        scene: verdict.scene.as_ref().ok_or("the verdict names no scene")?,
        width: verdict.width,
        height: verdict.height,
        image,
        legend,
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
        for (a, b) in e.rows() {
            let same = matches!((a, b), (Some(a), Some(b)) if a.same_fragment(b));
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
