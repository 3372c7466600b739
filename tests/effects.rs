//! The effects of issue 7: the three effects shade every scheme (key-only and primitive-only
//! captures through the deferred attribute pass) and the error-pixel rate sees exactly what a
//! scheme lost; Fresnel's per-fragment term is Schlick's; sRGB encoding is the standard's.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use fragsim::raster::attributes::Attributes;
use fragsim::raster::{OrbitCamera, Scene, Viewport};
use fragsim::shade::effects::{
    encode_srgb, schlick_transmittance, shade_pixel, Effect, Entries, Geometry, Material,
};
use serde_json::Value;

fn out_dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("fragsim-effects-{name}-{}", std::process::id()))
}

/// `fragsim bench` at 64 × 64 with one frame; the report's rows.
fn bench(out: &Path, scene: &str, schemes: &str, effect: &str) -> Vec<Value> {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["bench", "--scene", scene, "--width", "64", "--height", "64"])
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
    let report: Value = serde_json::from_slice(&output.stdout).unwrap();
    report["rows"].as_array().unwrap().clone()
}

fn rate(row: &Value) -> f64 {
    row["error_pixel_rate"]
        .as_f64()
        .unwrap_or_else(|| panic!("no EPR: {row}"))
}

#[test]
fn exact_schemes_have_no_error_pixels_in_any_effect_whatever_their_words_hold() {
    // mdts: key and primitive; mdts32: keys only; mdts-packed: primitives only (the deferred
    // attribute pass completes both); abuffer: a second exact scheme.
    for effect in ["transparency", "translucency", "fresnel"] {
        let out = out_dir(effect);
        let rows = bench(&out, "spheres:3", "mdts,mdts32,mdts-packed,abuffer", effect);
        assert_eq!(rows.len(), 4);
        for row in &rows {
            assert_eq!(rate(row), 0.0, "{effect}: {row}");
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
    let red = diff.pixels().filter(|p| p.0 == [255, 0, 0]).count() as u64;
    assert_eq!(red, errors);
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
            for (got, base) in colour.iter().zip(material.base) {
                assert!((f64::from(*got) - ft * f64::from(base)).abs() < 1e-6);
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
    assert_eq!(schlick_transmittance(0.5), 1.0 - 0.5f64.powi(5));
}

#[test]
fn srgb_encoding_is_exact_at_the_ends_and_continuous_at_the_knee() {
    assert_eq!(encode_srgb(0.0), 0);
    assert_eq!(encode_srgb(1.0), 255);
    // At the knee 0.0031308 both branches give 0.04045 (10.31 of 255): the linear one below,
    // the power one just above.
    let knee = 0.003_130_8f32;
    assert_eq!(encode_srgb(knee), 10);
    assert_eq!(encode_srgb(knee.next_up()), 10);
    assert_eq!(encode_srgb(knee.next_down()), 10);
    // Out of range clamps; one linear step below 1 is still 255, 0.5 is 188 (not 128).
    assert_eq!(encode_srgb(-1.0), 0);
    assert_eq!(encode_srgb(2.0), 255);
    assert_eq!(encode_srgb(0.5), 188);
}
