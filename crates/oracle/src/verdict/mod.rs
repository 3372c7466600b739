//! The one verdict on a capture: what `fragsim compare` prints, what `fragsim conform`, the
//! testkit's battery and the wgpu backend's judge decide by, computed once, here.
//!
//! A [`Reference`] is what the candidate is judged against: fragsim's oracle of a view with the
//! [`Precision`] a declared vertex stage owes (every bit under f64, the derived bounds under
//! f32), the per-pixel view of the per-sample oracle for a masked-node dump, or another dump's
//! decoded lists. A [`Candidate`] is a dump (its lists decoded by the scheme's own post pass and
//! every word checked against its layout), a run's capture, or the oracle itself. [`judge`]
//! takes the two and returns one [`Verdict`]: the per-list verdicts and their totals (the
//! library's [`Comparison`]), whether the sides are equal, what was compared, the precision
//! bounds, per-sample and masked-node counts, the first differing lists with both sides
//! ([`Example`]) and every note that qualifies the verdict. [`judge_sides`] does the same for
//! two [`Side`]s as the command line names them (a dump directory or `oracle`): it checks the
//! headers against each other and rebuilds the oracle from the scene a dump names.
//!
//! Guarantee: every caller gets the same decision for the same inputs, the policy (which
//! comparison applies, what a reference dump cannot know, how a key-only reference reduces the
//! candidate, how a unorm depth is owed) being written in this module alone; the comparisons
//! themselves are [`compare_with`], [`compare_within`] and [`Dump::compare_masked`].

mod allowance;
mod reference;
mod report;
mod sides;
#[cfg(test)]
mod tests;

use std::borrow::Cow;

use fragsim_capture::{Capacity, Capture, Identity, Keeps};
use fragsim_raster::{EdgeTies, VertexPrecision};

use crate::compare::{verdict, with_identity, CompareOptions, Comparison};
use crate::dump::{DepthFormat, Dump};
use crate::edge_ties::TiePoints;
use crate::precision::{compare_within, Bounds, Precision};
use crate::Oracle;
use fragsim_raster::scene_spec::SceneSpec;

#[cfg(doc)]
use crate::compare::compare_with;

pub(crate) use allowance::hold_to_reference;
pub use allowance::MiscountedCounter;
pub use reference::Reference;
pub use report::{Corrupt, Entry, Example, FragmentTotals, SampleCounts, Summary, WordTotals};
pub use sides::{judge_sides, Side, SideReport, SidesOptions};

/// What a verdict is asked to judge: a candidate dump, a run's capture, or the oracle.
#[derive(Clone, Copy, Debug)]
pub enum Candidate<'a> {
    /// A dump: its lists decoded by its scheme's post pass, every word checked.
    Dump(&'a Dump),
    /// A run's capture (no words to check).
    Capture(&'a Capture),
    /// The oracle of the scene (against a reference dump): every fragment, nothing overflowed.
    Oracle(&'a Oracle),
}

/// How [`judge`] judges beyond what the reference says.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    /// Accept a candidate key within this many f32 ulps of the reference's (0: as the reference
    /// owes); under precision, every interval widened by this many ulps on each side.
    pub depth_ulps: u32,
    /// How many differing lists to keep as examples.
    pub examples: usize,
}

/// Everything a verdict says, as `fragsim compare` prints it.
#[derive(Clone, Debug)]
pub struct Verdict {
    /// Whether the candidate is equal to the reference: every list equal (or within precision,
    /// or ambiguous), every node of a linked list reached, and the reference dump free of
    /// corrupt words.
    pub equal: bool,
    /// The per-list verdicts and their totals.
    pub comparison: Comparison,
    /// The scene the sides name (with a `--mesh` override applied); `None` for a capture judged
    /// on a view.
    pub scene: Option<SceneSpec>,
    /// Viewport width, pixels.
    pub width: u32,
    /// Viewport height, pixels.
    pub height: u32,
    /// Lists per pixel: the sample count of a per-sample layout, else 1.
    pub lists_per_pixel: u32,
    /// What was compared, in words: the identity, the promise, the tolerance.
    pub compared: String,
    /// The ulps allowed beyond the reference ([`Options::depth_ulps`]).
    pub depth_ulps: u32,
    /// The vertex stage the candidate was judged as.
    pub vertex_precision: VertexPrecision,
    /// How the candidate stores depth (f32 unless a dump's payload says otherwise).
    pub stored_depth: DepthFormat,
    /// The bounds derived for an f32 vertex stage or a unorm depth (`None`: every bit owed).
    pub bounds: Option<Bounds>,
    /// A per-sample layout's differences by sample and by pixel.
    pub per_sample: Option<SampleCounts>,
    /// A masked-node dump: stored nodes whose coverage mask is not the reference's.
    pub wrong_masks: Option<u64>,
    /// Per list, how many fragments the reference holds.
    pub reference_fragments: Vec<u32>,
    /// The candidate's identity as judged (reduced to key-only against a key-only reference).
    pub identity: Identity,
    /// Notes that qualify the verdict, in the order they arose.
    pub notes: Vec<String>,
    /// The first differing lists, both sides.
    pub examples: Vec<Example>,
    /// The edge-tie rule (in fragsim's y-down rows) samples exactly on an edge were judged
    /// under: the declared one, or the one that explains the capture; `None` where the reference
    /// says how they fall (a dump, a masked-node reference, an oracle without its view).
    pub edge_ties: Option<EdgeTies>,
}

impl Verdict {
    /// Lists with a verdict that is an error.
    #[must_use]
    pub fn mismatched_lists(&self) -> u64 {
        errors(&self.comparison) as u64
    }
}

/// Judges `candidate` against `reference` (see the module documentation).
///
/// # Errors
/// A candidate dump of another viewport than the reference's or one that cannot be decoded, a
/// candidate of another number of lists than the reference, a masked-node dump against anything
/// but the per-sample oracle's per-pixel view.
pub fn judge(
    reference: &Reference<'_>,
    candidate: Candidate<'_>,
    options: &Options,
) -> Result<Verdict, String> {
    let oracle = reference.oracle();
    if let Candidate::Dump(dump) = candidate {
        let (w, h) = (dump.header.width, dump.header.height);
        if (w, h) != (reference.width, reference.height) {
            return Err(format!(
                "the dump covers {w}x{h} pixels, the reference {}x{}",
                reference.width, reference.height
            ));
        }
    }
    // A unorm payload cannot owe the f32 bits: the oracle's fragments are judged as the dump
    // stores depth, each interval the steps the conversion may land on.
    let stored = match (candidate, reference.precision()) {
        (Candidate::Dump(dump), Some(_)) if !reference.is_masked() => dump.depth_format(),
        _ => DepthFormat::F32,
    };
    let mut notes = reference.notes.clone();
    if stored != DepthFormat::F32 {
        notes.push(format!(
            "depth stored as {}: each reference depth z is owed as any step from \
             floor(z·s − 1/2) to ceil(z·s + 1/2), s = 2^{} − 1 (a rounding or truncating \
             conversion of the f32 product)",
            stored.name(),
            stored.bits()
        ));
    }
    notes.extend(reference.dump_notes());
    let (mut capture, words) = match candidate {
        Candidate::Dump(dump) => (
            dump.capture().map_err(|e| e.to_string())?,
            Some(dump.check_words().map_err(|e| e.to_string())?),
        ),
        Candidate::Capture(capture) => (capture.clone(), None),
        Candidate::Oracle(oracle) => (oracle_capture(oracle), None),
    };
    if let Some(unchecked) = words.as_ref().map(|w| w.unchecked).filter(|&u| u > 0) {
        notes.push(format!(
            "{unchecked} A-buffer slots past their pixel's counter were not checked: the header \
             does not say every slot was filled with the empty marker (\"filled\": true)"
        ));
    }
    if reference.identity() == Identity::KeyOnly && capture.identity != Identity::KeyOnly {
        notes.push("the reference holds depth keys only: primitive ids are not compared".into());
        capture = with_identity(&capture, Identity::KeyOnly);
    }
    if capture.pixels() != oracle.pixels() {
        return Err(format!(
            "the candidate covers {} pixels, the reference {}",
            capture.pixels(),
            oracle.pixels()
        ));
    }
    notes.extend(reference.drop_unknowable(&mut capture));
    let compare_options = CompareOptions {
        depth_ulps: options.depth_ulps,
        examples: options.examples,
        complete: reference.complete(),
    };
    // The analysis as the candidate stores depth: a unorm payload's steps.
    let as_stored = |precision: Cow<'_, Precision>, oracle: &Oracle| -> Precision {
        if stored == DepthFormat::F32 {
            precision.into_owned()
        } else {
            precision.into_owned().stored_as(stored, oracle)
        }
    };
    let precision = reference.precision().map(|precision| {
        if stored == DepthFormat::F32 {
            Cow::Borrowed(precision)
        } else {
            Cow::Owned(as_stored(Cow::Borrowed(precision), oracle))
        }
    });
    let mut wrong_masks = None;
    let compare = |oracle: &Oracle, precision: Option<&Precision>| match precision {
        Some(precision) => compare_within(
            precision,
            oracle,
            &capture,
            words.as_ref(),
            &compare_options,
        ),
        None => crate::compare::compare_with(oracle, &capture, words.as_ref(), &compare_options),
    };
    let mut comparison = match (candidate, reference.per_pixel()) {
        (Candidate::Dump(dump), Some(per_pixel)) => match reference.masked_within_precision() {
            // Per sample: a wrong mask is a missing or an extra node at the samples it gets
            // wrong, counted there.
            Some(within) => {
                dump.compare_masked_within(&within.precision, &within.samples, &compare_options)
                    .map_err(|e| e.to_string())?
                    .nodes
            }
            None => {
                let masked = dump
                    .compare_masked(per_pixel, &compare_options)
                    .map_err(|e| e.to_string())?;
                wrong_masks = Some(masked.wrong_masks.len() as u64);
                masked.nodes
            }
        },
        (_, Some(_)) => {
            return Err(
                "the per-pixel view of the per-sample oracle judges masked-node dumps \
                        only"
                    .into(),
            )
        }
        (_, None) => compare(oracle, precision.as_deref()),
    };
    let mut precision = precision;
    let mut edge_ties = None;
    if let Some(source) = reference.edge_ties() {
        let pipeline_fits = source.candidates.contains(&source.pipeline);
        edge_ties = Some(source.pipeline);
        if !(pipeline_fits && comparison.is_equal()) {
            let ties = TiePoints::of(source.view);
            let exact = precision.as_deref().is_none_or(Precision::is_exact);
            // Where no snapped triangle the vertices may reach puts a sample on an edge, every
            // rule gives the pipeline's lists.
            let met = !ties.is_empty()
                || precision
                    .as_deref()
                    .is_some_and(|p| p.bounds().edge_tie_pairs > 0);
            let mut best: Option<(EdgeTies, Comparison, Option<Precision>)> = None;
            if pipeline_fits || !met {
                best = Some((source.pipeline, comparison.clone(), None));
            }
            let others = source
                .candidates
                .iter()
                .copied()
                .filter(|&rule| met && rule != source.pipeline);
            for rule in others {
                let under = ties.oracle_under(oracle, source.pipeline, rule);
                let lists = under.as_ref().unwrap_or(oracle);
                let analysis = (!exact)
                    .then(|| Precision::derive_under(source.view, &source.conventions, rule));
                let analysis = match (analysis, stored) {
                    (Some(a), _) => Some(as_stored(Cow::Owned(a), lists)),
                    (None, DepthFormat::F32) => None,
                    (None, _) => Some(as_stored(Cow::Owned(Precision::exact()), lists)),
                };
                let judged = compare(lists, analysis.as_ref());
                let better = best.as_ref().is_none_or(|(_, b, _)| {
                    (judged.is_equal(), std::cmp::Reverse(errors(&judged)))
                        > (b.is_equal(), std::cmp::Reverse(errors(b)))
                });
                if better {
                    best = Some((rule, judged, analysis));
                }
            }
            if let Some((rule, judged, analysis)) = best {
                if rule != source.pipeline {
                    notes.push(format!(
                        "samples exactly on an edge judged under the {} rule (fragsim \
                         rasterizes with {}; they disagree on {} fragments): {}",
                        rule.name(),
                        source.pipeline.name(),
                        ties.differences(source.pipeline, rule),
                        if source.candidates.len() == 1 {
                            "the rule the dump declares"
                        } else {
                            "the one rule that explains the capture best"
                        }
                    ));
                    comparison = judged;
                    if let Some(analysis) = analysis {
                        precision = Some(Cow::Owned(analysis));
                    }
                }
                edge_ties = Some(rule);
            }
        }
    }
    if !matches!(capture.keeps, Keeps::All { .. }) {
        // A K-nearest (K-farthest) list claims nothing: what lies beyond K is its promise, as
        // the exact comparison counts it (the precision verdict leaves it at 0).
        comparison.claimed_overflow = comparison.diff.overflowed;
    }
    let bounds = precision
        .as_deref()
        .filter(|p| !p.is_exact())
        .map(Precision::bounds);
    notes.extend(overflow_notes(&comparison, &capture));
    notes.extend(allowance::counter_note(&comparison));
    let lists_per_pixel = reference.lists_per_pixel();
    let (width, height) = (reference.width, reference.height);
    let vertex_precision = reference.vertex_precision();
    Ok(Verdict {
        equal: comparison.is_equal() && reference.corrupt_words() == 0,
        per_sample: SampleCounts::of(&comparison, lists_per_pixel),
        examples: report::examples(&comparison, width, lists_per_pixel, capture.identity),
        compared: report::what_is_compared(
            &capture,
            options.depth_ulps,
            vertex_precision == VertexPrecision::F32,
            stored,
        ),
        comparison,
        scene: None,
        width,
        height,
        lists_per_pixel,
        depth_ulps: options.depth_ulps,
        vertex_precision,
        stored_depth: stored,
        bounds,
        wrong_masks,
        reference_fragments: reference
            .masked_within_precision()
            .map_or(oracle, |within| &within.samples)
            .depth_complexity(),
        identity: capture.identity,
        notes,
        edge_ties,
    })
}

/// The lists of a comparison whose verdict is an error.
fn errors(comparison: &Comparison) -> usize {
    comparison
        .verdicts
        .iter()
        .filter(|&&v| v & verdict::DIFFERS != 0)
        .count()
}

/// The notes on overflow: storage that stops without a count, and counters that claim another
/// overflow than the reference predicts.
fn overflow_notes(comparison: &Comparison, capture: &Capture) -> Vec<String> {
    let mut notes = Vec::new();
    // Storage that stops at `kept` without a count reports no overflow by design (the oracle
    // supplies it), and which fragments it keeps is the arrival order's choice.
    let uncounted = match capture.keeps {
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
    notes
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
