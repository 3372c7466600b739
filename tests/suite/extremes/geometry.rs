//! Geometry: degenerate and sliver triangles, huge and tiny coordinates and models, the near and
//! eye planes, and layers closer than the depth precision.

use fragsim::capture::executors::{run_parallel, run_serial};
use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::oracle::Oracle;
use fragsim::raster::{depth_key, Camera, CullMode, Mesh, OrbitCamera, Scene, View};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::{Direction, Mdts};

use super::camera::camera_from_columns;
use super::{
    all_fragments, assert_exact, coverage, identity_view, perspective, soup, square, viewport,
    MAX_KEY,
};
use crate::support::prim_of;

#[test]
fn degenerate_triangles_produce_no_fragments() {
    let tiny = 1.0 / 4096.0; // 1/256 of a pixel on a 16-pixel side: below the snapping grid
    let mesh = soup(&[
        // collinear
        [[-1.0, -1.0, 0.5], [0.0, 0.0, 0.5], [1.0, 1.0, 0.5]],
        // a repeated vertex
        [[-1.0, -1.0, 0.5], [1.0, 0.0, 0.5], [1.0, 0.0, 0.5]],
        // one point
        [[0.3, 0.3, 0.5], [0.3, 0.3, 0.5], [0.3, 0.3, 0.5]],
        // smaller than the snapping grid, at a pixel centre
        [
            [1.0 / 16.0, 1.0 / 16.0, 0.5],
            [1.0 / 16.0 + tiny, 1.0 / 16.0, 0.5],
            [1.0 / 16.0, 1.0 / 16.0 + tiny, 0.5],
        ],
    ]);
    let view = identity_view(&mesh, 16, 16);
    for prim in 0..view.triangle_count() {
        let mut n = 0;
        view.rasterize(prim, &mut |_| n += 1);
        assert_eq!(n, 0, "triangle {prim}");
    }
}

#[test]
fn sliver_triangles_tile_the_screen_without_cracks_or_overlaps() {
    // A fan of 1,000 slivers from the top-left corner to the bottom edge, plus the triangle that
    // completes the square, and a sliver one grid step thick along the right edge.
    let n = 1000;
    let mut triangles: Vec<[[f32; 3]; 3]> = (0..n)
        .map(|i| {
            let x = |step: usize| -1.0 + 2.0 * step as f32 / n as f32;
            [[-1.0, 1.0, 0.5], [x(i), -1.0, 0.5], [x(i + 1), -1.0, 0.5]]
        })
        .collect();
    let thin = 1.0 - 1.0 / 8192.0;
    triangles.push([[-1.0, 1.0, 0.5], [1.0, -1.0, 0.5], [thin, 1.0, 0.5]]);
    triangles.push([[thin, 1.0, 0.5], [1.0, -1.0, 0.5], [1.0, 1.0, 0.5]]);
    let mesh = soup(&triangles);
    let counts = coverage(&identity_view(&mesh, 64, 64));
    assert!(counts.iter().all(|&c| c == 1), "{counts:?}");
}

#[test]
fn vertices_at_1e7_are_clipped_to_the_guard_band_and_cover_the_screen_once() {
    // Identity camera: x = 1e7 is 3·10^8 pixels off screen, far beyond the guard band.
    let mesh = soup(&square(1e7, 0.5));
    for (width, height) in [(64, 48), (1, 1)] {
        let view = identity_view(&mesh, width, height);
        let fragments = all_fragments(&view);
        assert_eq!(fragments.len(), (width * height) as usize);
        assert!(coverage(&view).iter().all(|&c| c == 1));
        assert!(fragments
            .iter()
            .all(|f| f.depth_key == depth_key(0.5).unwrap()));
    }
    let huge = soup(&[[[-1e7, -1e7, 0.25], [3e7, -1e7, 0.25], [-1e7, 3e7, 0.25]]]);
    assert!(coverage(&identity_view(&huge, 33, 17))
        .iter()
        .all(|&c| c == 1));
}

#[test]
fn vertices_at_1e_minus_7_snap_to_one_point_and_produce_nothing() {
    // 1e-7 in clip space is 3·10^-6 pixels on a 64-pixel side: far below the 1/256 grid.
    let centre = 1.0 / 64.0; // the centre of pixel (32, 31)
    let mesh = soup(&[[
        [centre, centre, 0.5],
        [centre + 1e-7, centre, 0.5],
        [centre, centre + 1e-7, 0.5],
    ]]);
    assert!(all_fragments(&identity_view(&mesh, 64, 64)).is_empty());
}

/// Per-pixel depth complexity of `spheres:3` scaled by `scale`, seen by the orbit camera at
/// 64 × 64, after checking MDTS captures it exactly.
fn scaled_spheres(scale: f32) -> Vec<u32> {
    let mut scene = Scene::procedural("spheres:3").unwrap();
    for p in &mut scene.mesh.positions {
        *p = p.map(|c| c * scale);
    }
    let view = scene
        .view(viewport(64, 64), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let k = oracle.max_depth_complexity();
    assert_eq!(k, 6, "scale {scale:e}");
    let mdts = Mdts::<u64>::ascending(view.viewport(), k).unwrap();
    assert!(
        oracle.diff(&run_serial(&view, &mdts).capture).is_exact(),
        "MDTS is not exact on the extreme scene"
    );
    oracle.depth_complexity()
}

#[test]
fn a_model_scaled_by_1e7_or_1e_minus_5_renders_like_the_original() {
    let reference = scaled_spheres(1.0);
    for scale in [1e7, 1e-5] {
        let scaled = scaled_spheres(scale);
        let differing = reference
            .iter()
            .zip(&scaled)
            .filter(|(a, b)| a != b)
            .count();
        // Scaling is not exact in binary: a few vertices may snap one grid step apart.
        assert!(
            differing <= reference.len() / 100,
            "scale {scale:e}: {differing} pixels differ"
        );
    }
}

#[test]
fn a_model_below_2e_minus_6_across_is_framed_as_if_it_were_2e_minus_6() {
    // `OrbitCamera` clamps the bounding radius to at least 1e-6 (to survive a one-point mesh):
    // spheres of radius 1e-7 are still captured exactly, but drawn about ten times smaller.
    let covered = |counts: Vec<u32>| counts.iter().filter(|&&c| c > 0).count();
    let reference = covered(scaled_spheres(1.0));
    let tiny = covered(scaled_spheres(1e-7));
    assert!(
        tiny > 0 && tiny * 20 < reference,
        "{tiny} vs {reference} pixels"
    );
}

/// The eye-space triangle A, B, C clipped by hand at `z = −near` (exactly representable here),
/// as a mesh: what the pipeline's homogeneous clipping must reproduce.
fn coverage_clipped_by_hand(pieces: &[[[f32; 3]; 3]], camera: &Camera) -> Vec<u32> {
    let mesh = soup(pieces);
    coverage(&View::new(&mesh, camera, viewport(32, 32), CullMode::None))
}

#[test]
fn a_triangle_crossing_the_near_plane_is_clipped_and_keeps_its_primitive_id() {
    let camera = perspective(1.0, 100.0);
    // C lies between the eye and the near plane (z = −0.5); A and B beyond it (z = −1.5).
    let (a, b, c) = ([-1.5, -1.5, -1.5], [1.5, -1.5, -1.5], [0.0, 0.5, -0.5]);
    let hidden = [[-1.0, -1.0, -50.0], [1.0, -1.0, -50.0], [0.0, 1.0, -50.0]];
    let mesh = soup(&[hidden, hidden, [a, b, c]]);
    let view = View::new(&mesh, &camera, viewport(32, 32), CullMode::None);
    let mut clipped = Vec::new();
    view.rasterize(2, &mut |f| clipped.push(f));
    assert!(!clipped.is_empty());
    assert!(clipped
        .iter()
        .all(|f| f.prim == 2 && f.depth_key <= MAX_KEY));
    let mut counts = vec![0; 32 * 32];
    for f in &clipped {
        counts[f.pixel as usize] += 1;
    }
    // The near plane cuts CA and CB at their midpoints (z = −1).
    let (ca, cb) = ([-0.75, -0.5, -1.0], [0.75, -0.5, -1.0]);
    let by_hand = coverage_clipped_by_hand(&[[a, b, cb], [a, cb, ca]], &camera);
    assert_eq!(counts, by_hand);
}

#[test]
fn a_triangle_crossing_the_eye_plane_w_0_is_clipped_not_inverted() {
    let camera = perspective(1.0, 100.0);
    // C is behind the eye (z = +1, so w = −1); the near plane cuts CA and CB at z = −1.
    let (a, b, c) = ([-1.0, -1.0, -3.0], [1.0, -1.0, -3.0], [0.0, 1.0, 1.0]);
    let mesh = soup(&[[a, b, c]]);
    let counts = coverage(&View::new(&mesh, &camera, viewport(32, 32), CullMode::None));
    let (ca, cb) = ([-0.5, 0.0, -1.0], [0.5, 0.0, -1.0]);
    let by_hand = coverage_clipped_by_hand(&[[a, b, cb], [a, cb, ca]], &camera);
    assert!(by_hand.iter().sum::<u32>() > 0);
    assert_eq!(counts, by_hand);
    // FreePipe's bounding-box-only approach divides by w < 0: C lands at the bottom of the
    // screen instead of beyond the top, and the triangle drawn is a different, inverted one.
    let project = |[x, y, z]: [f32; 3]| {
        let w = -z;
        [x / w, y / w, 0.5]
    };
    let naive = soup(&[[project(a), project(b), project(c)]]);
    let naive_counts = coverage(&identity_view(&naive, 32, 32));
    assert_ne!(naive_counts, counts);
}

#[test]
fn a_piece_with_a_vertex_at_w_0_is_dropped_as_documented() {
    // A projection with w = z does not keep w away from 0 at the near plane (z ≥ 0 ⇔ w ≥ 0): a
    // triangle reaching w < 0 is clipped to a piece with a vertex at w = 0, which is dropped.
    let camera = camera_from_columns([
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, 0.0, 0.0],
    ]);
    let crossing = soup(&[[[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, -1.0]]]);
    let view = View::new(&crossing, &camera, viewport(16, 16), CullMode::None);
    assert!(all_fragments(&view).is_empty());
    // In front of w = 0 the same projection draws (depth z / w = 1 everywhere).
    let in_front = soup(&[[[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]]]);
    let in_front_view = View::new(&in_front, &camera, viewport(16, 16), CullMode::None);
    let fragments = all_fragments(&in_front_view);
    assert!(!fragments.is_empty());
    assert!(fragments.iter().all(|f| f.depth_key == MAX_KEY));
}

/// The depth keys of full-screen squares at these eye-space distances, under `camera`.
fn keys_of_layers(camera: &Camera, distances: &[f32]) -> (Vec<u32>, Mesh) {
    let triangles: Vec<[[f32; 3]; 3]> = distances
        .iter()
        .flat_map(|&d| square(2.0 * d, -d))
        .collect();
    let mesh = soup(&triangles);
    let view = View::new(&mesh, camera, viewport(1, 1), CullMode::None);
    let layers = u32::try_from(distances.len()).expect("ten layers");
    let keys = (0..layers)
        .map(|layer| {
            let mut key = None;
            for prim in [2 * layer, 2 * layer + 1] {
                view.rasterize(prim, &mut |f| key = Some(f.depth_key));
            }
            key.expect("each layer covers the pixel")
        })
        .collect();
    (keys, mesh)
}

#[test]
fn a_near_far_ratio_of_1e_minus_7_merges_distinct_layers_ordered_by_primitive() {
    let distances: Vec<f32> = (1..=10).map(|i| i as f32 / 10.0).collect();
    let (keys, _) = keys_of_layers(&perspective(1e-7, 1.0), &distances);
    let mut distinct = keys.clone();
    distinct.dedup();
    // Depth ≈ 1 − 1e-7 / d: ten layers from 0.1 to 1.0 get only a handful of keys just below 1.0.
    assert!(keys.iter().all(|&k| k > depth_key(0.999_998).unwrap()));
    assert!(distinct.len() < distances.len(), "{keys:x?}");
    eprintln!(
        "near/far 1e-7: layers at 0.1..1.0 get {} distinct keys: {keys:x?}",
        distinct.len()
    );
    // With near/far = 1e-2 they are all distinct.
    let (far_keys, _) = keys_of_layers(&perspective(1e-2, 1.0), &distances);
    let mut far_distinct = far_keys.clone();
    far_distinct.dedup();
    assert_eq!(far_distinct.len(), distances.len());
    // Merged layers are still captured exactly: equal keys in primitive order, as the oracle.
    let camera = perspective(1e-7, 1.0);
    let (_, mesh) = keys_of_layers(&camera, &[0.9, 0.8, 0.7, 0.6, 0.5]);
    let view = View::new(&mesh, &camera, viewport(8, 8), CullMode::None);
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), oracle.max_depth_complexity()).unwrap();
    assert_exact(&view, &oracle, &mdts);
}

#[test]
fn two_layers_closer_than_one_ulp_keep_both_in_primitive_order() {
    let camera = perspective(1.0, 100.0);
    // Eye-space distances one f32 ulp apart; the farther layer has the lower primitive ids.
    let far = 50.0_f32;
    let near = f32::from_bits(far.to_bits() - 1);
    let (keys, mesh) = keys_of_layers(&camera, &[far, near]);
    assert_eq!(keys[0], keys[1], "one depth key for both layers");
    let view = View::new(&mesh, &camera, viewport(4, 4), CullMode::None);
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), 2).unwrap();
    let run = run_serial(&view, &mdts);
    assert!(oracle.diff(&run.capture).is_exact());
    for p in 0..view.viewport().pixels() {
        let list = run.capture.pixel(p);
        assert_eq!(list.len(), 2, "pixel {p}");
        assert_eq!(list[0] >> 32, list[1] >> 32);
        assert!(
            prim_of(list[0]) < 2 && prim_of(list[1]) >= 2,
            "pixel {p}: {list:x?}"
        );
    }
    let keys_only =
        Mdts::<u32>::new(view.viewport(), 2, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let capture = run_serial(&view, &keys_only).capture;
    assert!(oracle.diff(&capture).is_exact());
    assert!((0..capture.pixels()).all(|p| capture.pixel(p).len() == 2));
}

#[test]
fn ten_thousand_coincident_triangles_on_one_pixel_are_ordered_by_primitive_id() {
    let n = 10_000_u32;
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]; n as usize],
    };
    let view = identity_view(&mesh, 1, 1);
    let oracle = Oracle::build(&view);
    let key = u64::from(depth_key(0.5).unwrap()) << 32;
    let expected: Vec<u64> = (0..n).map(|prim| key | u64::from(prim)).collect();
    assert_eq!(oracle.pixel(0), expected.as_slice());
    let mdts = Mdts::<u64>::ascending(view.viewport(), n).unwrap();
    for run in [run_serial(&view, &mdts), run_parallel(&view, &mdts)] {
        assert_eq!(run.capture.pixel(0), expected.as_slice());
    }
    // Serially, fragment i walks past the i equal-key fragments before it: n (n + 1) / 2 steps.
    let steps = run_serial(&view, &mdts).stats.counters.steps;
    assert_eq!(steps, u64::from(n) * u64::from(n + 1) / 2);
    let abuffer = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Insertion,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    assert_exact(&view, &oracle, &abuffer);
    let bitonic = ABuffer::exact(
        &oracle.depth_complexity(),
        PostSort::Bitonic,
        MEMORY_CAP_DEFAULT,
    )
    .unwrap();
    assert_exact(&view, &oracle, &bitonic);
    let keys_only =
        Mdts::<u32>::new(view.viewport(), n, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    let capture = run_serial(&view, &keys_only).capture;
    assert_eq!(capture.pixel(0), vec![key; n as usize].as_slice());
}
