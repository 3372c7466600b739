//! Reusable proptest strategies for fragsim's integration tests.
//!
//! Everything here is small on purpose: viewports of 8 to 64 pixels a side and meshes of at most
//! a few thousand triangles, so that a property runs dozens of cases in a second or two of a
//! release build.
//!
//! | strategy | value |
//! |---|---|
//! | [`viewport`], [`viewport_with_sides`] | a [`Viewport`] |
//! | [`orbit_camera`], [`orbit_camera_outside`], [`orbit_camera_with_distance`] | an [`OrbitCamera`] |
//! | [`procedural_scene_name`], [`procedural_scene`] | a name for [`Scene::procedural`], the scene |
//! | [`random_mesh`], [`random_mesh_in_box`] | a triangle soup with near-degenerate and coincident triangles |
//! | [`scene_spec`] | a [`SceneSpec`]: a procedural name or a random mesh |
//! | [`closed_mesh`] | a watertight mesh (perturbed icosphere or subdivided cube) |
//! | [`planar_tiling`], [`viewport_and_tiling`] | a [`PlanarTiling`]: triangles tiling a rectangle |
//! | [`depth_plane`] | a [`DepthPlane`] to put a tiling on, crossing the near plane |
//! | [`hinge`] | a [`Hinge`]: two triangles sharing an edge that crosses the near plane |
//! | [`k_choice`] | a [`KChoice`]: a `K` (or capacity) relative to the depth complexity |
//! | [`unit_depth`], [`unit_depth_pair`] | depths in `[0, 1]` for the depth-key order |
//! | [`concurrency`] | a [`Concurrency`]: how a run interleaves (task size, schedule) |
//!
//! Scenes are generated as a [`SceneSpec`] rather than as a [`Scene`] so that a failing case
//! prints a short procedural name rather than thousands of vertices.

use std::collections::HashMap;
use std::ops::{Range, RangeInclusive};

use fragsim::capture::executor::{ParallelExecutor, Run};
use fragsim::capture::scheduled::{run_scheduled, Granularity, Policy, Schedule};
use fragsim::capture::Scheme;
use fragsim::raster::{Camera, Mesh, OrbitCamera, Scene, View, Viewport, SUBPIXEL_BITS};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

// ---------------------------------------------------------------------------------------------
// Viewports
// ---------------------------------------------------------------------------------------------

/// A viewport with each side drawn independently from `8..=64` (square and non-square).
pub fn viewport() -> impl Strategy<Value = Viewport> {
    viewport_with_sides(8..=64)
}

/// A viewport with each side drawn independently from `sides`.
///
/// # Panics
/// (When sampled) if `sides` contains 0 or a side above [`Viewport::MAX_SIDE`].
pub fn viewport_with_sides(sides: RangeInclusive<u32>) -> impl Strategy<Value = Viewport> {
    (sides.clone(), sides).prop_map(|(w, h)| Viewport::new(w, h).expect("valid viewport side"))
}

// ---------------------------------------------------------------------------------------------
// Cameras
// ---------------------------------------------------------------------------------------------

/// An orbit angle in degrees: uniform in `[0, 360)`, or one of the axis-aligned and diagonal
/// angles, which look straight at the faces of `quads` and cubes (edges through pixel centres,
/// equal depths across a face).
fn orbit_angle() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => 0.0f64..360.0,
        1 => select(vec![0.0, 45.0, 90.0, 180.0, 270.0, 315.0]),
    ]
}

/// An elevation in degrees: uniform in `[-89, 89]`, level, or the poles (clamped to ±89° by the
/// camera).
fn orbit_elevation() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -89.0f64..=89.0,
        1 => select(vec![0.0, 90.0, -90.0]),
    ]
}

/// A random orbit camera: any angle and elevation, a vertical field of view of 5° to 150°, and a
/// distance scale in `[0.2, 3)`. A third of the cameras have a scale below 1: the eye is close to
/// or inside the model's bounding sphere, so the near plane clips triangles.
pub fn orbit_camera() -> impl Strategy<Value = OrbitCamera> {
    prop_oneof![
        2 => orbit_camera_with_distance(1.0..3.0),
        1 => orbit_camera_with_distance(0.2..1.0),
    ]
}

/// A random orbit camera that sees the whole model from outside: distance scale in
/// `[1.05, 3)`, so no triangle is near-clipped and every fragment has a depth strictly inside
/// `(0, 1)`.
pub fn orbit_camera_outside() -> impl Strategy<Value = OrbitCamera> {
    orbit_camera_with_distance(1.05..3.0)
}

/// A random orbit camera with `distance_scale` drawn from `distance`.
pub fn orbit_camera_with_distance(distance: Range<f64>) -> impl Strategy<Value = OrbitCamera> {
    (orbit_angle(), orbit_elevation(), 5.0f64..150.0, distance).prop_map(
        |(angle_degrees, elevation_degrees, fov_y_degrees, distance_scale)| OrbitCamera {
            angle_degrees,
            elevation_degrees,
            fov_y_degrees,
            distance_scale,
        },
    )
}

/// The identity camera: model x and y in `[-1, 1]` map straight onto the viewport (y up in the
/// model, down in the window), model z is the depth. Used with
/// `View::new(&mesh, &identity_camera(), viewport, CullMode::None)`.
pub fn identity_camera() -> Camera {
    // `DMat4::default()` is the identity; going through `Default` spares the tests a direct
    // dependency on glam.
    Camera {
        view_projection: Default::default(),
    }
}

// ---------------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------------

/// A name understood by [`Scene::procedural`], kept cheap enough for hundreds of cases:
/// `spheres:N` with `N` in `1..=6` (2,208 triangles a sphere: more than one rayon task of 1,024
/// triangles, so the parallel executor really interleaves), `soup:COUNT:SEED` with any seed and
/// `COUNT` in `1..=200` or, less often, in `1025..=2500` (several rayon tasks over the same
/// pixels, depth complexity in the hundreds), or `quads:N` with `N` in `1..=16` (coplanar pairs,
/// shared diagonals, equal depths across a quad when seen face-on).
pub fn procedural_scene_name() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (1u32..=6).prop_map(|n| format!("spheres:{n}")),
        3 => (1u32..=200, any::<u64>()).prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        1 => (1025u32..=2500, any::<u64>())
            .prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        2 => (1u32..=16).prop_map(|n| format!("quads:{n}")),
    ]
}

/// A procedural scene (see [`procedural_scene_name`]).
pub fn procedural_scene() -> impl Strategy<Value = Scene> {
    procedural_scene_name()
        .prop_map(|name| Scene::procedural(&name).expect("procedural names are valid"))
}

/// A scene to build inside a test: a procedural name, or a random mesh.
#[derive(Clone, Debug)]
pub enum SceneSpec {
    /// A name for [`Scene::procedural`].
    Procedural(String),
    /// A mesh, e.g. from [`random_mesh_in_box`].
    Mesh(Mesh),
}

impl SceneSpec {
    /// The scene.
    ///
    /// # Panics
    /// If a procedural name is invalid (never for names from [`procedural_scene_name`]).
    pub fn scene(&self) -> Scene {
        match self {
            Self::Procedural(name) => Scene::procedural(name).expect("valid procedural name"),
            Self::Mesh(mesh) => Scene {
                name: "random-mesh".into(),
                mesh: mesh.clone(),
            },
        }
    }
}

/// A procedural scene (weight 2) or a random soup of up to 40 triangles in a random box
/// (weight 1).
pub fn scene_spec() -> impl Strategy<Value = SceneSpec> {
    prop_oneof![
        2 => procedural_scene_name().prop_map(SceneSpec::Procedural),
        1 => random_mesh_in_box(40).prop_map(SceneSpec::Mesh),
    ]
}

// ---------------------------------------------------------------------------------------------
// Random triangle soups
// ---------------------------------------------------------------------------------------------

/// A coordinate in `[-1, 1]`: uniform, or (a quarter of the time) on the coarse grid `k / 4`, so
/// that vertices, edges and planes coincide.
pub fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -1.0f32..=1.0,
        1 => (-4i32..=4).prop_map(|k| k as f32 / 4.0),
    ]
}

/// A point in the box `[-1, 1]^3` (see [`coordinate`]).
pub fn point() -> impl Strategy<Value = [f32; 3]> {
    [coordinate(), coordinate(), coordinate()]
}

/// One element of a random soup, turned into a triangle by [`random_mesh`].
#[derive(Clone, Debug)]
enum Piece {
    /// Three independent points.
    Free([[f32; 3]; 3]),
    /// `a`, `b` and a point on the segment `a b` at `t`, pushed off it by `offset` (tiny or zero):
    /// a needle or a zero-area triangle.
    Sliver {
        a: [f32; 3],
        b: [f32; 3],
        t: f32,
        offset: [f32; 3],
    },
    /// Two equal vertices: zero area.
    Collapsed { a: [f32; 3], b: [f32; 3] },
    /// An exact copy of an earlier triangle (index modulo the count so far): equal depths at every
    /// pixel they share. `shared` reuses its vertex indices; otherwise the coordinates are copied.
    /// `reversed` flips the winding.
    Coincident {
        of: usize,
        shared: bool,
        reversed: bool,
    },
    /// A triangle sharing edge `edge % 3` of an earlier triangle, with a new apex.
    SharedEdge {
        of: usize,
        edge: usize,
        apex: [f32; 3],
    },
}

/// A tiny offset: exactly zero, or a random vector scaled by `1e-7`, `1e-5` or `1e-3`.
fn tiny_offset() -> impl Strategy<Value = [f32; 3]> {
    (select(vec![0.0f32, 1e-7, 1e-5, 1e-3]), point()).prop_map(|(s, p)| p.map(|c| c * s))
}

fn piece() -> impl Strategy<Value = Piece> {
    prop_oneof![
        4 => [point(), point(), point()].prop_map(Piece::Free),
        1 => (point(), point(), 0.0f32..=1.0, tiny_offset())
            .prop_map(|(a, b, t, offset)| Piece::Sliver { a, b, t, offset }),
        1 => (point(), point()).prop_map(|(a, b)| Piece::Collapsed { a, b }),
        2 => (any::<usize>(), any::<bool>(), any::<bool>())
            .prop_map(|(of, shared, reversed)| Piece::Coincident { of, shared, reversed }),
        2 => (any::<usize>(), any::<usize>(), point())
            .prop_map(|(of, edge, apex)| Piece::SharedEdge { of, edge, apex }),
    ]
}

/// A random triangle soup of `1..=max_triangles` triangles with vertices in `[-1, 1]^3`.
///
/// Besides free triangles it holds near-degenerate ones (needles, slivers, zero-area triangles
/// with two equal vertices), exact copies of earlier triangles (coincident: equal depths, with
/// shared or copied vertices, either winding) and triangles sharing an edge with an earlier one.
/// Triangle `i` is primitive `i`; every index is valid.
pub fn random_mesh(max_triangles: usize) -> impl Strategy<Value = Mesh> {
    let max_triangles = max_triangles.max(1);
    ([point(), point(), point()], vec(piece(), 0..max_triangles)).prop_map(|(first, pieces)| {
        let mut mesh = Mesh::default();
        let push = |mesh: &mut Mesh, points: [[f32; 3]; 3]| {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(points);
            mesh.triangles.push([base, base + 1, base + 2]);
        };
        push(&mut mesh, first);
        for piece in pieces {
            match piece {
                Piece::Free(points) => push(&mut mesh, points),
                Piece::Sliver { a, b, t, offset } => {
                    let c = [0, 1, 2].map(|i| a[i] + t * (b[i] - a[i]) + offset[i]);
                    push(&mut mesh, [a, b, c]);
                }
                Piece::Collapsed { a, b } => push(&mut mesh, [a, a, b]),
                Piece::Coincident {
                    of,
                    shared,
                    reversed,
                } => {
                    let mut tri = mesh.triangles[of % mesh.triangles.len()];
                    if reversed {
                        tri.swap(1, 2);
                    }
                    if shared {
                        mesh.triangles.push(tri);
                    } else {
                        let points = tri.map(|i| mesh.positions[i as usize]);
                        push(&mut mesh, points);
                    }
                }
                Piece::SharedEdge { of, edge, apex } => {
                    let tri = mesh.triangles[of % mesh.triangles.len()];
                    let (i, j) = (tri[edge % 3], tri[(edge + 1) % 3]);
                    let k = mesh.positions.len() as u32;
                    mesh.positions.push(apex);
                    // The opposite winding along the shared edge, as in a consistent mesh.
                    mesh.triangles.push([j, i, k]);
                }
            }
        }
        mesh
    })
}

/// A [`random_mesh`] scaled by 0.01, 1, 100 or 3000 and moved by up to 10 times its scale, so that
/// the camera's fit and the f32 coordinates see very different magnitudes.
pub fn random_mesh_in_box(max_triangles: usize) -> impl Strategy<Value = Mesh> {
    (
        random_mesh(max_triangles),
        select(vec![0.01f32, 1.0, 100.0, 3000.0]),
        [-10.0f32..10.0, -10.0f32..10.0, -10.0f32..10.0],
    )
        .prop_map(|(mut mesh, scale, offset)| {
            for p in &mut mesh.positions {
                for axis in 0..3 {
                    p[axis] = (p[axis] + offset[axis]) * scale;
                }
            }
            mesh
        })
}

// ---------------------------------------------------------------------------------------------
// Closed meshes
// ---------------------------------------------------------------------------------------------

/// An icosphere of radius 1: the icosahedron subdivided `level` times (20 · 4^level triangles),
/// vertices shared, closed.
pub fn icosphere(level: u32) -> Mesh {
    let t = (1.0 + 5.0f64.sqrt()) / 2.0;
    let mut points: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let mut mid = |i: u32, j: u32| {
                *midpoints.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    let (p, q) = (points[i as usize], points[j as usize]);
                    points.push([0, 1, 2].map(|k| (p[k] + q[k]) / 2.0));
                    points.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions = points
        .iter()
        .map(|p| {
            let length = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            p.map(|c| (c / length) as f32)
        })
        .collect();
    Mesh {
        positions,
        triangles,
    }
}

/// The surface of the cube `[-1, 1]^3` cut into `n × n` squares a face, each split along the
/// diagonal that `diagonals[i % len]` picks; vertices shared, closed.
pub fn lattice_cube(n: u32, diagonals: &[bool]) -> Mesh {
    let n = n.max(1);
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut mesh = Mesh::default();
    let mut vertex = |mesh: &mut Mesh, lattice: [u32; 3]| -> u32 {
        *index.entry(lattice).or_insert_with(|| {
            mesh.positions
                .push(lattice.map(|c| 2.0 * c as f32 / n as f32 - 1.0));
            mesh.positions.len() as u32 - 1
        })
    };
    let mut quad = 0usize;
    for axis in 0..3 {
        for side in [0, n] {
            let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
            for u in 0..n {
                for v in 0..n {
                    let corner = |du: u32, dv: u32| {
                        let mut lattice = [0u32; 3];
                        lattice[axis] = side;
                        lattice[u_axis] = u + du;
                        lattice[v_axis] = v + dv;
                        lattice
                    };
                    let [a, b, c, d] = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|l| vertex(&mut mesh, l));
                    let flip = diagonals
                        .get(quad % diagonals.len().max(1))
                        .copied()
                        .unwrap_or(false);
                    quad += 1;
                    if flip {
                        mesh.triangles.extend([[a, b, d], [b, c, d]]);
                    } else {
                        mesh.triangles.extend([[a, b, c], [a, c, d]]);
                    }
                }
            }
        }
    }
    mesh
}

/// Whether every edge (an unordered pair of vertex indices) is used by an even number of
/// triangles: a closed surface, mod 2. Vertex positions may coincide; the projection of such a
/// mesh covers every point of the window an even number of times.
pub fn is_closed(mesh: &Mesh) -> bool {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for tri in &mesh.triangles {
        for e in 0..3 {
            let (i, j) = (tri[e], tri[(e + 1) % 3]);
            if i != j {
                *uses.entry((i.min(j), i.max(j))).or_default() += 1;
            }
        }
    }
    uses.values().all(|&u| u % 2 == 0)
}

/// A closed mesh: an icosphere (level 0 to 2) or a lattice cube (1 to 3 squares a side, random
/// diagonals), every vertex moved by a random vector of up to `amplitude ∈ [0, 0.6)` per axis
/// (it may self-intersect, it stays closed), and up to 3 vertices collapsed onto others (zero-area
/// triangles, still closed). See [`is_closed`].
pub fn closed_mesh() -> impl Strategy<Value = Mesh> {
    prop_oneof![
        (0u32..=2).prop_map(icosphere),
        (1u32..=3, vec(any::<bool>(), 54)).prop_map(|(n, d)| lattice_cube(n, &d)),
    ]
    .prop_flat_map(|mesh| {
        let n = mesh.positions.len();
        let offset = [-1.0f32..=1.0, -1.0f32..=1.0, -1.0f32..=1.0];
        (
            Just(mesh),
            0.0f32..0.6,
            vec(offset, n),
            vec((0..n, 0..n), 0..=3),
        )
    })
    .prop_map(|(mut mesh, amplitude, offsets, collapses)| {
        for (p, o) in mesh.positions.iter_mut().zip(offsets) {
            for axis in 0..3 {
                p[axis] += amplitude * o[axis];
            }
        }
        for (from, onto) in collapses {
            mesh.positions[from] = mesh.positions[onto];
        }
        mesh
    })
}

// ---------------------------------------------------------------------------------------------
// Planar tilings (seen through the identity camera)
// ---------------------------------------------------------------------------------------------

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
pub fn snap_ndc_x(x: f32, width: u32) -> i64 {
    let one = f64::from(1u32 << SUBPIXEL_BITS);
    ((f64::from(x) / 1.0 * 0.5 + 0.5) * f64::from(width) * one).round() as i64
}

/// The snapped fixed-point window y (1/256 pixel, down) of NDC `y` through the identity camera.
pub fn snap_ndc_y(y: f32, height: u32) -> i64 {
    let one = f64::from(1u32 << SUBPIXEL_BITS);
    ((0.5 - f64::from(y) / 1.0 * 0.5) * f64::from(height) * one).round() as i64
}

/// NDC x of window x (pixels).
fn ndc_x(x: f64, width: u32) -> f32 {
    (2.0 * x / f64::from(width) - 1.0) as f32
}

/// NDC y of window y (pixels, down).
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
        let one = 1i64 << SUBPIXEL_BITS;
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
    (-64i32..=64, -64i32..=64, -32i32..=48).prop_map(|(a, b, c)| DepthPlane {
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
/// by up to [`JITTER`] of a cell (anywhere, or onto pixel centres or corners when that stays within
/// the bound), boundary vertices moved along their side only, each quad split along a random
/// diagonal.
pub fn jittered_grid(viewport: Viewport) -> impl Strategy<Value = PlanarTiling> {
    let (w, h) = (viewport.width, viewport.height);
    (
        window_interval(w),
        window_interval(h),
        1usize..=6,
        1usize..=6,
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
                vec(0.1f32..0.9, vertices),
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
    let side_points = || vec((0.0f64..=1.0, quantize()), 0..=4);
    let fraction = || {
        prop_oneof![
            3 => 0.001f64..0.999,
            1 => select(vec![1e-4, 1.0 - 1e-4, 0.5]),
        ]
    };
    (
        window_interval(w),
        window_interval(h),
        [side_points(), side_points(), side_points(), side_points()],
        (fraction(), fraction(), quantize()),
        vec(0.1f32..0.9, 21),
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
    let dyadic = || (-256i32..=256).prop_map(|k| k as f32 / 256.0);
    let wing = || (0.1f32..0.9, 0.05f32..1.5, 1i32..=63);
    (
        [dyadic(), dyadic()],
        -64i32..=-1,
        [dyadic(), dyadic()],
        1i32..=64,
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

// ---------------------------------------------------------------------------------------------
// K (slots, capacities)
// ---------------------------------------------------------------------------------------------

/// A choice of `K` (MDTS slots, A-buffer capacity) made before the scene's depth complexity is
/// known; [`KChoice::resolve`] turns it into a number once the oracle is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KChoice {
    /// `K = 1`.
    One,
    /// `K = max(1, ⌊fraction · max depth complexity⌋)`: usually below the maximum, so fragments
    /// overflow.
    Fraction(f64),
    /// `K` = the maximum depth complexity (at least 1): exact, with no slot to spare.
    Max,
    /// `K` = the maximum depth complexity plus `1..=3`.
    AboveMax(u32),
    /// A fixed `K` in `1..=8`, whatever the scene.
    Absolute(u32),
}

impl KChoice {
    /// The `K` for a scene whose largest per-pixel depth complexity is `max_depth_complexity`;
    /// always at least 1.
    pub fn resolve(self, max_depth_complexity: u32) -> u32 {
        let max = max_depth_complexity;
        match self {
            Self::One => 1,
            Self::Fraction(f) => (f * f64::from(max)) as u32,
            Self::Max => max,
            Self::AboveMax(extra) => max + extra,
            Self::Absolute(k) => k,
        }
        .max(1)
    }
}

/// A [`KChoice`]: below the maximum depth complexity about half of the time.
pub fn k_choice() -> impl Strategy<Value = KChoice> {
    prop_oneof![
        1 => Just(KChoice::One),
        3 => (0.0f64..1.0).prop_map(KChoice::Fraction),
        2 => Just(KChoice::Max),
        1 => (1u32..=3).prop_map(KChoice::AboveMax),
        1 => (1u32..=8).prop_map(KChoice::Absolute),
    ]
}

/// A [`KChoice`] for a small fixed capacity: 1 to 4 slots, or a fraction of the maximum.
pub fn small_capacity() -> impl Strategy<Value = KChoice> {
    prop_oneof![
        2 => (1u32..=4).prop_map(KChoice::Absolute),
        1 => (0.0f64..1.0).prop_map(KChoice::Fraction),
    ]
}

// ---------------------------------------------------------------------------------------------
// Depths
// ---------------------------------------------------------------------------------------------

/// The bit pattern of 1.0f32: the largest depth key.
const ONE_BITS: u32 = 0x3F80_0000;

/// A depth in `[0, 1]`: any f32 in the range with equal weight per bit pattern (so subnormals and
/// tiny depths are common), uniform in value, or a special value (`±0.0`, the smallest subnormal,
/// the smallest normal, 0.5, the largest float below 1, 1.0).
pub fn unit_depth() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => (0u32..=ONE_BITS).prop_map(f32::from_bits),
        2 => 0.0f32..=1.0,
        1 => select(vec![
            0.0f32,
            -0.0,
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            0.5,
            1.0 - f32::EPSILON / 2.0,
            1.0,
        ]),
    ]
}

/// Two depths in `[0, 1]`: independent (see [`unit_depth`]), or neighbours 1 to 4 ulps apart.
pub fn unit_depth_pair() -> impl Strategy<Value = (f32, f32)> {
    prop_oneof![
        (unit_depth(), unit_depth()),
        (0u32..ONE_BITS, 1u32..=4).prop_map(|(bits, ulps)| (
            f32::from_bits(bits),
            f32::from_bits((bits + ulps).min(ONE_BITS))
        )),
    ]
}

// ---------------------------------------------------------------------------------------------
// Concurrency
// ---------------------------------------------------------------------------------------------

/// How a property's concurrent runs interleave: the parallel executor with a small task size
/// (1 to 8 triangles a rayon task, so that even a scene of a dozen triangles runs on every
/// thread), and the scheduled executor under a random policy, width, granularity and seed (a
/// replayable interleaving, so that a failure shrinks and reproduces).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Concurrency {
    /// Triangles per rayon task of the parallel executor.
    pub task_size: usize,
    /// The scheduled executor's interleaving.
    pub schedule: Schedule,
}

impl Concurrency {
    /// `scheme`'s runs under this concurrency: the parallel executor's and the scheduled one's,
    /// each labelled for failure messages.
    pub fn runs<S: Scheme>(&self, view: &View<'_>, scheme: &S) -> [(String, Run); 2] {
        [
            (
                format!("parallel, {} triangles a task", self.task_size),
                ParallelExecutor::with_task_size(self.task_size).run(view, scheme),
            ),
            (
                format!("scheduled {:?}", self.schedule),
                run_scheduled(view, scheme, &self.schedule, false).run,
            ),
        ]
    }
}

/// A scheduling policy: random, lockstep warps, or PCT of depth 1 to 3.
pub fn policy() -> impl Strategy<Value = Policy> {
    prop_oneof![
        Just(Policy::Random),
        Just(Policy::Warps),
        (1u32..=3).prop_map(|depth| Policy::Pct { depth }),
    ]
}

/// A [`Concurrency`]: task sizes 1 to 8, 2 to 64 threads in flight, either granularity, any
/// seed. Shrinks towards one triangle a task and two fragments in flight under the random policy.
pub fn concurrency() -> impl Strategy<Value = Concurrency> {
    (
        1usize..=8,
        policy(),
        2usize..=64,
        prop_oneof![Just(Granularity::Fragment), Just(Granularity::Triangle)],
        any::<u64>(),
    )
        .prop_map(
            |(task_size, policy, in_flight, granularity, seed)| Concurrency {
                task_size,
                schedule: Schedule {
                    policy,
                    in_flight,
                    granularity,
                    seed,
                },
            },
        )
}
