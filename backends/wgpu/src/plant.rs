//! Planted bugs: shader variants that break a scheme on purpose, so that a test can show that
//! `fragsim compare` calls each of them an error while it calls the correct
//! shader equal.
//!
//! Each plant is a value of the WGSL pipeline-overridable constant `plant` (`common.wgsl`), so a
//! planted capture runs the scheme's own shader, specialised; the dump still names the scheme it
//! pretends to be (its `extra` names the plant). The fragments a plant hits are one in 256, picked
//! by a hash of (pixel, primitive id) (`planted` in `common.wgsl`).
//!
//! Guarantee: a plant that cannot show in a scheme (an unsorted list where nothing is sorted, a
//! wrong id in key-only words, the pixel centre's depth where the sample is the centre) is
//! refused for it, naming the schemes it applies to.

use crate::device::GpuError;
use crate::shaders::GpuScheme;

/// A planted bug.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plant {
    /// A hit fragment is dropped before any store.
    Dropped,
    /// A hit fragment is stored with primitive id `prim ^ 1`.
    WrongId,
    /// The A-buffer never writes its last slot while its counter counts on: one fragment of every
    /// pixel with at least `capacity` fragments (exact storage: every covered pixel) is lost, and
    /// the counter's overflow disagrees with what was stored.
    OffByOneCapacity,
    /// The A-buffer's sort pass returns at once; the dump still says `"sorted": true`.
    Unsorted,
    /// A hit fragment's head exchange drops the old head: the rest of its pixel's list is lost.
    LostNode,
    /// Per sample only: a hit sample's fragment carries the depth at its pixel's centre instead
    /// of the sample's (what `position.z` gives under sample shading on the H200,
    /// `docs/semantics.md` §11).
    CentreDepth,
}

/// The names [`Plant::parse`] accepts, in [`Plant::ALL`]'s order.
pub const NAMES: [&str; 6] = [
    "dropped",
    "wrong-id",
    "off-by-one-capacity",
    "unsorted",
    "lost-node",
    "centre-depth",
];

impl Plant {
    /// Every plant.
    pub const ALL: [Self; 6] = [
        Self::Dropped,
        Self::WrongId,
        Self::OffByOneCapacity,
        Self::Unsorted,
        Self::LostNode,
        Self::CentreDepth,
    ];

    /// The plant called `name` ([`NAMES`]).
    ///
    /// # Errors
    /// An unknown name; the message lists [`NAMES`].
    pub fn parse(name: &str) -> Result<Self, GpuError> {
        NAMES
            .iter()
            .position(|&n| n == name)
            .map(|i| Self::ALL[i])
            .ok_or_else(|| {
                GpuError::Refused(format!(
                    "unknown plant {name:?}: expected {}",
                    NAMES.join(", ")
                ))
            })
    }

    /// Its name ([`NAMES`]).
    #[must_use]
    pub fn name(self) -> &'static str {
        NAMES[self as usize]
    }

    /// The value of the shader's `plant` constant (0 is the correct shader).
    #[must_use]
    pub fn constant(self) -> f64 {
        f64::from(self as u32 + 1)
    }

    /// Whether the plant is in `scheme`'s shader and shows in its dump at one sample a pixel.
    #[must_use]
    pub fn applies_to(self, scheme: &GpuScheme) -> bool {
        self.applies_at(scheme, 1)
    }

    /// Whether the plant is in `scheme`'s shader and shows in its dump at `samples` a pixel.
    #[must_use]
    pub fn applies_at(self, scheme: &GpuScheme, samples: u32) -> bool {
        use GpuScheme as S;
        match self {
            // At one sample the sample is the centre; the per-sample variants carry the plant.
            Self::CentreDepth => samples > 1 && scheme.per_sample_source().is_some(),
            Self::Dropped => true,
            Self::WrongId => !matches!(scheme, S::Mdts32 { .. }),
            Self::OffByOneCapacity | Self::Unsorted => {
                matches!(scheme, S::ABuffer { .. } | S::ABufferExact)
            }
            Self::LostNode => matches!(scheme, S::LinkedList { .. }),
        }
    }

    /// Refuses the plant for a scheme it does not apply to at one sample a pixel.
    ///
    /// # Errors
    /// As [`Plant::check_at`].
    pub fn check(self, scheme: &GpuScheme) -> Result<(), GpuError> {
        self.check_at(scheme, 1)
    }

    /// Refuses the plant for a scheme it does not apply to at `samples` a pixel.
    ///
    /// # Errors
    /// The plant, the scheme, the sample count and the schemes it applies to there (none: the
    /// plant needs more samples).
    pub fn check_at(self, scheme: &GpuScheme, samples: u32) -> Result<(), GpuError> {
        if self.applies_at(scheme, samples) {
            return Ok(());
        }
        let fits: Vec<&str> = crate::shaders::NAMES
            .iter()
            .filter(|&&n| GpuScheme::parse(n, 1, 1).is_ok_and(|s| self.applies_at(&s, samples)))
            .copied()
            .collect();
        let fits = if fits.is_empty() {
            "none at this sample count".to_string()
        } else {
            fits.join(", ")
        };
        Err(GpuError::Refused(format!(
            "plant {} does not apply to {} at {samples} sample(s) a pixel: it applies to {fits}",
            self.name(),
            scheme.name(),
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_to_its_plant_and_back() {
        for plant in Plant::ALL {
            assert_eq!(Plant::parse(plant.name()), Ok(plant));
        }
        let e = Plant::parse("typo").unwrap_err();
        assert!(e.to_string().contains("expected dropped, wrong-id"), "{e}");
    }

    #[test]
    #[expect(clippy::shadow_unrelated, reason = "each `e` is its own case's error")]
    fn a_plant_the_scheme_cannot_show_is_refused_naming_those_it_fits() {
        let mdts = GpuScheme::Mdts { k: 4 };
        let e = Plant::LostNode.check(&mdts).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("applies to linked-list, linked-list-nearest"),
            "{e}"
        );
        let e = Plant::WrongId
            .check(&GpuScheme::Mdts32 { k: 4 })
            .unwrap_err();
        assert!(e.to_string().contains("mdts32"), "{e}");
        assert!(Plant::Unsorted.check(&GpuScheme::ABufferExact).is_ok());
        assert!(Plant::Dropped.check(&mdts).is_ok());
    }

    #[test]
    #[expect(clippy::shadow_unrelated, reason = "each `e` is its own case's error")]
    fn the_centre_depth_plant_needs_samples_and_a_per_sample_variant() {
        let mdts = GpuScheme::Mdts { k: 4 };
        let e = Plant::CentreDepth.check(&mdts).unwrap_err();
        assert!(e.to_string().ends_with("none at this sample count"), "{e}");
        assert!(Plant::CentreDepth.check_at(&mdts, 4).is_ok());
        let e = Plant::CentreDepth
            .check_at(&GpuScheme::Kbuffer { k: 4 }, 4)
            .unwrap_err();
        assert!(
            e.to_string().contains("abuffer, abuffer-exact, mdts"),
            "{e}"
        );
    }
}
