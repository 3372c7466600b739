//! A candidate judged against fragsim's oracle of a view: every bit owed under an f64 vertex
//! stage, the derived bounds under an f32 one, each reference depth as the steps a unorm payload
//! may land on; samples exactly on an edge under the declared rule, or under whichever one rule
//! explains the capture best (`docs/semantics.md` §4, "Edge ties").

use std::borrow::Cow;

use fragsim_raster::EdgeTies;

use super::reference::EdgeTieSource;
use super::{compare_options, errors, Judged, Options, Outcome};
use crate::compare::{compare_with, CompareOptions, Comparison};
use crate::edge_ties::TiePoints;
use crate::precision::{compare_within, Precision};
use crate::Oracle;
use fragsim_dump::DepthFormat;

/// Compares `judged` with `oracle`, owed within `precision` (as the candidate stores depth), and
/// where `edge_ties` gives the view, under the edge-tie rule that explains the capture.
pub(super) fn compare<'p>(
    judged: &mut Judged,
    oracle: &Oracle,
    precision: &'p Precision,
    edge_ties: Option<&EdgeTieSource<'_>>,
    options: &Options,
) -> Outcome<'p> {
    let options = compare_options(options, None);
    let precision = as_stored(Cow::Borrowed(precision), judged.stored, oracle);
    let comparison = lists(judged, &options, oracle, Some(&precision));
    let outcome = Outcome {
        precision: Some(precision),
        ..Outcome::exact(comparison)
    };
    match edge_ties {
        Some(source) => under_edge_ties(judged, &options, oracle, source, outcome),
        None => outcome,
    }
}

/// The analysis `precision` as a candidate storing depth as `stored` owes it, against `lists`:
/// a unorm payload's steps.
fn as_stored<'p>(
    precision: Cow<'p, Precision>,
    stored: DepthFormat,
    lists: &Oracle,
) -> Cow<'p, Precision> {
    if stored == DepthFormat::F32 {
        precision
    } else {
        Cow::Owned(precision.into_owned().stored_as(stored, lists))
    }
}

/// The candidate's lists compared with `lists`, within `precision` (`None`: every bit).
fn lists(
    judged: &Judged,
    options: &CompareOptions<'_>,
    lists: &Oracle,
    precision: Option<&Precision>,
) -> Comparison {
    let words = judged.words.as_ref();
    match precision {
        Some(precision) => compare_within(precision, lists, &judged.capture, words, options),
        None => compare_with(lists, &judged.capture, words, options),
    }
}

/// `outcome`, the comparison under the pipeline's rule, kept where that rule may be followed and
/// explains the capture; else the capture judged under each other rule the implementation may
/// follow, and the best kept (equal first, then fewest differing lists), with a note.
fn under_edge_ties<'p>(
    judged: &mut Judged,
    options: &CompareOptions<'_>,
    oracle: &Oracle,
    source: &EdgeTieSource<'_>,
    mut outcome: Outcome<'p>,
) -> Outcome<'p> {
    let pipeline_fits = source.candidates.contains(&source.pipeline);
    outcome.edge_ties = Some(source.pipeline);
    if pipeline_fits && outcome.comparison.is_equal() {
        return outcome;
    }
    let ties = TiePoints::of(source.view);
    let precision = outcome.precision.as_deref();
    let exact = precision.is_none_or(Precision::is_exact);
    // Where no snapped triangle the vertices may reach puts a sample on an edge, every rule gives
    // the pipeline's lists.
    let met = !ties.is_empty() || precision.is_some_and(|p| p.bounds().edge_tie_pairs > 0);
    let mut best: Option<(EdgeTies, Comparison, Option<Precision>)> = None;
    if pipeline_fits || !met {
        best = Some((source.pipeline, outcome.comparison.clone(), None));
    }
    let others = source
        .candidates
        .iter()
        .copied()
        .filter(|&rule| met && rule != source.pipeline);
    for rule in others {
        let under = ties.oracle_under(oracle, source.pipeline, rule);
        let rule_lists = under.as_ref().unwrap_or(oracle);
        let analysis =
            (!exact).then(|| Precision::derive_under(source.view, &source.conventions, rule));
        let analysis = match (analysis, judged.stored) {
            (Some(a), stored) => Some(as_stored(Cow::Owned(a), stored, rule_lists).into_owned()),
            (None, DepthFormat::F32) => None,
            (None, stored) => {
                Some(as_stored(Cow::Owned(Precision::exact()), stored, rule_lists).into_owned())
            }
        };
        let compared = lists(judged, options, rule_lists, analysis.as_ref());
        let better = best.as_ref().is_none_or(|(_, b, _)| {
            (compared.is_equal(), std::cmp::Reverse(errors(&compared)))
                > (b.is_equal(), std::cmp::Reverse(errors(b)))
        });
        if better {
            best = Some((rule, compared, analysis));
        }
    }
    if let Some((rule, compared, analysis)) = best {
        if rule != source.pipeline {
            judged.notes.push(format!(
                "samples exactly on an edge judged under the {} rule (fragsim rasterizes with \
                 {}; they disagree on {} fragments): {}",
                rule.name(),
                source.pipeline.name(),
                ties.differences(source.pipeline, rule),
                if source.candidates.len() == 1 {
                    "the rule the dump declares"
                } else {
                    "the one rule that explains the capture best"
                }
            ));
            outcome.comparison = compared;
            if let Some(analysis) = analysis {
                outcome.precision = Some(Cow::Owned(analysis));
            }
        }
        outcome.edge_ties = Some(rule);
    }
    outcome
}
