//! One snap per vertex (`docs/semantics.md` §10): what the capture tells of where each vertex
//! snapped, inferred over every pixel whose coverage hangs on a snap, and each pixel judged under
//! the joint snaps left ([`Snaps`]).

use fragsim_capture::Identity;

use super::{Judged, Pixel};
use crate::compare::{flags, SnapCounts};
use crate::precision::{Doubt, Possible, Precision};

/// The most joint snaps of one pixel's vertices that are enumerated (one vertex with two points
/// almost always, `2^8` for four vertices with two points each).
const MAX_JOINT: usize = 256;

/// What the capture tells of the snaps (`docs/semantics.md` §10, "One snap per vertex"): a
/// conforming implementation snaps each vertex once, to one of its reachable grid points, and
/// every triangle that uses the vertex takes it there. So the coverage of two triangles on a
/// shared edge is decided together (exactly one covers a centre beside it), and each pixel whose
/// coverage hangs on a vertex's snap is evidence of where that vertex went: the grid points a
/// vertex may still take are those that explain, without an error, every pixel that depends on
/// it (arc consistency over the pixels' joint snaps). A pixel is then judged under the snaps
/// left; it is ambiguous by coverage only while they leave more than one fitting set of its
/// fragments that the dump can tell apart (with key-only words, sets of one size cannot be:
/// [`SnapCounts::unnamed_pixels`]).
pub(super) struct Snaps {
    /// Per mesh vertex, a bit per reachable grid point it may still take.
    domain: Vec<u64>,
    pub(super) counts: SnapCounts,
}

/// The fragments of a pixel under one joint snap: the entries it may emit, and which of the
/// enumerated ones cover the centre.
struct Under {
    possible: Vec<Possible>,
    covered: Vec<usize>,
}

impl Snaps {
    /// Reads every pixel's evidence and narrows each vertex to the grid points that explain all
    /// the pixels that depend on it. A pixel no joint snap explains is left out of the narrowing
    /// (an error the final judgement reports), and so is one whose evidence contradicts what the
    /// others already pinned.
    pub(super) fn infer<'a>(precision: &Precision, pixel_of: &impl Fn(usize) -> Pixel<'a>) -> Self {
        let mut snaps = Self {
            domain: precision
                .vertex_points
                .iter()
                .map(|&n| if n > 1 { all_points(n) } else { 1 })
                .collect(),
            counts: SnapCounts::default(),
        };
        // Per pixel with joint evidence: its vertices of undecided snap and the joint snaps
        // under which it has no error.
        let mut evidence: Vec<(Vec<u32>, Vec<Vec<u8>>)> = Vec::new();
        let mut involved = vec![false; snaps.domain.len()];
        for p in 0..precision.pixels() {
            let vertices = snaps.joint_vertices(precision, p);
            if vertices.is_empty() {
                continue;
            }
            for &v in &vertices {
                involved[v as usize] = true;
            }
            let pixel = pixel_of(p);
            let Some(joint) = snaps.assignments(&vertices) else {
                continue;
            };
            if pixel.corrupt() {
                continue;
            }
            let fitting: Vec<Vec<u8>> = joint
                .into_iter()
                .filter(|choice| {
                    let under = snaps.under(precision, p, &vertices, choice);
                    pixel.judge(&under.possible).flags & flags::DIFFERS == 0
                })
                .collect();
            if !fitting.is_empty() {
                evidence.push((vertices, fitting));
            }
        }
        let mut contradicted = vec![false; evidence.len()];
        let mut changed = true;
        while changed {
            changed = false;
            for (i, (vertices, fitting)) in evidence.iter().enumerate() {
                if contradicted[i] {
                    continue;
                }
                let mut support = vec![0_u64; vertices.len()];
                for choice in fitting.iter().filter(|c| snaps.allows(vertices, c)) {
                    for (s, &point) in support.iter_mut().zip(choice) {
                        *s |= 1 << point;
                    }
                }
                if support.contains(&0) {
                    contradicted[i] = true;
                    continue;
                }
                for (&v, s) in vertices.iter().zip(support) {
                    let narrowed = snaps.domain[v as usize] & s;
                    changed |= narrowed != snaps.domain[v as usize];
                    snaps.domain[v as usize] = narrowed;
                }
            }
        }
        for (v, _) in involved.iter().enumerate().filter(|(_, &i)| i) {
            snaps.counts.undecided_vertices += 1;
            snaps.counts.pinned_vertices += u64::from(snaps.domain[v].count_ones() == 1);
        }
        snaps
    }

    /// Pixel `p` judged under the snaps left: over every joint snap of its vertices, the best
    /// judgement (one without an error if any), ambiguous by coverage where the snaps without
    /// an error give it different sets of fragments.
    pub(super) fn judge(
        &self,
        precision: &Precision,
        pixel: &Pixel<'_>,
        counts: &mut SnapCounts,
    ) -> Judged {
        let p = pixel.p;
        if precision.pixel_dependencies(p).iter().all(Option::is_none) {
            return pixel.judge(precision.pixel(p));
        }
        counts.joint_pixels += 1;
        // Empty when the capture pinned every vertex: one joint snap, the pinned one.
        let vertices = self.joint_vertices(precision, p);
        let Some(joint) = self.assignments(&vertices) else {
            counts.unjoined_pixels += 1;
            return pixel.judge(precision.pixel(p));
        };
        let mut best: Option<Judged> = None;
        let mut fitting_sets: Vec<Vec<usize>> = Vec::new();
        for choice in &joint {
            let under = self.under(precision, p, &vertices, choice);
            let judged = pixel.judge(&under.possible);
            let fits = judged.flags & flags::DIFFERS == 0;
            if fits && !fitting_sets.contains(&under.covered) {
                fitting_sets.push(under.covered);
            }
            let errors = |j: &Judged| (j.flags & flags::DIFFERS != 0, j.lost + j.extra);
            if best.as_ref().is_none_or(|b| errors(&judged) < errors(b)) {
                best = Some(judged);
            }
        }
        let mut judged = best.unwrap_or_default();
        // Key-only words name no triangle: snaps that explain the pixel with as many fragments
        // each agree on everything it stores (its count, and keys inside every interval matched).
        let unnamed = pixel.candidate.identity == Identity::KeyOnly
            && fitting_sets.windows(2).all(|w| w[0].len() == w[1].len());
        match fitting_sets.len() {
            0 => counts.contradicting_pixels += 1,
            1 => counts.decided_pixels += 1,
            _ if unnamed => counts.unnamed_pixels += 1,
            _ => judged.doubt(Doubt::Coverage),
        }
        judged
    }

    /// The vertices of undecided snap (more than one grid point left) that pixel `p`'s
    /// enumerated fragments depend on, in order.
    fn joint_vertices(&self, precision: &Precision, p: usize) -> Vec<u32> {
        let mut vertices: Vec<u32> = precision
            .pixel_dependencies(p)
            .iter()
            .flatten()
            .flat_map(|d| d.vertices)
            .filter(|&v| self.domain[v as usize].count_ones() > 1)
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        vertices
    }

    /// Every joint snap of `vertices` (a grid point index each) within their domains; `None`
    /// past [`MAX_JOINT`].
    fn assignments(&self, vertices: &[u32]) -> Option<Vec<Vec<u8>>> {
        let total = vertices.iter().try_fold(1_usize, |n, &v| {
            n.checked_mul(self.domain[v as usize].count_ones() as usize)
        })?;
        if total > MAX_JOINT {
            return None;
        }
        let mut joint = vec![Vec::with_capacity(vertices.len())];
        for &v in vertices {
            let domain = self.domain[v as usize];
            joint = joint
                .into_iter()
                .flat_map(|choice| {
                    (0..64_u8)
                        .filter(move |&i| domain >> i & 1 == 1)
                        .map(move |i| {
                            let mut next = choice.clone();
                            next.push(i);
                            next
                        })
                })
                .collect();
        }
        Some(joint)
    }

    /// Pixel `p`'s possible fragments when `vertices` snap to `choice` and every other vertex
    /// to the one grid point its domain leaves: an enumerated fragment whose triangle then
    /// covers the centre is certain (unless its depth may leave `[0, 1]`), one whose triangle
    /// does not is no possibility.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a trailing-zero count of a u32 is at most 32"
    )]
    fn under(&self, precision: &Precision, p: usize, vertices: &[u32], choice: &[u8]) -> Under {
        let point = |v: u32| match vertices.binary_search(&v) {
            Ok(i) => choice[i],
            Err(_) => self.domain[v as usize].trailing_zeros() as u8,
        };
        let mut under = Under {
            possible: Vec::new(),
            covered: Vec::new(),
        };
        for (i, (q, d)) in precision
            .pixel(p)
            .iter()
            .zip(precision.pixel_dependencies(p))
            .enumerate()
        {
            match d {
                None => under.possible.push(*q),
                Some(d) if d.covers_with(point) => {
                    under.covered.push(i);
                    under.possible.push(Possible {
                        doubt: (!d.depth_certain).then_some(Doubt::Depth),
                        ..*q
                    });
                }
                Some(_) => {}
            }
        }
        under
    }

    /// Whether each of `vertices` may still take its point in `choice`.
    fn allows(&self, vertices: &[u32], choice: &[u8]) -> bool {
        vertices
            .iter()
            .zip(choice)
            .all(|(&v, &point)| self.domain[v as usize] >> point & 1 == 1)
    }
}

/// A bit for each of `n` grid points.
fn all_points(n: u8) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1 << n) - 1
    }
}
