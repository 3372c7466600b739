//! Sizes: the smallest and largest viewports, `K` of 1 and 1024, empty scenes, and depth
//! complexity above `K`.

use std::time::Instant;

use assert_cmd::Command;
use fragsim::capture::executors::run_serial;
use fragsim::capture::{CaptureError, Scheme, MEMORY_CAP_DEFAULT};
use fragsim::oracle::Oracle;
use fragsim::raster::{Mesh, MeshError, OrbitCamera, Scene, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::{Direction, Mdts};

use super::{assert_exact, coverage, identity_view, soup, viewport};

#[test]
fn a_1x1_viewport_is_captured_exactly() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene.view(viewport(1, 1), &OrbitCamera::default()).unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 6);
    assert_exact(
        &view,
        &oracle,
        &Mdts::<u64>::ascending(view.viewport(), 6).unwrap(),
    );
    let abuffer = ABuffer::exact_default(&oracle.depth_complexity()).unwrap();
    assert_exact(&view, &oracle, &abuffer);
}

#[test]
fn a_16384_square_viewport_beyond_the_memory_cap_is_refused_naming_the_bytes() {
    let side = Viewport::MAX_SIDE;
    assert_eq!(side, 16384);
    let huge = viewport(side, side);
    let cap = 1_000_000;
    let pixels = u64::from(side) * u64::from(side);
    let refused = |result: Result<(), CaptureError>, needed: u64| {
        let err = result.unwrap_err();
        assert_eq!(
            err,
            CaptureError::TooMuchMemory {
                scheme: match &err {
                    CaptureError::TooMuchMemory { scheme, .. } => scheme.clone(),
                    other => panic!("{other}"),
                },
                needed,
                cap,
            }
        );
        let message = err.to_string();
        assert!(message.contains(&needed.to_string()), "{message}");
    };
    // The storage addressed, as documented; what the cap refuses at build is what is allocated
    // before any fragment (the page tables), the pages being checked as a frame writes them.
    let unbounded = u64::MAX;
    let mdts = Mdts::<u64>::new(huge, 1, Direction::Ascending, unbounded).unwrap();
    let mdts32 = Mdts::<u32>::new(huge, 1, Direction::Ascending, unbounded).unwrap();
    let abuffer = ABuffer::fixed(huge, 1, PostSort::Insertion, unbounded).unwrap();
    assert_eq!(mdts.layout().bytes(), pixels * 8);
    assert_eq!(mdts32.layout().bytes(), pixels * 4);
    assert_eq!(abuffer.layout().bytes(), pixels * 12);
    refused(
        Mdts::<u64>::new(huge, 1, Direction::Ascending, cap).map(drop),
        mdts.layout().least_bytes(),
    );
    refused(
        Mdts::<u32>::new(huge, 1, Direction::Ascending, cap).map(drop),
        mdts32.layout().least_bytes(),
    );
    refused(
        ABuffer::fixed(huge, 1, PostSort::Insertion, cap).map(drop),
        abuffer.layout().least_bytes(),
    );
    // One more pixel per side is refused by the viewport itself.
    let err = Viewport::new(side + 1, 1).unwrap_err().to_string();
    assert!(err.contains("16384"), "{err}");
}

#[test]
fn the_binary_refuses_a_16384_square_viewport_beyond_the_memory_cap_before_the_oracle() {
    let start = Instant::now();
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "--width",
            "16384",
            "--height",
            "16384",
            "--memory-cap",
            "1000000",
            "--no-images",
        ])
        .output()
        .unwrap();
    let elapsed = start.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success());
    assert!(!stderr.contains("panicked"), "{stderr}");
    // MDTS with 64-bit words and the default K = 20: the page tables of 16384² × 20 words.
    let huge = viewport(16384, 16384);
    let least = Mdts::<u64>::new(huge, 20, Direction::Ascending, u64::MAX)
        .unwrap()
        .layout()
        .least_bytes();
    assert!(
        stderr.contains(&least.to_string()) && stderr.contains("1000000"),
        "{stderr}"
    );
    // Refused before the oracle's counting pass (which took 20 s and 5.4 GB here before the fix).
    assert!(elapsed.as_secs() < 10, "took {elapsed:?}");
}

#[test]
fn k_1_keeps_exactly_the_nearest_layer_and_counts_the_rest() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene
        .view(viewport(48, 48), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let mdts = Mdts::<u64>::ascending(view.viewport(), 1).unwrap();
    // The overflow, counted here from the depth complexity alone: every fragment but one per
    // covered pixel; the scheme's own drops must equal it (`assert_exact`).
    let covered = oracle.depth_complexity().iter().filter(|&&c| c > 0).count() as u64;
    assert_eq!(
        assert_exact(&view, &oracle, &mdts),
        oracle.fragments() as u64 - covered
    );
    let run = run_serial(&view, &mdts);
    for p in 0..oracle.pixels() {
        assert_eq!(
            run.capture.pixel(p),
            &oracle.pixel(p)[..oracle.pixel(p).len().min(1)]
        );
    }
}

#[test]
fn k_1024_costs_memory_but_no_extra_steps() {
    let scene = Scene::procedural("spheres:3").unwrap();
    let view = scene
        .view(viewport(32, 32), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    let full = oracle.max_depth_complexity();
    let wide = Mdts::<u64>::ascending(view.viewport(), 1024).unwrap();
    let tight = Mdts::<u64>::ascending(view.viewport(), full).unwrap();
    assert_exact(&view, &oracle, &wide);
    let (w, t) = (run_serial(&view, &wide), run_serial(&view, &tight));
    assert_eq!(w.capture.entries, t.capture.entries);
    assert_eq!(w.capture.offsets, t.capture.offsets);
    // A walk stops at the first empty slot: slots beyond the depth complexity are never touched.
    assert_eq!(w.stats.counters.steps, t.stats.counters.steps);
    assert_eq!(w.stats.memory_bytes, 32 * 32 * 1024 * 8);
    assert_eq!(t.stats.memory_bytes, 32 * 32 * u64::from(full) * 8);
}

#[test]
fn a_scene_with_zero_triangles_is_a_clear_error() {
    let empty = Scene {
        name: "nothing".into(),
        mesh: Mesh {
            positions: vec![[0.0; 3]; 3],
            triangles: Vec::new(),
        },
    };
    let err = empty
        .view(viewport(8, 8), &OrbitCamera::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("nothing") && err.contains("no triangles"),
        "{err}"
    );
    let points_err =
        Mesh::read_obj(&mut "v 0 0 0\nv 1 0 0\nv 1 1 0\n".as_bytes(), "points.obj").unwrap_err();
    assert!(
        matches!(points_err, MeshError::Empty { .. }),
        "{points_err}"
    );
    assert!(points_err
        .to_string()
        .contains("points.obj has no triangles"));
}

#[test]
fn one_triangle_covering_the_whole_screen_covers_every_pixel_once() {
    let mesh = soup(&[[[-1.0, -1.0, 0.75], [3.0, -1.0, 0.75], [-1.0, 3.0, 0.75]]]);
    for (width, height) in [(64, 48), (1, 1), (1, 64)] {
        let view = identity_view(&mesh, width, height);
        assert!(coverage(&view).iter().all(|&c| c == 1), "{width}x{height}");
        let oracle = Oracle::build(&view);
        let mdts = Mdts::<u64>::ascending(view.viewport(), 1).unwrap();
        assert_exact(&view, &oracle, &mdts);
        assert_eq!(run_serial(&view, &mdts).stats.counters.dropped, 0);
    }
}

#[test]
fn depth_complexity_above_k_is_counted_as_overflow_equal_to_drops() {
    let scene = Scene::procedural("spheres:4").unwrap();
    let view = scene
        .view(viewport(48, 48), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    assert_eq!(oracle.max_depth_complexity(), 8);
    let k = 3;
    let beyond_k: u64 = oracle
        .depth_complexity()
        .iter()
        .map(|&c| u64::from(c.saturating_sub(k)))
        .sum();
    assert!(beyond_k > 0);
    let vp = view.viewport();
    let asc = Mdts::<u64>::ascending(vp, k).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &asc), beyond_k);
    let desc = Mdts::<u64>::new(vp, k, Direction::Descending, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &desc), beyond_k);
    let keys = Mdts::<u32>::new(vp, k, Direction::Ascending, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &keys), beyond_k);
    let fixed = ABuffer::fixed(vp, k, PostSort::Insertion, MEMORY_CAP_DEFAULT).unwrap();
    assert_eq!(assert_exact(&view, &oracle, &fixed), beyond_k);
}
