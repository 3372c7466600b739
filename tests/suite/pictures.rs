//! Issue 20, items 4 and 10: pictures read at a glance, and the outputs a user reads without the
//! source. Through the binary on small scenes: the heat map has a colour bar and a fixed scale,
//! the nearest depth a key, compare's difference image a legend and zoomed insets, bench's chart
//! a table beside it, `hazard` writes PNG (SVG on request); `bench --no-images` writes none,
//! bench.md explains its columns, `explain` prints a key, the README names every command.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use image::RgbImage;

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("pictures", name)
}

fn run(args: &[&str], out: &Path) -> String {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{args:?}: {stderr}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn png(path: &Path) -> RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// Pixels of `image` in columns `x0..` whose colour is dark (text, ticks).
fn dark_beyond(image: &RgbImage, x0: u32) -> usize {
    image
        .enumerate_pixels()
        .filter(|&(x, _, p)| x >= x0 && p.0.iter().all(|&c| c < 100))
        .count()
}

const WHITE: [u8; 3] = [255, 255, 255];

#[test]
fn the_heat_map_has_a_colour_bar_and_a_fixed_scale_and_the_depth_a_key() {
    // quads:3 at 32 × 32: three stacked squares, depth complexity up to 3.
    let scene = [
        "render", "--scene", "quads:3", "--width", "32", "--height", "32",
    ];
    let own = scratch("heat-own");
    run(&scene, &own);
    let heat = png(&own.join("depth-complexity.png"));
    // The picture, then the bar and its labels beside it.
    assert!(heat.width() > 32 + 100, "{:?}", heat.dimensions());
    assert!(dark_beyond(&heat, 40) > 100, "no bar labels");
    // Scaled to its own maximum, the deepest pixels are white.
    let picture_white = |image: &RgbImage| {
        image
            .enumerate_pixels()
            .filter(|&(x, y, p)| x < 32 && y < 32 && p.0 == WHITE)
            .count()
    };
    assert!(picture_white(&heat) > 0);
    // On a fixed scale of 6 fragments, 3 is halfway: no white pixel in the picture.
    let fixed = scratch("heat-fixed");
    run(&[&scene[..], &["--scale-max", "6"]].concat(), &fixed);
    let fixed_heat = png(&fixed.join("depth-complexity.png"));
    assert_eq!(picture_white(&fixed_heat), 0);
    // The nearest depth has its key beside it.
    let nearest = png(&own.join("nearest-depth.png"));
    assert!(nearest.width() > 32 + 100 && dark_beyond(&nearest, 40) > 100);
}

#[test]
fn compare_draws_a_legend_and_zoomed_insets_of_the_first_differing_pixels() {
    let dir = scratch("compare");
    let dumps = dir.join("dumps");
    let made = Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "render", "--scene", "quads:3", "--width", "32", "--height", "32",
        ])
        .args([
            "--scheme",
            "mdts,abuffer",
            "--k",
            "1",
            "--no-images",
            "--dump",
        ])
        .arg(&dumps)
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    // Equal: the image has its legend, and no inset.
    let image = dir.join("diff.png");
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(dumps.join("mdts"))
        .arg("--image")
        .arg(&image)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0));
    let equal = png(&image);
    assert!(equal.width() > 32 + 100 && dark_beyond(&equal, 40) > 100);
    // Corrupt one word of the dump: one differing pixel, ringed and zoomed below the picture.
    let slots = dumps.join("mdts/slots.u64");
    let mut bytes = std::fs::read(&slots).unwrap();
    let pixel = bytes.chunks_exact(8).position(|w| w != [0xff; 8]).unwrap();
    bytes[pixel * 8..pixel * 8 + 8].copy_from_slice(&[0xff; 8]);
    std::fs::write(&slots, &bytes).unwrap();
    let second_output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(dumps.join("mdts"))
        .arg("--image")
        .arg(&image)
        .output()
        .unwrap();
    assert_eq!(second_output.status.code(), Some(1));
    let different = png(&image);
    // The inset, 8× zoomed below the picture and the legend (whose nine entries end above
    // y = 280), shows the missing pixel's red over a block of 8 × 8 inside its outline.
    let insets = |picture: &RgbImage| {
        picture
            .enumerate_pixels()
            .filter(|&(_, y, p)| y > 280 && p.0 == [230, 40, 40])
            .count()
    };
    assert_eq!(insets(&equal), 0);
    let red = insets(&different);
    assert!(red >= 36, "{red} red pixels in the insets");
}

#[test]
fn bench_charts_speed_against_accuracy_with_a_table_and_no_images_writes_none() {
    let dir = scratch("bench");
    let args = [
        "bench",
        "--scene",
        "quads:3",
        "--width",
        "32",
        "--height",
        "32",
        "--frames",
        "1",
        "--scheme",
        "mdts,zbuffer,peeling",
    ];
    let table = run(&args, &dir);
    let chart = png(&dir.join("bench-speed-accuracy.png"));
    assert_eq!(chart.dimensions(), (1280, 640));
    // The table beside the chart: text in the right third.
    assert!(dark_beyond(&chart, 900) > 200);
    assert!(dir.join("bench-mdts-parallel-diff.png").exists());
    // bench.md explains its columns, and says its rates are percentages.
    let md = std::fs::read_to_string(dir.join("bench.md")).unwrap();
    assert!(md.contains("Columns:") && md.contains("**EPR %**"), "{md}");
    assert!(table.contains("Columns:"));

    let bare = scratch("bench-bare");
    run(&[&args[..], &["--no-images"]].concat(), &bare);
    let written: Vec<String> = std::fs::read_dir(&bare)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(written.iter().all(|f| !f.ends_with(".png")), "{written:?}");
    assert!(written.contains(&"bench.md".to_string()), "{written:?}");
}

#[test]
fn hazard_writes_png_charts_and_svg_on_request() {
    let args = [
        "hazard",
        "--scene",
        "quads:3",
        "--width",
        "16",
        "--height",
        "16",
        "--threads-in-flight",
        "1,32",
        "--seeds",
        "1",
    ];
    let dir = scratch("hazard");
    run(&args, &dir);
    for chart in ["hazard-vs-width", "hazard-vs-depth-complexity"] {
        let image = png(&dir.join(format!("{chart}.png")));
        assert!(image.width() > 100);
        assert!(!dir.join(format!("{chart}.svg")).exists());
    }
    let svg = scratch("hazard-svg");
    run(&[&args[..], &["--svg"]].concat(), &svg);
    let text = std::fs::read_to_string(svg.join("hazard-vs-depth-complexity.svg")).unwrap();
    // The buckets are named on the axis, not numbered.
    assert!(text.contains("<svg") && text.contains("3–4"), "{text}");
}

#[test]
fn explain_prints_a_key_to_its_symbols() {
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .arg("explain")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success());
    for symbol in [
        "key:",
        "∅ = an empty slot",
        "← = the value written",
        "→ = the value",
    ] {
        assert!(text.contains(symbol), "{symbol:?} not in {text}");
    }
}
