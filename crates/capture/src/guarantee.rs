//! What a scheme guarantees against the oracle, as a type: the verdict of a run is whether its
//! capture keeps the guarantee, whatever the guarantee is.

use std::fmt;

/// What a scheme promises to capture, relative to the serial oracle's exact lists.
///
/// Every run is diffed against the oracle; the guarantee says which diffs break the promise. The
/// diff itself already knows the scheme's capacity and tie policy ([`crate::Keeps`]), so a
/// guarantee only adds *when* exactness is owed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Guarantee {
    /// Fragment for fragment, under any interleaving (the `K` nearest where it keeps `K`).
    Exact,
    /// Exact while a pixel's fragments fit the `C` slots the scheme has; past them it keeps a
    /// subset of exactly `C` and counts the rest as overflow, which the oracle checks.
    ExactWithinCapacity(u32),
    /// Exact when no two fragments of a pixel share a depth key: equal depths merge (32-bit depth
    /// peeling, nvpro-samples' loop32). Judged with the oracle's equal depths merged.
    ExactDistinctDepths,
    /// Exact when no other fragment of the pixel runs between a fragment's read and its write
    /// (read–modify–write schemes): owed on executors that serialise each pixel's fragments.
    ExactWithoutHazards,
    /// Exact when every pass sees a pixel's fragments in one arrival order (multi-pass routing):
    /// owed on executors that serialise each pixel's fragments.
    ExactInArrivalOrder,
    /// Loses fragments in situations its paper describes; the loss is reported, never a breach.
    Approximate,
}

impl Guarantee {
    /// Whether an exact capture is owed on an executor; `pixels_serialised` is true when the
    /// executor runs each pixel's fragments one after another in primitive order (serial, tiled).
    #[must_use]
    pub fn owes_exactness(self, pixels_serialised: bool) -> bool {
        match self {
            Self::Exact | Self::ExactWithinCapacity(_) => true,
            Self::ExactDistinctDepths => true,
            Self::ExactWithoutHazards | Self::ExactInArrivalOrder => pixels_serialised,
            Self::Approximate => false,
        }
    }

    /// Whether the oracle must merge equal depths before judging (see
    /// [`Guarantee::ExactDistinctDepths`]).
    #[must_use]
    pub fn merges_equal_depths(self) -> bool {
        self == Self::ExactDistinctDepths
    }
}

impl fmt::Display for Guarantee {
    /// The spelling used in tables and JSON: `exact`, `exact-within-capacity(8)`, …
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Exact => f.write_str("exact"),
            Self::ExactWithinCapacity(c) => write!(f, "exact-within-capacity({c})"),
            Self::ExactDistinctDepths => f.write_str("exact-distinct-depths"),
            Self::ExactWithoutHazards => f.write_str("exact-without-hazards"),
            Self::ExactInArrivalOrder => f.write_str("exact-in-arrival-order"),
            Self::Approximate => f.write_str("approximate"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hazard_guarantees_are_owed_only_where_pixels_are_serialised() {
        for g in [
            Guarantee::ExactWithoutHazards,
            Guarantee::ExactInArrivalOrder,
        ] {
            assert!(g.owes_exactness(true));
            assert!(!g.owes_exactness(false));
        }
        assert!(Guarantee::ExactWithinCapacity(4).owes_exactness(false));
        assert!(!Guarantee::Approximate.owes_exactness(true));
        assert_eq!(
            Guarantee::ExactWithinCapacity(8).to_string(),
            "exact-within-capacity(8)"
        );
    }
}
