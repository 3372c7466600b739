//! What a conforming implementation may produce: the bounds derived from its declared vertex-stage
//! precision, and for every (pixel, triangle) whether coverage is decided within them and the
//! interval of depth keys it may carry.
//!
//! Guarantee: for an implementation whose vertex stage computes in f32 (`VertexPrecision::F32`)
//! and which otherwise follows `docs/semantics.md` (snapping to the declared subpixel grid with
//! any round-to-nearest, the window origin's fill rule, depth planes evaluated in f32), every
//! fragment it emits at a pixel is one of the [`Possible`] entries listed for that pixel, with its
//! depth key inside that entry's interval; every entry marked `certain` is emitted. Coverage is
//! enumerated over the snapped triangles its vertices may reach, so it is exact. With f64 vertex
//! precision the contract is bit-exactness and the analysis is empty ([`Precision::is_exact`]).
//!
//! Per sample: for a view that rasterizes per sample (`View::with_samples`, a dump declaring
//! `conventions.samples`), the same bounds are derived at each sample position of the standard
//! pattern instead of the pixel centre, and the entries index the sample-expanded framebuffer
//! (sample `s` of pixel `p` at `p · n + s`), as the per-sample oracle and per-sample dumps do.
//! A vertex still snaps once for every sample of every triangle that uses it.
//! Source: the
//! derivation in `docs/semantics.md`, "Precision of a conforming implementation" (standard
//! floating-point error analysis, Higham's `γ_n`; the Vulkan CTS rasterization verifier's
//! "definitely / maybe covered" classification).

use fragsim_raster::conventions::{DepthRange, VertexPrecision};
use fragsim_raster::samples::SamplePattern;
use fragsim_raster::{
    depth_key, edge_function as edge, Conventions, EdgeTies, View, Viewport, SUBPIXEL_BITS,
};
use serde::Serialize;

use crate::dump::DepthFormat;
use crate::edge_ties::{pipeline_rule, thresholds};
use crate::Oracle;

/// f32's unit roundoff, `2^-24`.
const U32: f64 = 1.0 / 16_777_216.0;
/// f64's unit roundoff, `2^-53`: the reference's own rounding, added to every term.
const U64: f64 = f64::EPSILON / 2.0;
/// The depth key of 1.0, the largest a fragment carries.
const KEY_ONE: u32 = 0x3F80_0000;
/// The most snapped triangles (combinations of the vertices' reachable grid points) whose
/// coverage is enumerated: two points per axis and vertex, `2^6`. Past it the bilinear edge
/// bound decides (sound, looser).
const MAX_COMBINATIONS: usize = 64;

/// `γ_n = n·u / (1 − n·u)`: the relative error bound of `n` rounded operations.
fn gamma(n: f64, u: f64) -> f64 {
    n * u / (1.0 - n * u)
}

/// Both roundings of `n` operations: the implementation's in f32 and the reference's in f64.
fn gamma_both(n: f64) -> f64 {
    gamma(n, U32) + gamma(n, U64)
}

/// One fragment a conforming implementation may emit at a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Possible {
    /// The triangle.
    pub prim: u32,
    /// The smallest depth key it may carry.
    pub key_lo: u32,
    /// The largest depth key it may carry.
    pub key_hi: u32,
    /// Why not every conforming implementation emits it; `None`: every one does (coverage
    /// decided outside the margin and its depth interval inside `[0, 1]`).
    pub doubt: Option<Doubt>,
    /// The reference's depth key where the reference emits it.
    pub reference: Option<u32>,
}

impl Possible {
    /// Whether every conforming implementation emits it.
    #[must_use]
    pub fn certain(&self) -> bool {
        self.doubt.is_none()
    }
}

/// What leaves a possible fragment undecided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Doubt {
    /// Some snapped triangle the vertices may reach covers the sample position and another does
    /// not (or the edge bound cannot decide): present or absent, both conform.
    Coverage,
    /// Coverage is certain but the depth interval leaves `[0, 1]`: the fragment may be clipped.
    Depth,
    /// The reference clips the triangle (near plane or guard band): not analysed.
    Clipped,
}

/// The bounds the analysis derived, as `compare` prints them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Bounds {
    /// The largest window-position error bound of any vertex before snapping, in subpixels.
    pub max_vertex_error_subpixels: f64,
    /// The largest snapped-position radius of any vertex, in subpixels (what the coverage test
    /// uses: the snapped positions an implementation may reach).
    pub max_snap_radius_subpixels: i64,
    /// The widest depth interval of any reference fragment, in f32 ulps (`key_hi − key_lo`).
    pub max_depth_interval_ulps: u32,
    /// (pixel, triangle) pairs whose coverage or depth range is decided inside the margin.
    pub ambiguous_pairs: u64,
    /// Of those, pairs the reference does not cover (the implementation may emit them).
    pub may_be_present_pairs: u64,
    /// Of those, pairs the reference covers whose coverage is decided inside the margin (the
    /// implementation may not emit them).
    pub coverage_undecided_pairs: u64,
    /// Of those, pairs whose coverage is certain but whose depth interval leaves `[0, 1]`.
    pub depth_undecided_pairs: u64,
    /// Of those, pairs of triangles the reference clips ([`Bounds::unanalysed_triangles`]).
    pub clipped_pairs: u64,
    /// Triangles the reference clips (near plane or guard band): not analysed, their fragments
    /// taken as ambiguous with any depth.
    pub unanalysed_triangles: u64,
    /// Triangles whose vertices may reach more than 64 combinations of snapped positions: their
    /// coverage judged by the bilinear edge bound over the radius instead of by enumeration.
    pub bounded_triangles: u64,
    /// (sample, triangle) pairs lying exactly on an edge of some snapped triangle the vertices
    /// may reach, where the implementation's edge-tie rule may decide coverage
    /// ([`crate::edge_ties`]).
    pub edge_tie_pairs: u64,
}

/// The per-pixel possibilities of a view under an implementation's conventions.
#[derive(Clone, Debug, PartialEq)]
pub struct Precision {
    exact: bool,
    offsets: Vec<usize>,
    entries: Vec<Possible>,
    /// Parallel to `entries`: how an entry whose coverage was enumerated depends on its
    /// vertices' snaps (`None`: decided, clipped, or judged by the edge bound).
    dependencies: Vec<Option<Dependence>>,
    /// Per mesh vertex, how many snapped positions it may reach (1: its snap is decided; 0: not
    /// analysed).
    vertex_points: Vec<u8>,
    bounds: Bounds,
}

/// How the coverage of one possible fragment depends on the snaps of its triangle's vertices,
/// when it was enumerated (`docs/semantics.md` §10, "One snap per vertex"): the verdict uses it
/// to judge the fragments of a pixel jointly, every triangle that shares a vertex taking that
/// vertex at the same grid point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Dependence {
    /// The triangle's vertices (mesh indices), in the order [`combinations`] enumerates them.
    vertices: [u32; 3],
    /// How many grid points each may reach: the `i`-th combination takes point
    /// `i / (n1·n2)` of vertex 0, `(i / n2) mod n1` of vertex 1 and `i mod n2` of vertex 2.
    points: [u8; 3],
    /// Bit `i`: the `i`-th combination covers the sample position.
    covering: u64,
    /// Whether the fragment is certain wherever its triangle covers the centre (its depth
    /// interval inside `[0, 1]`): else a covering snap may still drop it.
    depth_certain: bool,
}

impl Dependence {
    /// Whether the triangle covers the centre when each of its vertices takes the grid point
    /// `point(vertex)` (an index into the vertex's reachable points).
    fn covers_with(&self, point: impl Fn(u32) -> u8) -> bool {
        let [a, b, c] = self.vertices.map(|v| u64::from(point(v)));
        let [_, n1, n2] = self.points.map(u64::from);
        self.covering >> ((a * n1 + b) * n2 + c) & 1 == 1
    }
}

/// A vertex's error bounds: the snapped positions it may reach, their radius (subpixels) and the
/// window-depth error.
#[derive(Clone, Copy, Debug)]
struct VertexBound {
    snapped: [i64; 2],
    depth: f64,
    /// Per axis, the first and last grid point (subpixels) any round-to-nearest of the vertex's
    /// f32 window position may give; every grid point between them, `step` apart, is reachable.
    reach: [[i64; 2]; 2],
    /// The grid's spacing in subpixels (`2^(8 − subpixel bits)`).
    step: i64,
    /// Subpixels from `snapped` to any snapped position an implementation may reach.
    radius: i64,
    /// The reference's unsnapped window position, in subpixels: an interpolator that sets up its
    /// plane on the float positions (llvmpipe's `lp_state_setup.c`) uses one within `error`.
    unsnapped: [f64; 2],
    /// The window-position error bound before snapping, in subpixels (the larger axis).
    error: f64,
    depth_error: f64,
}

impl Precision {
    /// The analysis of `view` (built under the reference's f64 pipeline) for an implementation
    /// declaring `conventions`: empty for f64 vertex precision, where the contract is bit-exact.
    /// Samples exactly on an edge are decided by the pipeline's rule (the top-left rule of the
    /// window origin), as the oracle of the view decides them.
    #[must_use]
    pub fn derive(view: &View<'_>, conventions: &Conventions) -> Self {
        Self::derive_under(view, conventions, pipeline_rule(conventions.window_origin))
    }

    /// [`Precision::derive`] for an implementation that decides samples exactly on an edge by
    /// `rule` (in fragsim's y-down rows, [`crate::edge_ties`]): every snapped triangle its
    /// vertices may reach is rasterized with that rule, and the reference keys are those of the
    /// oracle under it.
    #[must_use]
    pub fn derive_under(view: &View<'_>, conventions: &Conventions, rule: EdgeTies) -> Self {
        if conventions.vertex_precision == VertexPrecision::F64 {
            return Self::exact();
        }
        let mut bounds = Bounds::default();
        let target = Target {
            pixels: view.pixel_viewport(),
            pattern: view.samples().unwrap_or(SamplePattern::CENTRE),
        };
        let vertices: Vec<Option<VertexBound>> = (0..view.mesh().positions.len() as u32)
            .map(|i| vertex_bound(view, conventions, i, &mut bounds))
            .collect();
        let vertex_points: Vec<u8> = vertices
            .iter()
            .map(|v| v.map_or(0, |v| u8::try_from(reachable_points(&v)).unwrap_or(0)))
            .collect();
        let mut found: Vec<(u32, Possible)> = Vec::new();
        let mut dependent: Vec<(usize, Dependence)> = Vec::new();
        for prim in 0..view.triangle_count() {
            let ids = view.mesh().triangles[prim as usize];
            match ids.map(|i| vertices[i as usize]) {
                [Some(a), Some(b), Some(c)] => {
                    let tri = Triangle {
                        prim,
                        ids,
                        verts: [a, b, c],
                    };
                    if !triangle(target, rule, tri, &mut found, &mut dependent, &mut bounds) {
                        bounds.bounded_triangles += 1;
                    }
                }
                _ => {
                    bounds.unanalysed_triangles += 1;
                    view.rasterize(prim, &mut |f| {
                        bounds.ambiguous_pairs += 1;
                        bounds.clipped_pairs += 1;
                        found.push((
                            f.pixel,
                            Possible {
                                prim,
                                key_lo: 0,
                                key_hi: KEY_ONE,
                                doubt: Some(Doubt::Clipped),
                                reference: Some(f.depth_key),
                            },
                        ));
                    });
                }
            }
        }
        let mut dependency_of: Vec<Option<Dependence>> = vec![None; found.len()];
        for (entry, dependence) in dependent {
            dependency_of[entry] = Some(dependence);
        }
        let mut order: Vec<usize> = (0..found.len()).collect();
        order.sort_by_key(|&i| found[i].0);
        let pixels = view.viewport().pixels();
        let mut offsets = vec![0usize; pixels + 1];
        for &(p, _) in &found {
            offsets[p as usize + 1] += 1;
        }
        for i in 0..pixels {
            offsets[i + 1] += offsets[i];
        }
        let entries: Vec<Possible> = order.iter().map(|&i| found[i].1).collect();
        let dependencies: Vec<Option<Dependence>> =
            order.iter().map(|&i| dependency_of[i]).collect();
        for e in &entries {
            if e.reference.is_some() {
                bounds.max_depth_interval_ulps =
                    bounds.max_depth_interval_ulps.max(e.key_hi - e.key_lo);
            }
        }
        Self {
            exact: false,
            offsets,
            entries,
            dependencies,
            vertex_points,
            bounds,
        }
    }

    /// The analysis as a dump whose words store depth in `format` reads back
    /// ([`DepthFormat::stored_keys`], `docs/semantics.md` §10, "Stored depth"): every interval
    /// becomes the keys the stored field may read back as, and every reference key the one
    /// fragsim's own conversion gives. An exact analysis (f64 vertex precision) first becomes
    /// `reference`'s fragments, each certain at its own key: a unorm field cannot owe the f32
    /// bits, only the steps the conversion may land on. f32 words leave the analysis as it is.
    #[must_use]
    pub fn stored_as(self, format: DepthFormat, reference: &Oracle) -> Self {
        if format == DepthFormat::F32 {
            return self;
        }
        let mut stored = if self.exact {
            Self::certain(reference)
        } else {
            self
        };
        let mut widest = 0;
        for e in &mut stored.entries {
            (e.key_lo, e.key_hi) = format.stored_keys(e.key_lo, e.key_hi);
            if let Some(key) = &mut e.reference {
                *key = format.key_of_field(format.field_of_key(*key));
                widest = widest.max(e.key_hi - e.key_lo);
            }
        }
        stored.bounds.max_depth_interval_ulps = widest;
        stored
    }

    /// `reference`'s fragments as an analysis in which each is certain at its own key.
    fn certain(reference: &Oracle) -> Self {
        let mut offsets = vec![0];
        let mut entries = Vec::with_capacity(reference.fragments());
        for p in 0..reference.pixels() {
            entries.extend(reference.pixel(p).iter().map(|&word| {
                let key = (word >> 32) as u32;
                Possible {
                    prim: word as u32,
                    key_lo: key,
                    key_hi: key,
                    doubt: None,
                    reference: Some(key),
                }
            }));
            offsets.push(entries.len());
        }
        Self {
            exact: false,
            offsets,
            dependencies: vec![None; entries.len()],
            entries,
            vertex_points: Vec::new(),
            bounds: Bounds::default(),
        }
    }

    /// The analysis of an implementation that owes every bit (f64 vertex precision): empty, the
    /// exact comparison applies.
    #[must_use]
    pub fn exact() -> Self {
        Self {
            exact: true,
            offsets: Vec::new(),
            entries: Vec::new(),
            dependencies: Vec::new(),
            vertex_points: Vec::new(),
            bounds: Bounds::default(),
        }
    }

    /// Whether the implementation owes bit-exactness (f64 vertex precision): no analysis, the
    /// exact comparison applies.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.exact
    }

    /// The bounds derived.
    #[must_use]
    pub fn bounds(&self) -> Bounds {
        self.bounds
    }

    /// Number of pixels analysed (0 when exact).
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// What pixel `p` may hold (empty when exact).
    #[must_use]
    pub fn pixel(&self, p: usize) -> &[Possible] {
        if self.exact {
            return &[];
        }
        &self.entries[self.offsets[p]..self.offsets[p + 1]]
    }

    /// How each of [`Precision::pixel`]`(p)`'s entries depends on its vertices' snaps.
    fn pixel_dependencies(&self, p: usize) -> &[Option<Dependence>] {
        if self.exact {
            return &[];
        }
        &self.dependencies[self.offsets[p]..self.offsets[p + 1]]
    }
}

/// The error bounds of vertex `index`, `None` when the reference clips it or its `w` is not
/// bounded away from 0 by the transform's error.
fn vertex_bound(
    view: &View<'_>,
    conventions: &Conventions,
    index: u32,
    bounds: &mut Bounds,
) -> Option<VertexBound> {
    let (snapped, depth) = view.vertex_window(index)?;
    let clip = view.vertex_clip(index);
    let m = view.view_projection().to_cols_array();
    let p = view.mesh().positions[index as usize];
    let v = [f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0];
    // An engine's matrix recorded at the precision it used (every entry an f32): the rounding
    // errors of the actual products and partial sums, in any order ([`dot_error`]). A matrix
    // rounded to f32 first: |fl(Σ M_rj v_j) − Σ M_rj v_j| ≤ γ_5 Σ |M_rj||v_j| (the standard
    // bound of four products and three sums in any order, one more u for the entries).
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
    let [ex, ey, ez, ew] = [0, 1, 2, 3].map(transform_error);
    let w = clip.w;
    if w.abs() <= ew {
        return None;
    }
    // x̃/w̃ − x/w = (dx − (x/w) dw) / w̃, and the divide rounds once more.
    let ndc_error = |c: f64, e: f64| {
        let q = c / w;
        let e = (e + q.abs() * ew) / (w.abs() - ew);
        e + half_ulp(q.abs() + e) + gamma(1.0, U64) * (q.abs() + e)
    };
    let (nx, ny, nz) = (clip.x / w, clip.y / w, clip.z / w);
    let (enx, eny, enz) = (
        ndc_error(clip.x, ex),
        ndc_error(clip.y, ey),
        ndc_error(clip.z, ez),
    );
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
    let grid = 1i64 << (SUBPIXEL_BITS - conventions.subpixel_bits.min(SUBPIXEL_BITS));
    let one = f64::from(1u32 << SUBPIXEL_BITS);
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
    2f64.powi(exponent - 24)
}

/// A bound on the error of an f32 dot product `Σ p_j` of four exact products `p_j = M_rj·v_j`
/// (`v_3 = 1`, so `p_3` is exact), evaluated in any order, with or without fused multiply-adds:
/// every rounding of a result `y` errs by at most `½ulp(y)`, and the errors of a sum tree add.
/// The three products' roundings (none under an FMA) plus, for the worst of the 15 trees on four
/// addends, the roundings of its three partial sums, each at most `½ulp` of a bound on it
/// (`|Σ_S p| + γ_4 Σ_S |p|`). Tighter than `γ_4 Σ |p|` by the cancellation in the partial sums
/// and by the distance to the next power of two (`docs/semantics.md` §10, step 1).
fn dot_error(p: [f64; 4]) -> f64 {
    let products: f64 = p[..3].iter().map(|&x| half_ulp(x)).sum();
    let sum_bound = |set: u32| {
        let (sum, magnitude) = (0..4)
            .filter(|j| set >> j & 1 == 1)
            .fold((0.0, 0.0), |(s, m), j| (s + p[j], m + p[j].abs()));
        half_ulp(sum.abs() + gamma(4.0, U32) * magnitude)
    };
    let pairs = (0u32..16).filter(|s| s.count_ones() == 2);
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
fn snap_reach(x: f64, error: f64, bits: u32) -> [i64; 2] {
    let bits = bits.min(SUBPIXEL_BITS);
    let (scale, grid) = (f64::from(1u32 << bits), 1i64 << (SUBPIXEL_BITS - bits));
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
fn edge_bound(p0: [f64; 2], q: [f64; 2], p: [f64; 2], r0: f64, rq: f64, rp: f64) -> f64 {
    let (alpha, s) = (r0 + rq, rp + r0);
    let (a, c) = ((q[0] - p0[0]).abs(), (q[1] - p0[1]).abs());
    let (b, d) = ((p[1] - p0[1]).abs(), (p[0] - p0[0]).abs());
    (a + c) * s + (b + d) * alpha + 2.0 * alpha * s
}

/// Integer subpixel coordinates as f64 (exact).
fn real(p: [i64; 2]) -> [f64; 2] {
    p.map(|c| c as f64)
}

/// The largest f32 not above `x`, and the smallest not below.
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x {
        f.next_down()
    } else {
        f
    }
}

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
struct Plane {
    at: [[f64; 2]; 3],
    radius: [f64; 3],
}

/// The depth keys an implementation may give the fragment of triangle `v` at sample position `p`
/// when its plane is one of `planes`, around the reference's plane value `z`; and whether the
/// whole interval lies in `[0, 1]` (else the fragment may be dropped). The interval is the hull
/// of each plane's ([`plane_interval`]), with the reference's value in it; one unbounded plane
/// leaves it the whole range. `docs/semantics.md` §10, step 6, derives each term.
fn depth_interval(
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
fn plane_interval(
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

/// How many grid points vertex `b` may reach along `axis`.
fn axis_points(b: &VertexBound, axis: usize) -> usize {
    usize::try_from((b.reach[axis][1] - b.reach[axis][0]) / b.step + 1).unwrap_or(usize::MAX)
}

/// How many grid points vertex `b` may snap to (saturating).
fn reachable_points(b: &VertexBound) -> usize {
    axis_points(b, 0).saturating_mul(axis_points(b, 1))
}

/// Every snapped triangle an implementation may rasterize for `v`: each vertex at any grid
/// point it may reach; `None` when there are more than [`MAX_COMBINATIONS`].
fn combinations(v: &[VertexBound; 3]) -> Option<Vec<[[i64; 2]; 3]>> {
    let total = v.iter().try_fold(1usize, |n, b| {
        n.checked_mul(axis_points(b, 0))?
            .checked_mul(axis_points(b, 1))
    });
    if total.is_none_or(|n| n > MAX_COMBINATIONS) {
        return None;
    }
    let points = |b: &VertexBound| -> Vec<[i64; 2]> {
        let axis =
            |k: usize| (0..axis_points(b, k) as i64).map(move |i| b.reach[k][0] + i * b.step);
        axis(0).flat_map(|x| axis(1).map(move |y| [x, y])).collect()
    };
    let [a, b, c] = v.map(|x| points(&x));
    let mut all = Vec::with_capacity(a.len() * b.len() * c.len());
    for &pa in &a {
        for &pb in &b {
            all.extend(c.iter().map(|&pc| [pa, pb, pc]));
        }
    }
    Some(all)
}

/// Whether the pipeline covers sample position `p` with the snapped triangle `xy` (`scan.rs`: the
/// triangle oriented positively, a degenerate one covering nothing, each edge under the
/// rasterizer's fill rule with the ownership of `rule`, [`thresholds`]); and whether `p` lies
/// exactly on one of its edges and inside the others, where the rule decides.
fn covers(rule: EdgeTies, xy: [[i64; 2]; 3], p: [i64; 2]) -> (bool, bool) {
    let [a, mut b, mut c] = xy;
    let area = edge(a, b, c);
    if area == 0 {
        return (false, false);
    }
    if area < 0 {
        std::mem::swap(&mut b, &mut c);
    }
    let edges = [(b, c), (c, a), (a, b)];
    let threshold = thresholds(edges, rule);
    let e = edges.map(|(q, r)| edge(q, r, p));
    (
        (0..3).all(|k| e[k] >= threshold[k]),
        e.contains(&0) && e.iter().all(|&v| v >= 0),
    )
}

/// Lists, for every sample of `target`'s pattern within the grown bounding box of an unclipped
/// triangle (the pixel centres at one sample), what an
/// implementation may emit there: coverage enumerated over every snapped triangle the vertices
/// may reach (step 5 of `docs/semantics.md` §10), or past [`MAX_COMBINATIONS`] decided by the
/// bilinear edge bound over their radius; depth over the planes of the snapped triangles that
/// cover the centre and the plane of the unsnapped positions (step 6). Counts the ambiguous
/// pairs by cause in `bounds`, and records in `dependent` (by index into `found`) how each
/// enumerated fragment whose coverage is split depends on the vertices' snaps. Returns whether it
/// enumerated.
fn triangle(
    target: Target,
    rule: EdgeTies,
    tri: Triangle,
    found: &mut Vec<(u32, Possible)>,
    dependent: &mut Vec<(usize, Dependence)>,
    bounds: &mut Bounds,
) -> bool {
    let Triangle { prim, ids, verts } = tri;
    let [a, mut b, mut c] = verts;
    let [ia, mut ib, mut ic] = ids;
    let mut area = edge(a.snapped, b.snapped, c.snapped);
    if area < 0 {
        std::mem::swap(&mut b, &mut c);
        std::mem::swap(&mut ib, &mut ic);
        area = -area;
    }
    let v = [a, b, c];
    let ids = [ia, ib, ic];
    let reachable = combinations(&v);
    // Each vertex's reachable points (at most 64 while enumerating), for `Dependence`.
    let points = v.map(|x| u8::try_from(reachable_points(&x)).unwrap_or(u8::MAX));
    let radius = v.map(|x| x.radius as f64);
    let area_bound = edge_bound(
        real(b.snapped),
        real(c.snapped),
        real(a.snapped),
        radius[1],
        radius[2],
        radius[0],
    );
    // An interpolator on the float positions: the plane through the unsnapped ones.
    let unsnapped = Plane {
        at: v.map(|x| x.unsnapped),
        radius: v.map(|x| x.error),
    };
    // Past enumeration, every snapped plane within the radius.
    let snapped_within_radius = Plane {
        at: v.map(|x| real(x.snapped)),
        radius,
    };
    let grow = v.iter().map(|x| x.radius).max().unwrap_or(0);
    let one = 1i64 << SUBPIXEL_BITS;
    let Target { pixels, pattern } = target;
    let lo = [0, 1].map(|k| v.iter().map(|x| x.snapped[k]).min().unwrap_or(0) - grow);
    let hi = [0, 1].map(|k| v.iter().map(|x| x.snapped[k]).max().unwrap_or(0) + grow);
    // The pixels one of whose samples may lie in the grown box (at one sample, the centres).
    let [min_offset, max_offset] = pattern.fixed_extent();
    let span = |axis: usize, side: u32| {
        let from = (lo[axis] - max_offset[axis] + one - 1)
            .div_euclid(one)
            .max(0);
        let to = (hi[axis] - min_offset[axis])
            .div_euclid(one)
            .min(i64::from(side) - 1);
        (from, to)
    };
    let (x0, x1) = span(0, pixels.width);
    let (y0, y1) = span(1, pixels.height);
    let samples = i64::from(pattern.count());
    let edges = [(1, 2), (2, 0), (0, 1)];
    // The rasterizer's own fill rule (`scan.rs`) with `rule`'s ownership: an edge covers a point
    // where its value is at least its threshold.
    let threshold = thresholds(edges.map(|(i, j)| (v[i].snapped, v[j].snapped)), rule);
    let area_stable = area as f64 > area_bound;
    // Per edge, whether an end lies outside the viewport: the edge leaves the clip volume.
    let window = [pixels.width, pixels.height].map(|side| i64::from(side) * one);
    let outside = |x: &VertexBound| (0..2).any(|a| !(0..=window[a]).contains(&x.snapped[a]));
    let leaves = edges.map(|(i, j)| outside(&v[i]) || outside(&v[j]));
    let mut planes = Vec::new();
    let positions =
        (y0..=y1).flat_map(|y| (x0..=x1).flat_map(move |x| (0..samples).map(move |s| (x, y, s))));
    for (x, y, s) in positions {
        let [ox, oy] = pattern.fixed_offset(s as usize);
        let p = [x * one + ox, y * one + oy];
        let e = edges.map(|(i, j)| edge(v[i].snapped, v[j].snapped, p));
        let passes = |k: usize| e[k] >= threshold[k];
        let covered = area > 0 && (0..3).all(passes);
        planes.clear();
        planes.push(unsnapped);
        let mut covering = 0u64;
        let mut on_edge = e.contains(&0) && e.iter().all(|&v| v >= 0);
        let (certain, possible) = match &reachable {
            // The reference's own triangle is one of them: `certain` implies `covered`.
            Some(all) => {
                let mut split = false;
                for (i, &xy) in all.iter().enumerate() {
                    let (covers, tie) = covers(rule, xy, p);
                    on_edge |= tie;
                    if covers {
                        planes.push(Plane {
                            at: xy.map(real),
                            radius: [0.0; 3],
                        });
                        covering |= 1 << i;
                        split |= !covered;
                    } else {
                        split |= covered;
                    }
                }
                (covered && !split, covered || split)
            }
            None => {
                planes.push(snapped_within_radius);
                let eb = edges.map(|(i, j)| {
                    edge_bound(
                        real(v[i].snapped),
                        real(v[j].snapped),
                        real(p),
                        radius[i],
                        radius[j],
                        0.0,
                    )
                });
                let decided = |k: usize| eb[k] == 0.0 || e[k].abs() as f64 > eb[k];
                if area_stable {
                    let out = (0..3).any(|k| decided(k) && !passes(k));
                    ((0..3).all(|k| decided(k) && passes(k)), !out)
                } else {
                    // The orientation itself may flip: either side's coverage may be emitted.
                    let pos = (0..3).all(|k| e[k] as f64 >= -eb[k]);
                    let neg = (0..3).all(|k| e[k] as f64 <= eb[k]);
                    (false, pos || neg)
                }
            }
        };
        bounds.edge_tie_pairs += u64::from(on_edge);
        // A sample exactly on an edge that leaves the clip volume: an implementation may clip
        // the triangle there (Vulkan clips to `−w ≤ x, y ≤ w`; a guard band only where the result
        // is the same), and the clipped edge's new end is computed and snapped in its own
        // arithmetic, so the sample may fall on either side whatever the fill rule.
        let clipped_tie = (0..3).any(|k| e[k] == 0 && leaves[k]) && e.iter().all(|&v| v >= 0);
        let (certain, possible) = if clipped_tie {
            (false, true)
        } else {
            (certain, possible)
        };
        if !possible && !covered {
            continue;
        }
        let area_f = area as f64;
        let z = (e[0] as f64 * v[0].depth + e[1] as f64 * v[1].depth + e[2] as f64 * v[2].depth)
            / area_f;
        let reference = if covered { depth_key(z as f32) } else { None };
        let (key_lo, key_hi, inside) = depth_interval(pixels, &v, &planes, p, z);
        if !certain && !clipped_tie && reachable.is_some() {
            dependent.push((
                found.len(),
                Dependence {
                    vertices: ids,
                    points,
                    covering,
                    depth_certain: inside && (reference.is_some() || !covered),
                },
            ));
        }
        let doubt = if !certain {
            Some(Doubt::Coverage)
        } else if !inside || reference.is_none() {
            Some(Doubt::Depth)
        } else {
            None
        };
        if doubt.is_some() {
            bounds.ambiguous_pairs += 1;
            if reference.is_none() && !covered {
                bounds.may_be_present_pairs += 1;
            } else if doubt == Some(Doubt::Coverage) {
                bounds.coverage_undecided_pairs += 1;
            } else {
                bounds.depth_undecided_pairs += 1;
            }
        }
        found.push((
            ((y * i64::from(pixels.width) + x) * samples + s) as u32,
            Possible {
                prim,
                key_lo,
                key_hi,
                doubt,
                reference,
            },
        ));
    }
    reachable.is_some()
}

/// Where a view's fragments are analysed: the render target in pixels and the sample positions of
/// each pixel ([`SamplePattern::CENTRE`] for single-sample rasterization). A fragment of sample `s`
/// of pixel `(x, y)` is entry `(y · width + x) · n + s`, the index of the sample-expanded
/// framebuffer the raster crate's per-sample views emit (`fragsim_raster::samples`).
#[derive(Clone, Copy, Debug)]
struct Target {
    pixels: Viewport,
    pattern: SamplePattern,
}

/// A triangle to analyse: its primitive id, its vertices' mesh indices and their bounds.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    prim: u32,
    ids: [u32; 3],
    verts: [VertexBound; 3],
}

#[cfg(test)]
mod tests;
mod verdict;

pub use verdict::{compare_within, f32_reference};
