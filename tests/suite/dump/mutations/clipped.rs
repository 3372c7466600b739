//! The battery's clipped family: the kinds applied to triangles the near plane and the guard
//! band clip, judged exactly and within the precision of an f32 vertex stage, which bounds a
//! clipped triangle's pieces from the vertices the clipping makes (`docs/semantics.md` §10,
//! "Clipped triangles"). The scene is an engine's: two ground strips that pass behind the eye
//! (every pixel that sees them two clipped fragments deep) and a post standing on them, seen
//! through an explicit view-projection matrix in f32, as a uniform holds it.
//!
//! The strips are narrow enough that the near plane's crossings stay inside the guard band. A
//! triangle the guard band clips as well (a ground 80 units wide, `backends/wgpu/tests/clipped.rs`)
//! is analysed too, but its vertices on the guard band, 16384 pixels out, carry errors of
//! thousands of subpixels under the analysis's per-coordinate bounds, and no pixel of it is clean
//! of doubt enough to mutate; that scene is judged from a real lavapipe capture instead.

use fragsim::catalog::SchemeName;
use fragsim::dump::Direction;
use fragsim::dump::{DepthFormat, Dump, DumpScheme, LayoutSpec, Payload, SlotOrder};
use fragsim::oracle::precision::{f32_reference, Precision};
use fragsim::raster::conventions::VertexPrecision;
use fragsim::raster::scene_spec::{SceneSpec, ViewProjection};
use fragsim::raster::{Conventions, Viewport};

use super::{run_battery, scratch, Judge, Layout, CAPACITY, K, UNORM24};
use crate::support::prim_of;

/// Two ground strips 6 units wide from 2 units behind the eye to 30 ahead, at `y = 0`
/// (primitives 0 and 1) and `y = 0.1` (2 and 3), and a post 3 units ahead standing through both
/// (4 and 5, not clipped).
const SCENE_OBJ: &str = "\
v -3 0 -30\nv 3 0 -30\nv 3 0 2\nv -3 0 2\n\
v -3 0.1 -30\nv 3 0.1 -30\nv 3 0.1 2\nv -3 0.1 2\n\
v -0.5 0 -3\nv 0.5 0 -3\nv 0.5 0.6 -3\nv -0.5 0.6 -3\n\
f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 9 10 11\nf 9 11 12\n";

/// How many of the scene's triangles the reference clips, the first ones: both strips' pairs.
const CLIPPED: usize = 4;

/// `a × b`.
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a · b`.
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum()
}

/// `a` scaled to length 1.
fn normalized(a: [f64; 3]) -> [f64; 3] {
    let length = dot(a, a).sqrt();
    a.map(|c| c / length)
}

/// An engine's camera 0.3 above the lower ground looking down ahead (towards the point
/// `(0, −0.2, −1)`): a right-handed view and a Vulkan projection (depth in [0, 1]) of 60° with
/// the near plane at 0.1 and the far one at 100, their product's entries the f32 values a uniform
/// holds (the matrix of `backends/wgpu/tests/clipped.rs`, built without glam).
#[expect(
    clippy::cast_possible_truncation,
    reason = "narrowing is the point: the engine's matrix holds each f64 product rounded to f32"
)]
fn engine_matrix() -> ViewProjection {
    let (near, far) = (0.1, 100.0);
    let focal = 1.0 / 30_f64.to_radians().tan();
    let range = far / (near - far);
    let projection = [
        [focal, 0.0, 0.0, 0.0],
        [0.0, focal, 0.0, 0.0],
        [0.0, 0.0, range, range * near],
        [0.0, 0.0, -1.0, 0.0],
    ];
    let eye = [0.0, 0.3, 0.0];
    let forward = normalized([0.0, -0.5, -1.0]);
    let side = normalized(cross(forward, [0.0, 1.0, 0.0]));
    let up = cross(side, forward);
    let view = [
        [side[0], side[1], side[2], -dot(side, eye)],
        [up[0], up[1], up[2], -dot(up, eye)],
        [-forward[0], -forward[1], -forward[2], dot(forward, eye)],
        [0.0, 0.0, 0.0, 1.0],
    ];
    ViewProjection {
        row_major: std::array::from_fn(|i| {
            let (row, column) = (i / 4, i % 4);
            let entry: f64 = (0..4).map(|j| projection[row][j] * view[j][column]).sum();
            f64::from(entry as f32)
        }),
        precision: VertexPrecision::F32,
    }
}

#[test]
fn mutants_of_clipped_triangles_are_different_exactly_and_under_f32() {
    let dir = scratch("mutation-battery-clipped");
    let mesh = dir.join("ground.obj");
    std::fs::write(&mesh, SCENE_OBJ).unwrap();
    let mut spec = SceneSpec::mesh(&mesh, 0.0, 0.0);
    spec.view_projection = Some(engine_matrix());
    let scene = spec.load(None).unwrap();
    let viewport = Viewport::new(64, 48).unwrap();
    let view = spec.view(&scene, viewport).unwrap();
    let triangle_count =
        u32::try_from(scene.mesh.triangles.len()).expect("a ground of a few strips");
    let clipped = (0..triangle_count)
        .filter(|&prim| view.clipped(prim).is_some())
        .count();
    assert_eq!(clipped, CLIPPED, "the ground's triangles are clipped");
    let (oracle, f32_analysis) = f32_reference(&spec, viewport, None).unwrap();
    let bounds = f32_analysis.bounds();
    assert_eq!(
        (bounds.clipped_triangles, bounds.unanalysed_triangles),
        (CLIPPED as u64, 0),
        "every clipped triangle analysed"
    );
    // The mutants' sites are pixels of two fragments or more: each holds a clipped one.
    let clipped_prims = u32::try_from(CLIPPED).expect("a few clipped triangles");
    assert!(
        (0..oracle.pixels())
            .filter(|&p| oracle.pixel(p).len() >= 2)
            .all(|p| oracle.pixel(p).iter().any(|&w| prim_of(w) < clipped_prims)),
        "every pixel two fragments deep holds a clipped one"
    );
    let exact_conventions = Conventions {
        vertex_precision: VertexPrecision::F64,
        ..spec.conventions
    };
    let unorm_exact =
        Precision::derive(&view, &exact_conventions).stored_as(UNORM24.depth, &oracle);
    let unorm_f32 = f32_analysis.clone().stored_as(UNORM24.depth, &oracle);
    let record =
        |scheme: DumpScheme| Dump::record(&view, spec.clone(), &scheme, "clipped").unwrap();
    let mdts = DumpScheme::Mdts {
        k: K,
        direction: Direction::Ascending,
    };
    let engine_lists = DumpScheme::LinkedLists {
        scheme: SchemeName::LinkedList,
        k: K,
        pool: u32::try_from(oracle.fragments()).expect("a 64 × 48 view's fragments") + 8,
        spec: LayoutSpec::FRAGSIM_LISTS,
    };
    let schemes: [(&str, DumpScheme, Option<LayoutSpec>); 5] = [
        ("mdts", mdts.clone(), None),
        (
            "kbuf-ordered",
            DumpScheme::KBuffer {
                scheme: SchemeName::KbufferInterlockOrdered,
                k: K,
            },
            None,
        ),
        (
            "abuffer",
            DumpScheme::ABufferFixed {
                capacity: CAPACITY,
                sorted: false,
            },
            None,
        ),
        (
            "list-engine",
            engine_lists,
            Some(LayoutSpec::LinkedList {
                payload: Payload::FRAGMENT,
                null: u32::MAX,
                node_base: 0,
            }),
        ),
        (
            "mdts-unorm24",
            mdts,
            Some(LayoutSpec::Slots {
                order: SlotOrder::PixelMajor,
                payload: Some(UNORM24),
            }),
        ),
    ];
    let triangles = &scene.mesh.triangles[..];
    let layouts: Vec<Layout<'_>> = schemes
        .into_iter()
        .map(|(name, scheme, encoding)| {
            let unorm = encoding.is_some_and(
                |layout| matches!(layout, LayoutSpec::Slots { payload: Some(p), .. } if p == UNORM24),
            );
            let (exact, within) = if unorm {
                (unorm_exact.clone(), unorm_f32.clone())
            } else {
                (f32_analysis.clone(), f32_analysis.clone())
            };
            Layout {
                name,
                own: record(scheme),
                encoding,
                oracle: &oracle,
                judges: vec![
                    (
                        "exact",
                        if unorm {
                            Judge::Within(Box::new(exact))
                        } else {
                            Judge::Exact
                        },
                    ),
                    ("f32", Judge::Within(Box::new(within))),
                ],
                possible: Some(if unorm { &unorm_f32 } else { &f32_analysis }),
                format: if unorm {
                    UNORM24.depth
                } else {
                    DepthFormat::F32
                },
                triangles,
            }
        })
        .collect();
    run_battery(
        &layouts,
        300,
        &format!(
            "clipped scene: {} fragments, depth complexity up to {}, {CLIPPED} of {} triangles \
             clipped and analysed; f32 analysis: vertex error up to {:.2} subpixels, {} (pixel, \
             triangle) pairs in doubt",
            oracle.fragments(),
            oracle.max_depth_complexity(),
            triangles.len(),
            bounds.max_vertex_error_subpixels,
            bounds.ambiguous_pairs,
        ),
    );
}
