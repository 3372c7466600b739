//! Strategies for planar tilings (seen through the identity camera), the depth planes they lie
//! on and hinges across the near plane.

use fragsim_raster::{Mesh, Viewport, SUBPIXEL_BITS};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

use super::viewport;

/// Where a generated window coordinate is moved before it becomes a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantize {
    /// Anywhere.
    None,
    /// Onto a pixel centre (`k + 0.5`): exercises the top-left rule.
    PixelCentre,
    /// Onto a pixel corner (an integer).
    PixelCorner,
    /// Onto the nearest window coordinate whose NDC coordinate is a multiple of 1/256: with a
    /// viewport side that is not a power of two, such coordinates make clipped vertices land
    /// exactly halfway between two points of the fixed-point grid.
    Dyadic,
}

impl Quantize {
    /// Window coordinate `x` (pixels, on an axis of `side` pixels) moved as `self` says.
    pub fn apply(self, x: f64, side: u32) -> f64 {
        match self {
            Self::None => x,
            Self::PixelCentre => x.floor() + 0.5,
            Self::PixelCorner => x.round(),
            Self::Dyadic => {
                let side = f64::from(side);
                let ndc = ((2.0 * x / side - 1.0) * 256.0).round() / 256.0;
                (ndc + 1.0) * side / 2.0
            }
        }
    }
}

/// A [`Quantize`]: anywhere 40% of the time.
pub fn quantize() -> impl Strategy<Value = Quantize> {
    prop_oneof![
        2 => Just(Quantize::None),
        1 => Just(Quantize::PixelCentre),
        1 => Just(Quantize::PixelCorner),
        1 => Just(Quantize::Dyadic),
    ]
}

/// The snapped fixed-point window x (1/256 pixel) of NDC `x` through the identity camera: the
/// pipeline's rule 4 (`docs/semantics.md`), restated.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a snapped window x of NDC in [-1, 1] over at most 16384 pixels, far within i64"
)]
pub fn snap_ndc_x(x: f32, width: u32) -> i64 {
    let one = f64::from(1_u32 << SUBPIXEL_BITS);
    ((f64::from(x) / 1.0 * 0.5 + 0.5) * f64::from(width) * one).round() as i64
}

/// The snapped fixed-point window y (1/256 pixel, down) of NDC `y` through the identity camera.
#[expect(
    clippy::cast_possible_truncation,
    reason = "a snapped window y of NDC in [-1, 1] over at most 16384 pixels, far within i64"
)]
pub fn snap_ndc_y(y: f32, height: u32) -> i64 {
    let one = f64::from(1_u32 << SUBPIXEL_BITS);
    ((0.5 - f64::from(y) / 1.0 * 0.5) * f64::from(height) * one).round() as i64
}

/// NDC x of window x (pixels).
#[expect(
    clippy::cast_possible_truncation,
    reason = "positions are f32, as the mesh stores them"
)]
fn ndc_x(x: f64, width: u32) -> f32 {
    (2.0 * x / f64::from(width) - 1.0) as f32
}

/// NDC y of window y (pixels, down).
#[expect(
    clippy::cast_possible_truncation,
    reason = "positions are f32, as the mesh stores them"
)]
fn ndc_y(y: f64, height: u32) -> f32 {
    (1.0 - 2.0 * y / f64::from(height)) as f32
}

/// Triangles that tile an axis-aligned rectangle exactly, for the identity camera.
#[derive(Clone, Debug)]
pub struct PlanarTiling {
    /// The triangles, z in `[0.1, 0.9]`.
    pub mesh: Mesh,
    /// The rectangle `[x0, y0, x1, y1]` in NDC (`x0 < x1`, `y0 < y1`); every vertex on its boundary
    /// has exactly these f32 coordinates, so the boundary snaps to straight lines.
    pub rect: [f32; 4],
}

impl PlanarTiling {
    /// How many times each pixel centre must be covered: once for centres in the snapped rectangle
    /// closed on its left and top sides and open on its right and bottom sides (the top-left rule
    /// applied to the union), zero elsewhere.
    pub fn expected_coverage(&self, viewport: Viewport) -> Vec<u32> {
        let [x0, y0, x1, y1] = self.rect;
        let (left, right) = (
            snap_ndc_x(x0, viewport.width),
            snap_ndc_x(x1, viewport.width),
        );
        // y is flipped: the top of the window is NDC y1.
        let (top, bottom) = (
            snap_ndc_y(y1, viewport.height),
            snap_ndc_y(y0, viewport.height),
        );
        let one = 1_i64 << SUBPIXEL_BITS;
        let mut expected = Vec::with_capacity(viewport.pixels());
        for j in 0..i64::from(viewport.height) {
            for i in 0..i64::from(viewport.width) {
                let (cx, cy) = (i * one + one / 2, j * one + one / 2);
                expected.push(u32::from(
                    left <= cx && cx < right && top <= cy && cy < bottom,
                ));
            }
        }
        expected
    }
}

impl PlanarTiling {
    /// This tiling with every vertex's z moved onto `plane` (rounded to f32).
    #[expect(
        clippy::cast_possible_truncation,
        reason = "positions are f32, as the mesh stores them"
    )]
    pub fn on_plane(mut self, plane: DepthPlane) -> Self {
        for p in &mut self.mesh.positions {
            p[2] = plane.at(f64::from(p[0]), f64::from(p[1])) as f32;
        }
        self
    }

    /// What each pixel centre must hold once the tiling is [on a plane](PlanarTiling::on_plane)
    /// that may cross the near plane `z = 0` (and the far depth 1) of the identity camera, where
    /// that is certain whatever the rounding: `Some(1)` for centres clearly inside the rectangle
    /// (by 1/64 pixel) where the plane's depth is clearly inside `(0, 1)`, `Some(0)` for centres
    /// clearly outside the rectangle or clearly in front of the near plane or beyond depth 1,
    /// `None` (at most once) in the thin bands between.
    pub fn robust_expectation(&self, viewport: Viewport, plane: DepthPlane) -> Vec<Option<u32>> {
        let (w, h) = (f64::from(viewport.width), f64::from(viewport.height));
        let [x0, y0, x1, y1] = self.rect.map(f64::from);
        // 1/64 pixel in NDC: far more than snapping (1/512 pixel) moves anything.
        let (mx, my) = (2.0 / w / 64.0, 2.0 / h / 64.0);
        // Snapping moves a vertex by less than 1/64 pixel, so the depth interpolated at a centre
        // is the plane's depth at a point that near; 1e-6 covers the f32 rounding of vertex z.
        let mz = plane.a.abs() * mx + plane.b.abs() * my + 1e-6;
        let mut expected = Vec::with_capacity(viewport.pixels());
        for j in 0..viewport.height {
            for i in 0..viewport.width {
                let x = 2.0 * (f64::from(i) + 0.5) / w - 1.0;
                let y = 1.0 - 2.0 * (f64::from(j) + 0.5) / h;
                let z = plane.at(x, y);
                let inside = x0 + mx < x && x < x1 - mx && y0 + my < y && y < y1 - my;
                let outside = x < x0 - mx || x > x1 + mx || y < y0 - my || y > y1 + my;
                expected.push(if outside || z < -mz || z > 1.0 + mz {
                    Some(0)
                } else if inside && mz < z && z < 1.0 - mz {
                    Some(1)
                } else {
                    None
                });
            }
        }
        expected
    }
}

/// A depth plane `z = a·x + b·y + c` over NDC x and y, for [`PlanarTiling::on_plane`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthPlane {
    /// dz/dx.
    pub a: f64,
    /// dz/dy.
    pub b: f64,
    /// z at the centre of the window.
    pub c: f64,
}

impl DepthPlane {
    /// The plane's z at NDC `(x, y)`.
    pub fn at(&self, x: f64, y: f64) -> f64 {
        self.a * x + self.b * y + self.c
    }
}

/// A depth plane with coefficients that are multiples of 1/64 (`a`, `b` in `[-1, 1]`, `c` in
/// `[-0.5, 0.75]`): it usually crosses the near plane `z = 0` inside the window, so triangles are
/// clipped there, and the dyadic coefficients with dyadic vertices (see [`Quantize::Dyadic`])
/// make clipped vertices fall on exact halves of the fixed-point grid.
pub fn depth_plane() -> impl Strategy<Value = DepthPlane> {
    (-64_i32..=64, -64_i32..=64, -32_i32..=48).prop_map(|(a, b, c)| DepthPlane {
        a: f64::from(a) / 64.0,
        b: f64::from(b) / 64.0,
        c: f64::from(c) / 64.0,
    })
}

/// A window interval `[lo, hi]` (pixels) for a side of `side` pixels: starting in
/// `[-4, 0.7 · side]`, at least 3 pixels long before quantization (so at least 2 after), possibly
/// past the far edge of the window.
fn window_interval(side: u32) -> impl Strategy<Value = (f64, f64)> {
    let length = f64::from(side);
    (
        -4.0..length * 0.7,
        3.0..length + 8.0,
        quantize(),
        quantize(),
    )
        .prop_map(move |(lo, length, q_lo, q_hi)| {
            (q_lo.apply(lo, side), q_hi.apply(lo + length, side))
        })
}

/// How far a jittered grid vertex may move, as a fraction of the cell: below 1/6 every quad stays
/// convex and every triangle keeps its orientation, with margin to spare for snapping.
const JITTER: f64 = 0.12;

/// A jittered grid: `nx × ny` cells (1 to 6 each) over a random rectangle, interior vertices moved
/// by up to `JITTER` (0.12) of a cell (anywhere, or onto pixel centres or corners when that stays within
/// the bound), boundary vertices moved along their side only, each quad split along a random
/// diagonal.
pub fn jittered_grid(viewport: Viewport) -> impl Strategy<Value = PlanarTiling> {
    let (w, h) = (viewport.width, viewport.height);
    (
        window_interval(w),
        window_interval(h),
        1_usize..=6,
        1_usize..=6,
    )
        .prop_flat_map(|(bx, by, nx, ny)| {
            let vertices = (nx + 1) * (ny + 1);
            (
                Just((bx, by, nx, ny)),
                vec(
                    (-JITTER..JITTER, -JITTER..JITTER, quantize(), quantize()),
                    vertices,
                ),
                vec(any::<bool>(), nx * ny),
                vec(0.1_f32..0.9, vertices),
            )
        })
        .prop_map(
            move |(((x_lo, x_hi), (y_lo, y_hi), nx, ny), jitter, diagonals, z)| {
                let rect = [
                    ndc_x(x_lo, w),
                    ndc_y(y_hi, h),
                    ndc_x(x_hi, w),
                    ndc_y(y_lo, h),
                ];
                let (cell_x, cell_y) = ((x_hi - x_lo) / nx as f64, (y_hi - y_lo) / ny as f64);
                // One axis of a grid vertex: fixed on the boundary, jittered (and maybe quantized)
                // inside.
                #[expect(
                    clippy::shadow_unrelated,
                    reason = "each call passes its own axis's jitter"
                )]
                let axis = |i: usize, lo: f64, cell: f64, jitter: f64, q: Quantize, side: u32| {
                    let base = lo + i as f64 * cell;
                    let moved = base + jitter * cell;
                    let quantized = q.apply(moved, side);
                    if (quantized - base).abs() <= JITTER * cell {
                        quantized
                    } else {
                        moved
                    }
                };
                let mut mesh = Mesh::default();
                for j in 0..=ny {
                    for i in 0..=nx {
                        let (jx, jy, qx, qy) = jitter[j * (nx + 1) + i];
                        let x = match i {
                            0 => rect[0],
                            _ if i == nx => rect[2],
                            _ => ndc_x(axis(i, x_lo, cell_x, jx, qx, w), w),
                        };
                        let y = match j {
                            0 => rect[3],
                            _ if j == ny => rect[1],
                            _ => ndc_y(axis(j, y_lo, cell_y, jy, qy, h), h),
                        };
                        mesh.positions.push([x, y, z[j * (nx + 1) + i]]);
                    }
                }
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "a generated mesh has at most a few thousand vertices"
                )]
                let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
                for j in 0..ny {
                    for i in 0..nx {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        if diagonals[j * nx + i] {
                            mesh.triangles.extend([[a, b, d], [b, c, d]]);
                        } else {
                            mesh.triangles.extend([[a, b, c], [a, c, d]]);
                        }
                    }
                }
                PlanarTiling { mesh, rect }
            },
        )
}

/// A fan: a centre vertex anywhere strictly inside a random rectangle (sometimes within 1e-4 of a
/// side: needle triangles) joined to the corners and to 0 to 4 extra points on each side (random,
/// maybe on pixel centres or corners, maybe coincident: zero-area triangles).
pub fn fan(viewport: Viewport) -> impl Strategy<Value = PlanarTiling> {
    let (w, h) = (viewport.width, viewport.height);
    let side_points = || vec((0.0_f64..=1.0, quantize()), 0..=4);
    let fraction = || {
        prop_oneof![
            3 => 0.001_f64..0.999,
            1 => select(vec![1e-4, 1.0 - 1e-4, 0.5]),
        ]
    };
    (
        window_interval(w),
        window_interval(h),
        [side_points(), side_points(), side_points(), side_points()],
        (fraction(), fraction(), quantize()),
        vec(0.1_f32..0.9, 21),
    )
        .prop_map(move |((x_lo, x_hi), (y_lo, y_hi), sides, (u, v, q), z)| {
            let rect = [
                ndc_x(x_lo, w),
                ndc_y(y_hi, h),
                ndc_x(x_hi, w),
                ndc_y(y_lo, h),
            ];
            // Points along [lo, hi], quantized but kept inside and in order.
            let along = |lo: f64, hi: f64, points: &[(f64, Quantize)], side: u32| -> Vec<f64> {
                #[expect(clippy::shadow_unrelated, reason = "each point's own quantization")]
                let mut out: Vec<f64> = points
                    .iter()
                    .map(|&(t, q)| q.apply(lo + t * (hi - lo), side).clamp(lo, hi))
                    .collect();
                out.sort_by(f64::total_cmp);
                out
            };
            // The boundary counter-clockwise in the window (y down): top side left to right, right
            // side downwards, bottom side right to left, left side upwards; corners included.
            let mut boundary: Vec<[f32; 2]> = Vec::new();
            boundary.push([rect[0], rect[3]]);
            boundary.extend(
                along(x_lo, x_hi, &sides[0], w)
                    .iter()
                    .map(|&x| [ndc_x(x, w), rect[3]]),
            );
            boundary.push([rect[2], rect[3]]);
            boundary.extend(
                along(y_lo, y_hi, &sides[1], h)
                    .iter()
                    .map(|&y| [rect[2], ndc_y(y, h)]),
            );
            boundary.push([rect[2], rect[1]]);
            boundary.extend(
                along(x_lo, x_hi, &sides[2], w)
                    .iter()
                    .rev()
                    .map(|&x| [ndc_x(x, w), rect[1]]),
            );
            boundary.push([rect[0], rect[1]]);
            boundary.extend(
                along(y_lo, y_hi, &sides[3], h)
                    .iter()
                    .rev()
                    .map(|&y| [rect[0], ndc_y(y, h)]),
            );
            let inside = |lo: f64, hi: f64, t: f64, side: u32| {
                let c = lo + t * (hi - lo);
                let quantized = q.apply(c, side);
                if lo < quantized && quantized < hi {
                    quantized
                } else {
                    c
                }
            };
            let centre = [
                ndc_x(inside(x_lo, x_hi, u, w), w),
                ndc_y(inside(y_lo, y_hi, v, h), h),
            ];
            let mut mesh = Mesh::default();
            mesh.positions.push([centre[0], centre[1], z[0]]);
            for (i, p) in boundary.iter().enumerate() {
                mesh.positions.push([p[0], p[1], z[(i + 1) % z.len()]]);
            }
            #[expect(
                clippy::cast_possible_truncation,
                reason = "a generated mesh has at most a few thousand vertices"
            )]
            let n = boundary.len() as u32;
            for i in 0..n {
                mesh.triangles.push([0, 1 + i, 1 + (i + 1) % n]);
            }
            PlanarTiling { mesh, rect }
        })
}

/// A planar tiling of a random rectangle for `viewport`: a [`jittered_grid`] or a [`fan`].
pub fn planar_tiling(viewport: Viewport) -> impl Strategy<Value = PlanarTiling> {
    prop_oneof![jittered_grid(viewport), fan(viewport)]
}

/// A [`viewport`] and a [`planar_tiling`] for it.
pub fn viewport_and_tiling() -> impl Strategy<Value = (Viewport, PlanarTiling)> {
    viewport().prop_flat_map(|viewport| (Just(viewport), planar_tiling(viewport)))
}

/// Two triangles sharing the edge `a b` that crosses the near plane of the identity camera (`a`
/// behind it, `b` in front), one on each side: vertices `[a, b, c1, c2]`, triangles `[a, b, c1]`
/// and `[b, a, c2]` (consistent orientation, so the clipper meets the shared edge once from each
/// end). Their union is the convex quadrilateral `a c1 b c2`.
#[derive(Clone, Debug)]
pub struct Hinge {
    /// The two triangles.
    pub mesh: Mesh,
}

/// A [`Hinge`]: `a` and `b` with NDC x and y on multiples of 1/256 and z on multiples of 1/64
/// (`a` behind the near plane, `b` in front), `c1` and `c2` anywhere in front on either side.
/// With a viewport side that is not a power of two such coordinates put the clipped vertex of
/// `a b` exactly halfway between two points of the fixed-point grid now and then.
pub fn hinge() -> impl Strategy<Value = Hinge> {
    let dyadic = || (-256_i32..=256).prop_map(|k| k as f32 / 256.0);
    let wing = || (0.1_f32..0.9, 0.05_f32..1.5, 1_i32..=63);
    (
        [dyadic(), dyadic()],
        -64_i32..=-1,
        [dyadic(), dyadic()],
        1_i32..=64,
        wing(),
        wing(),
    )
        .prop_filter("a and b must differ in x or y", |(a, _, b, _, _, _)| a != b)
        .prop_map(|(a, za, b, zb, (t1, s1, z1), (t2, s2, z2))| {
            let d = [b[0] - a[0], b[1] - a[1]];
            let side = |t: f32, s: f32, z: i32, sign: f32| {
                [
                    a[0] + d[0] * t - sign * d[1] * s,
                    a[1] + d[1] * t + sign * d[0] * s,
                    z as f32 / 64.0,
                ]
            };
            Hinge {
                mesh: Mesh {
                    positions: vec![
                        [a[0], a[1], za as f32 / 64.0],
                        [b[0], b[1], zb as f32 / 64.0],
                        side(t1, s1, z1, 1.0),
                        side(t2, s2, z2, -1.0),
                    ],
                    triangles: vec![[0, 1, 2], [1, 0, 3]],
                },
            }
        })
}

impl Hinge {
    /// What each pixel centre must hold under the identity camera, where that is certain whatever
    /// the rounding: `Some(1)` for centres clearly (by 1/64 pixel) inside the quadrilateral where
    /// both triangles' planes give a depth clearly inside `(0, 1)` (near the shared edge the two
    /// planes agree), `Some(0)` for centres clearly outside it or where both planes are clearly in
    /// front of the near plane (or both beyond depth 1), `None` (at most once) elsewhere.
    pub fn robust_expectation(&self, viewport: Viewport) -> Vec<Option<u32>> {
        let (w, h) = (f64::from(viewport.width), f64::from(viewport.height));
        let window = |p: [f32; 3]| {
            [
                (f64::from(p[0]) * 0.5 + 0.5) * w,
                (0.5 - f64::from(p[1]) * 0.5) * h,
                f64::from(p[2]),
            ]
        };
        let [a, b, c1, c2] = [0, 1, 2, 3].map(|i| window(self.mesh.positions[i]));
        let cross = |o: [f64; 3], p: [f64; 3], q: [f64; 2]| {
            (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
        };
        // Depth planes over window coordinates, as z = gx·X + gy·Y + z0.
        let plane = |p: [f64; 3], q: [f64; 3], r: [f64; 3]| {
            let area = cross(p, q, [r[0], r[1]]);
            let gx = ((q[2] - p[2]) * (r[1] - p[1]) - (r[2] - p[2]) * (q[1] - p[1])) / area;
            let gy = ((r[2] - p[2]) * (q[0] - p[0]) - (q[2] - p[2]) * (r[0] - p[0])) / area;
            (gx, gy, p[2] - gx * p[0] - gy * p[1])
        };
        let planes = [plane(a, b, c1), plane(b, a, c2)];
        let m = 1.0 / 64.0;
        let mz = planes
            .iter()
            .map(|(gx, gy, _)| (gx.abs() + gy.abs()) * m)
            .fold(0.0, f64::max)
            + 1e-6;
        let quad = [a, c1, b, c2];
        let orientation = cross(a, c1, [b[0], b[1]]).signum();
        let mut expected = Vec::with_capacity(viewport.pixels());
        for j in 0..viewport.height {
            for i in 0..viewport.width {
                let p = [f64::from(i) + 0.5, f64::from(j) + 0.5];
                let distances = (0..4).map(|e| {
                    let (u, v) = (quad[e], quad[(e + 1) % 4]);
                    orientation * cross(u, v, p) / (v[0] - u[0]).hypot(v[1] - u[1])
                });
                let inside = distances.clone().all(|d| d > m);
                let outside = distances.clone().any(|d| d < -m);
                let z = planes.map(|(gx, gy, z0)| gx * p[0] + gy * p[1] + z0);
                let (lo, hi) = (z[0].min(z[1]), z[0].max(z[1]));
                expected.push(if outside || hi < -mz || lo > 1.0 + mz {
                    Some(0)
                } else if inside && lo > mz && hi < 1.0 - mz {
                    Some(1)
                } else {
                    None
                });
            }
        }
        expected
    }
}
