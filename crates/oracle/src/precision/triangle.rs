//! One triangle analysed: every snapped triangle its vertices may reach enumerated (or, past
//! [`MAX_COMBINATIONS`], the bilinear edge bound), the pipeline's coverage test at each sample
//! position, and what an implementation may emit at each sample of the triangle's bounding box.

use fragsim_raster::samples::SamplePattern;
use fragsim_raster::{depth_key, edge_function as edge, EdgeTies, Viewport, SUBPIXEL_BITS};

use super::error_analysis::{depth_interval, edge_bound, real, Plane};
use super::{Bounds, Dependence, Doubt, Found, Possible, VertexBound, MAX_COMBINATIONS};
use crate::edge_ties::thresholds;

/// How many grid points vertex `b` may reach along `axis`.
fn axis_points(b: &VertexBound, axis: usize) -> usize {
    usize::try_from((b.reach[axis][1] - b.reach[axis][0]) / b.step + 1).unwrap_or(usize::MAX)
}

/// How many grid points vertex `b` may snap to (saturating).
pub(super) fn reachable_points(b: &VertexBound) -> usize {
    axis_points(b, 0).saturating_mul(axis_points(b, 1))
}

/// Every snapped triangle an implementation may rasterize for `v`: each vertex at any grid
/// point it may reach; `None` when there are more than [`MAX_COMBINATIONS`].
pub(super) fn combinations(v: &[VertexBound; 3]) -> Option<Vec<[[i64; 2]; 3]>> {
    let total = v.iter().try_fold(1_usize, |n, b| {
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
pub(super) fn covers(rule: EdgeTies, xy: [[i64; 2]; 3], p: [i64; 2]) -> (bool, bool) {
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
pub(super) fn triangle(
    target: Target,
    rule: EdgeTies,
    tri: Triangle,
    found: &mut Vec<Found>,
    dependent: &mut Vec<(usize, Dependence)>,
    bounds: &mut Bounds,
) -> bool {
    let Triangle {
        prim,
        ids,
        verts,
        shared,
    } = tri;
    let [a, mut b, mut c] = verts;
    let [ia, mut ib, mut ic] = ids;
    let mut area = edge(a.snapped, b.snapped, c.snapped);
    if area < 0 {
        std::mem::swap(&mut b, &mut c);
        std::mem::swap(&mut ib, &mut ic);
        area = -area;
    }
    let v = [a, b, c];
    #[expect(clippy::shadow_unrelated, reason = "the vertex ids of `v`, in order")]
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
    let one = 1_i64 << SUBPIXEL_BITS;
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
    let outside =
        |x: &VertexBound| (0..2).any(|axis| !(0..=window[axis]).contains(&x.snapped[axis]));
    let leaves = edges.map(|(i, j)| outside(&v[i]) || outside(&v[j]));
    let mut planes = Vec::new();
    let positions =
        (y0..=y1).flat_map(|y| (x0..=x1).flat_map(move |x| (0..samples).map(move |s| (x, y, s))));
    for (x, y, s) in positions {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "s is a sample index, below the pattern's count, at most 16"
        )]
        let [ox, oy] = pattern.fixed_offset(s as usize);
        let p = [x * one + ox, y * one + oy];
        let e = edges.map(|(i, j)| edge(v[i].snapped, v[j].snapped, p));
        let passes = |k: usize| e[k] >= threshold[k];
        let covered = area > 0 && (0..3).all(passes);
        planes.clear();
        planes.push(unsnapped);
        let mut covering = 0_u64;
        let mut on_edge = e.contains(&0) && e.iter().all(|&value| value >= 0);
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
        let clipped_tie =
            (0..3).any(|k| e[k] == 0 && leaves[k]) && e.iter().all(|&value| value >= 0);
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
        #[expect(
            clippy::cast_possible_truncation,
            reason = "depths are f32, as a GPU's"
        )]
        let reference = if covered { depth_key(z as f32) } else { None };
        let (key_lo, key_hi, inside) = depth_interval(pixels, &v, &planes, p, z);
        if shared && !certain && !clipped_tie && reachable.is_some() {
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
        #[expect(
            clippy::cast_possible_truncation,
            reason = "list indices are below the sample-expanded viewport's pixels, at most Viewport::MAX_SIDE² (SampleError::TooWide)"
        )]
        found.push(Found {
            pixel: ((y * i64::from(pixels.width) + x) * samples + s) as u32,
            possible: Possible {
                prim,
                key_lo,
                key_hi,
                doubt,
                reference,
            },
            covered,
        });
    }
    reachable.is_some()
}

/// Where a view's fragments are analysed: the render target in pixels and the sample positions of
/// each pixel ([`SamplePattern::CENTRE`] for single-sample rasterization). A fragment of sample `s`
/// of pixel `(x, y)` is entry `(y · width + x) · n + s`, the index of the sample-expanded
/// framebuffer the raster crate's per-sample views emit (`fragsim_raster::samples`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Target {
    pub(super) pixels: Viewport,
    pub(super) pattern: SamplePattern,
}

/// A triangle to analyse: its primitive id, its vertices' indices and their bounds.
#[derive(Clone, Copy, Debug)]
pub(super) struct Triangle {
    pub(super) prim: u32,
    pub(super) ids: [u32; 3],
    pub(super) verts: [VertexBound; 3],
    /// Whether `ids` are mesh vertices, each snapped once for every triangle that uses it (a
    /// piece of a clipped triangle has vertices of its own: its fragments are judged one by one).
    pub(super) shared: bool,
}
