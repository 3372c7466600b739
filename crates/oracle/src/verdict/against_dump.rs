//! A candidate judged against another dump's decoded lists: every bit owed, but only what the
//! reference dump can know (its full K-lists and overflowed pixels do not hold every fragment,
//! and a key-only reference names no primitive).

use fragsim_capture::Identity;

use super::{compare_options, Judged, Options, Outcome, Reference};
use crate::compare::{compare_with, with_identity};

/// Compares `judged` with `reference`, a dump's lists whose words are of `identity` and which
/// knows every fragment of pixel `p` where `complete[p]`.
pub(super) fn compare<'p>(
    judged: &mut Judged,
    reference: &Reference<'_>,
    complete: &[bool],
    identity: Identity,
    options: &Options,
) -> Outcome<'p> {
    if identity == Identity::KeyOnly && judged.capture.identity != Identity::KeyOnly {
        judged
            .notes
            .push("the reference holds depth keys only: primitive ids are not compared".into());
        judged.capture = with_identity(&judged.capture, Identity::KeyOnly);
    }
    judged
        .notes
        .extend(reference.drop_unknowable(&mut judged.capture));
    Outcome::exact(compare_with(
        reference.oracle(),
        &judged.capture,
        judged.words.as_ref(),
        &compare_options(options, Some(complete)),
    ))
}
