//! The effects: the three effects shade every scheme (key-only and primitive-only
//! captures through the deferred attribute pass) and the error-pixel rate sees exactly what a
//! scheme lost; Fresnel's per-fragment term is Schlick's; sRGB encoding is the standard's.

use std::path::{Path, PathBuf};

use crate::support::prim_of;
use assert_cmd::Command;
use fragsim::oracle::Oracle;
use fragsim::raster::attributes::Attributes;
use fragsim::raster::{OrbitCamera, Scene, Viewport};
use fragsim::shade::effects::{
    encode_srgb, schlick_transmittance, shade_pixel, Effect, Entries, Geometry, Material,
};
use serde_json::Value;

fn out_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("fragsim-effects-{name}-{}", std::process::id()))
}

/// `fragsim bench` on a procedural scene at 64 × 64 with one frame; the report's rows.
fn bench(out: &Path, scene: &str, schemes: &str, effect: &str) -> Vec<Value> {
    bench_on(out, &["--scene", scene], schemes, effect)
}

/// `fragsim bench` with the scene options `scene` at 64 × 64 with one frame; the report's rows.
fn bench_on(out: &Path, scene: &[&str], schemes: &str, effect: &str) -> Vec<Value> {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .arg("bench")
        .args(scene)
        .args(["--width", "64", "--height", "64"])
        .args([
            "--frames", "1", "--json", "--scheme", schemes, "--effect", effect,
        ])
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    crate::support::json_lines(&output.stdout)
}

fn rate(row: &Value) -> f64 {
    row["error_pixel_rate"]
        .as_f64()
        .unwrap_or_else(|| panic!("no EPR: {row}"))
}

#[test]
fn exact_schemes_have_no_error_pixels_in_any_effect_whatever_their_words_hold() {
    // mdts: key and primitive; mdts32: keys only (primitive ids completed from the oracle);
    // mdts-packed: primitive ids at its own 20-bit depths, nothing completed (the nested
    // spheres' layers lie many 2^-20 steps apart); abuffer: a second exact scheme.
    for effect in ["transparency", "translucency", "fresnel"] {
        let out = out_dir(effect);
        let rows = bench(&out, "spheres:3", "mdts,mdts32,mdts-packed,abuffer", effect);
        assert_eq!(rows.len(), 4);
        for row in &rows {
            assert_eq!(rate(row), 0.0, "{effect}: {row}");
            // Fresnel recomputes normals; only the key-only capture is completed.
            let pass = &row["attribute_pass"];
            assert_eq!(
                pass.is_null(),
                effect != "fresnel" && row["scheme"] != "mdts32"
            );
            let completed = !pass.is_null() && !pass["completed_from_oracle"].is_null();
            assert_eq!(completed, row["scheme"] == "mdts32", "{row}");
        }
        assert!(out.join(format!("bench-oracle-{effect}.png")).is_file());
        std::fs::remove_dir_all(out).unwrap();
    }
}

#[test]
fn a_lossy_scheme_has_error_pixels_and_the_difference_image_shows_each_in_red() {
    // The z-buffer keeps the nearest of the nested spheres' six layers.
    let out = out_dir("lossy");
    let rows = bench(&out, "spheres:3", "zbuffer", "translucency");
    let errors = rows[0]["error_pixels"].as_u64().unwrap();
    assert!(rate(&rows[0]) > 0.5, "{}", rows[0]);
    let diff = image::open(out.join("bench-zbuffer-parallel-diff.png"))
        .unwrap()
        .to_rgb8();
    // The picture is the figure's top-left 64 × 64 (its legend and insets lie beside and below).
    let red = diff
        .enumerate_pixels()
        .filter(|&(x, y, p)| x < 64 && y < 64 && p.0 == [255, 0, 0])
        .count() as u64;
    assert_eq!(red, errors);
    std::fs::remove_dir_all(out).unwrap();
}

/// Writes two parallel squares `[-1, 1]²` as an OBJ file: primitives 0 and 1 at z = 0, and 2
/// and 3 at z = `separation`, the nearer from the orbit at angle 0 (its eye is on the +z side).
fn two_squares(path: &Path, separation: f32) {
    let mut obj = String::new();
    for z in [0.0, separation] {
        for (x, y) in [(-1, -1), (1, -1), (1, 1), (-1, 1)] {
            obj += &format!("v {x} {y} {z:?}\n");
        }
    }
    obj += "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n";
    std::fs::write(path, obj).unwrap();
}

/// Pixels of `mesh` at 64 × 64 (orbit at angle 0) whose two layers packed MDTS must misorder:
/// their 20-bit depths tie (the top 20 mantissa bits of `d' = 0.5 + 0.5·d`, rounded once to f32
/// from f64, independently of the library) and the nearer has the larger primitive id. With the
/// ids as colours, all below 4096 (one high half), a tie sorts by id; the oracle sorts by depth.
fn predicted_misorders(mesh: &Path) -> u64 {
    let scene = Scene::from_file(mesh).unwrap();
    let view = scene
        .view(Viewport::new(64, 64).unwrap(), &OrbitCamera::default())
        .unwrap();
    let oracle = Oracle::build(&view);
    #[expect(
        clippy::cast_possible_truncation,
        reason = "narrowing is the point: the shader remaps the depth in f32"
    )]
    let bucket = |entry: u64| {
        let depth = f64::from(f32::from_bits((entry >> 32) as u32));
        (((0.5 + 0.5 * depth) as f32).to_bits() & 0x7F_FFFF) >> 3
    };
    (0..oracle.pixels())
        .filter(|&p| match oracle.pixel(p) {
            [near, far] => bucket(*near) == bucket(*far) && prim_of(*near) > prim_of(*far),
            _ => false,
        })
        .count() as u64
}

/// FreePipe §5's precision loss, in an image: two differently coloured surfaces closer than
/// 2^-20 in depth. Packed MDTS sorts them by colour where their 20-bit depths tie, and the
/// transparency image is wrong at exactly those pixels; with the surfaces far apart it is exact.
#[test]
fn packed_mdts_has_error_pixels_exactly_where_its_20_bit_depths_misorder_two_surfaces() {
    let out = out_dir("near-tie");
    std::fs::create_dir_all(&out).unwrap();
    // 5·10^-7 in z is about 2.5 f32 steps of window depth here: most pixels tie in 20 bits
    // (2^-20 is 16 steps), some straddle a bucket edge. 10^-2 is thousands of buckets.
    for (separation, near_tie) in [(5e-7_f32, true), (1e-2, false)] {
        let mesh = out.join(format!("two-squares-{separation:e}.obj"));
        two_squares(&mesh, separation);
        let misordered = predicted_misorders(&mesh);
        assert_eq!(misordered > 0, near_tie, "{separation}: {misordered}");
        let scene = ["--mesh", mesh.to_str().unwrap(), "--view", "0"];
        let rows = bench_on(&out, &scene, "mdts,mdts-packed", "transparency");
        // The exact scheme shades the scene right: the errors are packed MDTS's own.
        assert_eq!(rows[0]["error_pixels"], 0, "{}", rows[0]);
        let packed = &rows[1];
        assert_eq!(packed["scheme"], "mdts-packed");
        assert_eq!(packed["error_pixels"], misordered, "{separation}: {packed}");
        assert_eq!(rate(packed) > 0.0, near_tie);
        assert!(packed["attribute_pass"].is_null(), "{packed}");
        // The oracle's diff sees the same pixels, by primitive sequence.
        assert_eq!(packed["mismatched_pixels"], misordered, "{packed}");
    }
    std::fs::remove_dir_all(out).unwrap();
}

#[test]
fn fresnel_of_one_fragment_is_schlicks_transmittance() {
    // One square in z = 0 seen from straight ahead: normal (0, 0, 1).
    let scene = Scene {
        name: "square".into(),
        mesh: fragsim::raster::Mesh {
            positions: vec![
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        },
    };
    let orbit = OrbitCamera {
        elevation_degrees: 0.0,
        ..OrbitCamera::default()
    };
    let view = scene.view(Viewport::new(33, 33).unwrap(), &orbit).unwrap();
    let attributes = Attributes::new(&view);
    let material = Material::default();
    let flat = |_: f32| 0.0;
    let eye = attributes.eye();
    let mut fragments = 0;
    for prim in 0..view.triangle_count() {
        view.rasterize(prim, &mut |f| {
            fragments += 1;
            // cos θ from first principles: the normal against the ray from the point to the eye.
            let p = attributes.point(f.prim, f.pixel).unwrap();
            let ray: Vec<f64> = (0..3).map(|i| eye[i] - p[i]).collect();
            let length = ray.iter().map(|c| c * c).sum::<f64>().sqrt();
            let cos = ray[2].abs() / length;
            let got = attributes.cosine(f.prim, f.pixel).unwrap();
            assert!(
                (got - cos).abs() < 1e-9,
                "pixel {}: {got} vs {cos}",
                f.pixel
            );
            let lookup = |_: usize, _: u64| got;
            let geometry = Geometry {
                distance: &flat,
                cosine: &lookup,
            };
            let colour = shade_pixel(
                Effect::Fresnel,
                &material,
                Entries::KeyAndPrim,
                f.pixel as usize,
                &[f.packed()],
                geometry,
            )
            .unwrap();
            let ft = 1.0 - (1.0 - cos).powi(5);
            for (channel, base) in colour.iter().zip(material.base) {
                assert!((f64::from(*channel) - ft * f64::from(base)).abs() < 1e-6);
            }
            // The centre pixel looks straight at the square: Ft = 1.
            if f.pixel == 16 * 33 + 16 {
                assert!((got - 1.0).abs() < 1e-12, "{got}");
                assert_eq!(schlick_transmittance(got), 1.0);
            }
        });
    }
    assert!(fragments > 100, "{fragments}");
    assert_eq!(schlick_transmittance(0.0), 0.0);
    assert_eq!(schlick_transmittance(0.5), 1.0 - 0.5_f64.powi(5));
}

#[test]
fn srgb_encoding_is_exact_at_the_ends_and_continuous_at_the_knee() {
    assert_eq!(encode_srgb(0.0), 0);
    assert_eq!(encode_srgb(1.0), 255);
    // At the knee 0.0031308 both branches give 0.04045 (10.31 of 255): the linear one below,
    // the power one just above.
    let knee = 0.003_130_8_f32;
    assert_eq!(encode_srgb(knee), 10);
    assert_eq!(encode_srgb(knee.next_up()), 10);
    assert_eq!(encode_srgb(knee.next_down()), 10);
    // Out of range clamps; one linear step below 1 is still 255, 0.5 is 188 (not 128).
    assert_eq!(encode_srgb(-1.0), 0);
    assert_eq!(encode_srgb(2.0), 255);
    assert_eq!(encode_srgb(0.5), 188);
}
