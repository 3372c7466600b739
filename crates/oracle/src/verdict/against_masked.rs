//! A masked-node dump judged against the per-pixel view of the per-sample oracle: its nodes as an
//! A-buffer's fragments and each node's coverage mask, every bit owed, or (for an f32 vertex
//! stage) each node at each sample it covers within the bounds derived at every sample.

use std::borrow::Cow;

use fragsim_capture::MaskedLists;

use super::reference::MaskedWithin;
use super::{compare_options, Candidate, JudgeDump, Options, Outcome, VerdictError};

/// Compares `candidate` with `nodes`, the per-pixel view of the per-sample oracle, within
/// `within` where given.
///
/// # Errors
/// A candidate that is not a masked-node dump, or one whose nodes cannot be decoded.
pub(super) fn compare<'p>(
    candidate: Candidate<'_>,
    nodes: &MaskedLists,
    within: Option<&'p MaskedWithin>,
    options: &Options,
) -> Result<Outcome<'p>, VerdictError> {
    let Candidate::Dump(dump) = candidate else {
        return Err(VerdictError::MaskedOnly);
    };
    let options = compare_options(options, None);
    Ok(match within {
        // Per sample: a wrong mask is a missing or an extra node at the samples it gets wrong,
        // counted there.
        Some(within) => Outcome {
            precision: Some(Cow::Borrowed(&within.precision)),
            ..Outcome::exact(
                dump.compare_masked_within(&within.precision, &within.samples, &options)?
                    .nodes,
            )
        },
        None => {
            let masked = dump.compare_masked(nodes, &options)?;
            Outcome {
                wrong_masks: Some(masked.wrong_masks.len() as u64),
                ..Outcome::exact(masked.nodes)
            }
        }
    })
}
