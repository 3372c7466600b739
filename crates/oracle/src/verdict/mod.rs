//! The one verdict on a capture: what `fragsim compare` prints, what `fragsim render` and
//! `fragsim bench` say of each run, what `fragsim conform`, the testkit's battery and the wgpu
//! backend's judge decide by, computed once, here.
//!
//! A [`Reference`] is what the candidate is judged against: fragsim's oracle of a view with the
//! [`Precision`] a declared vertex stage owes (every bit under f64, the derived bounds under
//! f32), the per-pixel view of the per-sample oracle for a masked-node dump, or another dump's
//! decoded lists. A [`Candidate`] is a dump (its lists decoded by the scheme's own post pass and
//! every word checked against its layout), a run's capture, or the oracle itself. [`judge`]
//! takes the two and returns one [`Verdict`]: the per-list verdicts and their totals (the
//! library's [`Comparison`]), whether the sides are equal, what was compared, the precision
//! bounds, per-sample and masked-node counts, the first differing lists with both sides
//! ([`Example`]) and every note that qualifies the verdict. It prepares the candidate once and
//! compares it as its kind of reference asks, one module each: `against_oracle` (exact, within
//! an f32 vertex stage's bounds or a unorm payload's steps, samples on an edge under the rule
//! that explains the capture), `against_masked` (masked nodes, exact or per sample within
//! precision), `against_dump` (what a reference dump can know). [`judge_sides`] does the same
//! for two [`Side`]s as the command line names them (a dump directory or `oracle`): it checks
//! the headers against each other and rebuilds the oracle from the scene a dump names.
//! [`judge_run`] judges a run's capture by its scheme's own guarantee, on the executor that ran
//! it. Where no verdict can be given the error says why ([`VerdictError`]).
//!
//! Guarantee: every caller gets the same decision for the same inputs, the policy (which
//! comparison applies, what a reference dump cannot know, how a key-only reference reduces the
//! candidate, how a unorm depth is owed, which guarantee is owed where) being written in this
//! module alone; the comparisons themselves are [`compare_with`], [`compare_within`] and
//! [`JudgeDump::compare_masked`].

mod against_dump;
mod against_masked;
mod against_oracle;
mod error;
mod hints;
mod judge_dump;
mod reference;
mod report;
mod rows;
mod run;
mod sides;
#[cfg(test)]
mod tests;

use std::borrow::Cow;

use fragsim_capture::{Capacity, Capture, Identity, Keeps};
use fragsim_raster::{EdgeTies, VertexPrecision};

use crate::compare::{flags, CompareOptions, Comparison};
use crate::precision::{Bounds, Precision};
use crate::Oracle;
use fragsim_dump::{DepthFormat, Dump, DumpScheme, WordCheck};
use fragsim_raster::scene_spec::SceneSpec;
use reference::Kind;

#[cfg(doc)]
use crate::{compare::compare_with, precision::compare_within};

pub use crate::compare::MiscountedCounter;
pub use error::VerdictError;
pub use judge_dump::{JudgeDump, MaskedComparison, WrongMask};
pub use reference::Reference;
pub use report::{Corrupt, Entry, Example, FragmentTotals, SampleCounts, Summary, WordTotals};
pub use rows::{aligned, Row};
pub use run::{judge_run, RunVerdict};
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
    /// What to check next, where the differences have a shape that names a cause (the whole
    /// frame, depth rounding only, edges only); never a change to the verdict.
    pub hints: Vec<String>,
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

/// Judges `candidate` against `reference` (see the module documentation): the candidate
/// prepared once, compared as the kind of reference asks (the oracle, exactly or
/// within precision; the per-sample oracle's per-pixel view; another dump), the verdict
/// assembled from the outcome.
///
/// # Errors
/// A candidate dump of another viewport than the reference's or one that cannot be decoded, a
/// candidate of another number of lists than the reference, a masked-node dump against anything
/// but the per-sample oracle's per-pixel view.
pub fn judge(
    reference: &Reference<'_>,
    candidate: Candidate<'_>,
    options: &Options,
) -> Result<Verdict, VerdictError> {
    let mut judged = Judged::of(reference, candidate)?;
    let outcome = match &reference.kind {
        Kind::Oracle {
            precision,
            edge_ties,
            ..
        } => against_oracle::compare(
            &mut judged,
            reference.oracle(),
            precision,
            edge_ties.as_ref(),
            options,
        ),
        Kind::Masked { nodes, within } => {
            against_masked::compare(candidate, nodes, within.as_ref(), options)?
        }
        Kind::Dump {
            complete, identity, ..
        } => against_dump::compare(&mut judged, reference, complete, *identity, options),
    };
    Ok(judged.verdict(reference, outcome, options))
}

/// The candidate as every kind of reference judges it: its lists (decoded, for a dump), its
/// words' check, how it stores depth, and the notes that qualify the verdict so far.
struct Judged {
    capture: Capture,
    words: Option<WordCheck>,
    stored: DepthFormat,
    notes: Vec<String>,
}

/// What comparing with one kind of reference found.
struct Outcome<'p> {
    /// The per-list verdicts.
    comparison: Comparison,
    /// The precision the lists were judged within (`None`: every bit owed).
    precision: Option<Cow<'p, Precision>>,
    /// The edge-tie rule samples exactly on an edge were judged under, where the reference
    /// let the rule vary.
    edge_ties: Option<EdgeTies>,
    /// A masked-node dump judged exactly: stored nodes whose mask is not the reference's.
    wrong_masks: Option<u64>,
}

impl Outcome<'_> {
    /// A comparison of every bit, with nothing else to say.
    fn exact(comparison: Comparison) -> Self {
        Self {
            comparison,
            precision: None,
            edge_ties: None,
            wrong_masks: None,
        }
    }
}

impl Judged {
    /// `candidate` decoded and checked against `reference`'s viewport and lists, with the notes
    /// the reference and the candidate's words give.
    fn of(reference: &Reference<'_>, candidate: Candidate<'_>) -> Result<Self, VerdictError> {
        let oracle = reference.oracle();
        if let Candidate::Dump(dump) = candidate {
            let size = (dump.header.width, dump.header.height);
            if size != (reference.width, reference.height) {
                return Err(VerdictError::Viewport {
                    candidate: size,
                    reference: (reference.width, reference.height),
                });
            }
        }
        // A unorm payload cannot owe the f32 bits: the oracle's fragments are judged as the dump
        // stores depth, each interval the steps the conversion may land on.
        let stored = match (candidate, &reference.kind) {
            (Candidate::Dump(dump), Kind::Oracle { .. }) => dump.depth_format(),
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
        if let Kind::Dump { notes: caveats, .. } = &reference.kind {
            notes.extend(caveats.iter().cloned());
        }
        let (capture, words) = match candidate {
            Candidate::Dump(dump) => (dump.capture()?, Some(dump.check_words()?)),
            Candidate::Capture(capture) => (capture.clone(), None),
            Candidate::Oracle(other) => (oracle_capture(other), None),
        };
        if let (Candidate::Dump(dump), Some(words)) = (candidate, &words) {
            notes.extend(unread_notes(dump, words)?);
        }
        if capture.pixels() != oracle.pixels() {
            return Err(VerdictError::Lists {
                candidate: capture.pixels(),
                reference: oracle.pixels(),
            });
        }
        Ok(Self {
            capture,
            words,
            stored,
            notes,
        })
    }

    /// The verdict of `outcome`, what comparing this candidate with `reference` found.
    fn verdict(
        mut self,
        reference: &Reference<'_>,
        outcome: Outcome<'_>,
        options: &Options,
    ) -> Verdict {
        let Outcome {
            mut comparison,
            precision,
            edge_ties,
            wrong_masks,
        } = outcome;
        let capture = &self.capture;
        if !matches!(capture.keeps, Keeps::All { .. }) {
            // A K-nearest (K-farthest) list claims nothing: what lies beyond K is its promise, as
            // the exact comparison counts it (the precision verdict leaves it at 0).
            comparison.claimed_overflow = comparison.diff.overflowed;
        }
        let bounds = precision
            .as_deref()
            .filter(|p| !p.is_exact())
            .map(Precision::bounds);
        self.notes.extend(overflow_notes(&comparison, capture));
        self.notes.extend(crate::compare::counter_note(&comparison));
        let lists_per_pixel = reference.lists_per_pixel();
        let (width, height) = (reference.width, reference.height);
        let vertex_precision = reference.vertex_precision();
        // Masked nodes are judged by coverage masks, not the lists the hints read.
        let hint = match &reference.kind {
            Kind::Masked { .. } => None,
            kind => hints::hint(
                reference.oracle(),
                capture,
                &comparison,
                &hints::Judging {
                    row: (width * lists_per_pixel) as usize,
                    f32_stage_applies: matches!(kind, Kind::Oracle { .. })
                        && vertex_precision == VertexPrecision::F64,
                },
            ),
        };
        Verdict {
            equal: comparison.is_equal() && reference.corrupt_words() == 0,
            per_sample: SampleCounts::of(&comparison, lists_per_pixel),
            examples: report::examples(&comparison, width, lists_per_pixel, capture.identity),
            compared: report::what_is_compared(
                capture,
                options.depth_ulps,
                vertex_precision == VertexPrecision::F32,
                self.stored,
            ),
            comparison,
            scene: None,
            width,
            height,
            lists_per_pixel,
            depth_ulps: options.depth_ulps,
            vertex_precision,
            stored_depth: self.stored,
            bounds,
            wrong_masks,
            reference_fragments: reference
                .masked_within_precision()
                .map_or(reference.oracle(), |within| &within.samples)
                .depth_complexity(),
            identity: capture.identity,
            notes: self.notes,
            hints: hint.into_iter().collect(),
            edge_ties,
        }
    }
}

/// How [`compare_with`] and [`compare_within`] are asked to compare under `options`, the
/// reference knowing every fragment where `complete` says so (everywhere: `None`).
fn compare_options<'c>(options: &Options, complete: Option<&'c [bool]>) -> CompareOptions<'c> {
    CompareOptions {
        depth_ulps: options.depth_ulps,
        examples: options.examples,
        complete,
    }
}

/// The lists of a comparison whose verdict is an error.
fn errors(comparison: &Comparison) -> usize {
    comparison
        .verdicts
        .iter()
        .filter(|&&v| v & flags::DIFFERS != 0)
        .count()
}

/// The notes on the words of `dump` that its check did not read ([`WordCheck::unchecked`],
/// [`WordCheck::spare`]), each worded for the layout they belong to: what they are, and whether
/// a header field would have had them checked.
///
/// # Errors
/// A header whose scheme is unknown (the check that counted the words has read it already).
fn unread_notes(dump: &Dump, words: &WordCheck) -> Result<Vec<String>, VerdictError> {
    let scheme = if dump.is_masked() {
        None
    } else {
        Some(dump.scheme()?)
    };
    let (unchecked, spare) = (words.unchecked, words.spare);
    let mut notes = Vec::new();
    if unchecked > 0 {
        notes.push(match &scheme {
            None => format!(
                "{unchecked} words of masked-node slots past their pixel's counter (a node and a \
                 mask each) were not checked: the header does not say every slot was cleared \
                 (\"filled\": true)"
            ),
            Some(DumpScheme::Memory { .. }) => format!(
                "the {unchecked} words of this memory dump were not checked: a scheme's own \
                 memory has no word rules here, only the lists its resolve decodes are judged"
            ),
            Some(_) => format!(
                "{unchecked} A-buffer slots past their pixel's counter were not checked: the \
                 header does not say every slot was filled with the empty marker (\"filled\": \
                 true)"
            ),
        });
    }
    if spare > 0 {
        notes.push(match &scheme {
            Some(DumpScheme::LinkedLists { pool, .. }) => format!(
                "{} of the pool's {pool} nodes lie past the node counter and were not read: the \
                 counter never handed them out, so no list may reach them (a link to one is \
                 corrupt) and what they hold is whatever the pool held",
                spare / 2
            ),
            _ => format!(
                "{spare} layers past their pixel's counter were not read: no list holds them, \
                 and the layout does not say what they hold"
            ),
        });
    }
    Ok(notes)
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
            .filter(|&&v| v & flags::OVERFLOWED != 0)
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
