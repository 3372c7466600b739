//! The parts of a verdict that describe it: what was compared, in words; the first differing
//! lists with both sides; a per-sample layout's counts by sample and by pixel; the totals a
//! report shows ([`Summary`]). Each serialises as `fragsim compare --json` writes it
//! (`docs/json-schema.md`).

use fragsim_capture::{Capture, Identity, Keeps};
use fragsim_raster::{depth_from_key, EdgeTies, VertexPrecision};
use serde::Serialize;

use super::{SideReport, Verdict};
use crate::compare::{flags, AmbiguityCounts, Comparison, SnapCounts, VerdictCounts};
use crate::precision::Bounds;
use fragsim_dump::{CorruptWord, DepthFormat};

/// A fragment as a report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct Entry {
    /// The depth key, 8 hex digits.
    pub key: String,
    /// The depth the key stands for.
    pub depth: f32,
    /// The primitive id (absent for key-only words).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prim: Option<u32>,
}

impl Entry {
    /// The fragment word `word` (`depth key << 32 | primitive id`) of a capture of `identity`.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an entry's low half is its primitive id"
    )]
    pub fn of(word: u64, identity: Identity) -> Self {
        let key = (word >> 32) as u32;
        Self {
            key: format!("{key:08x}"),
            depth: depth_from_key(key),
            prim: (identity != Identity::KeyOnly).then_some(word as u32),
        }
    }
}

/// A stored word the layout says cannot be there, as a report shows it.
#[derive(Clone, Debug, Serialize)]
pub struct Corrupt {
    /// The slot of the pixel's storage.
    pub slot: usize,
    /// The word, in hex.
    pub word: String,
    /// Why it cannot be there.
    pub why: &'static str,
}

/// One differing pixel (or sample of a per-sample layout), both lists.
#[derive(Clone, Debug, Serialize)]
pub struct Example {
    /// The pixel's index, row-major.
    pub pixel: usize,
    /// Its column.
    pub x: u32,
    /// Its row.
    pub y: u32,
    /// The sample index within the pixel, for a per-sample layout.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample: Option<u32>,
    /// The names of its verdict's flags ([`flags::names`]).
    pub verdict: Vec<&'static str>,
    /// The reference's list.
    pub reference: Vec<Entry>,
    /// The candidate's list.
    pub candidate: Vec<Entry>,
    /// The pixel's corrupt words.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub corrupt_words: Vec<Corrupt>,
}

/// A per-sample layout's differences counted both ways: by sample (what each list covers) and by
/// pixel (a pixel differs when any of its samples does).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SampleCounts {
    /// Samples a pixel.
    pub samples: u32,
    /// Samples compared.
    pub compared: u64,
    /// Samples with a verdict that is an error.
    pub differing_samples: u64,
    /// Pixels with at least one such sample.
    pub differing_pixels: u64,
}

impl SampleCounts {
    /// The counts of `comparison`, whose lists are `samples` a pixel (`None` for one a pixel).
    pub(super) fn of(comparison: &Comparison, samples: u32) -> Option<Self> {
        let differs = |v: &u8| v & flags::DIFFERS != 0;
        (samples > 1).then(|| Self {
            samples,
            compared: comparison.verdicts.len() as u64,
            differing_samples: comparison.verdicts.iter().filter(|v| differs(v)).count() as u64,
            differing_pixels: comparison
                .verdicts
                .chunks(samples as usize)
                .filter(|pixel| pixel.iter().any(differs))
                .count() as u64,
        })
    }
}

/// The examples of `comparison`, whose lists are `samples` a pixel of a `width`-pixel row.
#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel coordinates and sample indices fit u32: viewports are at most 16384² pixels (Viewport::new) of at most 16 samples"
)]
pub(super) fn examples(
    comparison: &Comparison,
    width: u32,
    samples: u32,
    identity: Identity,
) -> Vec<Example> {
    let n = samples as usize;
    let row = (width as usize).max(1);
    comparison
        .diff
        .first_mismatches
        .iter()
        .map(|m| Example {
            pixel: m.pixel / n,
            x: (m.pixel / n % row) as u32,
            y: (m.pixel / n / row) as u32,
            sample: (n > 1).then_some((m.pixel % n) as u32),
            verdict: flags::names(comparison.verdicts[m.pixel]),
            reference: m.expected.iter().map(|&w| Entry::of(w, identity)).collect(),
            candidate: m.got.iter().map(|&w| Entry::of(w, identity)).collect(),
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

/// What is compared, in words: the candidate's identity and promise, and the tolerance.
pub(super) fn what_is_compared(
    candidate: &Capture,
    ulps: u32,
    f32_vertex_stage: bool,
    stored: DepthFormat,
) -> String {
    let words = match candidate.identity {
        Identity::KeyAndPrim => "depth key (f32 bits) and primitive id of every fragment",
        Identity::MaskedNodes(_) => {
            "nearest depth key (f32 bits), primitive id and samples covered of every masked node"
        }
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

/// A verdict's totals as `fragsim compare` reports them: `--json` flattens each group into the
/// record's fields (`docs/json-schema.md`), the text report prints them line by line.
#[derive(Debug, Serialize)]
pub struct Summary<'a> {
    /// Whether the sides are equal ([`Verdict::equal`]).
    pub equal: bool,
    /// The reference side.
    pub reference: SideReport,
    /// The candidate side.
    pub candidate: SideReport,
    /// What was compared, in words.
    pub compared: &'a str,
    /// The ulps allowed beyond the reference.
    pub depth_ulps: u32,
    /// `f64` or `f32`: the vertex stage the candidate was judged as.
    pub vertex_precision: &'static str,
    /// How the candidate dump stores depth (`f32`, `unorm24`, `unorm16`): a unorm depth is
    /// judged by the steps its conversion may land on.
    pub stored_depth: &'static str,
    /// The bounds derived for an f32 vertex stage or a unorm depth (absent when every bit is
    /// owed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precision: Option<Bounds>,
    /// The ambiguous lists by cause (absent when every bit is owed; a list may have several).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ambiguous_by_cause: Option<AmbiguityCounts>,
    /// What the capture told of the vertices' snaps (absent when every bit is owed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub snaps: Option<SnapCounts>,
    /// Lists compared: pixels, or the samples of a per-sample layout.
    pub pixels: u64,
    /// Lists with a verdict that is an error (missing, extra, misordered, miscounted, corrupt).
    pub mismatched_pixels: u64,
    /// A per-sample layout: differing samples and pixels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_sample: Option<SampleCounts>,
    /// A masked-node dump: stored nodes whose coverage mask differs from the reference's (each
    /// also a missing and an extra node of its pixel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wrong_masks: Option<u64>,
    /// Lists per verdict.
    pub verdicts: VerdictCounts,
    /// Fragment totals.
    pub fragments: FragmentTotals,
    /// Word totals of the candidate's storage.
    pub words: WordTotals,
    /// The first differing lists, both sides.
    pub first_differences: &'a [Example],
    /// The edge-tie rule samples exactly on an edge were judged under, in fragsim's y-down rows
    /// (`top-left`, …; absent where the reference decides them: a dump, a masked-node reference).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_ties: Option<&'static str>,
    /// Notes that qualify the verdict.
    pub notes: &'a [String],
    /// What to check next, where the differences have a shape that names a cause
    /// ([`Verdict::hints`]).
    pub hints: &'a [String],
}

/// Fragment totals of a verdict.
#[derive(Debug, Serialize)]
pub struct FragmentTotals {
    /// Fragments the reference holds.
    pub reference: u64,
    /// Fragments the candidate holds.
    pub captured: u64,
    /// Fragments the candidate owes and lacks.
    pub lost: u64,
    /// Fragments the candidate holds and the reference does not allow.
    pub extra: u64,
    /// What the reference predicts: `Σ max(0, n − capacity)` where it knows `n`.
    pub overflowed: u64,
    /// What the candidate's counters claim: `Σ (counter − stored)`.
    pub overflow_claimed: u64,
}

/// Word totals of a candidate's storage.
#[derive(Debug, Serialize)]
pub struct WordTotals {
    /// Whether the words were read at all (not when the candidate is the oracle or a capture).
    pub checked: bool,
    /// Words the layout says cannot be there.
    pub corrupt: u64,
    /// Words a header could have defined but did not, so not checked (an unfilled A-buffer's
    /// slots past the counter, a memory dump's words): they keep the verdict from
    /// `EQUAL (bit-identical)`.
    pub unchecked: u64,
    /// Words of room no counter handed out, which no header field defines, so not read (a linked
    /// list's pool nodes past the node counter, layers past a pixel's counter): no list holds
    /// them, and they leave a dump bit-identical.
    pub spare: u64,
    /// Linked lists: nodes the pool counter handed out that no list reaches (each a lost
    /// fragment, missing at its pixel, or a node no fragment took): never equal.
    pub unreachable: u64,
}

impl Summary<'_> {
    /// The verdict in a word or three: `EQUAL (bit-identical)` where every list is equal bit for
    /// bit and every word a header can define was read (a linked list's pool past its counter is
    /// room no header defines), `EQUAL (lists bit-identical)` where some words were unseen (an
    /// unfilled A-buffer's spare slots, a memory dump, the oracle as the candidate), `EQUAL
    /// (within tolerance)` under a tolerance or precision, else `DIFFERENT`.
    #[must_use]
    pub fn word(&self) -> &'static str {
        let bit_for_bit = self.compared.ends_with("bit for bit");
        match () {
            () if !self.equal => "DIFFERENT",
            () if bit_for_bit && self.words.checked && self.words.unchecked == 0 => {
                "EQUAL (bit-identical)"
            }
            () if bit_for_bit => "EQUAL (lists bit-identical)",
            () => "EQUAL (within tolerance)",
        }
    }
}

impl Verdict {
    /// The verdict's totals as a report shows them, its sides described as `reference` and
    /// `candidate`.
    #[must_use]
    pub fn summary(&self, reference: SideReport, candidate: SideReport) -> Summary<'_> {
        let c = &self.comparison;
        Summary {
            equal: self.equal,
            reference,
            candidate,
            compared: &self.compared,
            depth_ulps: self.depth_ulps,
            vertex_precision: match self.vertex_precision {
                VertexPrecision::F64 => "f64",
                VertexPrecision::F32 => "f32",
            },
            stored_depth: self.stored_depth.name(),
            precision: self.bounds,
            ambiguous_by_cause: self.bounds.map(|_| c.ambiguity),
            snaps: self.bounds.map(|_| c.snaps),
            pixels: c.verdicts.len() as u64,
            mismatched_pixels: self.mismatched_lists(),
            per_sample: self.per_sample,
            wrong_masks: self.wrong_masks,
            verdicts: c.counts,
            fragments: FragmentTotals {
                reference: self.reference_fragments.iter().map(|&n| u64::from(n)).sum(),
                captured: c.diff.captured,
                lost: c.diff.lost,
                extra: c.diff.extra,
                overflowed: c.diff.overflowed,
                overflow_claimed: c.claimed_overflow,
            },
            words: WordTotals {
                checked: c.words_checked,
                corrupt: c.corrupt_words,
                unchecked: c.unchecked_words,
                spare: c.spare_words,
                unreachable: c.unreachable_nodes,
            },
            first_differences: &self.examples,
            edge_ties: self.edge_ties.map(EdgeTies::name),
            notes: &self.notes,
            hints: &self.hints,
        }
    }
}
