//! What a candidate owes beyond its lists' fragments, derived from the reference and the
//! declared scheme, never taken from the candidate's own storage (`docs/semantics.md`,
//! "Allowances come from the reference").
//!
//! The per-pixel comparisons ([`compare_with`](crate::compare::compare_with),
//! [`compare_within`](crate::precision::compare_within)) judge each list under the capture's
//! promise and each A-buffer counter against the pixel's fragment count. Two promises reach past a
//! pixel's list and are held here, after every pixel was judged, by both comparisons alike:
//!
//! - **The first K in primitive order** (`kbuffer-interlock-ordered-first`): a full list holds
//!   the K fragments submitted first, so every fragment the reference is certain of whose
//!   primitive comes before the last one held must be held. Any K would pass the capacity's
//!   allowance alone (`max(0, n − K)` missing), whichever K they are.
//! - **A linked list's node counter** counts every allocation, past the pool's end too: it ends
//!   at the number of fragments the scene has, whatever the pool size. Its allowance (the
//!   reference's count, or under an f32 vertex stage the counts from the certain fragments to
//!   every possible one) comes from the reference, so a pool that equals the fragment count
//!   cannot hide a counter past it.

use fragsim_capture::{Capture, Identity};
use serde::Serialize;

use crate::compare::{flags, CompareOptions, Comparison};
use crate::precision::Precision;
use crate::{Oracle, PixelMismatch};
use fragsim_dump::WordCheck;

/// A linked list's node counter outside the counts the reference allows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct MiscountedCounter {
    /// The counter as stored.
    pub counter: u32,
    /// The fewest fragments the scene may have (the reference's count under exact vertices).
    pub least: u64,
    /// The most fragments the scene may have.
    pub most: u64,
}

/// The note that names a miscounted node counter, if the comparison found one.
pub(crate) fn counter_note(comparison: &Comparison) -> Option<String> {
    comparison.miscounted_counter.map(|m| {
        let owed = if m.least == m.most {
            m.least.to_string()
        } else {
            format!("{} to {}", m.least, m.most)
        };
        format!(
            "the node counter is {}, the reference holds {owed} fragments: a counter counts every \
             allocation, past the pool's end too, so it ends at the fragment count whatever the \
             pool",
            m.counter
        )
    })
}

/// Holds the candidate to what its declared scheme owes beyond each list (see the module
/// documentation): its verdicts and totals amended in `comparison`. `precision` is the f32
/// analysis where the comparison was within it (`None`: every fragment of `reference` is
/// certain); `options.complete` says where a reference dump knows every fragment.
#[expect(
    clippy::cast_possible_truncation,
    reason = "an entry's low half is its primitive id"
)]
pub(crate) fn hold_to_reference(
    comparison: &mut Comparison,
    candidate: &Capture,
    words: Option<&WordCheck>,
    reference: &Oracle,
    precision: Option<&Precision>,
    options: &CompareOptions<'_>,
) {
    let Some(words) = words else {
        return;
    };
    let knows = |p: usize| options.complete.is_none_or(|c| c[p]);
    // Each pixel's fragments as (primitive, certain).
    let owed = |p: usize| -> Vec<(u32, bool)> {
        match precision {
            Some(precision) => precision
                .pixel(p)
                .iter()
                .map(|e| (e.prim, e.certain()))
                .collect(),
            None => reference
                .pixel(p)
                .iter()
                .map(|&e| (e as u32, true))
                .collect(),
        }
    };
    if let Some(counter) = words.list_counter {
        let pixels = 0..reference.pixels();
        if pixels.clone().all(knows) {
            let (least, most) = pixels.fold((0, 0), |(least, most), p| {
                let fragments = owed(p);
                let certain = fragments.iter().filter(|(_, c)| *c).count() as u64;
                (least + certain, most + fragments.len() as u64)
            });
            if !(least..=most).contains(&u64::from(counter)) {
                comparison.miscounted_counter = Some(MiscountedCounter {
                    counter,
                    least,
                    most,
                });
            }
        }
    }
    let Some(k) = words.first_in_primitive_order else {
        return;
    };
    if candidate.identity != Identity::KeyAndPrim {
        return;
    }
    let mut late = Vec::new();
    for p in (0..candidate.pixels()).filter(|&p| knows(p)) {
        let held: Vec<u32> = candidate
            .pixel(p)
            .iter()
            .filter(|&&e| e != u64::MAX)
            .map(|&e| e as u32)
            .collect();
        // A list short of K left nothing out: the comparison owes it every certain fragment.
        let Some(&last) = held.iter().max().filter(|_| held.len() >= k as usize) else {
            continue;
        };
        let skipped = owed(p)
            .iter()
            .filter(|&&(prim, certain)| certain && prim < last && !held.contains(&prim))
            .count() as u64;
        if skipped > 0 {
            comparison.diff.lost += skipped;
            comparison.diff.overflowed = comparison.diff.overflowed.saturating_sub(skipped);
            late.push((p, flags::MISSING));
        }
    }
    comparison.add_flags(&late, options.examples, |p| PixelMismatch {
        pixel: p,
        expected: reference.pixel(p).to_vec(),
        got: candidate.pixel(p).to_vec(),
    });
}
