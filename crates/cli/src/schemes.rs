//! The command line's names for schemes: exactly the catalog's ([`fragsim_capture::catalog`]),
//! plus `all`. Building and running them is the library's ([`SchemeRunner::run`]).

use clap::builder::PossibleValue;
use clap::ValueEnum;
use std::sync::OnceLock;

pub(crate) use fragsim_capture::catalog::{
    check_memory_cap_early, NamedRun, SchemeName, SchemeRunner, CATALOG,
};

/// A `--scheme` value: one catalog entry, or `all` of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SchemeChoice {
    /// One scheme.
    One(SchemeName),
    /// Every catalog entry.
    All,
}

impl SchemeChoice {
    /// `choices` with `all` expanded and duplicates removed, in the order given.
    #[must_use]
    pub fn expand(choices: &[Self]) -> Vec<SchemeName> {
        if choices.contains(&Self::All) {
            return CATALOG.iter().map(|e| e.scheme).collect();
        }
        let mut unique = Vec::new();
        for &choice in choices {
            if let Self::One(name) = choice {
                if !unique.contains(&name) {
                    unique.push(name);
                }
            }
        }
        unique
    }
}

impl ValueEnum for SchemeChoice {
    fn value_variants<'a>() -> &'a [Self] {
        static VARIANTS: OnceLock<Vec<SchemeChoice>> = OnceLock::new();
        VARIANTS.get_or_init(|| {
            CATALOG
                .iter()
                .map(|e| Self::One(e.scheme))
                .chain([Self::All])
                .collect()
        })
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(match self {
            Self::One(name) => PossibleValue::new(name.name()).help(name.entry().description),
            Self::All => PossibleValue::new("all").help("Every scheme above."),
        })
    }
}

/// The family a scheme belongs to, as charts mark it (one marker shape a family): `mdts`,
/// `a-buffer` (A-buffers, linked lists, the layer counter, the stencil-routed A-buffer),
/// `peeling` (depth peeling and the z-buffer), `k-buffer` (k-buffers and loop32), `bucket`
/// (bucket and adaptive depth peeling), `approximate` (WBOIT, MLAB, tail blending:
/// `--approximate`).
#[must_use]
pub(crate) fn family(scheme: &str) -> &'static str {
    const FAMILIES: [(&str, &str); 15] = [
        ("mdts", "mdts"),
        ("abuffer", "a-buffer"),
        ("linked-list", "a-buffer"),
        ("layer-counter", "a-buffer"),
        ("srab", "a-buffer"),
        ("peeling", "peeling"),
        ("dual-peeling", "peeling"),
        ("zbuffer", "peeling"),
        ("kbuffer", "k-buffer"),
        ("loop32", "k-buffer"),
        ("bdp", "bucket"),
        ("adp", "bucket"),
        ("wboit", "approximate"),
        ("mlab", "approximate"),
        ("tail-blend", "approximate"),
    ];
    FAMILIES
        .iter()
        .find(|(prefix, _)| scheme.starts_with(prefix))
        .map_or("other", |&(_, family)| family)
}

/// A deliberate fault, for the tests that show a verdict can fail (`render --inject-fault`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Fault {
    /// Every scheme that counts its own overflow reports one fragment more at pixel 0.
    MiscountOverflow,
}

impl From<Fault> for fragsim_capture::catalog::Fault {
    fn from(fault: Fault) -> Self {
        match fault {
            Fault::MiscountOverflow => Self::MiscountOverflow,
        }
    }
}

#[cfg(test)]
mod tests {
    /// Every scheme's family has its own marker on the charts (`fragsim_shade::plot::FAMILIES`),
    /// so a family looks the same on bench's chart and sweep's.
    #[test]
    fn every_catalog_family_has_a_chart_marker() {
        for entry in fragsim_capture::catalog::CATALOG {
            let family = super::family(entry.name);
            assert!(
                fragsim_shade::plot::FAMILIES.contains(&family),
                "{}: {family}",
                entry.name
            );
        }
    }
}
