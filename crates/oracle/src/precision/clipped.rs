//! Triangles the reference clips (near plane, guard band) analysed as the unclipped ones are:
//! every vertex of the clipped polygon bounded as an f32 implementation may compute it, each
//! piece of the fan analysed as a triangle ([`super::triangle`]), and the pieces' entries at a
//! sample merged into one fragment of the primitive (`docs/semantics.md` §10, "Clipped
//! triangles").
//!
//! A corner of the triangle that survives the clipping keeps the bounds of its transform
//! ([`clip_error`]). A vertex the clipping makes is where the segment between two earlier points
//! crosses a plane: the implementation computes the same crossing from its own f32 ends, so its
//! error follows from theirs and from the roundings of the plane distances, the parameter and the
//! interpolation ([`crossing_error`]), in any of the usual forms (from either end,
//! `a + t·(b − a)` or `a·(1 − t) + b·t`). The implementation clips against the same planes in the
//! same order, on points on the same side of each plane as the reference's: a point whose
//! distance to a later plane its error could flip leaves the triangle not analysed.

use fragsim_raster::{ClipOrigin, Conventions, EdgeTies, View};

use super::error_analysis::{clip_error, window_bound, Located};
use super::triangle::{triangle, Target, Triangle};
use super::{gamma_both, Bounds, Doubt, Found, VertexBound};

/// Pixels either side of an edge made by clipping within which a sample's coverage is in doubt
/// (`pieces`): the gap between an exact per-sample depth clip and a clipped polygon's snapped,
/// tie-ruled edge.
const CLIP_EDGE_MARGIN: f64 = 1.0 / 16.0;

/// The pieces of clipped triangle `prim` with their vertices' bounds: the fan
/// `(polygon[0], polygon[i], polygon[i + 1])` of the pieces whose vertices all have `w > 0`, as
/// the pipeline rasterizes them (`View::screen_triangles`). `None` when the reference does not
/// clip the triangle, or when some vertex cannot be bounded (its `w`, or its side of a clipping
/// plane, within its error). Each piece's ids are its polygon vertices' indices.
pub(super) fn pieces(
    view: &View<'_>,
    conventions: &Conventions,
    prim: u32,
    bounds: &mut Bounds,
) -> Option<Vec<([u32; 3], [VertexBound; 3])>> {
    let clipped = view.clipped(prim)?;
    let trace = &clipped.trace;
    let planes = view.clip_planes().map(|p| p.to_array());
    let corners = view.mesh().triangles[prim as usize];
    // Each point's error, in the order the clipping made them (a crossing's ends come first).
    let mut errors: Vec<[f64; 4]> = Vec::with_capacity(trace.points.len());
    for (i, origin) in trace.origins.iter().enumerate() {
        let point = trace.points[i].to_array();
        let (error, first_plane) = match *origin {
            ClipOrigin::Corner(k) => (clip_error(view, corners[k]), 0),
            ClipOrigin::Crossing {
                inside,
                outside,
                plane,
            } => {
                let ends = [inside, outside].map(|j| (trace.points[j].to_array(), errors[j]));
                (crossing_error(ends, planes[plane])?, plane + 1)
            }
        };
        // A later plane the point lies within its error of: the implementation may keep what
        // the reference drops, or the reverse.
        for plane in &planes[first_plane..] {
            if distance(plane, point).abs() <= distance_error(plane, point, error) {
                return None;
            }
        }
        errors.push(error);
    }
    let polygon = &trace.polygon;
    let viewport = view.viewport();
    let mut located = Vec::with_capacity(polygon.len());
    for (k, &i) in polygon.iter().enumerate() {
        let used = clipped.polygon[k].to_array();
        let traced = trace.points[i].to_array();
        // The pipeline's clamp to the guard band moves a point only by its own rounding: what it
        // moved is added to the point's error.
        let mut error: [f64; 4] =
            std::array::from_fn(|c| errors[i][c] + (used[c] - traced[c]).abs());
        // A vertex the clipping made lies on a clip edge, which an implementation may also draw
        // without making it: a rasterizer that clips depth per sample (lavapipe keeps a sample
        // at depth exactly 0) has the exact plane where one that clips the polygon has a snapped
        // edge and its fill rule. Samples within a sixteenth of a pixel of such an edge are in
        // doubt either way.
        if matches!(trace.origins[i], ClipOrigin::Crossing { .. }) {
            let w = used[3].abs();
            error[0] += CLIP_EDGE_MARGIN * 2.0 * w / f64::from(viewport.width);
            error[1] += CLIP_EDGE_MARGIN * 2.0 * w / f64::from(viewport.height);
        }
        let (snapped, depth) = clipped.snapped[k];
        let at = Located {
            clip: used,
            error,
            snapped,
            depth,
        };
        located.push((used[3] > 0.0).then_some(at));
    }
    let mut out = Vec::new();
    for i in 1..polygon.len().saturating_sub(1) {
        #[expect(
            clippy::shadow_unrelated,
            reason = "this fan triangle's corners, indices into the clipped polygon"
        )]
        let corners = [0, i, i + 1];
        // A piece with a vertex not in front of the eye is dropped, as the pipeline drops it.
        let Some(at) = corners
            .iter()
            .map(|&k| located[k])
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let mut verts = Vec::with_capacity(3);
        for a in at {
            verts.push(window_bound(view, conventions, a, bounds)?);
        }
        let verts: [VertexBound; 3] = verts.try_into().ok()?;
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a clipped polygon has at most nine corners"
        )]
        out.push((corners.map(|k| k as u32), verts));
    }
    Some(out)
}

/// The entries of clipped triangle `prim` from its `pieces` ([`pieces`]): each analysed as a
/// triangle of its own vertices, then merged at each sample into one fragment of the primitive
/// (the implementation emits one there, whichever piece of its own it comes from): certain when
/// some piece covers the sample certainly, its depth interval the hull of the pieces'.
pub(super) fn analyse(
    target: Target,
    rule: EdgeTies,
    prim: u32,
    pieces: &[([u32; 3], [VertexBound; 3])],
    bounds: &mut Bounds,
) -> Vec<Found> {
    let mut found: Vec<Found> = Vec::new();
    let mut unused = Vec::new();
    for &(ids, verts) in pieces {
        let tri = Triangle {
            prim,
            ids,
            verts,
            shared: false,
        };
        if !triangle(target, rule, tri, &mut found, &mut unused, bounds) {
            bounds.bounded_triangles += 1;
        }
    }
    found.sort_by_key(|f| f.pixel);
    let mut merged: Vec<Found> = Vec::with_capacity(found.len());
    for f in found {
        match merged.last_mut() {
            Some(m) if m.pixel == f.pixel => {
                let (a, b) = (&mut m.possible, f.possible);
                a.key_lo = a.key_lo.min(b.key_lo);
                a.key_hi = a.key_hi.max(b.key_hi);
                a.reference = a.reference.or(b.reference);
                a.doubt = match (a.doubt, b.doubt) {
                    (None, _) | (_, None) => None,
                    (Some(Doubt::Depth), _) | (_, Some(Doubt::Depth)) => Some(Doubt::Depth),
                    (doubt, _) => doubt,
                };
                m.covered |= f.covered;
            }
            _ => merged.push(f),
        }
    }
    merged
}

/// `plane · point`.
fn distance(plane: &[f64; 4], point: [f64; 4]) -> f64 {
    (0..4).map(|c| plane[c] * point[c]).sum()
}

/// A bound on the error of an implementation's `plane · point` in f32 for a point within `error`
/// of `point` in each coordinate: the coordinates' errors, and the roundings of the plane's
/// coefficients (the guard band's are not f32), the products and the sums.
fn distance_error(plane: &[f64; 4], point: [f64; 4], error: [f64; 4]) -> f64 {
    let moved: f64 = (0..4).map(|c| plane[c].abs() * error[c]).sum();
    let magnitude: f64 = (0..4)
        .map(|c| plane[c].abs() * (point[c].abs() + error[c]))
        .sum();
    moved + gamma_both(5.0) * magnitude
}

/// A bound on each coordinate's error of the point where the segment between `ends` (the inside
/// end first, each with its coordinates' error) crosses `plane`, as an implementation computes it
/// from its own ends in f32, against the reference's (whose own f64 roundings each `γ` below
/// also covers); `None` when the parameter is not
/// bounded (the ends' distances to the plane may reach each other).
///
/// With `d_a = plane · a ≥ 0 > d_b` and `D = d_a − d_b`, the parameter `t = d_a / D` is computed
/// from distances within `ε_a`, `ε_b` ([`distance_error`]) and a difference within
/// `ε_D = ε_a + ε_b + γ_1 (D + ε_a + ε_b)`: `|t̃ − t| ≤ (ε_a + t ε_D) / (D − ε_D)` plus its
/// rounding and that of `1 − t`. The point `ã + t̃ (b̃ − ã)` then differs from `a + t (b − a)` by
/// `(1 − t̃) δa + t̃ δb + (t̃ − t)(b − a)` and the interpolation's own roundings (at most three,
/// in any of the usual forms, each of a value below `|a| + |b|` grown by the errors).
fn crossing_error(ends: [([f64; 4], [f64; 4]); 2], plane: [f64; 4]) -> Option<[f64; 4]> {
    let [(a, ea), (b, eb)] = ends;
    let (da, db) = (distance(&plane, a), distance(&plane, b));
    let (epsilon_a, epsilon_b) = (distance_error(&plane, a, ea), distance_error(&plane, b, eb));
    let denominator = da - db;
    let epsilon_d = epsilon_a + epsilon_b + gamma_both(1.0) * (denominator + epsilon_a + epsilon_b);
    if denominator - epsilon_d <= 0.0 {
        return None;
    }
    let t = da / denominator;
    let quotient = (epsilon_a + t * epsilon_d) / (denominator - epsilon_d);
    let epsilon_t = quotient + gamma_both(2.0) * (1.0 + t + quotient);
    Some(std::array::from_fn(|c| {
        let span = (b[c] - a[c]).abs();
        let ends_moved = (1.0 - t + epsilon_t) * ea[c] + (t + epsilon_t) * eb[c];
        let rounding = gamma_both(3.0) * (a[c].abs() + b[c].abs() + ea[c] + eb[c]);
        ends_moved + epsilon_t * span + rounding
    }))
}
