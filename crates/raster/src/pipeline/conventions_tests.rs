//! Tests of the pipeline under [`Conventions`]: the reference conventions give today's fragments
//! bit for bit, and each other convention changes exactly what `docs/semantics.md` says, on a
//! scene built for it.

use super::*;
use crate::conventions::{DepthRange, VertexPrecision, WindowOrigin};
use crate::{OrbitCamera, Scene};

/// FNV-1a 64 over every fragment's pixel, depth key and primitive id, in emission order.
fn fingerprint(view: &View<'_>) -> (u64, u64) {
    let (mut hash, mut count) = (0xcbf2_9ce4_8422_2325_u64, 0_u64);
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| {
            count += 1;
            for word in [f.pixel, f.depth_key, f.prim] {
                for byte in word.to_le_bytes() {
                    hash = (hash ^ u64::from(byte)).wrapping_mul(0x100_0000_01b3);
                }
            }
        });
    }
    (count, hash)
}

/// Fragment counts and fingerprints measured on commit ac9437f, before conventions were wired
/// (the same loop as [`reference_conventions_give_the_fragments_of_before`], run on that tree):
/// (scene, width, height, orbit angle, distance scale, fragments, fingerprint). Distance 0.3
/// puts the eye inside the bounding sphere, so the near plane clips.
const BEFORE: [(&str, u32, u32, f64, f64, u64, u64); 24] = [
    ("spheres:3", 64, 48, 0.0, 1.1, 1424, 0xe18f_7ba9_74e6_6725),
    ("spheres:3", 64, 48, 37.5, 1.1, 1424, 0x907f_586c_0d3d_1daa),
    (
        "spheres:3",
        64,
        48,
        200.0,
        0.3,
        13058,
        0x1926_e8ce_030e_b37a,
    ),
    ("spheres:3", 97, 131, 0.0, 1.1, 5990, 0x6f4d_b2a0_8155_6725),
    ("spheres:3", 97, 131, 37.5, 1.1, 5990, 0x24a6_b5df_aa86_bb64),
    (
        "spheres:3",
        97,
        131,
        200.0,
        0.3,
        53250,
        0xd925_aae1_e35d_af9e,
    ),
    ("soup:300:7", 64, 48, 0.0, 1.1, 11580, 0xe87f_0e6c_89d7_8a25),
    (
        "soup:300:7",
        64,
        48,
        37.5,
        1.1,
        12277,
        0x192d_26e2_3d79_ee3f,
    ),
    (
        "soup:300:7",
        64,
        48,
        200.0,
        0.3,
        135_544,
        0xad12_c0f9_d87d_9351,
    ),
    (
        "soup:300:7",
        97,
        131,
        0.0,
        1.1,
        49870,
        0x4d5a_f3fa_2483_c5a2,
    ),
    (
        "soup:300:7",
        97,
        131,
        37.5,
        1.1,
        52296,
        0xba26_9668_7460_01b0,
    ),
    (
        "soup:300:7",
        97,
        131,
        200.0,
        0.3,
        560_536,
        0xddf3_59a0_b94d_c64d,
    ),
    ("quads:4", 64, 48, 0.0, 1.1, 3002, 0xd117_f35e_5c87_4f92),
    ("quads:4", 64, 48, 37.5, 1.1, 2381, 0xeaf1_ff23_ebd1_4d33),
    ("quads:4", 64, 48, 200.0, 0.3, 11823, 0x2c3a_449c_b9b4_408c),
    ("quads:4", 97, 131, 0.0, 1.1, 12700, 0x67f9_cb6a_697e_fc9c),
    ("quads:4", 97, 131, 37.5, 1.1, 10113, 0x4448_a633_e065_16e4),
    ("quads:4", 97, 131, 200.0, 0.3, 50207, 0xd21a_42b1_1cec_a0d9),
    ("bunny", 64, 48, 0.0, 1.1, 885, 0x42d3_8da5_2da7_abf5),
    ("bunny", 64, 48, 37.5, 1.1, 851, 0xaac2_a0e8_f400_385b),
    ("bunny", 64, 48, 200.0, 0.3, 4679, 0x781f_9afa_b9de_5445),
    ("bunny", 97, 131, 0.0, 1.1, 3768, 0x6495_647d_08d9_1271),
    ("bunny", 97, 131, 37.5, 1.1, 3645, 0xea8a_e407_9a18_81fa),
    ("bunny", 97, 131, 200.0, 0.3, 19082, 0xac49_9f09_16b2_db03),
];

#[test]
fn reference_conventions_give_the_fragments_of_before() {
    for (name, width, height, angle, distance, count, hash) in BEFORE {
        let scene = Scene::procedural(name).unwrap();
        let viewport = Viewport::new(width, height).unwrap();
        let orbit = OrbitCamera {
            angle_degrees: angle,
            distance_scale: distance,
            ..OrbitCamera::default()
        };
        let camera = scene.orbit_camera(viewport, &orbit, DepthRange::ZeroToOne);
        let plain = scene.view(viewport, &orbit).unwrap();
        let under = scene
            .view_under(viewport, &camera, Conventions::REFERENCE)
            .unwrap();
        let case = format!("{name} {width}x{height} at {angle}°, distance {distance}");
        assert_eq!(fingerprint(&plain), (count, hash), "View::new, {case}");
        assert_eq!(
            fingerprint(&under),
            (count, hash),
            "with_conventions, {case}"
        );
    }
}

/// A view of `mesh` through the identity matrix (model x, y in `[-1, 1]` are the window, z the
/// depth) under `conventions`.
fn identity_view(mesh: &Mesh, side: u32, conventions: Conventions) -> View<'_> {
    let camera = Camera {
        view_projection: DMat4::IDENTITY,
    };
    let viewport = Viewport::new(side, side).unwrap();
    View::with_conventions(mesh, &camera, viewport, CullMode::None, conventions).unwrap()
}

fn with(change: impl FnOnce(&mut Conventions)) -> Conventions {
    let mut conventions = Conventions::REFERENCE;
    change(&mut conventions);
    conventions
}

/// Per pixel, the primitive ids that covered it.
fn owners(view: &View<'_>) -> Vec<Vec<u32>> {
    let mut owners = vec![Vec::new(); view.viewport().pixels()];
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| owners[f.pixel as usize].push(f.prim));
    }
    owners
}

#[test]
fn the_owner_of_a_shared_horizontal_edge_flips_with_the_window_origin() {
    // Two triangles sharing the horizontal line y_ndc = 0.25, which on a 4 × 4 viewport runs
    // through the centres of fragsim's row 1 (window y 1.5 from the top): prim 0 above it, prim
    // 1 below, both wider than the viewport.
    let mesh = Mesh {
        positions: vec![
            [-3.0, 0.25, 0.5],
            [3.0, 0.25, 0.5],
            [0.0, 3.0, 0.5],
            [0.0, -3.0, 0.5],
        ],
        triangles: vec![[0, 1, 2], [0, 1, 3]],
    };
    let upper = owners(&identity_view(&mesh, 4, Conventions::REFERENCE));
    let lower = owners(&identity_view(
        &mesh,
        4,
        with(|c| c.window_origin = WindowOrigin::LowerLeft),
    ));
    for (pixel, (u, l)) in upper.iter().zip(&lower).enumerate() {
        let row = pixel / 4;
        // Rows stay fragsim's (row 0 at the top of the picture) under either origin.
        let above = u32::from(row >= 1);
        let expected_upper = if row == 1 { 1 } else { above };
        // Upper-left: the edge is the lower triangle's top edge; lower-left (GL's top-left rule
        // in its y-up window, the bottom-left rule in fragsim's rows): the upper one's.
        let expected_lower = if row == 1 { 0 } else { above };
        assert_eq!(u, &vec![expected_upper], "upper-left, pixel {pixel}");
        assert_eq!(l, &vec![expected_lower], "lower-left, pixel {pixel}");
    }
}

#[test]
fn a_lower_left_origin_keeps_the_picture_upright() {
    // A small triangle in the top-left quadrant of NDC covers the same fragsim pixels under
    // both origins when no centre lies on its edges.
    let mesh = Mesh {
        positions: vec![[-0.9, 0.1, 0.5], [-0.1, 0.1, 0.5], [-0.9, 0.93, 0.5]],
        triangles: vec![[0, 1, 2]],
    };
    let upper = owners(&identity_view(&mesh, 16, Conventions::REFERENCE));
    let lower = owners(&identity_view(
        &mesh,
        16,
        with(|c| c.window_origin = WindowOrigin::LowerLeft),
    ));
    assert!(upper.iter().take(16 * 8).any(|o| !o.is_empty()));
    assert!(upper.iter().skip(16 * 8).all(Vec::is_empty));
    assert_eq!(upper, lower);
}

/// The snapped x of the first vertex of the only screen triangle of `mesh`.
fn snapped_xs(mesh: &Mesh, side: u32, conventions: Conventions) -> Vec<i64> {
    let view = identity_view(mesh, side, conventions);
    let mut xs = Vec::new();
    view.screen_triangles(0, &mut |t| xs.extend(t.xy.map(|p| p[0])));
    xs.sort_unstable();
    xs
}

#[test]
fn four_subpixel_bits_snap_to_sixteenths_rounding_half_away() {
    // Window x on a 4-pixel viewport: 1.53 (8 bits: 392/256; 4 bits: 24.48/16 → 24/16 = 384/256)
    // and 1.53125 = 24.5/16 exactly (a tie on the coarse grid: half away from zero, 25/16).
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an f32 vertex coordinate, as the mesh stores it"
    )]
    let ndc = |window_x: f64| (window_x / 2.0 - 1.0) as f32;
    let mesh = Mesh {
        positions: vec![
            [ndc(1.53), -0.5, 0.5],
            [ndc(1.531_25), 0.5, 0.5],
            [0.9, 0.0, 0.5],
        ],
        triangles: vec![[0, 1, 2]],
    };
    let fine = snapped_xs(&mesh, 4, Conventions::REFERENCE);
    let coarse = snapped_xs(&mesh, 4, with(|c| c.subpixel_bits = 4));
    assert_eq!(&fine[..2], &[392, 392]);
    assert_eq!(&coarse[..2], &[384, 400]);
    assert!(coarse.iter().all(|x| x % 16 == 0), "{coarse:?}");
}

#[test]
fn four_subpixel_bits_move_a_centre_onto_an_edge() {
    // A vertical left edge at window x 1.53: right of the centres of column 1 (x 1.5) at 8
    // bits, on them at 4 bits, where the left edge owns them.
    #[expect(
        clippy::cast_possible_truncation,
        reason = "an f32 vertex coordinate, as the mesh stores it"
    )]
    let x = (1.53_f64 / 2.0 - 1.0) as f32;
    let mesh = Mesh {
        positions: vec![[x, -1.0, 0.5], [3.0, -1.0, 0.5], [x, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]],
    };
    let column_1 = |view: View<'_>| {
        owners(&view)
            .iter()
            .skip(1)
            .step_by(4)
            .all(|o| !o.is_empty())
    };
    assert!(!column_1(identity_view(&mesh, 4, Conventions::REFERENCE)));
    assert!(column_1(identity_view(
        &mesh,
        4,
        with(|c| c.subpixel_bits = 4)
    )));
}

#[test]
fn minus_one_to_one_keeps_what_lies_between_minus_w_and_zero() {
    // z = −0.5 with w = 1: behind the [0, 1] near plane, inside GL's [−1, 1], at window depth
    // (−0.5 + 1) / 2 = 0.25.
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, -0.5], [3.0, -1.0, -0.5], [-1.0, 3.0, -0.5]],
        triangles: vec![[0, 1, 2]],
    };
    let mut keys = Vec::new();
    identity_view(&mesh, 4, Conventions::REFERENCE).rasterize(0, &mut |f| keys.push(f.depth_key));
    assert!(keys.is_empty());
    let gl = with(|c| c.depth_range = DepthRange::MinusOneToOne);
    identity_view(&mesh, 4, gl).rasterize(0, &mut |f| keys.push(f.depth_key));
    assert_eq!(keys, vec![0.25_f32.to_bits(); 16]);
}

#[test]
fn minus_one_to_one_clips_at_minus_w() {
    // One vertex beyond z = −w: the triangle is clipped there, not rejected, and every
    // fragment's depth stays in [0, 1].
    let mesh = Mesh {
        positions: vec![[-1.0, -1.0, -3.0], [3.0, -1.0, 0.5], [-1.0, 3.0, 0.5]],
        triangles: vec![[0, 1, 2]],
    };
    let gl = identity_view(
        &mesh,
        8,
        with(|c| c.depth_range = DepthRange::MinusOneToOne),
    );
    let mut pieces = 0;
    gl.screen_triangles(0, &mut |t| {
        pieces += 1;
        assert!(t.z.iter().all(|z| (0.0..=1.0).contains(z)), "{:?}", t.z);
    });
    assert_eq!(pieces, 2, "a quadrilateral after clipping one corner");
    let (fragments, _) = fingerprint(&gl);
    assert!(fragments > 0 && fragments < 64, "{fragments}");
}

#[test]
fn the_f32_vertex_stage_rounds_as_a_vertex_shader() {
    // A matrix whose entries f32 cannot hold (1/3, 0.1): f64 and f32 depths differ, and the f32
    // one is exactly the f32 evaluation of row 2 and the divide.
    let third = 1.0 / 3.0;
    let camera = Camera::from_row_major([
        third, 0.0, 0.0, 0.0, //
        0.0, third, 0.0, 0.0, //
        0.0, 0.0, third, 0.1, //
        0.0, 0.0, 0.0, 1.0,
    ]);
    let p = [0.7_f32, -0.3, 0.77];
    let mesh = Mesh {
        positions: vec![p, [2.9, -2.9, 0.77], [0.7, 2.9, 0.77]],
        triangles: vec![[0, 1, 2]],
    };
    let viewport = Viewport::new(64, 64).unwrap();
    let f32_stage = with(|c| c.vertex_precision = VertexPrecision::F32);
    let depth_of_vertex_0 = |conventions| {
        let view = View::with_conventions(&mesh, &camera, viewport, CullMode::None, conventions);
        view.unwrap().snapped(0).1
    };
    #[expect(
        clippy::cast_possible_truncation,
        reason = "the f32 stage's arithmetic, which the expected depth repeats"
    )]
    let expected = f64::from(((third as f32) * p[2] + 0.1_f32) / 1.0_f32);
    assert_eq!(depth_of_vertex_0(f32_stage).to_bits(), expected.to_bits());
    let reference = third * f64::from(p[2]) + 0.1;
    assert_eq!(depth_of_vertex_0(Conventions::REFERENCE), reference);
    assert_ne!(expected, reference);
}

#[test]
fn the_f32_vertex_stage_moves_few_fragments_of_a_scene() {
    let scene = Scene::procedural("bunny").unwrap();
    let viewport = Viewport::new(97, 131).unwrap();
    let camera = scene.orbit_camera(viewport, &OrbitCamera::default(), DepthRange::ZeroToOne);
    let f32_stage = with(|c| c.vertex_precision = VertexPrecision::F32);
    let pixels = |conventions| {
        let view = scene.view_under(viewport, &camera, conventions).unwrap();
        let mut pixels = Vec::new();
        for prim in 0..view.triangle_count() {
            view.rasterize(prim, &mut |f| pixels.push((f.pixel, f.prim, f.depth_key)));
        }
        pixels
    };
    let (reference, single) = (pixels(Conventions::REFERENCE), pixels(f32_stage));
    // Depths differ in their low bits, coverage almost nowhere.
    assert_ne!(reference, single);
    let covered = |v: &[(u32, u32, u32)]| v.iter().map(|f| (f.0, f.1)).collect::<Vec<_>>();
    let (a, b) = (covered(&reference), covered(&single));
    let moved = a.iter().filter(|f| !b.contains(f)).count();
    assert!(
        moved * 100 < a.len(),
        "{moved} of {} fragments moved",
        a.len()
    );
}

#[test]
fn subpixel_bits_outside_the_grid_are_refused() {
    let mesh = Mesh::default();
    let camera = Camera {
        view_projection: DMat4::IDENTITY,
    };
    let viewport = Viewport::new(4, 4).unwrap();
    for bits in [0, 9] {
        let conventions = with(|c| c.subpixel_bits = bits);
        let error = View::with_conventions(&mesh, &camera, viewport, CullMode::None, conventions)
            .unwrap_err();
        assert_eq!(error, ConventionsError::SubpixelBits { bits });
        assert!(
            error.to_string().contains(&format!("{bits} subpixel bits")),
            "{error}"
        );
    }
}
