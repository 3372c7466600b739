//! A conformance case: a tiny triangle soup drawn straight in window coordinates (the identity
//! view-projection), a viewport, a submission order and a schedule, and its proptest strategy
//! ([`case`]).
//!
//! Guarantee: most cases are **deep**: three in four hold at least [`Limits::depth`] triangles
//! (two more than the larger of K and the capacity, as the battery sets it), most of them layers
//! on one footprint (the first triangle's, which then covers the viewport: stacked on it at
//! their own depths, crossing the plane of the one before, an exact coplanar duplicate of it) or
//! covering the whole viewport, so that the depth complexity passes
//! K and the capacity and fixed storage overflows: what a scheme's guarantee is about. Every case
//! also makes the rasterizer's hard decisions often: its corners lie on the half-pixel grid
//! (pixel centres and pixel edges), so edges pass exactly through pixel centres (the fill rule;
//! some triangles are drawn with their legs on the centre lines), triangles share edges and
//! vertices (some are drawn sharing an edge with the triangle before them, as a mesh's quads do:
//! a hole or a double there is wrong under every edge-tie rule), coplanar triangles lie at equal
//! depths (the tie policy), depths are exactly 0 and 1, triangles cross the near plane (`z < 0`)
//! and the far one, and a few corners lie far beyond the guard band. The snapped corners are
//! exact: a corner at `h` half pixels is `h / width − 1` in normalised device coordinates, which
//! f32 holds to far below the 1/256-pixel snapping grid at these viewport sizes, so snapping
//! gives back `128 · h`.
//!
//! Source: the rules of `docs/semantics.md` §1–6 (what is hard for a scan and a depth
//! interpolation), the case shapes the proptest suite's regressions were found with, and the
//! plants of `docs/testing.md` (an A-buffer bug that only overflow or a third fragment shows).

use fragsim_capture::executors::scheduled::Schedule;
use fragsim_raster::scene_spec::{SceneSpec, ViewProjection};
use fragsim_raster::{Camera, Mesh, Scene, VertexPrecision, Viewport};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

use crate::strategies::schedule;

/// The identity matrix, row major: model x and y are normalised device coordinates, z the depth.
const IDENTITY: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

/// A corner far beyond the guard band (16,384 pixels), in half pixels: its triangle is clipped.
const FAR_OUT: i32 = 100_000;

/// One triangle of a case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CaseTriangle {
    /// The corners in half pixels of the window, y down: `(1, 1)` is pixel (0, 0)'s centre,
    /// `(2, 2)` the corner it shares with pixel (1, 1).
    pub corners: [[i32; 2]; 3],
    /// Each corner's depth (`z`; the view-projection is the identity, so `z` is the window
    /// depth): in `[0, 1]`, or outside it to cross the near or the far plane.
    pub depths: [f32; 3],
}

/// A conformance case: what a backend is given to capture.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The viewport.
    pub viewport: Viewport,
    /// The triangles, in submission order (primitive `i` is `triangles[i]`).
    pub triangles: Vec<CaseTriangle>,
    /// Sort keys of the other submission order the battery checks ([`Case::permuted`]).
    pub order_keys: Vec<u8>,
    /// The interleaving, for backends that take one (fragsim's scheduled executor).
    pub schedule: Schedule,
}

/// How large cases may be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// The largest viewport side, in pixels (at least 1).
    pub max_side: u32,
    /// The most triangles a case holds (at least 1).
    pub max_triangles: usize,
    /// Whether every viewport side is a power of two (at most `max_side`): for backends that
    /// take no other ([`crate::Backend::power_of_two_viewports`]).
    pub power_of_two: bool,
    /// Whether some corners lie far beyond the guard band (their triangles clipped by fragsim
    /// before snapping). On by default; off only to look past a known difference in clipping
    /// (the wgpu backend on lavapipe: `backends/wgpu/tests/conform.rs`).
    pub far_corners: bool,
    /// How many triangles a deep case holds at least (three cases in four are deep; capped at
    /// `max_triangles`). 0, the default, lets the battery set it from the scheme's sizes: two
    /// more than the larger of K and the capacity, so that most cases overflow both.
    pub depth: usize,
}

impl Default for Limits {
    /// Viewports up to 8×8, up to 6 triangles: enough to overlap several fragments a pixel, small
    /// enough that a failing case reads at a glance.
    fn default() -> Self {
        Self {
            max_side: 8,
            max_triangles: 6,
            power_of_two: false,
            far_corners: true,
            depth: 0,
        }
    }
}

impl Case {
    /// The case's mesh: three vertices of its own per triangle, in submission order.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "positions are f32, as the mesh stores them; a case has a few triangles"
    )]
    pub fn mesh(&self) -> Mesh {
        let (w, h) = (
            f64::from(self.viewport.width),
            f64::from(self.viewport.height),
        );
        let mut positions = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            for (corner, &z) in t.corners.iter().zip(&t.depths) {
                // Window X = (x + 1) / 2 · width in half pixels is h_x: x = h_x / width − 1.
                let x = f64::from(corner[0]) / w - 1.0;
                let y = 1.0 - f64::from(corner[1]) / h;
                positions.push([x as f32, y as f32, z]);
            }
        }
        let triangles = (0..self.triangles.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        Mesh {
            positions,
            triangles,
        }
    }

    /// The case as a scene (named `case`).
    #[must_use]
    pub fn scene(&self) -> Scene {
        Scene {
            name: "case".into(),
            mesh: self.mesh(),
        }
    }

    /// The camera every case is seen through: the identity view-projection.
    #[must_use]
    pub fn camera() -> Camera {
        Camera::from_row_major(IDENTITY)
    }

    /// The scene object of a dump header for this case's mesh stored at `mesh` (an OBJ file)
    /// whose bytes hash to `mesh_hash`: the identity matrix in f64, the reference conventions.
    #[must_use]
    pub fn scene_and_camera(mesh: &str, mesh_hash: String) -> SceneSpec {
        SceneSpec {
            mesh_hash: Some(mesh_hash),
            view_projection: Some(ViewProjection {
                row_major: IDENTITY,
                precision: VertexPrecision::F64,
            }),
            ..SceneSpec::mesh(std::path::Path::new(mesh), 0.0, 0.0)
        }
    }

    /// The smallest case a backend can be given: a 1×1 viewport and one triangle covering its
    /// pixel at depth 0.5 (one fragment), under `schedule`. A backend that fails this case too
    /// fails whatever the case ([`crate::Battery`] stops at once and shrinks nothing).
    #[must_use]
    pub fn smallest(schedule: Schedule) -> Self {
        Self {
            viewport: Viewport::new(1, 1).expect("a 1x1 viewport"),
            triangles: vec![CaseTriangle {
                corners: [[-1, -1], [5, -1], [-1, 5]],
                depths: [0.5; 3],
            }],
            order_keys: vec![0],
            schedule,
        }
    }

    /// The same triangles submitted in another order: sorted by their order keys (ties keep
    /// submission order). Primitive ids follow the new order.
    #[must_use]
    pub fn permuted(&self) -> Self {
        let mut order: Vec<usize> = (0..self.triangles.len()).collect();
        order.sort_by_key(|&i| self.order_keys.get(i).copied().unwrap_or(0));
        Self {
            triangles: order.iter().map(|&i| self.triangles[i]).collect(),
            ..self.clone()
        }
    }

    /// The window rectangle of `width` × `height` pixels from pixel `(x, y)` as a case of its
    /// own: the viewport shrunk, every corner moved by whole pixels, so each pixel of the
    /// rectangle keeps its fragments (coverage and depth move with the grid).
    #[must_use]
    pub fn cropped(&self, x: u32, y: u32, width: u32, height: u32) -> Option<Self> {
        let viewport = Viewport::new(width, height).ok()?;
        let (dx, dy) = (2 * i32::try_from(x).ok()?, 2 * i32::try_from(y).ok()?);
        let triangles = self
            .triangles
            .iter()
            .map(|t| CaseTriangle {
                corners: t.corners.map(|[cx, cy]| [cx - dx, cy - dy]),
                ..*t
            })
            .collect();
        Some(Self {
            viewport,
            triangles,
            ..self.clone()
        })
    }

    /// The case without triangle `index` (and its order key).
    #[must_use]
    pub fn without(&self, index: usize) -> Self {
        let mut case = self.clone();
        case.triangles.remove(index);
        if index < case.order_keys.len() {
            case.order_keys.remove(index);
        }
        case
    }

    /// The mesh as OBJ text: every coordinate printed as the shortest decimal that reads back to
    /// the same f32, so a backend (and `compare`) loading the file sees the case's very mesh.
    #[must_use]
    pub fn obj(&self) -> String {
        let mesh = self.mesh();
        let mut text = String::from("# a fragsim conformance case (identity view-projection)\n");
        for [x, y, z] in &mesh.positions {
            text.push_str(&format!("v {x} {y} {z}\n"));
        }
        for [a, b, c] in &mesh.triangles {
            text.push_str(&format!("f {} {} {}\n", a + 1, b + 1, c + 1));
        }
        text
    }
}

/// A corner coordinate in half pixels: on the grid from just outside the viewport's top-left
/// corner to just past its largest side, or (rarely, with `far_corners`) far beyond the guard
/// band. Shrinks towards 0, the viewport's top-left corner.
fn coordinate(max_side: u32, far_corners: bool) -> BoxedStrategy<i32> {
    let side = i32::try_from(max_side).unwrap_or(i32::MAX / 4);
    let near = -2..=2 * side + 2;
    if far_corners {
        prop_oneof![
            24 => near,
            1 => select(vec![-FAR_OUT, FAR_OUT]),
        ]
        .boxed()
    } else {
        near.boxed()
    }
}

/// A corner depth: one of a few exact values (so that coplanar triangles tie and depths 0 and 1
/// occur), any value in `[0, 1]`, or beyond the near or far plane. Shrinks towards 0.
fn depth() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => select(vec![0.0_f32, 0.25, 0.5, 0.75, 1.0]),
        2 => 0.0_f32..=1.0,
        1 => select(vec![-0.5_f32, 1.5]),
    ]
}

/// A corner depth of a deep case's layer: as [`depth`], but beyond the near or far plane one
/// time in twelve (a layer clipped away adds no depth). Shrinks towards 0.
fn layer_depth() -> impl Strategy<Value = f32> {
    prop_oneof![
        6 => select(vec![0.0_f32, 0.25, 0.5, 0.75, 1.0]),
        5 => 0.0_f32..=1.0,
        1 => select(vec![-0.5_f32, 1.5]),
    ]
}

/// A [`CaseTriangle`] (with `layer`, its depths those of a deep case's layer). Shrinks towards a
/// degenerate triangle at the top-left corner.
fn triangle(max_side: u32, far_corners: bool, layer: bool) -> impl Strategy<Value = CaseTriangle> {
    let corner = || {
        [
            coordinate(max_side, far_corners),
            coordinate(max_side, far_corners),
        ]
    };
    let z = move || {
        if layer {
            layer_depth().boxed()
        } else {
            depth().boxed()
        }
    };
    ([corner(), corner(), corner()], [z(), z(), z()])
        .prop_map(|(corners, depths)| CaseTriangle { corners, depths })
}

/// A viewport side from 1 to `max_side`, or with `power_of_two` one of the powers of two up to
/// it. Shrinks towards 1.
fn side(max_side: u32, power_of_two: bool) -> BoxedStrategy<u32> {
    if power_of_two {
        (0..=max_side.max(1).ilog2()).prop_map(|e| 1 << e).boxed()
    } else {
        (1..=max_side).boxed()
    }
}

/// A [`Case`] within `limits`: a viewport of sides 1 to `max_side` (powers of two with
/// `power_of_two`), another submission order, a [`schedule`], and triangles: one case in four
/// shallow (1 to `max_triangles` triangles, most placed freely), three in four deep (from
/// [`Limits::depth`], at least 1, to `max_triangles` triangles, most stacked on the one before or
/// covering the viewport). Shrinks towards fewer triangles, each placed freely, a 1×1 viewport,
/// corners at the top-left, depth 0, submission order, and the schedule's own simplest.
///
/// # Panics
/// (When sampled) if `limits.max_side` is 0 or above [`Viewport::MAX_SIDE`].
pub fn case(limits: Limits) -> impl Strategy<Value = Case> {
    let max_triangles = limits.max_triangles.max(1);
    let deep = limits.depth.clamp(1, max_triangles);
    let side = || side(limits.max_side, limits.power_of_two);
    let triangle = |layer| triangle(limits.max_side, limits.far_corners, layer);
    let drawn = prop_oneof![
        1 => vec((triangle(false), shape()), 1..=max_triangles),
        3 => vec((triangle(true), deep_shape()), deep..=max_triangles),
    ];
    (
        (side(), side()),
        drawn,
        vec(any::<u8>(), max_triangles),
        schedule(),
    )
        .prop_map(|((w, h), drawn, order_keys, schedule)| {
            let viewport = Viewport::new(w, h).expect("valid viewport side");
            Case {
                viewport,
                triangles: placed(&drawn, viewport),
                order_keys,
                schedule,
            }
        })
}

/// How a generated triangle is placed.
#[derive(Clone, Copy, Debug)]
enum Shape {
    /// At its own three corners.
    Free,
    /// A right triangle on the pixel-centre lines: its first corner moved onto a pixel centre,
    /// its second onto that centre's row and its third onto its column (each onto the centre
    /// line nearest its own coordinate), so that its legs pass through pixel centres, where
    /// the fill rule decides.
    OnCentres,
    /// Sharing an edge with the triangle before it: that triangle's edge `k` (from corner `k`),
    /// walked the other way as in a consistently wound mesh, with a third corner reflected
    /// through the edge's midpoint (a parallelogram split along the shared edge), so that the
    /// centres on the edge belong to exactly one of the two.
    SharesEdge(usize),
    /// On the corners of the case's first triangle at its own depths: a layer more over the
    /// same pixels (parallel, tilted against it, or coplanar where the depths agree).
    Stacked,
    /// On the corners of the triangle before it with that triangle's depths turned one corner
    /// on: the two planes cross inside the footprint (interpenetrating), unless it is flat.
    Crossing,
    /// The triangle before it again, corners and depths: a coplanar duplicate, tied at every
    /// pixel and ordered by primitive id.
    Duplicate,
    /// Covering every pixel of the viewport, at its own depths: its corners just outside the
    /// top-left corner and past twice the viewport's sides, inside the guard band.
    Covering,
}

/// A [`Shape`] of a shallow case: a triangle placed freely three times in six. Shrinks towards
/// [`Shape::Free`].
fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        3 => Just(Shape::Free),
        1 => Just(Shape::OnCentres),
        2 => (0_usize..3).prop_map(Shape::SharesEdge),
    ]
}

/// A [`Shape`] of a deep case: a layer on the triangle before (stacked, crossing or duplicated)
/// nine times in sixteen, covering the viewport four times, the shallow shapes the rest. Shrinks
/// towards [`Shape::Free`].
fn deep_shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        1 => Just(Shape::Free),
        1 => Just(Shape::OnCentres),
        1 => (0_usize..3).prop_map(Shape::SharesEdge),
        6 => Just(Shape::Stacked),
        2 => Just(Shape::Crossing),
        1 => Just(Shape::Duplicate),
        4 => Just(Shape::Covering),
    ]
}

/// The triangles `drawn` placed by their shapes in `viewport`, in order. The first has no
/// triangle to share an edge with or lie on: it stays where it was drawn, or covers the viewport
/// where it was to be a layer (stacked, crossing, a duplicate), so that the layers after it lie
/// on the viewport's every pixel.
fn placed(drawn: &[(CaseTriangle, Shape)], viewport: Viewport) -> Vec<CaseTriangle> {
    let mut placed: Vec<CaseTriangle> = Vec::with_capacity(drawn.len());
    // The centre line nearest a coordinate in half pixels: centres lie at odd ones.
    let centre_line = |h: i32| h | 1;
    // Past twice the sides: the hypotenuse from (4w + 1, −1) to (−1, 4h + 1) passes the last
    // pixel's centre (2w − 1, 2h − 1) by a pixel or more.
    let (w, h) = (
        i32::try_from(viewport.width).unwrap_or(i32::MAX / 8),
        i32::try_from(viewport.height).unwrap_or(i32::MAX / 8),
    );
    let covering = [[-1, -1], [4 * w + 1, -1], [-1, 4 * h + 1]];
    for &(t, shape) in drawn {
        let next = match (shape, placed.last()) {
            (Shape::OnCentres, _) => {
                let [a, b, c] = t.corners;
                let corner = a.map(centre_line);
                CaseTriangle {
                    corners: [
                        corner,
                        [centre_line(b[0]), corner[1]],
                        [corner[0], centre_line(c[1])],
                    ],
                    ..t
                }
            }
            (Shape::Covering | Shape::Stacked | Shape::Crossing | Shape::Duplicate, None)
            | (Shape::Covering, _) => CaseTriangle {
                corners: covering,
                ..t
            },
            (Shape::SharesEdge(k), Some(before)) => {
                let (p, q, r) = (k, (k + 1) % 3, (k + 2) % 3);
                let [p_at, q_at, r_at] = [p, q, r].map(|i| before.corners[i]);
                CaseTriangle {
                    corners: [
                        q_at,
                        p_at,
                        [p_at[0] + q_at[0] - r_at[0], p_at[1] + q_at[1] - r_at[1]],
                    ],
                    depths: [before.depths[q], before.depths[p], t.depths[2]],
                }
            }
            (Shape::Stacked, Some(_)) => CaseTriangle {
                corners: placed[0].corners,
                ..t
            },
            (Shape::Crossing, Some(before)) => {
                let [a, b, c] = before.depths;
                CaseTriangle {
                    corners: before.corners,
                    depths: [b, c, a],
                }
            }
            (Shape::Duplicate, Some(before)) => *before,
            _ => t,
        };
        placed.push(next);
    }
    placed
}
