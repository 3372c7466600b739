//! The battery's clipped-triangle family: every kind of the battery on a scene whose triangles
//! the near plane and the guard band clip (two ground planes under an engine's camera close above
//! them, both reaching behind the eye), judged bit-exactly and within the precision of an f32
//! vertex stage, whose analysis bounds the clipped pieces (`docs/semantics.md` §10, "Clipped
//! triangles") instead of excusing their fragments with any depth.

use std::path::Path;

use fragsim::capture::schemes::mdts::Direction;
use fragsim::oracle::dump::{DepthFormat, Dump, DumpScheme, LayoutSpec};
use fragsim::oracle::precision::f32_reference;
use fragsim::raster::conventions::VertexPrecision;
use fragsim::raster::scene_spec::{SceneSpec, ViewProjection};
use fragsim::raster::{Scene, Viewport};

use super::{run, scratch, table, Judge, Layout, CAPACITY, K};

/// Two squares 80 units a side around the eye, the ground at `y = 0` and a water surface at
/// `y = 0.1` (primitives 0–1 and 2–3), and a post standing on the ground 3 units ahead.
const SCENE_OBJ: &str = "\
v -40 0 -40\nv 40 0 -40\nv 40 0 40\nv -40 0 40\n\
v -40 0.1 -40\nv 40 0.1 -40\nv 40 0.1 40\nv -40 0.1 40\n\
v -0.5 0 -3\nv 0.5 0 -3\nv 0.5 0.6 -3\nv -0.5 0.6 -3\n\
f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 9 10 11\nf 9 11 12\n";

/// An engine's camera 0.3 above the ground looking down ahead: a 60° projection with depth in
/// [0, 1] and the near plane at 0.1, `look_at` toward `(0, −0.2, −1)`, written out row by row at
/// the precision of the f32 values a uniform holds (rounded when read).
fn engine_matrix() -> ViewProjection {
    // perspective_rh(60°, 48/36, 0.1, 100) · look_at_rh((0, 0.3, 0), (0, −0.2, −1), y).
    let f = 1.0 / 30_f64.to_radians().tan();
    let (aspect, near, far) = (48.0 / 36.0, 0.1, 100.0);
    let projection = [
        [f / aspect, 0.0, 0.0, 0.0],
        [0.0, f, 0.0, 0.0],
        [0.0, 0.0, far / (near - far), near * far / (near - far)],
        [0.0, 0.0, -1.0, 0.0],
    ];
    // The camera's axes: forward d = (0, −0.5, −1)/|…|, right = (1, 0, 0), up = right × −d.
    let length = 1.25_f64.sqrt();
    let (dy, dz) = (-0.5 / length, -1.0 / length);
    let eye = [0.0, 0.3, 0.0];
    let rows = [[1.0, 0.0, 0.0], [0.0, -dz, dy], [0.0, -dy, -dz]];
    let mut view = [[0.0; 4]; 4];
    for (r, axis) in rows.iter().enumerate() {
        view[r][..3].copy_from_slice(axis);
        view[r][3] = -(0..3).map(|c| axis[c] * eye[c]).sum::<f64>();
    }
    view[3][3] = 1.0;
    let row_major = std::array::from_fn(|i| {
        let (r, c) = (i / 4, i % 4);
        (0..4).map(|k| projection[r][k] * view[k][c]).sum::<f64>()
    });
    ViewProjection {
        row_major,
        precision: VertexPrecision::F32,
    }
}

fn scene_file(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("clipped.obj");
    std::fs::write(&path, SCENE_OBJ).unwrap();
    path
}

#[test]
fn clipped_triangles_are_judged_under_f32_as_exactly() {
    let dir = scratch("mutation-clipped");
    let mut spec = SceneSpec::mesh(&scene_file(&dir), 0.0, 0.0);
    spec.view_projection = Some(engine_matrix());
    let scene: Scene = spec.load(None).unwrap();
    let viewport = Viewport::new(48, 36).unwrap();
    let view = spec.view(&scene, viewport).unwrap();
    let (oracle, f32_analysis) = f32_reference(&spec, viewport, None).unwrap();
    let bounds = f32_analysis.bounds();
    assert_eq!(bounds.clipped_triangles, 4, "{bounds:?}");
    assert_eq!(bounds.unanalysed_triangles, 0);
    let record =
        |scheme: DumpScheme| Dump::record(&view, spec.clone(), &scheme, "battery").unwrap();
    let layouts: Vec<Layout<'_>> = [
        (
            "mdts",
            DumpScheme::Mdts {
                k: K,
                direction: Direction::Ascending,
            },
        ),
        (
            "abuffer",
            DumpScheme::ABufferFixed {
                capacity: CAPACITY,
                sorted: false,
            },
        ),
        (
            "list",
            DumpScheme::LinkedLists {
                scheme: fragsim::capture::catalog::SchemeName::LinkedList,
                k: K,
                pool: oracle.fragments() as u32 + 8,
                spec: LayoutSpec::FRAGSIM_LISTS,
            },
        ),
    ]
    .into_iter()
    .map(|(name, scheme)| Layout {
        name,
        own: record(scheme),
        encoding: None,
        oracle: &oracle,
        judges: vec![
            ("exact", Judge::Exact),
            ("f32", Judge::Within(f32_analysis.clone())),
        ],
        possible: Some(&f32_analysis),
        format: DepthFormat::F32,
        triangles: &scene.mesh.triangles,
    })
    .collect();
    let (mut tallies, mut wrong) = (Vec::new(), Vec::new());
    for (seed, layout) in layouts.iter().enumerate() {
        run(layout, 100 + seed as u64, &mut tallies, &mut wrong);
    }
    let names: Vec<&str> = layouts.iter().map(|l| l.name).collect();
    println!(
        "clipped family: {} fragments, 4 of 6 triangles clipped; f32 analysis: vertex error up to \
         {:.2} subpixels, depth intervals up to {} ulps, {} (pixel, triangle) pairs in doubt\n{}",
        oracle.fragments(),
        bounds.max_vertex_error_subpixels,
        bounds.max_depth_interval_ulps,
        bounds.ambiguous_pairs,
        table(&names, &tallies)
    );
    let total: usize = tallies.iter().map(|t| t.tried).sum();
    assert!(total > 200, "{total} judgements");
    assert!(wrong.is_empty(), "misjudged mutants: {wrong:#?}");
}
