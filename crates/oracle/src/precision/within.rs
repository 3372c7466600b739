//! The verdict under precision: a capture judged against what a conforming implementation may
//! produce ([`super::Precision`]) rather than against the reference's exact fragments.
//!
//! Guarantee: a pixel is an error only where no conforming implementation could have produced
//! it: a `certain` fragment absent where the promise owes it (missing), a fragment no possibility
//! admits (extra: another triangle, or a depth outside its interval), a list out of its own
//! stored order (misordered: an implementation sorts its own depths), a counter outside the
//! counts the pixel may have (overflow-miscounted), a corrupt word. Where the reference could
//! go either way the pixel is [`flags::AMBIGUOUS`]; equal with some depth moved inside its
//! interval, [`flags::WITHIN_PRECISION`]. With an exact analysis (f64 vertex precision) this is
//! [`compare_with`], unchanged.

use std::path::Path;

use fragsim_capture::{Capacity, Capture, Identity, Keeps};
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::{Conventions, Viewport};

use super::{Doubt, Possible, Precision};
use crate::compare::{
    compare_with, flags, inferred_counter, AmbiguityCounts, CompareOptions, Comparison,
};
use crate::{Oracle, PixelMismatch};
use fragsim_dump::{DumpError, WordCheck};
use fragsim_raster::scene_spec::SceneSpec;
use snaps::Snaps;

mod snaps;

/// The reference an f32 vertex stage is judged against: the oracle of `scene` on `viewport`
/// under its declared conventions but with the exact f64 vertex stage, and the analysis of an
/// f32 one under the same conventions (what `fragsim compare oracle DIR --vertex-precision f32`
/// builds). The bounds measure an implementation's distance from the exact positions, not from
/// another f32 evaluation order. `beside` is where a dump's relative mesh path is looked up.
///
/// # Errors
/// A scene that cannot be loaded or rasterized ([`SceneSpec::load`],
/// [`SceneSpec::view`]), or whose f32 vertex stage would leave f32's normal range
/// ([`fragsim_raster::View::check_f32_range`]).
pub fn f32_reference(
    scene: &SceneSpec,
    viewport: Viewport,
    beside: Option<&Path>,
) -> Result<(Oracle, Precision), DumpError> {
    let mut exact = scene.clone();
    exact.conventions.vertex_precision = VertexPrecision::F64;
    let loaded = exact.load(beside)?;
    let view = exact.view(&loaded, viewport)?;
    view.check_f32_range()
        .map_err(|e| DumpError::Invalid(format!("scene: {e}")))?;
    let f32_stage = Conventions {
        vertex_precision: VertexPrecision::F32,
        ..exact.conventions
    };
    Ok((Oracle::build(&view), Precision::derive(&view, &f32_stage)))
}

/// Compares `candidate` with what `precision` allows, pixel by pixel under the candidate's
/// promise; `reference` (the oracle of the same view) gives the examples' expected lists. With
/// `options.depth_ulps > 0` every interval is widened by that many ulps on each side (the manual
/// override). `options.complete` is ignored (the reference is the oracle, which knows every
/// pixel's fragments).
///
/// # Panics
/// If the capture, the reference, the analysis or `words` cover different numbers of pixels.
#[must_use]
pub fn compare_within(
    precision: &Precision,
    reference: &Oracle,
    candidate: &Capture,
    words: Option<&WordCheck>,
    options: &CompareOptions<'_>,
) -> Comparison {
    if precision.is_exact() {
        return compare_with(reference, candidate, words, options);
    }
    let pixels = candidate.pixels();
    assert_eq!(reference.pixels(), pixels, "capture and reference differ");
    assert_eq!(precision.pixels(), pixels, "analysis of another viewport");
    if let Some(words) = words {
        assert_eq!(
            words.corrupt.len(),
            pixels,
            "word check of another viewport"
        );
    }
    let mut comparison = Comparison::new(pixels, words);
    let pixel_of = |p: usize| Pixel {
        p,
        got: candidate
            .pixel(p)
            .iter()
            .copied()
            // The marker is no fragment: its word check calls it corrupt.
            .filter(|&e| {
                words.is_none() || !matches!(candidate.keeps, Keeps::All { .. }) || e != u64::MAX
            })
            .collect(),
        candidate,
        words,
        widen: options.depth_ulps,
        twins: &precision.twins,
    };
    let snaps = Snaps::infer(precision, &pixel_of);
    comparison.snaps = snaps.counts;
    for p in 0..pixels {
        let pixel = pixel_of(p);
        let judged = snaps.judge(precision, &pixel, &mut comparison.snaps);
        let got = pixel.got;
        let mut flags = judged.flags;
        if words.is_some_and(|w| !w.corrupt[p].is_empty()) {
            flags |= flags::CORRUPT;
        }
        comparison.claimed_overflow += judged.claimed_overflow;
        comparison.ambiguity.add(&judged.ambiguity);
        let total = &mut comparison.diff;
        total.captured += got.len() as u64;
        total.overflowed += judged.overflowed;
        total.lost += judged.lost;
        total.extra += judged.extra;
        total.misordered_pixels += u64::from(flags & flags::MISORDERED != 0);
        total.overflow_miscounted_pixels += u64::from(flags & flags::MISCOUNTED != 0);
        comparison.record(p, flags, options.examples, words, || {
            let mask = match candidate.identity {
                Identity::KeyAndPrim | Identity::MaskedNodes(_) => u64::MAX,
                Identity::KeyOnly => u64::MAX << 32,
                Identity::PrimOnly => u64::from(u32::MAX),
            };
            PixelMismatch {
                pixel: p,
                expected: reference.pixel(p).iter().map(|e| e & mask).collect(),
                got: got.clone(),
            }
        });
    }
    crate::compare::hold_to_reference(
        &mut comparison,
        candidate,
        words,
        reference,
        Some(precision),
        options,
    );
    comparison
}

/// One pixel of the capture as the verdict reads it.
struct Pixel<'a> {
    p: usize,
    /// Its stored fragment words, without A-buffer markers.
    got: Vec<u64>,
    candidate: &'a Capture,
    words: Option<&'a WordCheck>,
    widen: u32,
    /// Per primitive, its first twin ([`Precision`]'s `twins`).
    twins: &'a [u32],
}

impl Pixel<'_> {
    /// The pixel judged against `possible` fragment by fragment.
    fn judge(&self, possible: &[Possible]) -> Judged {
        judge_pixel(
            possible,
            &self.got,
            self.candidate,
            self.p,
            self.words,
            self.widen,
            self.twins,
        )
    }

    /// Whether its words are corrupt (no evidence of anything).
    fn corrupt(&self) -> bool {
        self.words.is_some_and(|w| !w.corrupt[self.p].is_empty())
    }
}

/// One pixel's judgement.
#[derive(Default)]
struct Judged {
    flags: u8,
    lost: u64,
    extra: u64,
    overflowed: u64,
    claimed_overflow: u64,
    /// What made the pixel ambiguous: each cause 0 or 1.
    ambiguity: AmbiguityCounts,
}

impl Judged {
    /// Marks the pixel ambiguous because of `doubt`.
    fn doubt(&mut self, doubt: Doubt) {
        self.flags |= flags::AMBIGUOUS;
        let cause = match doubt {
            Doubt::Coverage => &mut self.ambiguity.coverage,
            Doubt::Depth => &mut self.ambiguity.depth,
            Doubt::Clipped => &mut self.ambiguity.clipped,
        };
        *cause = 1;
    }
}

/// Assigns candidate fragments to possibilities: a maximum matching of candidate words to the
/// possibilities that admit them (its primitive, its key inside the interval widened by
/// `widen`), which among the maximum ones matches as many `certain` possibilities as any can.
/// Kuhn's augmenting paths from the possibility side, the certain ones first: a possibility once
/// matched stays matched while later ones augment, so the certain ones matched are a maximum set
/// of them and the whole matching is maximum (a greedy rule is not: with key-only words and
/// overlapping intervals it left certain fragments unmatched beside a match it could have moved).
/// Each possibility tries its exact reference key first, so an equal pixel reads equal.
///
/// Under a K-nearest (K-farthest) promise the certain possibilities go nearest (farthest)
/// first: an absent one is excused only where K others may be ahead of it, so the one to leave
/// unmatched is the farthest (nearest) that can be, and augmenting paths in that order keep the
/// matched set optimal on every prefix of it (the greedy rule of a transversal matroid). In
/// submission order instead, a far fragment whose wide interval also held a near key took it and
/// left a near certain fragment unmatched: one false missing pixel in every `mdts32` capture of
/// `bunny-spheres` at 512² (`docs/results/verdict-lavapipe.md`).
fn assign(
    possible: &[Possible],
    got: &[u64],
    identity: Identity,
    widen: u32,
    keeps: &Keeps,
) -> Vec<Option<usize>> {
    let admits = |q: &Possible, word: u64| {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
        )]
        let (key, prim) = ((word >> 32) as u32, word as u32);
        let inside =
            || key >= q.key_lo.saturating_sub(widen) && key <= q.key_hi.saturating_add(widen);
        match identity {
            Identity::PrimOnly => q.prim == prim,
            Identity::KeyOnly => inside(),
            Identity::KeyAndPrim | Identity::MaskedNodes(_) => q.prim == prim && inside(),
        }
    };
    // Per possibility, the candidates it admits, an exact reference match first.
    let edges: Vec<Vec<usize>> = possible
        .iter()
        .map(|q| {
            let mut admitted: Vec<usize> = (0..got.len()).filter(|&i| admits(q, got[i])).collect();
            admitted.sort_by_key(|&i| {
                identity == Identity::PrimOnly || q.reference != Some((got[i] >> 32) as u32)
            });
            admitted
        })
        .collect();
    let mut partner: Vec<Option<usize>> = vec![None; got.len()];
    let mut order: Vec<usize> = (0..possible.len()).collect();
    match keeps {
        Keeps::Nearest(_) => order.sort_by_key(|&j| (!possible[j].certain(), possible[j].key_hi)),
        Keeps::Farthest(_) => {
            order.sort_by_key(|&j| {
                (
                    !possible[j].certain(),
                    std::cmp::Reverse(possible[j].key_lo),
                )
            });
        }
        Keeps::All { .. } => order.sort_by_key(|&j| !possible[j].certain()),
    }
    for j in order {
        let mut seen = vec![false; got.len()];
        augment(j, &edges, &mut partner, &mut seen);
    }
    partner
}

/// One augmenting path from possibility `j` (Kuhn): a free candidate it admits, or one whose
/// possibility can move to another.
fn augment(
    j: usize,
    edges: &[Vec<usize>],
    partner: &mut [Option<usize>],
    seen: &mut [bool],
) -> bool {
    for &i in &edges[j] {
        if seen[i] {
            continue;
        }
        seen[i] = true;
        let current = partner[i];
        if current.is_none_or(|other| augment(other, edges, partner, seen)) {
            partner[i] = Some(j);
            return true;
        }
    }
    false
}

fn judge_pixel(
    possible: &[Possible],
    got: &[u64],
    candidate: &Capture,
    p: usize,
    words: Option<&WordCheck>,
    widen: u32,
    twins: &[u32],
) -> Judged {
    let identity = candidate.identity;
    let mut judged = Judged::default();
    let assigned = assign(possible, got, identity, widen, &candidate.keeps);
    let mut matched = vec![false; possible.len()];
    for (i, a) in assigned.iter().enumerate() {
        match a {
            None => judged.extra += 1,
            Some(j) => {
                matched[*j] = true;
                let q = &possible[*j];
                if let Some(doubt) = q.doubt {
                    judged.doubt(doubt);
                }
                let key = (got[i] >> 32) as u32;
                if identity != Identity::PrimOnly && q.reference != Some(key) {
                    judged.flags |= flags::WITHIN_PRECISION;
                }
            }
        }
    }
    // A reference fragment that may be absent and is: the coverage (or a clip) went the other way.
    for (q, _) in possible.iter().zip(&matched).filter(|(_, &m)| !m) {
        if let (Some(doubt), Some(_)) = (q.doubt, q.reference) {
            judged.doubt(doubt);
        }
    }
    let absent_certain: Vec<usize> = (0..possible.len())
        .filter(|&j| !matched[j] && possible[j].certain())
        .collect();
    let widened = |q: &Possible| {
        (
            q.key_lo.saturating_sub(widen),
            q.key_hi.saturating_add(widen),
        )
    };
    match &candidate.keeps {
        Keeps::Nearest(k) | Keeps::Farthest(k) => {
            let nearest = matches!(candidate.keeps, Keeps::Nearest(_));
            let k = *k as usize;
            if got.len() > k {
                judged.extra += (got.len() - k) as u64;
            }
            // A conforming list leaves a fragment it produced out only when it holds K fragments
            // ahead of it in the promise's order (nearer for K nearest, farther for K farthest),
            // and those are the fragments it holds: so an absent certain fragment is excused only
            // by K held fragments that may each be ahead of it. Fragments that could have been
            // ahead but are not in the list excuse nothing (a list of fewer than K fragments
            // left nothing out).
            let held: Vec<usize> = assigned.iter().flatten().copied().collect();
            // Twins (the same vertex indices) have the same depth in any implementation: which
            // one is ahead is the tie rule's, by primitive id, as the exact verdict has it. Words
            // without ids cannot tell them apart.
            let twin_ahead = |j: usize, f: usize| {
                let (a, b) = (possible[j].prim, possible[f].prim);
                let same = identity != Identity::KeyOnly
                    && a != b
                    && twins
                        .get(a as usize)
                        .is_some_and(|&t| twins.get(b as usize) == Some(&t));
                same.then_some(if nearest { a < b } else { a > b })
            };
            let mut owed = 0;
            for &f in &absent_certain {
                let (f_lo, f_hi) = widened(&possible[f]);
                let (mut surely, mut maybe) = (0, 0);
                for &j in &held {
                    let (lo, hi) = widened(&possible[j]);
                    let (sure, could) = if let Some(ahead) = twin_ahead(j, f) {
                        (ahead, ahead)
                    } else if nearest {
                        (hi < f_lo, lo <= f_hi)
                    } else {
                        (lo > f_hi, hi >= f_lo)
                    };
                    surely += usize::from(sure);
                    maybe += usize::from(could);
                }
                if maybe < k {
                    owed += 1;
                } else if surely >= k {
                    judged.overflowed += 1;
                } else {
                    judged.flags |= flags::AMBIGUOUS;
                    judged.ambiguity.order = 1;
                }
            }
            // The fragments lost are those the list lacks of the K it owes: K less what it holds
            // (one at least where a held fragment took an owed one's place); the other owed
            // fragments lie past the K nearest (farthest), beyond storage as the reference predicts.
            let lost = owed.min(k.saturating_sub(held.len()).max(1));
            judged.lost += lost as u64;
            judged.overflowed += (owed - lost) as u64;
            if judged.overflowed > 0 {
                judged.flags |= flags::OVERFLOWED;
            }
        }
        Keeps::All { capacity, overflow } => {
            let counter = match words.and_then(|w| w.counters.as_ref()) {
                Some(counters) => counters[p],
                None => inferred_counter(got.len(), overflow[p]),
            };
            judged.claimed_overflow = u64::from(overflow[p]);
            let certain = possible.iter().filter(|q| q.certain()).count();
            let count = counter.count as usize;
            let cap = match capacity {
                Capacity::Unbounded => usize::MAX,
                Capacity::PerPixel(_) => counter.capacity as usize,
                // Storage that stops at `c` without a count (a keep-first list's resolve): which
                // fragments a full list keeps follows arrival order, which the reference cannot
                // know, so any of them may be absent.
                Capacity::PerPixelUncounted(c) => *c as usize,
            };
            let counted = !matches!(capacity, Capacity::PerPixelUncounted(_));
            if counted && (count < certain || count > possible.len()) {
                judged.flags |= flags::MISCOUNTED;
            }
            let held = assigned.iter().flatten().count();
            // The fragments storage could not hold: the implementation's own count past the
            // capacity where it is one the pixel may have (a miscounted pixel is an error
            // already). Uncounted storage keeps every arrival until it is full, so a full list
            // may have left out any; a shorter one left nothing out, and lacks `cap − held` of
            // the fragments it owes (the others lie past its capacity).
            let allowed = if counted && count >= certain && count <= possible.len() {
                count.saturating_sub(cap)
            } else if !counted && held < cap {
                absent_certain.len().saturating_sub(cap - held)
            } else {
                possible.len().saturating_sub(cap)
            };
            judged.overflowed = allowed.min(absent_certain.len()) as u64;
            judged.lost = absent_certain.len().saturating_sub(allowed) as u64;
            if judged.overflowed > 0 {
                judged.flags |= flags::OVERFLOWED;
            }
        }
    }
    if judged.lost > 0 {
        judged.flags |= flags::MISSING;
    }
    if judged.extra > 0 {
        judged.flags |= flags::EXTRA;
    }
    let misordered = match identity {
        // Bare ids: out of order only where the stored neighbours' depths are decided reversed.
        Identity::PrimOnly => assigned.windows(2).any(|w| match (w[0], w[1]) {
            (Some(a), Some(b)) => possible[a].key_lo > possible[b].key_hi.saturating_add(widen),
            _ => false,
        }),
        // An implementation sorts its own depths: its stored list is in its own order.
        _ => got.windows(2).any(|w| w[0] > w[1]),
    };
    if misordered {
        judged.flags |= flags::MISORDERED;
    }
    judged
}
