//! A run's capture judged by its scheme's own guarantee: what `render` and `bench` say of each
//! (scheme, executor) row (`kept`, `BROKEN`, `not owed`), with the row's counts.
//!
//! Guarantee: the counts are the per-pixel diff ([`Oracle::diff_with`]) under the tie policy
//! the report asks for; the guarantee is judged under its own policy (equal depths merged for
//! [`Guarantee::ExactDistinctDepths`], the canonical order otherwise), and only where it owes
//! exact lists on the executor that ran ([`Guarantee::owes_exactness`]). Overflow is the
//! oracle's prediction from each pixel's fragment count and the scheme's declared capacity,
//! never the run's own count, which must equal it.

use fragsim_capture::{Capture, Guarantee};

use crate::{Diff, Oracle, Ties};

/// The verdict on one run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunVerdict {
    /// The run's lists against the oracle's, under the report's tie policy.
    pub diff: Diff,
    /// Whether the guarantee owes exact lists on the executor that ran.
    pub owed: bool,
    /// Whether the run kept its guarantee (`true` where it owes nothing).
    pub kept: bool,
}

/// Judges `capture`, a run of a scheme promising `guarantee` on an executor that serialises each
/// pixel's fragments (`pixels_serialised`: serial, tiled) or not, against `oracle`, its counts
/// taken under `ties`. One diff is made when `ties` is the guarantee's own policy, two
/// otherwise.
///
/// # Panics
/// If the capture covers a different number of pixels than the oracle.
#[must_use]
pub fn judge_run(
    oracle: &Oracle,
    capture: &Capture,
    guarantee: Guarantee,
    pixels_serialised: bool,
    ties: Ties,
) -> RunVerdict {
    let diff = oracle.diff_with(capture, ties);
    let owed = guarantee.owes_exactness(pixels_serialised);
    let judging = if guarantee.merges_equal_depths() {
        Ties::MergeEqualDepths
    } else {
        Ties::ByPrimitive
    };
    let kept = !owed
        || if ties == judging {
            diff.is_exact()
        } else {
            oracle.diff_with(capture, judging).is_exact()
        };
    RunVerdict { diff, owed, kept }
}

#[cfg(test)]
mod tests {
    use fragsim_capture::Keeps;
    use fragsim_raster::Fragment;

    use super::*;

    #[test]
    fn guarantees_are_judged_where_they_are_owed_and_by_their_own_ties() {
        // One pixel, two primitives at one depth; the capture merged them into the later one.
        let fragment = |prim| Fragment {
            pixel: 0,
            depth_key: 10,
            prim,
        };
        let oracle = Oracle::from_fragments(1, &[fragment(1), fragment(2)]);
        let mut merged =
            Capture::with_pixels(1, fragsim_capture::Identity::KeyAndPrim, Keeps::Nearest(2));
        merged.push_pixel([(10 << 32) | 2]);
        let judge =
            |guarantee, serialised, ties| judge_run(&oracle, &merged, guarantee, serialised, ties);
        // Merging equal depths is what a distinct-depths guarantee promises, whatever the
        // report's ties; the canonical count still calls the pixel different.
        let distinct = judge(Guarantee::ExactDistinctDepths, false, Ties::ByPrimitive);
        assert!(distinct.owed && distinct.kept);
        assert_eq!(distinct.diff.mismatched_pixels, 1);
        // The control: an exact guarantee is broken by the same capture.
        let exact = judge(Guarantee::Exact, false, Ties::ByPrimitive);
        assert!(exact.owed && !exact.kept);
        // A hazard-free guarantee is owed where pixels are serialised, and only there.
        assert!(!judge(Guarantee::ExactWithoutHazards, true, Ties::ByPrimitive).kept);
        let unserialised = judge(Guarantee::ExactWithoutHazards, false, Ties::ByPrimitive);
        assert!(!unserialised.owed && unserialised.kept);
        assert!(judge(Guarantee::Approximate, true, Ties::ByPrimitive).kept);
        // Counts under merged ties, the guarantee judged under its own.
        let counted = judge(Guarantee::Exact, true, Ties::MergeEqualDepths);
        assert!(counted.diff.is_exact() && !counted.kept);
    }
}
