//! Hints: what a user can check next when the differences of a verdict have a shape that names
//! a cause, besides the verdict itself (which they never change). Three shapes are recognised,
//! the first that holds being the one given:
//!
//! - **the whole frame**: most of the reference's fragments lost and as many extra, as when the
//!   backend drew another scene, camera or view than the header names;
//! - **depth only**: every differing list holds the reference's fragments (the same primitives,
//!   as many) with depth keys a few f32 ulps off, as an f32 vertex stage or f32 depth
//!   interpolation rounds them;
//! - **edges only**: every lost or extra fragment lies on the edge of its triangle's coverage
//!   in the reference (a 4-neighbour of the list holds the other answer), as when the candidate
//!   rasterizes under other conventions or edge-tie rules.

use fragsim_capture::{Capture, Identity, Keeps};

use crate::compare::{flags, Comparison};
use crate::Oracle;

/// The most f32 ulps a depth key may be off for the depth-only hint: rounding, not a wrong
/// fragment.
const ROUNDING_ULPS: u32 = 4;

/// What the hints need to know of how the candidate was judged.
pub(super) struct Judging {
    /// Lists in a row of the reference's grid (pixels, or samples of a per-sample layout).
    pub(super) row: usize,
    /// Whether `--vertex-precision f32` would judge the candidate otherwise: the reference is
    /// the oracle and the candidate was judged as an f64 vertex stage (every bit owed).
    pub(super) f32_stage_applies: bool,
}

/// The hint for `comparison` of `candidate` against `reference` (see the module documentation):
/// none where every list is equal or no shape holds.
pub(super) fn hint(
    reference: &Oracle,
    candidate: &Capture,
    comparison: &Comparison,
    judging: &Judging,
) -> Option<String> {
    let differing: Vec<usize> = comparison
        .verdicts
        .iter()
        .enumerate()
        .filter(|&(_, &v)| v & flags::DIFFERS != 0)
        .map(|(p, _)| p)
        .collect();
    if differing.is_empty() {
        return None;
    }
    let (lost, extra) = (comparison.diff.lost, comparison.diff.extra);
    let total = reference.fragments() as u64;
    if total > 0 && 2 * lost >= total && 2 * extra >= total {
        return Some(format!(
            "most of the frame differs ({lost} of the reference's {total} fragments lost, \
             {extra} extra): the candidate drew another scene or view than the header names; \
             check its scene (name or mesh, view_degrees, elevation_degrees, view_projection) \
             against what the backend drew"
        ));
    }
    // Only lists that differ in which fragments they hold make the two other shapes.
    let only_lists = differing.iter().all(|&p| {
        comparison.verdicts[p] & (flags::CORRUPT | flags::MISCOUNTED | flags::MISORDERED) == 0
    });
    if !only_lists {
        return None;
    }
    if let Some(ulps) = depth_only(reference, candidate, &differing) {
        let plural = if ulps == 1 { "" } else { "s" };
        let f32_stage = if judging.f32_stage_applies {
            "`--vertex-precision f32` (the bounds an f32 vertex stage owes) or "
        } else {
            ""
        };
        return Some(format!(
            "every difference is a depth key at most {ulps} f32 ulp{plural} from the \
             reference's, on the same primitive: the backend rounds depth as f32 arithmetic \
             does; judge it with {f32_stage}`--depth-ulps {ulps}`"
        ));
    }
    if candidate.identity != Identity::KeyOnly
        && on_edges(reference, candidate, &differing, judging.row)
    {
        let f32_stage = if judging.f32_stage_applies {
            ", or an f32 vertex stage (`--vertex-precision f32`)"
        } else {
            ""
        };
        return Some(format!(
            "every lost or extra fragment lies on the edge of its triangle's coverage: the \
             candidate decides edge pixels otherwise; check the header's conventions \
             (window_origin, subpixel_bits, depth_range) and the edge-tie rule \
             (conventions.edge_ties, docs/dump-format.md \"Edge ties\"){f32_stage}"
        ));
    }
    None
}

/// The fragments of `list` as `(primitive, depth key)`, keyed as `identity` names them.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn fragments(list: &[u64], identity: Identity) -> Vec<(u32, u32)> {
    let mut out: Vec<(u32, u32)> = list
        .iter()
        .map(|&word| match identity {
            Identity::KeyOnly => (0, (word >> 32) as u32),
            _ => (word as u32, (word >> 32) as u32),
        })
        .collect();
    out.sort_unstable();
    out
}

/// The part of the reference's sorted `list` that a candidate keeping `keeps` owes.
fn owed<'l>(list: &'l [u64], keeps: &Keeps) -> &'l [u64] {
    match *keeps {
        Keeps::Nearest(k) => &list[..list.len().min(k as usize)],
        Keeps::Farthest(k) => &list[list.len().saturating_sub(k as usize)..],
        Keeps::All { .. } => list,
    }
}

/// The most ulps any depth key of the `differing` lists is off where each holds the reference's
/// fragments (as many, the same primitives) with keys at most [`ROUNDING_ULPS`] off; `None`
/// where one does not (or the candidate stores no depth).
fn depth_only(reference: &Oracle, candidate: &Capture, differing: &[usize]) -> Option<u32> {
    if candidate.identity == Identity::PrimOnly {
        return None;
    }
    let mut most = 0;
    for &p in differing {
        let expected = fragments(
            owed(reference.pixel(p), &candidate.keeps),
            candidate.identity,
        );
        let got = fragments(candidate.lists.pixel(p), candidate.identity);
        if expected.len() != got.len() {
            return None;
        }
        for (&(prim_a, key_a), &(prim_b, key_b)) in expected.iter().zip(&got) {
            let ulps = key_a.abs_diff(key_b);
            if prim_a != prim_b || ulps > ROUNDING_ULPS {
                return None;
            }
            most = most.max(ulps);
        }
    }
    (most > 0).then_some(most)
}

/// Whether every fragment lost from or extra in the `differing` lists lies on the edge of its
/// primitive's coverage in the reference: a lost one beside a list of the reference without its
/// primitive, an extra one beside a list with it (4-neighbours in a grid of `row` lists a row).
/// A primitive in both lists at different depths is no edge's.
fn on_edges(reference: &Oracle, candidate: &Capture, differing: &[usize], row: usize) -> bool {
    let lists = reference.pixels();
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an entry's low half is its primitive id"
    )]
    let has = |p: usize, prim: u32| reference.pixel(p).iter().any(|&w| w as u32 == prim);
    let neighbours = |p: usize| {
        let (x, y) = (p % row, p / row);
        [
            (x > 0).then(|| p - 1),
            (x + 1 < row).then(|| p + 1),
            (y > 0).then(|| p - row),
            (p + row < lists).then(|| p + row),
        ]
        .into_iter()
        .flatten()
    };
    differing.iter().all(|&p| {
        let expected = fragments(
            owed(reference.pixel(p), &candidate.keeps),
            candidate.identity,
        );
        let got = fragments(candidate.lists.pixel(p), candidate.identity);
        let prims = |list: &[(u32, u32)]| list.iter().map(|&(prim, _)| prim).collect::<Vec<_>>();
        let (expected_prims, got_prims) = (prims(&expected), prims(&got));
        let lost = expected
            .iter()
            .filter(|f| !got.contains(f))
            .all(|&(prim, _)| !got_prims.contains(&prim) && neighbours(p).any(|q| !has(q, prim)));
        let extra = got
            .iter()
            .filter(|f| !expected.contains(f))
            .all(|&(prim, _)| {
                !expected_prims.contains(&prim) && neighbours(p).any(|q| has(q, prim))
            });
        lost && extra
    })
}
