//! Interleavings that explain a scheme, and the walks that measure the k-buffer's hazard.
//!
//! The simulator's schemes are per-fragment state machines doing one memory operation per step
//! (`fragsim_capture`), so a scheme's behaviour under concurrency is a question of how steps of
//! different fragments interleave. This crate computes what `fragsim explain` and
//! `fragsim hazard` print (the command line keeps only its options and the printing):
//! - [`interleaving`]: fragments on one pixel, the scheduled executor's seeds, the replay of an
//!   explicit order and the slot words after every step;
//! - [`kbuffer`]: the k-buffer's damage (fragments lost or duplicated), the search for a damaging
//!   seed and the shrinker that makes its interleaving the shortest (Bavoil et al. 2007's
//!   read–modify–write hazard; `fragsim_schemes::kbuffer` says why 4 steps suffice);
//! - [`mdts`]: `docs/proof.md`'s invariant of MDTS (FreePipe, Liu et al. 2010) checked at every
//!   step of the densest interleaving;
//! - [`hazard`]: the hazard rate over a scene against the oracle, by width and depth complexity
//!   (`docs/rmw-hazard.md`);
//! - [`baselines`]: the k-buffer family's passes and losses on every executor
//!   (`docs/baselines/kbuffer.md`);
//! - [`report`]: what `fragsim explain` reports of a scheme, the lines and the step table.
//!
//! Which catalog schemes can be explained is [`Shown::of`]; the command line offers
//! [`Shown::schemes`].

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod baselines;
pub mod hazard;
pub mod interleaving;
pub mod kbuffer;
pub mod mdts;
pub mod report;
pub mod spinlock;

use fragsim_catalog::{DumpLayout, Entry, Passes, SchemeName, SlotWord, CATALOG};
use fragsim_schemes::kbuffer::WriteBack;

/// What `fragsim explain` shows of a catalog scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shown {
    /// A lost or duplicated fragment of the k-buffer on its machine ([`kbuffer`]).
    Hazard(WriteBack),
    /// MDTS's invariant at every step ([`mdts`]).
    Invariant,
    /// The spinlock's shortest deadlock under lockstep warps ([`spinlock`]).
    Deadlock,
}

impl Shown {
    /// What `explain` shows of `name`, from its catalog entry: the hazard of a one-pass k-buffer
    /// on its machine; the invariant of the scheme that heads the layout of ascending u64
    /// fragment words in K slots (the words the invariant's replay prints: `mdts`); the deadlock
    /// of the spinlock whose loop deadlocks under lockstep warps (its fixed loop has none to
    /// show); `None` otherwise.
    #[must_use]
    pub fn of(name: SchemeName) -> Option<Self> {
        let entry = name.entry();
        let fragment_slots = DumpLayout::SlotArray(SlotWord::Fragment);
        match (entry.read_modify_write, entry.passes, entry.dump) {
            (Some(machine), Passes::Fixed(1), _) => Some(Self::Hazard(machine)),
            _ if name == SchemeName::KbufferSpinlock => Some(Self::Deadlock),
            (None, Passes::Fixed(1), Some(layout))
                if layout == fragment_slots && layout.scheme() == name =>
            {
                Some(Self::Invariant)
            }
            _ => None,
        }
    }

    /// The catalog's entries `explain` shows, in catalog order.
    pub fn schemes() -> impl Iterator<Item = &'static Entry> {
        CATALOG.iter().filter(|e| Self::of(e.scheme).is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explained_schemes_are_catalog_entries_with_their_machine() {
        let names: Vec<&str> = Shown::schemes().map(|e| e.name).collect();
        assert_eq!(
            names,
            ["mdts", "kbuffer", "kbuffer-stores", "kbuffer-spinlock"]
        );
        assert_eq!(
            Shown::of(SchemeName::KbufferStores),
            Some(Shown::Hazard(WriteBack::SeparateStores))
        );
        assert_eq!(Shown::of(SchemeName::Abuffer), None);
    }
}
