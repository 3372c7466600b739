//! Strategies for `K` (slots, capacities), relative to the depth complexity.

use proptest::prelude::*;

/// A choice of `K` (MDTS slots, A-buffer capacity) made before the scene's depth complexity is
/// known; [`KChoice::resolve`] turns it into a number once the oracle is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KChoice {
    /// `K = 1`.
    One,
    /// `K = max(1, ⌊fraction · max depth complexity⌋)`: usually below the maximum, so fragments
    /// overflow.
    Fraction(f64),
    /// `K` = the maximum depth complexity (at least 1): exact, with no slot to spare.
    Max,
    /// `K` = the maximum depth complexity plus `1..=3`.
    AboveMax(u32),
    /// A fixed `K` in `1..=8`, whatever the scene.
    Absolute(u32),
}

impl KChoice {
    /// The `K` for a scene whose largest per-pixel depth complexity is `max_depth_complexity`;
    /// always at least 1.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a fraction in [0, 1] of max, a u32"
    )]
    pub fn resolve(self, max_depth_complexity: u32) -> u32 {
        let max = max_depth_complexity;
        match self {
            Self::One => 1,
            Self::Fraction(f) => (f * f64::from(max)) as u32,
            Self::Max => max,
            Self::AboveMax(extra) => max + extra,
            Self::Absolute(k) => k,
        }
        .max(1)
    }
}

/// A [`KChoice`]: below the maximum depth complexity about half of the time.
pub fn k_choice() -> impl Strategy<Value = KChoice> {
    prop_oneof![
        1 => Just(KChoice::One),
        3 => (0.0_f64..1.0).prop_map(KChoice::Fraction),
        2 => Just(KChoice::Max),
        1 => (1_u32..=3).prop_map(KChoice::AboveMax),
        1 => (1_u32..=8).prop_map(KChoice::Absolute),
    ]
}

/// A [`KChoice`] for a small fixed capacity: 1 to 4 slots, or a fraction of the maximum.
pub fn small_capacity() -> impl Strategy<Value = KChoice> {
    prop_oneof![
        2 => (1_u32..=4).prop_map(KChoice::Absolute),
        1 => (0.0_f64..1.0).prop_map(KChoice::Fraction),
    ]
}
