//! The floating-point error analysis behind the bounds (`docs/semantics.md`, "Precision of a
//! conforming implementation"): each vertex's error and the grid points its snap may reach,
//! half-ulps of f32, the error of an f32 dot product, and the error bounds of edge functions and
//! depth planes.

use fragsim_raster::conventions::DepthRange;
use fragsim_raster::{depth_key, Conventions, View, Viewport, SUBPIXEL_BITS};

use super::{gamma, gamma_both, Bounds, VertexBound, KEY_ONE, U32, U64};

/// The error bounds of vertex `index`, `None` when the reference clips it or its `w` is not
/// bounded away from 0 by the transform's error.
pub(super) fn vertex_bound(
    view: &View<'_>,
    conventions: &Conventions,
    index: u32,
    bounds: &mut Bounds,
) -> Option<VertexBound> {
    let (snapped, depth) = view.vertex_window(index)?;
    let at = Located {
        clip: view.vertex_clip(index).to_array(),
        error: clip_error(view, index),
        snapped,
        depth,
    };
    window_bound(view, conventions, at, bounds)
}

/// A bound on each clip coordinate's error (x, y, z, w) of vertex `index` as an f32 vertex stage
/// computes it, against the reference's f64 transform (`docs/semantics.md` §10, step 1).
pub(super) fn clip_error(view: &View<'_>, index: u32) -> [f64; 4] {
    let m = view.view_projection().to_cols_array();
    let p = view.mesh().positions[index as usize];
    let v = [f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0];
    // An engine's matrix recorded at the precision it used (every entry an f32): the rounding
    // errors of the actual products and partial sums, in any order ([`dot_error`]). A matrix
    // rounded to f32 first: |fl(Σ M_rj v_j) − Σ M_rj v_j| ≤ γ_5 Σ |M_rj||v_j| (the standard
    // bound of four products and three sums in any order, one more u for the entries).
    #[expect(
        clippy::cast_possible_truncation,
        reason = "whether each entry is exactly an f32"
    )]
    let rounded = m.iter().any(|&e| f64::from(e as f32) != e);
    let transform_error = |row: usize| {
        let products = [0, 1, 2, 3].map(|c| m[c * 4 + row] * v[c]);
        let magnitude = products.iter().map(|x| x.abs()).sum::<f64>();
        if rounded {
            gamma_both(5.0) * magnitude
        } else {
            dot_error(products) + gamma(4.0, U64) * magnitude
        }
    };
    [0, 1, 2, 3].map(transform_error)
}

/// A point of the pipeline in clip space as the reference computed it, a bound on each of its
/// coordinates' error in an f32 implementation, and the reference's snapped window position and
/// depth of it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Located {
    pub(super) clip: [f64; 4],
    pub(super) error: [f64; 4],
    pub(super) snapped: [i64; 2],
    pub(super) depth: f64,
}

/// The error bounds of a point in the window, from its clip position and that position's error
/// (`docs/semantics.md` §10, steps 2–4): `None` when its `w` is not bounded away from 0.
pub(super) fn window_bound(
    view: &View<'_>,
    conventions: &Conventions,
    at: Located,
    bounds: &mut Bounds,
) -> Option<VertexBound> {
    let Located {
        clip,
        error: [ex, ey, ez, ew],
        snapped,
        depth,
    } = at;
    let [cx, cy, cz, w] = clip;
    if w.abs() <= ew {
        return None;
    }
    // x̃/w̃ − x/w = (dx − (x/w) dw) / w̃, and the divide rounds once more.
    let ndc_error = |c: f64, e: f64| {
        let q = c / w;
        let e = (e + q.abs() * ew) / (w.abs() - ew);
        e + half_ulp(q.abs() + e) + gamma(1.0, U64) * (q.abs() + e)
    };
    let (nx, ny, nz) = (cx / w, cy / w, cz / w);
    let (enx, eny, enz) = (ndc_error(cx, ex), ndc_error(cy, ey), ndc_error(cz, ez));
    // X = (ndc·½ + ½)·width, or the spec's (width/2)·ndc + width/2: the error scaled by
    // width/2, and two more roundings of results no larger than these (the halving is exact).
    // The render target in pixels: a view rasterizing per sample maps positions to pixels too.
    let viewport = view.pixel_viewport();
    let window_error = |n: f64, e: f64, side: u32| {
        let side = f64::from(side);
        let shifted = (n.abs() + e) / 2.0 + 0.5;
        let window = shifted * side * (1.0 + 4.0 * U32);
        let halves_first = side * half_ulp(shifted) + half_ulp(window);
        let spec_form = half_ulp(side / 2.0 * (n.abs() + e)) + half_ulp(window);
        side / 2.0 * e + halves_first.max(spec_form) + gamma(2.0, U64) * shifted * side
    };
    let error_x = window_error(nx, enx, viewport.width);
    let error_y = window_error(ny, eny, viewport.height);
    let depth_error = match conventions.depth_range {
        DepthRange::ZeroToOne => enz,
        DepthRange::MinusOneToOne => enz / 2.0 + gamma_both(2.0) * ((nz.abs() + enz) / 2.0 + 0.5),
    };
    // The reference's unsnapped position, exactly as its snap computes it.
    let (wf, hf) = (f64::from(viewport.width), f64::from(viewport.height));
    let exact = [(nx * 0.5 + 0.5) * wf, (0.5 - ny * 0.5) * hf];
    let grid = 1_i64 << (SUBPIXEL_BITS - conventions.subpixel_bits.min(SUBPIXEL_BITS));
    let one = f64::from(1_u32 << SUBPIXEL_BITS);
    let mut radius = 0;
    let mut reach = [[0; 2]; 2];
    for (axis, error) in [error_x, error_y].into_iter().enumerate() {
        let [lo, hi] = snap_reach(exact[axis], error, conventions.subpixel_bits);
        radius = radius.max(snapped[axis] - lo).max(hi - snapped[axis]);
        // The reference's own snap is one of them (it rounds the centre of the interval); the
        // bound keeps it so even where the f64 ends above round the other way.
        reach[axis] = [lo.min(snapped[axis]), hi.max(snapped[axis])];
    }
    let error = error_x.max(error_y) * one;
    bounds.max_vertex_error_subpixels = bounds.max_vertex_error_subpixels.max(error);
    bounds.max_snap_radius_subpixels = bounds.max_snap_radius_subpixels.max(radius);
    Some(VertexBound {
        snapped,
        depth,
        reach,
        step: grid,
        radius,
        unsnapped: exact.map(|c| c * one),
        error,
        depth_error,
    })
}

/// Half an f32 ulp at magnitude `x`: the largest error of rounding to f32 (to nearest) a real no
/// larger than `x` in magnitude (an ulp only grows with the magnitude); at least the smallest
/// subnormal's half. The exponent is read from the bits, not from a logarithm.
fn half_ulp(x: f64) -> f64 {
    let x = x.abs();
    if x < f64::from(f32::MIN_POSITIVE) {
        return f64::from(f32::from_bits(1)) / 2.0;
    }
    let exponent = ((x.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    2_f64.powi(exponent - 24)
}

/// A bound on the error of an f32 dot product `Σ p_j` of four exact products `p_j = M_rj·v_j`
/// (`v_3 = 1`, so `p_3` is exact), evaluated in any order, with or without fused multiply-adds:
/// every rounding of a result `y` errs by at most `½ulp(y)`, and the errors of a sum tree add.
/// The three products' roundings (none under an FMA) plus, for the worst of the 15 trees on four
/// addends, the roundings of its three partial sums, each at most `½ulp` of a bound on it
/// (`|Σ_S p| + γ_4 Σ_S |p|`). Tighter than `γ_4 Σ |p|` by the cancellation in the partial sums
/// and by the distance to the next power of two (`docs/semantics.md` §10, step 1).
pub(super) fn dot_error(p: [f64; 4]) -> f64 {
    let products: f64 = p[..3].iter().map(|&x| half_ulp(x)).sum();
    let sum_bound = |set: u32| {
        let (sum, magnitude) = (0..4)
            .filter(|j| set >> j & 1 == 1)
            .fold((0.0, 0.0), |(s, m), j| (s + p[j], m + p[j].abs()));
        half_ulp(sum.abs() + gamma(4.0, U32) * magnitude)
    };
    let pairs = (0_u32..16).filter(|s| s.count_ones() == 2);
    let worst_tree = pairs
        .flat_map(|pair| {
            // A pair, then a triple holding it; or the pair and the other pair.
            let triples = (0..4)
                .filter(move |j| pair >> j & 1 == 0)
                .map(move |j| sum_bound(pair | 1 << j));
            let other = sum_bound(0b1111 & !pair);
            triples
                .chain([other])
                .map(move |next| sum_bound(pair) + next)
        })
        .fold(0.0, f64::max);
    products + worst_tree + sum_bound(0b1111)
}

/// The first and last grid point, in subpixels, that any round-to-nearest (any tie rule) of a
/// value in `[x − e, x + e]` (pixels) may give on a grid of `bits` subpixel bits:
/// `[⌈(x − e)·2^b − ½⌉, ⌊(x + e)·2^b + ½⌋]` grid steps (`docs/semantics.md` §10, step 4). A value
/// that may reach a half step gives both neighbours, one whose interval holds none gives one.
#[expect(
    clippy::cast_possible_truncation,
    reason = "bounds of window positions inside the guard band, far within i64"
)]
pub(super) fn snap_reach(x: f64, error: f64, bits: u32) -> [i64; 2] {
    let bits = bits.min(SUBPIXEL_BITS);
    let (scale, grid) = (f64::from(1_u32 << bits), 1_i64 << (SUBPIXEL_BITS - bits));
    [
        ((x - error) * scale - 0.5).ceil() as i64 * grid,
        ((x + error) * scale + 0.5).floor() as i64 * grid,
    ]
}

/// The edge function of `(a, b, p)` in f64 for real positions, and a bound on its rounding:
/// two rounded differences per product, the products, the difference (`γ_3` of `|a·b| + |c·d|`;
/// 0 in effect for integer positions, whose products f64 holds exactly).
fn edge_value(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> (f64, f64) {
    let (first, second) = ((b[0] - a[0]) * (p[1] - a[1]), (b[1] - a[1]) * (p[0] - a[0]));
    (
        first - second,
        gamma(3.0, U64) * (first.abs() + second.abs()),
    )
}

/// The largest change of `edge(p0, q, p)` when `p0`, `q` and `p` move by at most `r0`, `rq`, `rp`
/// in each coordinate: the edge function is bilinear, so with `α = r0 + rq` (the edge vector's
/// change) and `s = rp + r0` (the offset's change) it is
/// `|Δ| ≤ (|a| + |c|)·s + (|b| + |d|)·α + 2αs`. Exact for integer arguments (f64 holds every
/// product of subpixel coordinates).
pub(super) fn edge_bound(p0: [f64; 2], q: [f64; 2], p: [f64; 2], r0: f64, rq: f64, rp: f64) -> f64 {
    let (alpha, s) = (r0 + rq, rp + r0);
    let (a, c) = ((q[0] - p0[0]).abs(), (q[1] - p0[1]).abs());
    let (b, d) = ((p[1] - p0[1]).abs(), (p[0] - p0[0]).abs());
    (a + c) * s + (b + d) * alpha + 2.0 * alpha * s
}

/// Integer subpixel coordinates as f64 (exact).
pub(super) fn real(p: [i64; 2]) -> [f64; 2] {
    p.map(|c| c as f64)
}

/// The largest f32 not above `x`, and the smallest not below.
#[expect(
    clippy::cast_possible_truncation,
    reason = "the nearest f32, then stepped to the side asked for"
)]
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x {
        f.next_down()
    } else {
        f
    }
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "the nearest f32, then stepped to the side asked for"
)]
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x {
        f.next_up()
    } else {
        f
    }
}

/// A plane a conforming implementation may set up for a triangle: through vertex positions
/// (subpixels, in the triangle's vertex order) each known to within `radius` per coordinate.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    pub(super) at: [[f64; 2]; 3],
    pub(super) radius: [f64; 3],
}

/// The depth keys an implementation may give the fragment of triangle `v` at sample position `p`
/// when its plane is one of `planes`, around the reference's plane value `z`; and whether the
/// whole interval lies in `[0, 1]` (else the fragment may be dropped). The interval is the hull
/// of each plane's ([`plane_interval`]), with the reference's value in it; one unbounded plane
/// leaves it the whole range. `docs/semantics.md` §10, step 6, derives each term.
pub(super) fn depth_interval(
    viewport: Viewport,
    v: &[VertexBound; 3],
    planes: &[Plane],
    p: [i64; 2],
    z: f64,
) -> (u32, u32, bool) {
    let mut hull = (z, z);
    for plane in planes {
        match plane_interval(viewport, v, plane, p) {
            Some((lo, hi)) => hull = (hull.0.min(lo), hull.1.max(hi)),
            None => return (0, KEY_ONE, false),
        }
    }
    let (lo, hi) = (round_down(hull.0), round_up(hull.1));
    let inside = lo >= 0.0 && hi <= 1.0;
    (
        depth_key(lo.max(0.0)).unwrap_or(0),
        depth_key(hi.min(1.0)).unwrap_or(KEY_ONE),
        inside,
    )
}

/// The real interval of depths at sample position `p` (subpixels) of an implementation whose plane passes
/// through `plane`'s positions (each moved within its radius) and `v`'s vertex depths (each within
/// its error), evaluated in f32; `None` when the moved triangle's area may reach 0. With
/// `λ_k = E_k/A` and `B` the edge bounds over the radii, `|Δλ_k| ≤ (B_k + |λ_k|·B_A)/(A − B_A)`
/// (`docs/semantics.md` §10, step 6).
pub(super) fn plane_interval(
    viewport: Viewport,
    v: &[VertexBound; 3],
    plane: &Plane,
    p: [i64; 2],
) -> Option<(f64, f64)> {
    let (at, r) = (plane.at, plane.radius);
    let centre = real(p);
    let (signed, area_rounding) = edge_value(at[1], at[2], at[0]);
    let area = signed.abs();
    let area_bound = edge_bound(at[1], at[2], at[0], r[1], r[2], r[0]) + area_rounding;
    let denominator = area - area_bound;
    if denominator <= 0.0 {
        return None;
    }
    let edges = [(1, 2), (2, 0), (0, 1)];
    let (mut z, mut moved, mut weights, mut magnitude) = (0.0, 0.0, 0.0, 0.0);
    let z_lo = v.iter().map(|x| x.depth).fold(f64::INFINITY, f64::min);
    let z_hi = v.iter().map(|x| x.depth).fold(f64::NEG_INFINITY, f64::max);
    for (k, (i, j)) in edges.into_iter().enumerate() {
        let (e, rounding) = edge_value(at[i], at[j], centre);
        let lambda = e * signed.signum() / area;
        let bound = edge_bound(at[i], at[j], centre, r[i], r[j], 0.0) + rounding;
        let d = (bound + lambda.abs() * area_bound) / denominator;
        z += lambda * v[k].depth;
        moved += d;
        weights += (lambda.abs() + d) * v[k].depth_error;
        magnitude += (lambda.abs() + d) * (v[k].depth.abs() + v[k].depth_error);
    }
    // Σ Δλ = 0, so the plane moves by Σ Δλ_k (Z_k − mid) ≤ Σ|Δλ| · range / 2; the vertex
    // depths' own errors add, and the plane's evaluation in f32: barycentric (γ_6 on the
    // weighted magnitudes) or from the window origin (`origin_form_error`).
    let origin_form = origin_form_error(viewport, v, plane, denominator, centre)?;
    let delta = moved * (z_hi - z_lo) / 2.0 + weights + gamma_both(6.0) * magnitude + origin_form;
    Some((z - delta, z + delta))
}

/// The rounding error of a depth plane set up and evaluated in f32 from the window origin, as
/// llvmpipe does (`lp_state_setup.c`: `a = a0 + ∂a/∂x·x + ∂a/∂y·y` with
/// `a0 = a_0 − (∂a/∂x·x_0 + ∂a/∂y·y_0)` and the gradients `(Δa_01·Δy_20 − Δa_20·Δy_01)/A` from f32
/// differences), for vertices within `plane`'s radii of its positions and a doubled area of at
/// least `area_lo`; `None` when the area's own rounding may reach it. With `G` bounds on the
/// gradients' magnitudes, `κ` the area's condition number, `c = (1 + γ_6)(1 + 2γ_4 κ) − 1` the
/// gradients' relative error and `X`, `Y` the largest coordinates from any viewport corner:
/// `γ_9 (|Z| + 2(1 + c)(G_x X + G_y Y)) + c (G_x |x − x_k| + G_y |y − y_k|)` (`docs/semantics.md`
/// §10, step 6).
fn origin_form_error(
    viewport: Viewport,
    v: &[VertexBound; 3],
    plane: &Plane,
    area_lo: f64,
    p: [f64; 2],
) -> Option<f64> {
    let (at, r) = (plane.at, plane.radius);
    // Upper bounds on |differences| of the implementation's coordinates (subpixels) and depths.
    let dxy = |i: usize, j: usize, axis: usize| (at[i][axis] - at[j][axis]).abs() + r[i] + r[j];
    let dz =
        |i: usize, j: usize| (v[i].depth - v[j].depth).abs() + v[i].depth_error + v[j].depth_error;
    let (dz01, dz20) = (dz(0, 1), dz(2, 0));
    let gradient_x = (dz01 * dxy(2, 0, 1) + dz20 * dxy(0, 1, 1)) / area_lo;
    let gradient_y = (dz01 * dxy(2, 0, 0) + dz20 * dxy(0, 1, 0)) / area_lo;
    let kappa = (dxy(0, 1, 0) * dxy(2, 0, 1) + dxy(2, 0, 0) * dxy(0, 1, 1)) / area_lo;
    let side = [viewport.width, viewport.height].map(|s| f64::from(s << SUBPIXEL_BITS));
    // The largest coordinate from whichever corner the implementation takes as its origin.
    let far = |axis: usize| {
        let from_corners =
            |c: f64, slack: f64| (c.abs() + slack).max((side[axis] - c).abs() + slack);
        (0..3)
            .map(|k| from_corners(at[k][axis], r[k]))
            .fold(from_corners(p[axis], 0.0), f64::max)
    };
    let near = |axis: usize| {
        (0..3)
            .map(|k| (p[axis] - at[k][axis]).abs() + r[k])
            .fold(0.0, f64::max)
    };
    let z_max = v
        .iter()
        .map(|x| x.depth.abs() + x.depth_error)
        .fold(0.0, f64::max);
    // The computed area's relative error is at most γ_4 κ, its reciprocal's 2γ_4 κ + u while
    // that is below one half (1/(1 − ε) ≤ 1 + 2ε).
    let area_error = gamma_both(4.0) * kappa;
    if area_error >= 0.5 {
        return None;
    }
    let c = (1.0 + gamma_both(6.0)) * (1.0 + 2.0 * area_error) - 1.0;
    Some(
        gamma_both(9.0) * (z_max + 2.0 * (1.0 + c) * (gradient_x * far(0) + gradient_y * far(1)))
            + c * (gradient_x * near(0) + gradient_y * near(1)),
    )
}
