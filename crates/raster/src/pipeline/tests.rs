//! Unit tests of the pipeline's rules.

use super::vertex::{round_half_away, VertexStage, ROUNDING_BOUND};
use super::*;
use crate::conventions::Conventions;

fn view_of(mesh: &Mesh, side: u32) -> View<'_> {
    // Identity projection: model x, y in [-1, 1] map straight to the window, z is depth.
    let camera = Camera {
        view_projection: DMat4::IDENTITY,
    };
    View::new(
        mesh,
        &camera,
        Viewport::new(side, side).unwrap(),
        CullMode::None,
    )
}

fn coverage(view: &View<'_>) -> Vec<u32> {
    let mut counts = vec![0; view.viewport().pixels()];
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| counts[f.pixel as usize] += 1);
    }
    counts
}

#[test]
fn two_triangles_sharing_a_diagonal_cover_each_centre_once() {
    // A full-screen quad split along the diagonal, which passes through pixel centres.
    let mesh = Mesh {
        positions: vec![
            [-1.0, -1.0, 0.5],
            [1.0, -1.0, 0.5],
            [1.0, 1.0, 0.5],
            [-1.0, 1.0, 0.5],
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    assert!(coverage(&view_of(&mesh, 8)).iter().all(|&c| c == 1));
}

#[test]
fn depth_is_interpolated_and_keyed() {
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 0.25], [3.0, -1.0, 0.25], [-1.0, 3.0, 0.25]],
        triangles: vec![[0, 1, 2]],
    };
    let view = view_of(&mesh, 4);
    let mut keys = Vec::new();
    view.rasterize(0, &mut |f| keys.push(f.depth_key));
    assert_eq!(keys.len(), 16);
    assert!(keys.iter().all(|&k| k == 0.25_f32.to_bits()));
}

#[test]
fn fragments_beyond_far_are_dropped() {
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, 1.5], [3.0, -1.0, 1.5], [-1.0, 3.0, 1.5]],
        triangles: vec![[0, 1, 2]],
    };
    assert!(coverage(&view_of(&mesh, 4)).iter().all(|&c| c == 0));
}

#[test]
fn a_clipped_vertex_lost_to_cancellation_is_clamped_into_the_guard_band() {
    // Found by the rasterize fuzz target: clipping the edge from x = 1.9e38 to x = −2.55e38
    // against x ≥ −513 w cancelled to x ≈ −3.8e22, which snapped to i64::MIN and overflowed
    // the edge function (a panic with overflow checks, garbage without).
    let mesh = Mesh {
        positions: vec![
            [-2.552_080_4e38, -2.046_936_3, 0.012],
            [1.900_796_2e38, 0.0, 0.004],
        ],
        triangles: vec![[0, 1, 1]],
    };
    let view = view_of(&mesh, 64);
    let [a, b] = [0, 1].map(|i| view.clip_position(i));
    let polygon = view.clip([a, b, b]);
    assert!(polygon.len() >= 3);
    let [gx, gy] = view.guard;
    for v in &polygon {
        assert!(v.x.abs() <= gx * v.w && v.y.abs() <= gy * v.w, "{v:?}");
    }
    assert!(coverage(&view).iter().all(|&c| c == 0));
}

#[test]
#[expect(
    clippy::cast_possible_truncation,
    reason = "the f32 vertex stage's matrix: a GPU's single-precision entries"
)]
fn the_written_out_outcode_equals_the_plane_dot_products() {
    let mesh = Mesh {
        positions: vec![],
        triangles: vec![],
    };
    let view = view_of(&mesh, 37);
    let stage = VertexStage {
        view_projection: DMat4::IDENTITY,
        view_projection_f32: DMat4::IDENTITY.to_cols_array().map(|e| e as f32),
        planes: view.planes(),
        viewport: view.viewport(),
        conventions: Conventions::REFERENCE,
    };
    let by_dot_products = |clip: DVec4| {
        let mut code = stage
            .planes
            .iter()
            .enumerate()
            .fold(0_u8, |code, (i, plane)| {
                code | (u8::from(plane.dot(clip) < 0.0) << i)
            });
        if DVec4::new(0.0, 0.0, -1.0, 1.0).dot(clip) < 0.0 {
            code |= FAR_BIT;
        }
        if !in_front(clip) {
            code |= NOT_IN_FRONT_BIT;
        }
        code
    };
    let mut x = 0x2545_F491_4F6C_DD1D_u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let specials = [0.0, -0.0, 1.0, -1.0, 1e-300, 3.4e38, -3.4e38, 1e300];
    for _ in 0..200_000 {
        let mut coordinate = || {
            let bits = next();
            match bits % 4 {
                0 => specials[(bits >> 8) as usize % specials.len()],
                1 => (bits >> 11) as f64 / (1_u64 << 53) as f64 * 4.0 - 2.0,
                _ => f64::from_bits(bits).clamp(-1e300, 1e300),
            }
        };
        let clip = DVec4::new(coordinate(), coordinate(), coordinate(), coordinate());
        if clip.is_finite() {
            assert_eq!(
                stage.outcode(clip),
                u64::from(by_dot_products(clip)),
                "{clip:?}"
            );
        }
    }
}

#[test]
#[allow(
    clippy::manual_clamp,
    reason = "NaN is rounded as `max` and `min` take it, which `f64::clamp` does not"
)]
fn rounding_without_libm_equals_f64_round() {
    let mut values = vec![
        0.5,
        -0.5,
        1.5,
        -2.5,
        0.499_999_999_999_999_94,
        -0.499_999_999_999_999_94,
        4_503_599_627_370_495.5,
        4_503_599_627_370_497.0,
        1e30,
        -1e30,
        f64::MAX,
        f64::MIN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        0.0,
        -0.0,
        f64::MIN_POSITIVE,
    ];
    // Halves and their neighbours over the snapped range, at the guard band's edge (2^24) and at
    // the bound, and a deterministic spread.
    let edges = [0, 1 << 24, -(1 << 24), 1 << 30, -(1 << 30)];
    for i in edges
        .into_iter()
        .flat_map(|at: i32| at.saturating_sub(3000)..at.saturating_add(3000))
    {
        let half = f64::from(i) + 0.5;
        values.extend([half, half.next_up(), half.next_down()]);
    }
    let mut x = 0x9E37_79B9_7F4A_7C15_u64;
    for _ in 0..100_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        values.push(f64::from_bits(x));
    }
    for v in values {
        // NaN goes to the lower bound (`f64::max` takes the number).
        #[expect(
            clippy::cast_possible_truncation,
            reason = "the bound keeps the value within i32 (ROUNDING_BOUND = 2^30)"
        )]
        let expected = v.max(-ROUNDING_BOUND).min(ROUNDING_BOUND).round() as i32;
        assert_eq!(round_half_away(v), expected, "{v:e}");
    }
}

/// Views of a triangle soup seen from far (tiny triangles), near (clipped ones) and inside
/// (w ≤ 0), on a viewport of odd sides.
pub(super) fn soup_views(mesh: &Mesh) -> impl Iterator<Item = (f64, View<'_>)> {
    [40.0, 1.0, 0.3, 0.01].into_iter().map(|distance_scale| {
        let orbit = crate::OrbitCamera {
            distance_scale,
            ..crate::OrbitCamera::default()
        };
        let camera = orbit.camera(mesh.bounds(), 1.0);
        let viewport = Viewport::new(97, 61).unwrap();
        (
            distance_scale,
            View::new(mesh, &camera, viewport, CullMode::None),
        )
    })
}

#[test]
fn the_inlined_fast_path_emits_what_the_general_path_emits() {
    // `rasterize` skips `screen_triangles` for unclipped triangles; both must agree.
    let mesh = crate::scenes::triangle_soup(3000, 7);
    for (distance_scale, view) in soup_views(&mesh) {
        let mut fragments = 0;
        for prim in 0..view.triangle_count() {
            let (mut fast, mut general) = (Vec::new(), Vec::new());
            view.rasterize(prim, &mut |f| fast.push(f));
            view.screen_triangles(prim, &mut |t| view.scan(&t, &mut |f| general.push(f)));
            assert_eq!(
                fast, general,
                "triangle {prim} at distance {distance_scale}"
            );
            fragments += fast.len();
        }
        assert!(fragments > 0, "distance {distance_scale} drew nothing");
    }
}

#[test]
fn rasterizing_triangles_in_batches_emits_them_one_after_the_other() {
    let mesh = crate::scenes::triangle_soup(1000, 9);
    for (distance_scale, view) in soup_views(&mesh) {
        // Reversed, so that the order is the caller's rather than the primitive ids'.
        let prims: Vec<u32> = (0..view.triangle_count()).rev().collect();
        let rect = PixelRect {
            x: (10, 70),
            y: (5, 50),
        };
        let mut one_by_one = Vec::new();
        for &prim in &prims {
            view.rasterize_in(prim, rect, &mut |f| one_by_one.push(f));
        }
        let mut batched = Vec::new();
        view.rasterize_each_in(prims.iter().copied(), rect, &mut |f| batched.push(f));
        assert_eq!(batched, one_by_one, "distance {distance_scale}");
    }
}

#[test]
fn tiles_split_a_triangle_s_fragments_exactly_and_its_bounds_hold_them() {
    // Tiles of 13 × 8 pixels, misaligned with the 97 × 61 viewport's sides on purpose.
    let mesh = crate::scenes::triangle_soup(3000, 11);
    for (distance_scale, view) in soup_views(&mesh) {
        let Viewport { width, height } = view.viewport();
        let tiles: Vec<PixelRect> = (0..height.div_ceil(8))
            .flat_map(|row| {
                (0..width.div_ceil(13)).map(move |column| PixelRect {
                    x: (column * 13, (column * 13 + 12).min(width - 1)),
                    y: (row * 8, (row * 8 + 7).min(height - 1)),
                })
            })
            .collect();
        for prim in 0..view.triangle_count() {
            let mut whole = Vec::new();
            view.rasterize(prim, &mut |f| whole.push(f));
            let bounds = view.pixel_bounds(prim);
            let inside = |rect: &PixelRect, pixel: u32| {
                let (x, y) = (pixel % width, pixel / width);
                (rect.x.0..=rect.x.1).contains(&x) && (rect.y.0..=rect.y.1).contains(&y)
            };
            match bounds {
                None => assert!(whole.is_empty(), "triangle {prim} at {distance_scale}"),
                Some(rect) => assert!(whole.iter().all(|f| inside(&rect, f.pixel))),
            }
            for tile in &tiles {
                let mut part = Vec::new();
                view.rasterize_in(prim, *tile, &mut |f| part.push(f));
                let expected: Vec<Fragment> = whole
                    .iter()
                    .copied()
                    .filter(|f| inside(tile, f.pixel))
                    .collect();
                assert_eq!(part, expected, "triangle {prim} at {distance_scale}");
            }
        }
    }
}

#[test]
fn a_triangle_crossing_the_near_plane_is_clipped_not_lost() {
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, -0.5], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]],
    };
    let counts = coverage(&view_of(&mesh, 8));
    let covered = counts.iter().filter(|&&c| c == 1).count();
    assert!(covered > 0 && covered < 64, "{covered}");
    assert!(counts.iter().all(|&c| c <= 1));
}

/// Rules 1 and 3 written the plain way, one vertex at a time, in i64 with `f64::round`: what the
/// batched, branch-free vertex stage must leave for every vertex inside the guard band, under
/// every vertex precision, window origin, depth range and a few grids.
#[test]
#[expect(
    clippy::cast_possible_truncation,
    reason = "vertex indices of the test scenes fit u32 (the mesh's own indices are u32)"
)]
fn the_batched_vertex_stage_equals_rules_1_and_3_vertex_by_vertex() {
    use crate::conventions::{DepthRange, VertexPrecision, WindowOrigin};
    let scene = crate::Scene::procedural("soup:300:7").unwrap();
    let viewport = Viewport::new(97, 61).unwrap();
    let mut checked = [0_usize; 2];
    for distance_scale in [40.0, 1.1, 0.3, 0.01] {
        let orbit = crate::OrbitCamera {
            distance_scale,
            ..crate::OrbitCamera::default()
        };
        for vertex_precision in [VertexPrecision::F64, VertexPrecision::F32] {
            for window_origin in [WindowOrigin::UpperLeft, WindowOrigin::LowerLeft] {
                for depth_range in [DepthRange::ZeroToOne, DepthRange::MinusOneToOne] {
                    for subpixel_bits in [8, 4, 1] {
                        let conventions = Conventions {
                            window_origin,
                            subpixel_bits,
                            depth_range,
                            vertex_precision,
                            ..Conventions::REFERENCE
                        };
                        let camera = scene.orbit_camera(viewport, &orbit, depth_range);
                        let view = View::with_conventions(
                            &scene.mesh,
                            &camera,
                            viewport,
                            CullMode::None,
                            conventions,
                        )
                        .unwrap();
                        for (index, p) in scene.mesh.positions.iter().enumerate() {
                            let inside = expected_window(&view, camera.view_projection, *p);
                            assert_eq!(
                                view.vertex_window(index as u32),
                                inside,
                                "{conventions:?}, vertex {index}"
                            );
                            checked[usize::from(inside.is_some())] += 1;
                        }
                    }
                }
            }
        }
    }
    // Both kinds of vertex were met: clipped (or behind the eye) and placed.
    assert!(checked[0] > 100 && checked[1] > 1000, "{checked:?}");
}

/// The snapped window position and depth of model position `p` under `view`'s conventions,
/// computed one vertex at a time from `docs/semantics.md` (rules 1 and 3, §9); `None` when the
/// vertex lies outside the near plane or the guard band, or not in front of the eye.
#[expect(
    clippy::cast_possible_truncation,
    reason = "the f32 stage narrows to f32 as a GPU does, which the expected window repeats; the snapped grid value is within the guard band"
)]
fn expected_window(view: &View<'_>, matrix: DMat4, p: [f32; 3]) -> Option<([i64; 2], f64)> {
    use crate::conventions::{DepthRange, VertexPrecision, WindowOrigin};
    let c = view.conventions();
    let clip = match c.vertex_precision {
        VertexPrecision::F64 => matrix * DVec4::new(p[0].into(), p[1].into(), p[2].into(), 1.0),
        VertexPrecision::F32 => {
            let m = matrix.to_cols_array().map(|e| e as f32);
            let row = |r: usize| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
            DVec4::new(row(0).into(), row(1).into(), row(2).into(), row(3).into())
        }
    };
    if view.planes().iter().any(|plane| plane.dot(clip) < 0.0) || clip.w <= 0.0 {
        return None;
    }
    let (width, height) = (view.viewport.width, view.viewport.height);
    let lower_left = c.window_origin == WindowOrigin::LowerLeft;
    let minus_one = c.depth_range == DepthRange::MinusOneToOne;
    let ([x, y], depth) = match c.vertex_precision {
        VertexPrecision::F64 => {
            let (x, y, z, w) = (clip.x, clip.y, clip.z, clip.w);
            let wy = if lower_left {
                y / w * 0.5 + 0.5
            } else {
                0.5 - y / w * 0.5
            };
            let depth = if minus_one { z / w * 0.5 + 0.5 } else { z / w };
            (
                [
                    (x / w * 0.5 + 0.5) * f64::from(width),
                    wy * f64::from(height),
                ],
                depth,
            )
        }
        VertexPrecision::F32 => {
            let [x, y, z, w] = clip.to_array().map(|v| v as f32);
            let wy = if lower_left {
                y / w * 0.5 + 0.5
            } else {
                0.5 - y / w * 0.5
            };
            let depth = if minus_one { z / w * 0.5 + 0.5 } else { z / w };
            let window = [(x / w * 0.5 + 0.5) * width as f32, wy * height as f32];
            (window.map(f64::from), f64::from(depth))
        }
    };
    let bits = c.subpixel_bits;
    let grid =
        |v: f64| (v * f64::from(1_u32 << bits)).round() as i64 * (1 << (SUBPIXEL_BITS - bits));
    let y = if lower_left {
        (i64::from(height) << SUBPIXEL_BITS) - grid(y)
    } else {
        grid(y)
    };
    Some(([grid(x), y], depth))
}

/// Triangles set up once for the whole framebuffer and scanned tile by tile give, in every tile,
/// what rasterizing the same triangles restricted to that tile gives, in the same order: under
/// both fill rules, per sample, and with tiny, large and clipped triangles.
#[test]
#[expect(clippy::shadow_unrelated, reason = "the loop checks each view alike")]
fn set_up_triangles_scanned_by_tiles_equal_rasterizing_each_tile() {
    let mesh = crate::scenes::triangle_soup(600, 11);
    let lower_left = Conventions {
        window_origin: crate::conventions::WindowOrigin::LowerLeft,
        ..Conventions::REFERENCE
    };
    let mut fragments = 0;
    for (_, view) in soup_views(&mesh) {
        let camera = Camera {
            view_projection: view.view_projection(),
        };
        let flipped =
            View::with_conventions(&mesh, &camera, view.viewport(), CullMode::None, lower_left)
                .unwrap();
        let sampled = view
            .clone()
            .with_samples(crate::SamplePattern::standard(4).unwrap())
            .unwrap();
        for view in [view, flipped, sampled] {
            let mut setups = Vec::new();
            view.set_up_each(0..view.triangle_count(), &mut |setup| setups.push(setup));
            let Viewport { width, height } = view.viewport();
            let side = 13;
            for tile_y in 0..height.div_ceil(side) {
                for tile_x in 0..width.div_ceil(side) {
                    let tile = PixelRect {
                        x: (tile_x * side, (tile_x * side + side - 1).min(width - 1)),
                        y: (tile_y * side, (tile_y * side + side - 1).min(height - 1)),
                    };
                    let mut expected = Vec::new();
                    view.rasterize_each_in(0..view.triangle_count(), tile, &mut |f| {
                        expected.push(f);
                    });
                    let mut scanned = Vec::new();
                    for setup in &setups {
                        view.scan_within(setup, tile, &mut |f| scanned.push(f));
                    }
                    assert_eq!(scanned, expected, "{tile:?}");
                    fragments += scanned.len();
                }
            }
        }
    }
    assert!(fragments > 10_000, "{fragments} fragments");
}
