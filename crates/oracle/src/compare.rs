//! Comparing a capture (a dump's decoded lists, or a run's) with a reference pixel by pixel: the
//! verdict of every pixel, and the totals.

mod allowance;

pub use allowance::MiscountedCounter;
pub(crate) use allowance::{counter_note, hold_to_reference};

use fragsim_capture::{Capacity, Capture, Identity, Keeps, PixelLists};
use serde::Serialize;

use crate::{Diff, Oracle, PixelMismatch};
use fragsim_dump::{CorruptWord, Counter, WordCheck};

/// A capture reduced to a coarser identity (e.g. to compare a u64 dump with a u32 reference).
#[must_use]
pub fn with_identity(capture: &Capture, identity: Identity) -> Capture {
    let mask = match identity {
        Identity::KeyAndPrim | Identity::MaskedNodes(_) => u64::MAX,
        Identity::KeyOnly => u64::MAX << 32,
        Identity::PrimOnly => u64::from(u32::MAX),
    };
    Capture {
        lists: PixelLists {
            offsets: capture.offsets.clone(),
            entries: capture.entries.iter().map(|e| e & mask).collect(),
        },
        identity,
        keeps: capture.keeps.clone(),
    }
}

/// Per-pixel verdict flags of a comparison (a pixel with none of [`flags::DIFFERS`] is equal).
pub mod flags {
    /// Fragments the reference has and the candidate should have kept are missing.
    pub const MISSING: u8 = 1;
    /// The candidate has fragments the reference does not.
    pub const EXTRA: u8 = 2;
    /// The candidate's list is out of canonical order.
    pub const MISORDERED: u8 = 4;
    /// Storage overflowed by design (beyond K, past a capacity): counted, not an error by itself.
    pub const OVERFLOWED: u8 = 8;
    /// An A-buffer counter that is not the pixel's fragment count: larger than the pixel could
    /// have, or an overflow `counter − capacity` other than `max(0, n − capacity)`.
    pub const MISCOUNTED: u8 = 16;
    /// A stored word that the layout says cannot be there ([`fragsim_dump::Corruption`]).
    pub const CORRUPT: u8 = 32;
    /// Every fragment matches one the reference allows, some with a depth other than the
    /// reference's but inside the precision bound ([`crate::precision`]): not an error.
    pub const WITHIN_PRECISION: u8 = 64;
    /// Coverage or order decided inside the precision margin: a fragment the reference has and
    /// a conforming implementation may lack (or the reverse), or a K-nearest cut among
    /// overlapping depth intervals. Counted and shown, never an error.
    pub const AMBIGUOUS: u8 = 128;
    /// Flags that make a pixel differ.
    pub const DIFFERS: u8 = MISSING | EXTRA | MISORDERED | MISCOUNTED | CORRUPT;

    /// Each flag with its name in reports, in report order.
    pub const NAMES: [(u8, &str); 8] = [
        (MISSING, "missing"),
        (EXTRA, "extra"),
        (MISORDERED, "misordered"),
        (OVERFLOWED, "overflowed"),
        (MISCOUNTED, "overflow-miscounted"),
        (CORRUPT, "corrupt"),
        (WITHIN_PRECISION, "within-precision"),
        (AMBIGUOUS, "ambiguous"),
    ];

    /// The names of the flags set in `flags`.
    #[must_use]
    pub fn names(flags: u8) -> Vec<&'static str> {
        NAMES
            .iter()
            .filter(|(flag, _)| flags & flag != 0)
            .map(|&(_, name)| name)
            .collect()
    }
}

/// Pixel counts per verdict; the JSON keys are the verdicts' names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct VerdictCounts {
    /// Pixels equal to the reference (possibly with overflow by design).
    pub equal: u64,
    /// Pixels missing fragments.
    pub missing: u64,
    /// Pixels with extra fragments.
    pub extra: u64,
    /// Pixels out of order.
    pub misordered: u64,
    /// Pixels whose storage overflowed by design.
    pub overflowed: u64,
    /// Pixels whose A-buffer counter is not their fragment count.
    #[serde(rename = "overflow-miscounted")]
    pub miscounted: u64,
    /// Pixels holding a word their layout says cannot be there.
    pub corrupt: u64,
    /// Pixels equal within the precision bound, not bit for bit.
    #[serde(rename = "within-precision")]
    pub within_precision: u64,
    /// Pixels whose coverage or order is decided inside the precision margin.
    pub ambiguous: u64,
}

impl VerdictCounts {
    /// Counts one pixel's flags.
    pub(crate) fn add(&mut self, flags: u8) {
        let counters = [
            (flags::MISSING, &mut self.missing),
            (flags::EXTRA, &mut self.extra),
            (flags::MISORDERED, &mut self.misordered),
            (flags::OVERFLOWED, &mut self.overflowed),
            (flags::MISCOUNTED, &mut self.miscounted),
            (flags::CORRUPT, &mut self.corrupt),
            (flags::WITHIN_PRECISION, &mut self.within_precision),
            (flags::AMBIGUOUS, &mut self.ambiguous),
        ];
        for (flag, count) in counters {
            *count += u64::from(flags & flag != 0);
        }
        self.equal += u64::from(flags & flags::DIFFERS == 0);
    }
}

/// The result of [`compare`] and [`compare_with`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Comparison {
    /// Totals over every pixel (the sum of one [`Oracle::diff`] per pixel), with the first
    /// `examples` differing pixels. `overflowed` is the overflow the reference predicts where it
    /// knows the pixel's fragment count (`max(0, n − capacity)`), not what counters claim;
    /// `mismatched_pixels` counts every pixel with a [`flags::DIFFERS`] flag.
    pub diff: Diff,
    /// Per pixel, `verdict` flags.
    pub verdicts: Vec<u8>,
    /// Pixels per verdict.
    pub counts: VerdictCounts,
    /// The overflow the candidate claims: its A-buffer counters' `Σ (counter − stored)`, or for
    /// MDTS what lies beyond K (its promise); equal to `diff.overflowed` unless a counter is
    /// miscounted.
    pub claimed_overflow: u64,
    /// Words that the layout says cannot be there (0 when no words were checked).
    pub corrupt_words: u64,
    /// Words a header could have defined but did not, not checked ([`WordCheck::unchecked`]).
    pub unchecked_words: u64,
    /// Words of room no counter handed out, not read ([`WordCheck::spare`]).
    pub spare_words: u64,
    /// Whether the candidate's words were checked at all ([`compare_with`] with a
    /// [`WordCheck`]), not only its decoded lists.
    pub words_checked: bool,
    /// The corrupt words of the pixels in `diff.first_mismatches`.
    pub first_corrupt: Vec<CorruptWord>,
    /// Of the [`flags::AMBIGUOUS`] pixels, how many each cause made so (a pixel may have
    /// several); all 0 outside a verdict within precision.
    pub ambiguity: AmbiguityCounts,
    /// What the capture told of the vertices' snaps (`docs/semantics.md` §10, "One snap per
    /// vertex"); all 0 outside a verdict within precision.
    pub snaps: SnapCounts,
    /// Linked lists: nodes the counter handed out that no list reaches ([`WordCheck::unreachable`]).
    /// Each is a fragment lost from the lists (missing at its pixel, where the node held one) or
    /// a counter that handed out a node no fragment took: never equal.
    pub unreachable_nodes: u64,
    /// Linked lists: a node counter other than any the reference's fragments allow
    /// ([`MiscountedCounter`]): never equal.
    pub miscounted_counter: Option<MiscountedCounter>,
}

/// The joint judgement of the pixels whose coverage hangs on a vertex's snap: every triangle
/// sharing a vertex takes it at the same grid point, so the capture's own pixels tell which.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SnapCounts {
    /// Vertices that may snap to more than one grid point and decide some pixel's coverage.
    pub undecided_vertices: u64,
    /// Of those, the vertices the capture pins to one grid point.
    pub pinned_vertices: u64,
    /// Pixels judged jointly over the snaps of their vertices.
    pub joint_pixels: u64,
    /// Of those, pixels whose coverage the pinned snaps decide (no longer ambiguous by coverage).
    pub decided_pixels: u64,
    /// Of those, pixels of a capture without primitive ids (key-only words) that more than one
    /// snap explains, all with the same number of fragments: the snaps differ only in which
    /// triangle a stored key came from, which the dump does not record. Every key lies in the
    /// interval of the fragment each snap matches it to, so the pixel is decided in all the dump
    /// records (`docs/semantics.md` §10, "One snap per vertex"), and not ambiguous.
    pub unnamed_pixels: u64,
    /// Pixels that no snap of their vertices explains together with the rest of the capture:
    /// judged under the snaps the rest of the capture pins, where they are errors.
    pub contradicting_pixels: u64,
    /// Pixels with more joint snaps than are enumerated (judged fragment by fragment).
    pub unjoined_pixels: u64,
}

/// Ambiguous pixels by what left them undecided (`docs/semantics.md` §10, Verdict).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct AmbiguityCounts {
    /// A fragment whose coverage is decided inside the margin: present though the reference
    /// does not cover it, or absent though it does.
    pub coverage: u64,
    /// A fragment whose coverage is certain but whose depth interval leaves `[0, 1]` (it may be
    /// clipped away) and which is absent or matched only by that interval.
    pub depth: u64,
    /// A K-nearest (K-farthest) cut among overlapping depth intervals.
    pub order: u64,
    /// A fragment of a triangle the reference clips (not analysed).
    pub clipped: u64,
}

impl AmbiguityCounts {
    /// Adds `other`'s counts.
    pub(crate) fn add(&mut self, other: &Self) {
        self.coverage += other.coverage;
        self.depth += other.depth;
        self.order += other.order;
        self.clipped += other.clipped;
    }
}

impl Comparison {
    /// An empty comparison of `pixels` pixels, with the totals of `words`.
    pub(crate) fn new(pixels: usize, words: Option<&WordCheck>) -> Self {
        Self {
            diff: Diff::default(),
            verdicts: Vec::with_capacity(pixels),
            counts: VerdictCounts::default(),
            claimed_overflow: 0,
            corrupt_words: words.map_or(0, WordCheck::corrupt_words),
            unchecked_words: words.map_or(0, |w| w.unchecked),
            spare_words: words.map_or(0, |w| w.spare),
            words_checked: words.is_some(),
            first_corrupt: Vec::new(),
            ambiguity: AmbiguityCounts::default(),
            snaps: SnapCounts::default(),
            unreachable_nodes: words.map_or(0, |w| w.unreachable),
            miscounted_counter: None,
        }
    }

    /// Records pixel `p`'s verdict `flags` (pixels come in order): counted, and where it
    /// differs kept as one of the first `examples` (`example` builds it, with the pixel's
    /// corrupt words from `words`).
    pub(crate) fn record(
        &mut self,
        p: usize,
        flags: u8,
        examples: usize,
        words: Option<&WordCheck>,
        example: impl FnOnce() -> PixelMismatch,
    ) {
        self.counts.add(flags);
        if flags & flags::DIFFERS != 0 {
            self.diff.mismatched_pixels += 1;
            if self.diff.first_mismatches.len() < examples {
                self.diff.first_mismatches.push(PixelMismatch {
                    pixel: p,
                    ..example()
                });
                if let Some(words) = words {
                    self.first_corrupt.extend_from_slice(&words.corrupt[p]);
                }
            }
        }
        self.verdicts.push(flags);
    }

    /// Adds `flags` to the verdicts of the pixels in `flagged` after every pixel was recorded:
    /// what the lists cannot show (a masked node's coverage mask). The counts are taken again,
    /// and each pixel that now differs joins the examples (`example` builds it) when it is among
    /// the first `examples` differing pixels.
    pub(crate) fn add_flags(
        &mut self,
        flagged: &[(usize, u8)],
        examples: usize,
        example: impl Fn(usize) -> PixelMismatch,
    ) {
        for &(p, flags) in flagged {
            let before = self.verdicts[p];
            self.verdicts[p] |= flags;
            let shown = self.diff.first_mismatches.iter().any(|m| m.pixel == p);
            if before & flags::DIFFERS == 0 && flags & flags::DIFFERS != 0 && !shown {
                self.diff.first_mismatches.push(example(p));
            }
        }
        self.diff.first_mismatches.sort_by_key(|m| m.pixel);
        self.diff.first_mismatches.truncate(examples);
        self.counts = VerdictCounts::default();
        for &v in &self.verdicts {
            self.counts.add(v);
        }
        self.diff.mismatched_pixels = self
            .verdicts
            .iter()
            .filter(|&&v| v & flags::DIFFERS != 0)
            .count() as u64;
    }

    /// Whether every pixel is equal (overflow by design allowed), every node a linked list's
    /// counter handed out is in a list, and the counter is one the reference allows.
    #[must_use]
    pub fn is_equal(&self) -> bool {
        self.diff.is_exact() && self.unreachable_nodes == 0 && self.miscounted_counter.is_none()
    }
}

/// How [`compare_with`] judges.
#[derive(Clone, Copy, Debug, Default)]
pub struct CompareOptions<'a> {
    /// Accept a candidate key within this many f32 ulps of an otherwise unmatched reference
    /// fragment of the same primitive (any, for key-only words); 0: bit for bit.
    pub depth_ulps: u32,
    /// How many differing pixels to keep as examples.
    pub examples: usize,
    /// Per pixel, whether the reference knows every fragment there; `None`: everywhere, as the
    /// oracle does. An A-buffer counter is checked against the pixel's fragment count only
    /// where the reference knows it ([`complete_pixels`] of a dump used as the reference).
    pub complete: Option<&'a [bool]>,
}

/// Per pixel, whether a capture holds every fragment of the pixel: fewer than K in an MDTS
/// pixel, no overflow in an A-buffer one. Where it does not, a comparison against it cannot
/// know the pixel's fragment count.
#[must_use]
pub fn complete_pixels(capture: &Capture) -> Vec<bool> {
    (0..capture.pixels())
        .map(|p| match &capture.keeps {
            Keeps::Nearest(k) | Keeps::Farthest(k) => capture.pixel(p).len() < *k as usize,
            Keeps::All { overflow, .. } => overflow[p] == 0,
        })
        .collect()
}

/// Compares `candidate`'s decoded lists with `reference` pixel by pixel under the candidate's
/// promise ([`compare_with`] with no word check and a reference that knows every fragment).
///
/// # Panics
/// If the capture and the reference cover different numbers of pixels.
#[must_use]
pub fn compare(
    reference: &Oracle,
    candidate: &Capture,
    depth_ulps: u32,
    examples: usize,
) -> Comparison {
    let options = CompareOptions {
        depth_ulps,
        examples,
        complete: None,
    };
    compare_with(reference, candidate, None, &options)
}

/// An A-buffer pixel's counter as a capture alone shows it: `stored + overflow`, and a capacity
/// of `stored` when it overflowed (storage ran out), unknown (at least `stored`) when not.
#[expect(
    clippy::cast_possible_truncation,
    reason = "stored slots are at most the pixel's capacity, a u32"
)]
pub(crate) fn inferred_counter(stored: usize, overflow: u32) -> Counter {
    Counter {
        // Saturating: a memory dump's words can claim any overflow (found by `dump_layouts`).
        count: (stored as u32).saturating_add(overflow),
        capacity: if overflow > 0 {
            stored as u32
        } else {
            u32::MAX
        },
    }
}

/// Compares `candidate` with `reference` pixel by pixel under the candidate's promise, with
/// [`Oracle::diff`] on each pixel, and adds what `words` (the candidate dump's
/// [`WordCheck`]) found: a pixel with a corrupt word is [`flags::CORRUPT`] whatever its list,
/// and an A-buffer slot holding the empty marker is taken out of the list (it is no fragment,
/// so it is corrupt, not extra).
///
/// An A-buffer counter must equal its pixel's fragment count `n`, which the reference knows
/// (where `options.complete` says so): every fragment adds one and the counter never wraps. A
/// counter that differs is [`flags::MISCOUNTED`]: larger than the pixel could have, or an
/// overflow `counter − capacity` other than `max(0, n − capacity)`. The overflow allowed to be
/// missing is then `max(0, n − capacity)`, never what the counter claims; without `words` the
/// counter and capacity are inferred from the capture ([`Keeps::All`]'s overflow).
///
/// With `options.depth_ulps > 0`, a candidate fragment whose key lies within that many f32 ulps
/// of an otherwise unmatched reference fragment of the same primitive (any, for key-only words)
/// counts as that fragment; a list the candidate stored in order stays in order.
///
/// # Panics
/// If the capture, the reference, `words` or `options.complete` cover different numbers of
/// pixels.
#[must_use]
#[expect(
    clippy::cast_possible_truncation,
    reason = "n is a pixel's reference count: a pixel holds at most one fragment per triangle, and triangle ids are u32"
)]
pub fn compare_with(
    reference: &Oracle,
    candidate: &Capture,
    words: Option<&WordCheck>,
    options: &CompareOptions<'_>,
) -> Comparison {
    let pixels = candidate.pixels();
    assert_eq!(
        reference.pixels(),
        pixels,
        "capture and reference cover different viewports"
    );
    if let Some(words) = words {
        assert_eq!(
            words.corrupt.len(),
            pixels,
            "word check of another viewport"
        );
    }
    if let Some(complete) = options.complete {
        assert_eq!(complete.len(), pixels, "completeness of another viewport");
    }
    let mut comparison = Comparison::new(pixels, words);
    let mut one_ref = Oracle {
        lists: PixelLists {
            offsets: vec![0, 0],
            entries: Vec::new(),
        },
    };
    let mut one = Capture::with_pixels(1, candidate.identity, Keeps::Nearest(0));
    one.offsets.push(0);
    for p in 0..pixels {
        let all = reference.pixel(p);
        let n = all.len();
        let knows_n = options.complete.is_none_or(|c| c[p]);
        one_ref.lists.entries.clear();
        one_ref.lists.entries.extend_from_slice(all);
        one_ref.lists.offsets[1] = n;
        let got = candidate.pixel(p);
        one.entries.clear();
        let mut flags = 0;
        one.keeps = match &candidate.keeps {
            Keeps::All {
                overflow,
                capacity: kept,
            } => {
                let counter = match (words.and_then(|w| w.counters.as_ref()), kept) {
                    (Some(counters), _) => counters[p],
                    // Storage that discards its overflow uncounted (Bevy's clamp, a list resolve
                    // stopping at `C` nodes, the ordered interlock keeping the first `C`): its
                    // count is the reference's, and its capacity is known.
                    (None, Capacity::PerPixelUncounted(c)) if knows_n => Counter {
                        count: n as u32,
                        capacity: *c,
                    },
                    (None, _) => inferred_counter(got.len(), overflow[p]),
                };
                comparison.claimed_overflow += u64::from(overflow[p]);
                // The marker is no fragment: its word check calls it corrupt.
                let marker_is_corrupt = words.is_some();
                one.entries
                    .extend(got.iter().filter(|&&e| !marker_is_corrupt || e != u64::MAX));
                let (capacity, allowed) = if knows_n {
                    if counter.count as usize != n {
                        flags |= flags::MISCOUNTED;
                    }
                    let allowed = n.saturating_sub(counter.capacity as usize) as u32;
                    (Capacity::PerPixel(counter.capacity), allowed)
                } else {
                    // The reference does not know the count: the claimed overflow stands, as
                    // the capacity that predicts exactly it from the fragments the reference has.
                    let stands = n.saturating_sub(overflow[p] as usize) as u32;
                    (Capacity::PerPixel(stands), overflow[p])
                };
                Keeps::All {
                    capacity,
                    overflow: vec![allowed],
                }
            }
            keeps => {
                one.entries.extend_from_slice(got);
                keeps.clone()
            }
        };
        let counted = matches!(candidate.keeps, Keeps::All { .. });
        if options.depth_ulps > 0 {
            snap_to_reference(
                &mut one.entries,
                all,
                candidate.identity,
                options.depth_ulps,
            );
        }
        one.offsets[1] = one.entries.len();
        let d = one_ref.diff(&one);
        if words.is_some_and(|w| !w.corrupt[p].is_empty()) {
            flags |= flags::CORRUPT;
        }
        if d.lost > 0 {
            flags |= flags::MISSING;
        }
        if d.extra > 0 {
            flags |= flags::EXTRA;
        }
        if d.misordered_pixels > 0 {
            flags |= flags::MISORDERED;
        }
        if d.overflowed > 0 {
            flags |= flags::OVERFLOWED;
        }
        // A pixel the diff rejects for no other reason has fewer fragments missing than the
        // overflow it was allowed. Where the reference knows the count that cannot happen (the
        // allowance is `n − capacity` and at most `capacity` are held), so it is named a miscount
        // rather than left unnamed; where the reference does not know the count, the claimed
        // overflow is all there is and a reference holding no more than the candidate is no gap.
        if d.mismatched_pixels > 0 && flags & flags::DIFFERS == 0 && knows_n {
            flags |= flags::MISCOUNTED;
        }
        if !counted {
            // MDTS claims nothing: what lies beyond K is its promise.
            comparison.claimed_overflow += d.overflowed;
        }
        let total = &mut comparison.diff;
        total.captured += d.captured;
        total.overflowed += d.overflowed;
        total.lost += d.lost;
        total.extra += d.extra;
        total.misordered_pixels += d.misordered_pixels;
        comparison.record(p, flags, options.examples, words, || {
            d.first_mismatches.into_iter().next().unwrap_or_else(|| {
                // Equal lists, wrong words: both sides are the list the pixel holds.
                PixelMismatch {
                    pixel: p,
                    expected: one.entries.clone(),
                    got: one.entries.clone(),
                }
            })
        });
    }
    hold_to_reference(&mut comparison, candidate, words, reference, None, options);
    comparison
}

/// Replaces each candidate fragment that has no exact match in `reference` by the nearest
/// unmatched reference fragment of the same primitive within `ulps` (the depth key is the f32's
/// bit pattern, so a key difference is a distance in ulps).
fn snap_to_reference(got: &mut [u64], reference: &[u64], identity: Identity, ulps: u32) {
    if identity == Identity::PrimOnly {
        return;
    }
    let mask = if identity == Identity::KeyOnly {
        u64::MAX << 32
    } else {
        u64::MAX
    };
    let was_sorted = got.windows(2).all(|w| w[0] <= w[1]);
    let mut used = vec![false; reference.len()];
    let mut unmatched = Vec::new();
    for (i, g) in got.iter().enumerate() {
        match (0..reference.len()).find(|&j| !used[j] && reference[j] & mask == *g) {
            Some(j) => used[j] = true,
            None => unmatched.push(i),
        }
    }
    for i in unmatched {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
        )]
        let (key, prim) = ((got[i] >> 32) as u32, got[i] as u32);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
        )]
        let nearest = (0..reference.len())
            .filter(|&j| !used[j])
            .filter(|&j| identity == Identity::KeyOnly || reference[j] as u32 == prim)
            .map(|j| (((reference[j] >> 32) as u32).abs_diff(key), j))
            .filter(|&(distance, _)| distance <= ulps)
            .min();
        if let Some((_, j)) = nearest {
            used[j] = true;
            got[i] = reference[j] & mask;
        }
    }
    if was_sorted {
        got.sort_unstable();
    }
}
