//! `fragsim compare REFERENCE CANDIDATE`: a GPU backend's dump (or fragsim's own) against the
//! oracle or another dump, pixel by pixel (`docs/dump-format.md`).
//!
//! Either side is a dump directory or the word `oracle`: fragsim's serial oracle on the scene
//! the other side's header names. The candidate's lists are decoded by the scheme's own post pass
//! and checked with `Oracle::diff` under the candidate's promise (the K nearest for MDTS, every
//! fragment but the overflow the reference predicts for the A-buffer), and every word of its
//! storage is checked against its layout (`Dump::check_words`): a word where the layout allows
//! none is `corrupt`, an A-buffer counter other than the pixel's fragment count is
//! `overflow-miscounted`. Exit code 0 only when every pixel is equal.

use std::path::{Path, PathBuf};

use clap::Args;
use fragsim_capture::{Capacity, Capture, Identity, Keeps, PixelLists};
use fragsim_oracle::compare::{
    compare_with, complete_pixels, verdict, with_identity, AmbiguityCounts, CompareOptions,
    Comparison, SnapCounts, VerdictCounts,
};
use fragsim_oracle::dump::{node_capture, CorruptWord, DepthFormat, Dump, Header, MASKED_SCHEME};
use fragsim_oracle::precision::{compare_within, f32_reference, Bounds, Precision};
use fragsim_oracle::samples::SampleOracle;
use fragsim_oracle::scene::SceneAndCamera;
use fragsim_oracle::Oracle;
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::{depth_from_key, Conventions};
use serde::Serialize;

use crate::record::{Context, Slots};

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
    /// `--no-images` still works).
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
}

/// One side of a comparison.
enum Side {
    Oracle,
    Dump(Box<Dump>, PathBuf),
}

impl Side {
    fn open(text: &str) -> Result<Self, String> {
        if text == "oracle" {
            return Ok(Self::Oracle);
        }
        let path = PathBuf::from(text);
        let dump = Dump::read(&path).map_err(|e| e.to_string())?;
        Ok(Self::Dump(Box::new(dump), path))
    }

    fn header(&self) -> Option<&Header> {
        match self {
            Self::Oracle => None,
            Self::Dump(dump, _) => Some(&dump.header),
        }
    }

    fn describe(&self) -> SideReport {
        match self {
            Self::Oracle => SideReport {
                source: "oracle".into(),
                scheme: "oracle".into(),
                producer: format!("fragsim {}", env!("CARGO_PKG_VERSION")),
                k: None,
                capacity: None,
            },
            Self::Dump(dump, path) => SideReport {
                source: path.display().to_string(),
                scheme: dump.header.scheme.clone(),
                producer: dump.header.producer.clone(),
                k: dump.header.k,
                capacity: dump.header.capacity,
            },
        }
    }
}

/// A side as the report names it.
#[derive(Debug, Serialize)]
struct SideReport {
    source: String,
    scheme: String,
    producer: String,
    k: Option<u32>,
    capacity: Option<u32>,
}

/// A fragment as the report shows it.
#[derive(Debug, Serialize)]
struct Entry {
    key: String,
    depth: f32,
    #[serde(skip_serializing_if = "Option::is_none")]
    prim: Option<u32>,
}

/// A stored word the layout says cannot be there, as the report shows it.
#[derive(Debug, Serialize)]
struct Corrupt {
    slot: usize,
    word: String,
    why: &'static str,
}

/// One differing pixel (or sample of a per-sample layout), both lists.
#[derive(Debug, Serialize)]
struct Example {
    pixel: usize,
    x: u32,
    y: u32,
    /// The sample index within the pixel, for a per-sample layout.
    #[serde(skip_serializing_if = "Option::is_none")]
    sample: Option<u32>,
    verdict: Vec<&'static str>,
    reference: Vec<Entry>,
    candidate: Vec<Entry>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    corrupt_words: Vec<Corrupt>,
}

/// Fragment totals.
#[derive(Debug, Serialize)]
struct Fragments {
    reference: u64,
    captured: u64,
    lost: u64,
    extra: u64,
    /// What the reference predicts: `Σ max(0, n − capacity)` where it knows `n`.
    overflowed: u64,
    /// What the candidate's counters claim: `Σ (counter − stored)`.
    overflow_claimed: u64,
}

/// Word totals of the candidate's storage.
#[derive(Debug, Serialize)]
struct WordsReport {
    /// Whether the words were read at all (not when the candidate is the oracle).
    checked: bool,
    /// Words the layout says cannot be there.
    corrupt: u64,
    /// Words the layout leaves undefined (unfilled A-buffer slots past the counter).
    unchecked: u64,
    /// Linked lists: nodes the pool counter handed out that no list reaches (each a lost
    /// fragment, missing at its pixel, or a node no fragment took): never equal.
    unreachable: u64,
}

/// A per-sample layout's differences counted both ways: by sample (what each list covers) and by
/// pixel (a pixel differs when any of its samples does).
#[derive(Debug, Serialize)]
struct SampleCounts {
    /// Samples a pixel.
    samples: u32,
    /// Samples compared.
    compared: u64,
    /// Samples with a verdict that is an error.
    differing_samples: u64,
    /// Pixels with at least one such sample.
    differing_pixels: u64,
}

/// The whole report (`--json`).
#[derive(Debug, Serialize)]
struct Report {
    equal: bool,
    reference: SideReport,
    candidate: SideReport,
    scene: SceneAndCamera,
    width: u32,
    height: u32,
    compared: String,
    depth_ulps: u32,
    vertex_precision: String,
    /// How the candidate dump stores depth (`f32`, `unorm24`, `unorm16`): a unorm depth is
    /// judged by the steps its conversion may land on.
    stored_depth: &'static str,
    /// The bounds derived for an f32 vertex stage or a unorm depth (absent when every bit is
    /// owed).
    #[serde(skip_serializing_if = "Option::is_none")]
    precision: Option<Bounds>,
    /// The ambiguous pixels by cause (absent when every bit is owed; a pixel may have several).
    #[serde(skip_serializing_if = "Option::is_none")]
    ambiguous_by_cause: Option<AmbiguityCounts>,
    /// What the capture told of the vertices' snaps (absent when every bit is owed).
    #[serde(skip_serializing_if = "Option::is_none")]
    snaps: Option<SnapCounts>,
    /// Lists compared: pixels, or the samples of a per-sample layout.
    pixels: u64,
    /// Lists with a verdict that is an error (missing, extra, misordered, miscounted, corrupt).
    mismatched_pixels: u64,
    /// A per-sample layout (`scene.conventions.samples` above 1): differing samples and pixels.
    #[serde(skip_serializing_if = "Option::is_none")]
    per_sample: Option<SampleCounts>,
    /// A masked-node dump: stored nodes whose coverage mask differs from the reference's (each
    /// also a missing and an extra node of its pixel).
    #[serde(skip_serializing_if = "Option::is_none")]
    wrong_masks: Option<u64>,
    verdicts: VerdictCounts,
    fragments: Fragments,
    words: WordsReport,
    first_differences: Vec<Example>,
    image: Option<String>,
    notes: Vec<String>,
}

/// Runs `compare`; returns whether the sides are equal.
///
/// # Errors
/// Unreadable or inconsistent dumps, a scene that cannot be rebuilt, an image that cannot be
/// written.
pub fn compare(args: &CompareArgs) -> Result<bool, String> {
    let reference = Side::open(&args.reference)?;
    let candidate = Side::open(&args.candidate)?;
    let (mut header, beside) = match (&reference, &candidate) {
        (Side::Dump(dump, path), _) | (Side::Oracle, Side::Dump(dump, path)) => {
            (dump.header.clone(), dump_dir(path))
        }
        (Side::Oracle, Side::Oracle) => {
            return Err("compare needs at least one dump: both sides are `oracle`".into())
        }
    };
    if let Some(mesh) = &args.mesh {
        (header.scene.mesh, header.scene.name) = (Some(mesh.display().to_string()), None);
    }
    let mut notes = Vec::new();
    if let (Some(a), Some(b)) = (reference.header(), candidate.header()) {
        if (a.width, a.height) != (b.width, b.height) {
            return Err(format!(
                "the dumps cover different viewports: {}x{} and {}x{}",
                a.width, a.height, b.width, b.height
            ));
        }
        if a.scene != b.scene {
            let which = format!(
                "the dumps name different scenes: {} and {}",
                a.scene.describe(),
                b.scene.describe()
            );
            if !args.allow_different_scenes {
                return Err(format!(
                    "{which} (--allow-different-scenes compares them anyway)"
                ));
            }
            notes.push(which);
        }
    }
    // The oracle is built only when a side asks for it (the scene may be a large mesh).
    let needs_oracle = matches!(reference, Side::Oracle) || matches!(candidate, Side::Oracle);
    // Without the flag the oracle is rebuilt under the conventions the dump declares, its vertex
    // stage included, and owes every bit (fragsim's own dumps under any conventions). With
    // `--vertex-precision f32` the oracle takes the exact f64 vertex stage under the declared
    // conventions, and the candidate is judged within the bounds derived for an f32 one: they
    // measure an implementation's distance from the exact positions, not from another f32 order.
    let judged_f32 = args.vertex_precision.as_deref() == Some("f32");
    let samples = header.samples().map_err(|e| e.to_string())?;
    // A masked-node dump is judged against the per-pixel view of the per-sample oracle, which
    // only the oracle side can give.
    let is_masked = |side: &Side| matches!(side, Side::Dump(dump, _) if dump.is_masked());
    let masked = is_masked(&candidate);
    if judged_f32 && masked {
        return Err(format!(
            "--vertex-precision f32 does not judge a masked-node dump ({MASKED_SCHEME}) in \
             compare yet (the oracle's Dump::compare_masked_within does, per sample): judge it \
             exactly"
        ));
    }
    if is_masked(&reference) || (masked && !matches!(reference, Side::Oracle)) {
        return Err(format!(
            "a masked-node dump ({MASKED_SCHEME}) is compared as the candidate against the \
             oracle: `fragsim compare oracle DUMP`"
        ));
    }
    let mut per_pixel = None;
    let conventions = Conventions {
        vertex_precision: if judged_f32 {
            VertexPrecision::F32
        } else {
            VertexPrecision::F64
        },
        ..header.scene.conventions
    };
    let (oracle, precision) = if !needs_oracle {
        (None, None)
    } else if judged_f32 {
        let viewport = fragsim_raster::Viewport::new(header.width, header.height)?;
        let (oracle, precision) =
            f32_reference(&header.scene, viewport, Some(&beside)).map_err(|e| e.to_string())?;
        (Some(oracle), Some(precision))
    } else {
        let scene = header
            .scene
            .load(Some(&beside))
            .map_err(|e| e.to_string())?;
        let viewport = fragsim_raster::Viewport::new(header.width, header.height)?;
        let view = header
            .scene
            .view(&scene, viewport)
            .map_err(|e| e.to_string())?;
        let oracle = if masked {
            let nodes = SampleOracle::build(&view)?.per_pixel();
            let oracle = Oracle::from_capture(&node_capture(&nodes, Capacity::Unbounded));
            per_pixel = Some(nodes);
            oracle
        } else {
            Oracle::build(&view)
        };
        (Some(oracle), Some(Precision::derive(&view, &conventions)))
    };
    // A unorm payload cannot owe the f32 bits: the oracle's fragments are judged as the dump
    // stores depth, each interval the steps the conversion may land on.
    let stored = match &candidate {
        Side::Dump(dump, _) if matches!(reference, Side::Oracle) && !masked => dump.depth_format(),
        _ => DepthFormat::F32,
    };
    let precision = match (precision, &oracle) {
        (Some(precision), Some(oracle)) => Some(precision.stored_as(stored, oracle)),
        (precision, _) => precision,
    };
    if stored != DepthFormat::F32 {
        notes.push(format!(
            "depth stored as {}: each reference depth z is owed as any step from \
             floor(z·s − 1/2) to ceil(z·s + 1/2), s = 2^{} − 1 (a rounding or truncating \
             conversion of the f32 product)",
            stored.name(),
            stored.bits()
        ));
    }
    if judged_f32 && !matches!(reference, Side::Oracle) {
        return Err(
            "--vertex-precision f32 needs the oracle as the reference: a dump holds no geometry \
             to derive bounds from"
                .into(),
        );
    }
    let from_dump;
    let mut complete = None;
    let mut reference_corrupt = 0;
    let mut reference_keeps = None;
    let (reference_oracle, reference_identity) = match (&reference, &oracle) {
        (Side::Dump(dump, _), _) => {
            let capture = dump.capture().map_err(|e| e.to_string())?;
            notes.extend(reference_caveats(&capture));
            reference_corrupt = dump
                .check_words()
                .map_err(|e| e.to_string())?
                .corrupt_words();
            if reference_corrupt > 0 {
                notes.push(format!(
                    "the reference dump holds {reference_corrupt} words its layout says cannot \
                     be there: the comparison cannot be trusted, and is not called equal"
                ));
            }
            complete = Some(complete_pixels(&capture));
            reference_keeps = Some(capture.keeps.clone());
            from_dump = Oracle::from_capture(&capture);
            (&from_dump, capture.identity)
        }
        (Side::Oracle, Some(oracle)) => (oracle, Identity::KeyAndPrim),
        (Side::Oracle, None) => unreachable!("the oracle is built when a side names it"),
    };
    let (mut candidate_capture, words) = match (&candidate, &oracle) {
        (Side::Dump(dump, _), _) => (
            dump.capture().map_err(|e| e.to_string())?,
            Some(dump.check_words().map_err(|e| e.to_string())?),
        ),
        (Side::Oracle, Some(oracle)) => (oracle_capture(oracle), None),
        (Side::Oracle, None) => unreachable!("the oracle is built when a side names it"),
    };
    if let Some(unchecked) = words.as_ref().map(|w| w.unchecked).filter(|&u| u > 0) {
        notes.push(format!(
            "{unchecked} A-buffer slots past their pixel's counter were not checked: the header \
             does not say every slot was filled with the empty marker (\"filled\": true)"
        ));
    }
    if reference_identity == Identity::KeyOnly && candidate_capture.identity != Identity::KeyOnly {
        notes.push("the reference holds depth keys only: primitive ids are not compared".into());
        candidate_capture = with_identity(&candidate_capture, Identity::KeyOnly);
    }
    if candidate_capture.pixels() != reference_oracle.pixels() {
        return Err(format!(
            "the candidate covers {} pixels, the reference {}",
            candidate_capture.pixels(),
            reference_oracle.pixels()
        ));
    }
    if let (Some(keeps), Some(complete)) = (&reference_keeps, &complete) {
        let (unjudged, pixels) =
            drop_unknowable(&mut candidate_capture, reference_oracle, keeps, complete);
        if unjudged > 0 {
            notes.push(format!(
                "{unjudged} candidate fragments in {pixels} pixels lie beyond what the reference \
                 kept there (its K-th fragment) and cannot be judged: not counted as extra"
            ));
        }
    }
    let options = CompareOptions {
        depth_ulps: args.depth_ulps,
        examples: args.show,
        complete: complete.as_deref(),
    };
    let mut wrong_masks = None;
    let comparison = match (&precision, &candidate, &per_pixel) {
        (_, Side::Dump(dump, _), Some(per_pixel)) => {
            let masked = dump
                .compare_masked(per_pixel, &options)
                .map_err(|e| e.to_string())?;
            wrong_masks = Some(masked.wrong_masks.len() as u64);
            masked.nodes
        }
        (Some(precision), _, _) => compare_within(
            precision,
            reference_oracle,
            &candidate_capture,
            words.as_ref(),
            &options,
        ),
        (None, _, _) => compare_with(
            reference_oracle,
            &candidate_capture,
            words.as_ref(),
            &options,
        ),
    };
    // A per-sample layout's lists are samples: `n` consecutive ones make a pixel.
    let per_sample = (samples > 1 && !masked).then(|| {
        let n = samples as usize;
        let differs = |v: &u8| v & verdict::DIFFERS != 0;
        SampleCounts {
            samples,
            compared: comparison.verdicts.len() as u64,
            differing_samples: comparison.verdicts.iter().filter(|v| differs(v)).count() as u64,
            differing_pixels: comparison
                .verdicts
                .chunks(n)
                .filter(|pixel| pixel.iter().any(differs))
                .count() as u64,
        }
    });
    let lists_per_pixel = if per_sample.is_some() { samples } else { 1 };
    let bounds = precision
        .as_ref()
        .filter(|p| !p.is_exact())
        .map(Precision::bounds);
    // Storage that stops at `kept` without a count reports no overflow by design (the oracle
    // supplies it), and which fragments it keeps is the arrival order's choice.
    let uncounted = match candidate_capture.keeps {
        Keeps::All {
            capacity: Capacity::PerPixelUncounted(kept),
            ..
        } => Some(kept),
        _ => None,
    };
    if let Some(kept) = uncounted {
        let pixels = comparison
            .verdicts
            .iter()
            .filter(|&&v| v & verdict::OVERFLOWED != 0)
            .count();
        if pixels > 0 {
            notes.push(format!(
                "{} fragments in {pixels} pixels past the {kept} the candidate keeps are absent: \
                 which ones it keeps follows the arrival order, which the reference cannot know, \
                 so they are counted as overflowed, not missing",
                comparison.diff.overflowed
            ));
        }
    }
    if uncounted.is_none() && comparison.claimed_overflow != comparison.diff.overflowed {
        notes.push(format!(
            "the counters claim {} fragments overflowed, the reference predicts {}",
            comparison.claimed_overflow, comparison.diff.overflowed
        ));
    }
    let image = if args.no_image {
        None
    } else {
        write_image(
            &comparison,
            header.width * lists_per_pixel,
            header.height,
            reference_oracle,
            &args.image,
        )?;
        Some(args.image.display().to_string())
    };
    let report = Report {
        equal: comparison.is_equal() && reference_corrupt == 0,
        reference: reference.describe(),
        candidate: candidate.describe(),
        scene: header.scene.clone(),
        width: header.width,
        height: header.height,
        compared: what_is_compared(&candidate_capture, args.depth_ulps, judged_f32, stored),
        depth_ulps: args.depth_ulps,
        vertex_precision: match conventions.vertex_precision {
            VertexPrecision::F64 => "f64".into(),
            VertexPrecision::F32 => "f32".into(),
        },
        stored_depth: stored.name(),
        precision: bounds,
        ambiguous_by_cause: bounds.map(|_| comparison.ambiguity),
        snaps: bounds.map(|_| comparison.snaps),
        pixels: comparison.verdicts.len() as u64,
        mismatched_pixels: comparison
            .verdicts
            .iter()
            .filter(|&&v| v & verdict::DIFFERS != 0)
            .count() as u64,
        per_sample,
        wrong_masks,
        verdicts: comparison.counts,
        fragments: Fragments {
            reference: reference_oracle.fragments() as u64,
            captured: comparison.diff.captured,
            lost: comparison.diff.lost,
            extra: comparison.diff.extra,
            overflowed: comparison.diff.overflowed,
            overflow_claimed: comparison.claimed_overflow,
        },
        words: WordsReport {
            checked: comparison.words_checked,
            corrupt: comparison.corrupt_words,
            unchecked: comparison.unchecked_words,
            unreachable: words.as_ref().map_or(0, |w| w.unreachable),
        },
        first_differences: examples(
            &comparison,
            header.width,
            lists_per_pixel,
            candidate_capture.identity,
        ),
        image,
        notes,
    };
    if args.json {
        print_json(&report)?;
    } else {
        print_report(&report);
    }
    Ok(report.equal)
}

fn dump_dir(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.to_path_buf()
    } else {
        path.parent().unwrap_or(Path::new(".")).to_path_buf()
    }
}

/// The oracle's lists as a capture that promises every fragment.
fn oracle_capture(oracle: &Oracle) -> Capture {
    Capture {
        lists: oracle.lists().clone(),
        identity: Identity::KeyAndPrim,
        keeps: Keeps::All {
            capacity: Capacity::Unbounded,
            overflow: vec![0; oracle.pixels()],
        },
    }
}

/// Takes out of `candidate` the fragments an MDTS reference cannot know: in a pixel where the
/// reference is full (`complete` false), those beyond its K-th (farther for K nearest, nearer for K
/// farthest), which it would have dropped itself. Returns how many, and in how many pixels.
fn drop_unknowable(
    candidate: &mut Capture,
    reference: &Oracle,
    keeps: &Keeps,
    complete: &[bool],
) -> (u64, u64) {
    let nearest = match keeps {
        Keeps::Nearest(_) => true,
        Keeps::Farthest(_) => false,
        Keeps::All { .. } => return (0, 0),
    };
    let mask = match candidate.identity {
        Identity::KeyAndPrim => u64::MAX,
        Identity::KeyOnly => u64::MAX << 32,
        Identity::PrimOnly => return (0, 0),
    };
    let mut lists = PixelLists::with_pixels(candidate.pixels());
    let (mut dropped, mut pixels) = (0, 0);
    for (p, &known) in complete.iter().enumerate() {
        let bound = if nearest {
            reference.pixel(p).last()
        } else {
            reference.pixel(p).first()
        };
        let got = candidate.pixel(p);
        let kept: Vec<u64> = match bound.filter(|_| !known) {
            Some(&bound) => got
                .iter()
                .copied()
                .filter(|&e| {
                    let beyond = if nearest {
                        e & mask > bound & mask
                    } else {
                        e & mask < bound & mask
                    };
                    e == u64::MAX || !beyond
                })
                .collect(),
            None => got.to_vec(),
        };
        let gone = (got.len() - kept.len()) as u64;
        dropped += gone;
        pixels += u64::from(gone > 0);
        lists.push_pixel(kept);
    }
    candidate.lists = lists;
    (dropped, pixels)
}

/// Why a dump used as the reference may not be the whole truth.
fn reference_caveats(capture: &Capture) -> Vec<String> {
    match &capture.keeps {
        Keeps::Nearest(k) | Keeps::Farthest(k) => {
            let full = (0..capture.pixels())
                .filter(|&p| capture.pixel(p).len() >= *k as usize)
                .count();
            if full > 0 {
                vec![format!(
                    "the reference is an MDTS dump keeping {k} fragments per pixel and {full} \
                     pixels are full: fragments beyond K there are unknown to it"
                )]
            } else {
                Vec::new()
            }
        }
        Keeps::All { overflow, .. } => {
            let lost: u64 = overflow.iter().map(|&o| u64::from(o)).sum();
            if lost > 0 {
                vec![format!(
                    "the reference A-buffer overflowed: {lost} fragments are unknown to it"
                )]
            } else {
                Vec::new()
            }
        }
    }
}

fn what_is_compared(
    candidate: &Capture,
    ulps: u32,
    f32_vertex_stage: bool,
    stored: DepthFormat,
) -> String {
    let words = match candidate.identity {
        Identity::KeyAndPrim => "depth key (f32 bits) and primitive id of every fragment",
        Identity::KeyOnly => "depth keys (f32 bits) of every fragment",
        Identity::PrimOnly => "primitive ids in depth order",
    };
    let promise = match &candidate.keeps {
        Keeps::Nearest(k) => format!("the {k} nearest per pixel"),
        Keeps::Farthest(k) => format!("the {k} farthest per pixel"),
        Keeps::All { .. } => "all per pixel, less the overflow the reference predicts".into(),
    };
    let tolerance = match (precision_of(f32_vertex_stage, stored), ulps) {
        (None, 0) => "bit for bit".to_string(),
        (None, _) => format!("depth keys within {ulps} ulps"),
        (Some(what), 0) => format!("within the precision of {what}"),
        (Some(what), _) => format!("within the precision of {what} widened by {ulps} ulps"),
    };
    format!("{words}, {promise}, in stored order, {tolerance}")
}

/// What the bounds are derived for: an f32 vertex stage, a unorm depth, or both (`None`: every
/// bit is owed).
fn precision_of(f32_vertex_stage: bool, stored: DepthFormat) -> Option<String> {
    let unorm = (stored != DepthFormat::F32).then(|| format!("a {} depth", stored.name()));
    match (f32_vertex_stage, unorm) {
        (false, None) => None,
        (false, Some(unorm)) => Some(unorm),
        (true, None) => Some("an f32 vertex stage".into()),
        (true, Some(unorm)) => Some(format!("an f32 vertex stage and {unorm}")),
    }
}

fn entry(word: u64, identity: Identity) -> Entry {
    let key = (word >> 32) as u32;
    Entry {
        key: format!("{key:08x}"),
        depth: depth_from_key(key),
        prim: (identity != Identity::KeyOnly).then_some(word as u32),
    }
}

/// The examples of `comparison`, whose lists are `samples` a pixel of a `width`-pixel row.
fn examples(comparison: &Comparison, width: u32, samples: u32, identity: Identity) -> Vec<Example> {
    let n = samples as usize;
    comparison
        .diff
        .first_mismatches
        .iter()
        .map(|m| Example {
            pixel: m.pixel / n,
            x: (m.pixel / n % width as usize) as u32,
            y: (m.pixel / n / width as usize) as u32,
            sample: (n > 1).then_some((m.pixel % n) as u32),
            verdict: verdict::names(comparison.verdicts[m.pixel]),
            reference: m.expected.iter().map(|&w| entry(w, identity)).collect(),
            candidate: m.got.iter().map(|&w| entry(w, identity)).collect(),
            corrupt_words: corrupt_of(&comparison.first_corrupt, m.pixel),
        })
        .collect()
}

fn corrupt_of(words: &[CorruptWord], pixel: usize) -> Vec<Corrupt> {
    words
        .iter()
        .filter(|w| w.pixel == pixel)
        .map(|w| Corrupt {
            slot: w.slot,
            word: format!("{:#x}", w.word),
            why: w.why.describe(),
        })
        .collect()
}

/// Colour of a pixel's verdict in the difference image.
fn colour(flags: u8, fragments: usize) -> [u8; 3] {
    let wrong = flags & (verdict::MISSING | verdict::EXTRA);
    match () {
        () if flags & verdict::CORRUPT != 0 => [40, 220, 40],
        () if wrong == verdict::MISSING | verdict::EXTRA => [220, 50, 220],
        () if wrong == verdict::MISSING => [230, 40, 40],
        () if wrong == verdict::EXTRA => [60, 90, 255],
        () if flags & verdict::MISORDERED != 0 => [250, 220, 0],
        () if flags & verdict::MISCOUNTED != 0 => [255, 140, 0],
        () if flags & verdict::OVERFLOWED != 0 => [0, 90, 90],
        () if fragments > 0 => [70, 70, 70],
        () => [0, 0, 0],
    }
}

/// The legend of the difference image: every colour [`colour`] gives, what it means, and how
/// many pixels have it.
fn legend(comparison: &Comparison, reference: &Oracle) -> Vec<(image::Rgb<u8>, String)> {
    let meanings: [(u8, usize, &str); 9] = [
        (verdict::CORRUPT, 0, "corrupt word"),
        (verdict::MISSING | verdict::EXTRA, 0, "missing and extra"),
        (verdict::MISSING, 0, "missing"),
        (verdict::EXTRA, 0, "extra"),
        (verdict::MISORDERED, 0, "misordered"),
        (verdict::MISCOUNTED, 0, "overflow miscounted"),
        (verdict::OVERFLOWED, 0, "overflowed (by design)"),
        (0, 1, "equal, covered"),
        (0, 0, "no fragment"),
    ];
    let mut counts = [0u64; 9];
    for (p, &flags) in comparison.verdicts.iter().enumerate() {
        let c = colour(flags, reference.pixel(p).len());
        if let Some(i) = meanings.iter().position(|&(f, n, _)| colour(f, n) == c) {
            counts[i] += 1;
        }
    }
    meanings
        .iter()
        .zip(counts)
        .map(|(&(f, n, meaning), count)| (image::Rgb(colour(f, n)), format!("{meaning}: {count}")))
        .collect()
}

fn write_image(
    comparison: &Comparison,
    width: u32,
    height: u32,
    reference: &Oracle,
    path: &Path,
) -> Result<(), String> {
    let image = image::RgbImage::from_fn(width, height, |x, y| {
        let p = (y * width + x) as usize;
        image::Rgb(colour(comparison.verdicts[p], reference.pixel(p).len()))
    });
    let differing = comparison
        .verdicts
        .iter()
        .enumerate()
        .filter(|&(_, &v)| v & verdict::DIFFERS != 0)
        .map(|(p, _)| ((p % width as usize) as u32, (p / width as usize) as u32));
    // Rings only where differences are sparse: dense ones show alone, and rings would hide some.
    let ring = differing.clone().count() <= fragsim_shade::legend::MARKS;
    let marks: Vec<(u32, u32)> = differing.take(fragsim_shade::legend::MARKS).collect();
    let figure = fragsim_shade::legend::difference_figure(
        &image,
        &legend(comparison, reference),
        &marks,
        ring,
    )?;
    fragsim_shade::save_png(&figure, path)
}

/// The report as JSON Lines: the report's fields flattened into one `compare` record (a group's
/// fields named as everywhere else: `missing_pixels`, `lost`, `reported_overflow`,
/// `corrupt_words`, `candidate_k`, `precision_…`), then one `difference` record per example.
fn print_json(r: &Report) -> Result<(), String> {
    let mut context = Context::new("compare", &r.scene, r.width, r.height);
    context.k = r.candidate.k.map(Slots::Fixed);
    context.capacity = r.candidate.capacity.map(Slots::Fixed);
    let serde_json::Value::Object(whole) = serde_json::to_value(r).map_err(|e| e.to_string())?
    else {
        return Err("the compare report is not a JSON object".into());
    };
    let mut flat = serde_json::Map::new();
    for (key, value) in whole {
        match (key.as_str(), value) {
            // The context carries the scene and viewport; the examples are records of their own.
            ("scene" | "width" | "height" | "first_differences", _) => {}
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
    crate::record::emit("compare", &context, &flat)?;
    for example in &r.first_differences {
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

fn print_report(r: &Report) {
    let side = |s: &SideReport| {
        let size = match (s.k, s.capacity) {
            (Some(k), _) => format!(" K={k}"),
            (None, Some(c)) => format!(" capacity={c}"),
            _ => String::new(),
        };
        if s.source == "oracle" {
            "fragsim oracle".to_string()
        } else {
            format!("{} ({}{size}, by {})", s.source, s.scheme, s.producer)
        }
    };
    outln!(
        "reference {}\ncandidate {}\nscene {} at {}x{}",
        side(&r.reference),
        side(&r.candidate),
        r.scene.describe(),
        r.width,
        r.height
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
             {} of clipped triangles), {} clipped triangles not analysed, {} judged by the edge \
             bound",
            match (r.vertex_precision.as_str(), r.stored_depth) {
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
            "words: every one read; corrupt {}, not defined by the layout {}, nodes no list \
             reaches {}",
            r.words.corrupt,
            r.words.unchecked,
            r.words.unreachable
        );
    }
    for note in &r.notes {
        outln!("note: {note}");
    }
    for e in &r.first_differences {
        let sample = e.sample.map_or(String::new(), |s| format!(", sample {s}"));
        outln!(
            "pixel {} (x {}, y {}{sample}): {}",
            e.pixel,
            e.x,
            e.y,
            e.verdict.join(", ")
        );
        outln!("  {:<36} {:<36}", "reference", "candidate");
        let show = |e: Option<&Entry>| {
            e.map_or(String::new(), |e| match e.prim {
                Some(prim) => format!("{:.9} [{}] prim {prim}", e.depth, e.key),
                None => format!("{:.9} [{}]", e.depth, e.key),
            })
        };
        for i in 0..e.reference.len().max(e.candidate.len()) {
            let (a, b) = (e.reference.get(i), e.candidate.get(i));
            let same = matches!((a, b), (Some(a), Some(b)) if a.key == b.key && a.prim == b.prim);
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
    if let Some(image) = &r.image {
        outln!("difference image: {image}");
    }
    outln!(
        "verdict: {}",
        if r.equal {
            // Bit-identical only if every word was read and defined: an unfilled A-buffer's
            // spare slots, or the oracle as the candidate, leave words unseen.
            if r.compared.ends_with("bit for bit") && r.words.checked && r.words.unchecked == 0 {
                "EQUAL (bit-identical)"
            } else if r.compared.ends_with("bit for bit") {
                "EQUAL (lists bit-identical)"
            } else {
                "EQUAL (within tolerance)"
            }
        } else {
            "DIFFERENT"
        }
    );
}
