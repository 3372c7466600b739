//! The command line's names for schemes: exactly the catalog's ([`fragsim_catalog`]),
//! plus `all`. Building and running them is the library's ([`SchemeRunner::run`]).

use clap::builder::PossibleValue;
use clap::ValueEnum;
use std::sync::OnceLock;

pub(crate) use fragsim_catalog::{
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
