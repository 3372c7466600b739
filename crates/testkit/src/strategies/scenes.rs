//! Scenes: procedural names, random triangle soups and closed meshes.

use std::collections::HashMap;

use fragsim_raster::{Mesh, Scene};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

// Scenes

/// A name understood by [`Scene::procedural`], kept cheap enough for hundreds of cases:
/// `spheres:N` with `N` in `1..=6` (2,208 triangles a sphere: more than one rayon task of 1,024
/// triangles, so the parallel executor really interleaves), `soup:COUNT:SEED` with any seed and
/// `COUNT` in `1..=200` or, less often, in `1025..=2500` (several rayon tasks over the same
/// pixels, depth complexity in the hundreds), or `quads:N` with `N` in `1..=16` (coplanar pairs,
/// shared diagonals, equal depths across a quad when seen face-on).
pub fn procedural_scene_name() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => (1_u32..=6).prop_map(|n| format!("spheres:{n}")),
        3 => (1_u32..=200, any::<u64>()).prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        1 => (1025_u32..=2500, any::<u64>())
            .prop_map(|(count, seed)| format!("soup:{count}:{seed}")),
        2 => (1_u32..=16).prop_map(|n| format!("quads:{n}")),
    ]
}

/// A scene to build inside a test: a procedural name, or a random mesh.
#[derive(Clone, Debug)]
pub enum GeneratedScene {
    /// A name for [`Scene::procedural`].
    Procedural(String),
    /// A mesh, e.g. from [`random_mesh_in_box`].
    Mesh(Mesh),
}

impl GeneratedScene {
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
pub fn generated_scene() -> impl Strategy<Value = GeneratedScene> {
    prop_oneof![
        2 => procedural_scene_name().prop_map(GeneratedScene::Procedural),
        1 => random_mesh_in_box(40).prop_map(GeneratedScene::Mesh),
    ]
}

// ---------------------------------------------------------------------------------------------
// Random triangle soups
// ---------------------------------------------------------------------------------------------

/// A coordinate in `[-1, 1]`: uniform, or (a quarter of the time) on the coarse grid `k / 4`, so
/// that vertices, edges and planes coincide.
pub fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -1.0_f32..=1.0,
        1 => (-4_i32..=4).prop_map(|k| k as f32 / 4.0),
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
    (select(vec![0.0_f32, 1e-7, 1e-5, 1e-3]), point()).prop_map(|(s, p)| p.map(|c| c * s))
}

fn piece() -> impl Strategy<Value = Piece> {
    prop_oneof![
        4 => [point(), point(), point()].prop_map(Piece::Free),
        1 => (point(), point(), 0.0_f32..=1.0, tiny_offset())
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
        #[expect(
            clippy::cast_possible_truncation, clippy::shadow_unrelated,
            reason = "the closure is handed the mesh it extends; a generated mesh has at most a few thousand vertices"
        )]
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
                    #[expect(
                        clippy::cast_possible_truncation,
                        reason = "a generated mesh has at most a few thousand vertices"
                    )]
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
        select(vec![0.01_f32, 1.0, 100.0, 3000.0]),
        [-10.0_f32..10.0, -10.0_f32..10.0, -10.0_f32..10.0],
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
#[expect(
    clippy::cast_possible_truncation,
    reason = "a generated mesh has at most a few thousand vertices; positions are f32, as the mesh stores them"
)]
pub fn icosphere(level: u32) -> Mesh {
    let t = (1.0 + 5.0_f64.sqrt()) / 2.0;
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
    #[expect(
        clippy::cast_possible_truncation,
        clippy::shadow_unrelated,
        reason = "the closure is handed the mesh it extends; a generated mesh has at most a few thousand vertices"
    )]
    let mut vertex = |mesh: &mut Mesh, lattice: [u32; 3]| -> u32 {
        *index.entry(lattice).or_insert_with(|| {
            mesh.positions
                .push(lattice.map(|c| 2.0 * c as f32 / n as f32 - 1.0));
            mesh.positions.len() as u32 - 1
        })
    };
    let mut quad = 0_usize;
    for axis in 0..3 {
        for side in [0, n] {
            let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
            for u in 0..n {
                for v in 0..n {
                    let corner = |du: u32, dv: u32| {
                        let mut lattice = [0_u32; 3];
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
        (0_u32..=2).prop_map(icosphere),
        (1_u32..=3, vec(any::<bool>(), 54)).prop_map(|(n, d)| lattice_cube(n, &d)),
    ]
    .prop_flat_map(|mesh| {
        let n = mesh.positions.len();
        let offset = [-1.0_f32..=1.0, -1.0_f32..=1.0, -1.0_f32..=1.0];
        (
            Just(mesh),
            0.0_f32..0.6,
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
