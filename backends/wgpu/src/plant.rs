//! Planted bugs: shader variants that break a scheme on purpose, so that a test can show that
//! `fragsim compare` calls each of them an error (issue 16's list) while it calls the correct
//! shader equal.
//!
//! Each plant is a value of the WGSL pipeline-overridable constant `plant` (`common.wgsl`), so a
//! planted capture runs the scheme's own shader, specialised; the dump still names the scheme it
//! pretends to be (its `extra` names the plant). The fragments a plant hits are one in 256, picked
//! by a hash of (pixel, primitive id) (`planted` in `common.wgsl`).
//!
//! Guarantee: a plant that cannot show in a scheme (an unsorted list where nothing is sorted, a
//! wrong id in key-only words) is refused for it, naming the schemes it applies to.

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
}

/// The names [`Plant::parse`] accepts, in [`Plant::ALL`]'s order.
pub const NAMES: [&str; 5] = [
    "dropped",
    "wrong-id",
    "off-by-one-capacity",
    "unsorted",
    "lost-node",
];

impl Plant {
    /// Every plant.
    pub const ALL: [Plant; 5] = [
        Plant::Dropped,
        Plant::WrongId,
        Plant::OffByOneCapacity,
        Plant::Unsorted,
        Plant::LostNode,
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
                GpuError(format!(
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

    /// Whether the plant is in `scheme`'s shader and shows in its dump.
    #[must_use]
    pub fn applies_to(self, scheme: &GpuScheme) -> bool {
        use GpuScheme as S;
        match self {
            Self::Dropped => true,
            Self::WrongId => !matches!(scheme, S::Mdts32 { .. }),
            Self::OffByOneCapacity | Self::Unsorted => {
                matches!(scheme, S::ABuffer { .. } | S::ABufferExact)
            }
            Self::LostNode => matches!(scheme, S::LinkedList { .. }),
        }
    }

    /// Refuses the plant for a scheme it does not apply to.
    ///
    /// # Errors
    /// The plant, the scheme and the schemes it applies to.
    pub fn check(self, scheme: &GpuScheme) -> Result<(), GpuError> {
        if self.applies_to(scheme) {
            return Ok(());
        }
        let fits: Vec<&str> = crate::shaders::NAMES
            .iter()
            .filter(|&&n| GpuScheme::parse(n, 1, 1).is_ok_and(|s| self.applies_to(&s)))
            .copied()
            .collect();
        Err(GpuError(format!(
            "plant {} does not apply to {}: it applies to {}",
            self.name(),
            scheme.name(),
            fits.join(", ")
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
        assert!(e.0.contains("expected dropped, wrong-id"), "{e}");
    }

    #[test]
    fn a_plant_the_scheme_cannot_show_is_refused_naming_those_it_fits() {
        let mdts = GpuScheme::Mdts { k: 4 };
        let e = Plant::LostNode.check(&mdts).unwrap_err();
        assert!(
            e.0.ends_with("applies to linked-list, linked-list-nearest"),
            "{e}"
        );
        let e = Plant::WrongId
            .check(&GpuScheme::Mdts32 { k: 4 })
            .unwrap_err();
        assert!(e.0.contains("mdts32"), "{e}");
        assert!(Plant::Unsorted.check(&GpuScheme::ABufferExact).is_ok());
        assert!(Plant::Dropped.check(&mdts).is_ok());
    }
}
