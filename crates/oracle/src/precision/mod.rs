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

use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::samples::SamplePattern;
use fragsim_raster::{Conventions, EdgeTies, View};
use serde::Serialize;

use crate::edge_ties::pipeline_rule;
use crate::Oracle;
use error_analysis::vertex_bound;
use fragsim_dump::DepthFormat;
use triangle::{reachable_points, triangle, Target, Triangle};

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
    /// The reference clips the triangle (near plane or guard band) and its pieces cannot be
    /// bounded (a vertex whose `w`, or whose side of a clipping plane, its error leaves open):
    /// not analysed.
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
    /// Of those, pairs of clipped triangles not analysed ([`Bounds::unanalysed_triangles`]).
    pub clipped_pairs: u64,
    /// Triangles the reference clips (near plane or guard band) analysed piece by piece, every
    /// vertex the clipping makes bounded as the implementation may compute it.
    pub clipped_triangles: u64,
    /// Triangles the reference clips whose pieces cannot be bounded (a vertex whose `w`, or whose
    /// side of a clipping plane, its error leaves open): not analysed, their fragments taken as
    /// ambiguous with any depth.
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
    /// Per primitive, the first primitive with the very same vertex indices in the same order
    /// (itself when none): such twins have the same depth at every sample in any implementation,
    /// so a tie between them is decided by primitive id as exactly (empty when exact).
    twins: Vec<u32>,
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

/// One (sample, triangle) the analysis lists: what the implementation may emit there, and
/// whether the reference's snapped triangle covers the sample (what tells a fragment that may be
/// present from one that may be absent).
#[derive(Clone, Copy, Debug)]
struct Found {
    pixel: u32,
    possible: Possible,
    covered: bool,
}

impl Found {
    /// Counts it in `bounds` by the cause of its doubt, if any.
    fn tally(&self, bounds: &mut Bounds) {
        let Some(doubt) = self.possible.doubt else {
            return;
        };
        bounds.ambiguous_pairs += 1;
        let cause = match doubt {
            _ if self.possible.reference.is_none() && !self.covered => {
                &mut bounds.may_be_present_pairs
            }
            Doubt::Coverage => &mut bounds.coverage_undecided_pairs,
            Doubt::Depth => &mut bounds.depth_undecided_pairs,
            Doubt::Clipped => &mut bounds.clipped_pairs,
        };
        *cause += 1;
    }
}

/// Per primitive of `view`, the first primitive with the same vertex indices in the same order.
#[expect(
    clippy::cast_possible_truncation,
    reason = "primitive ids are below View::triangle_count, a u32"
)]
fn twins(view: &View<'_>) -> Vec<u32> {
    let mut first = std::collections::HashMap::new();
    view.mesh()
        .triangles
        .iter()
        .enumerate()
        .map(|(prim, ids)| *first.entry(*ids).or_insert(prim as u32))
        .collect()
}

/// Triangle `prim`, which the reference clips and whose pieces cannot be bounded (a vertex whose
/// `w` or side of a clipping plane its error leaves open, as a corner exactly on the near plane):
/// its reference fragments listed as ambiguous with any depth, and the pixels next to them as
/// places a fragment of it may be (a clip edge through a sample: an implementation that clips
/// depth per sample keeps what the reference's clipped polygon leaves to its fill rule).
fn not_analysed(view: &View<'_>, prim: u32, found: &mut Vec<Found>, bounds: &mut Bounds) {
    bounds.unanalysed_triangles += 1;
    let doubt = |pixel: u32, reference: Option<u32>| Found {
        pixel,
        possible: Possible {
            prim,
            key_lo: 0,
            key_hi: KEY_ONE,
            doubt: Some(Doubt::Clipped),
            reference,
        },
        covered: reference.is_some(),
    };
    let mut covered = std::collections::BTreeSet::new();
    view.rasterize(prim, &mut |f| {
        covered.insert(f.pixel);
        found.push(doubt(f.pixel, Some(f.depth_key)));
    });
    let viewport = view.viewport();
    let (width, height) = (viewport.width, viewport.height);
    let mut near = std::collections::BTreeSet::new();
    for &pixel in &covered {
        let (x, y) = (pixel % width, pixel / width);
        for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
            for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                let neighbour = ny * width + nx;
                if !covered.contains(&neighbour) {
                    near.insert(neighbour);
                }
            }
        }
    }
    found.extend(near.into_iter().map(|pixel| doubt(pixel, None)));
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
        #[expect(
            clippy::cast_possible_truncation,
            reason = "vertex indices are u32, as the mesh's triangles hold them"
        )]
        let vertices: Vec<Option<VertexBound>> = (0..view.mesh().positions.len() as u32)
            .map(|i| vertex_bound(view, conventions, i, &mut bounds))
            .collect();
        let vertex_points: Vec<u8> = vertices
            .iter()
            .map(|v| v.map_or(0, |v| u8::try_from(reachable_points(&v)).unwrap_or(0)))
            .collect();
        let mut found: Vec<Found> = Vec::new();
        let mut dependent: Vec<(usize, Dependence)> = Vec::new();
        for prim in 0..view.triangle_count() {
            let ids = view.mesh().triangles[prim as usize];
            match ids.map(|i| vertices[i as usize]) {
                [Some(a), Some(b), Some(c)] => {
                    let tri = Triangle {
                        prim,
                        ids,
                        verts: [a, b, c],
                        shared: true,
                    };
                    if !triangle(target, rule, tri, &mut found, &mut dependent, &mut bounds) {
                        bounds.bounded_triangles += 1;
                    }
                }
                _ => {
                    let analysed = clipped::pieces(view, conventions, prim, &mut bounds)
                        .map(|pieces| clipped::analyse(target, rule, prim, &pieces, &mut bounds));
                    match analysed {
                        Some(entries) => {
                            bounds.clipped_triangles += 1;
                            found.extend(entries);
                        }
                        None => not_analysed(view, prim, &mut found, &mut bounds),
                    }
                }
            }
        }
        for f in &found {
            f.tally(&mut bounds);
        }
        let mut dependency_of: Vec<Option<Dependence>> = vec![None; found.len()];
        for (entry, dependence) in dependent {
            dependency_of[entry] = Some(dependence);
        }
        let mut order: Vec<usize> = (0..found.len()).collect();
        order.sort_by_key(|&i| found[i].pixel);
        let pixels = view.viewport().pixels();
        let mut offsets = vec![0_usize; pixels + 1];
        for f in &found {
            offsets[f.pixel as usize + 1] += 1;
        }
        for i in 0..pixels {
            offsets[i + 1] += offsets[i];
        }
        let entries: Vec<Possible> = order.iter().map(|&i| found[i].possible).collect();
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
            twins: twins(view),
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
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
    )]
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
            twins: Vec::new(),
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
            twins: Vec::new(),
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

mod clipped;
mod error_analysis;
#[cfg(test)]
mod tests;
mod triangle;
mod within;

pub use within::{compare_within, f32_reference};
