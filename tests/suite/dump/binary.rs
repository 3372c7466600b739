//! The `fragsim` binary's `--dump`, `compare` and `export`: exit codes, verdicts and reports.

use std::path::Path;

use assert_cmd::Command;
use fragsim::dump::triangles::TriangleExport;

use super::{scratch, spec, with_view, SCENE, WIDTH};

pub(super) fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

pub(super) fn stdout_of(cmd: &mut Command, code: i32) -> String {
    let output = cmd.output().unwrap();
    assert_eq!(
        output.status.code(),
        Some(code),
        "stdout {}\nstderr {}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

const SIZE: [&str; 4] = ["--width", "48", "--height", "36"];

/// `fragsim render` of the test scene running `schemes` serially (a dump holds the memory of
/// the run, and a parallel k-buffer may race), their dumps in `out`, with `options`.
pub(super) fn render_dump(out: &Path, schemes: &str, options: &[&str]) {
    stdout_of(
        fragsim()
            .args([
                "render",
                "--scene",
                SCENE,
                "--scheme",
                schemes,
                "--executor",
                "serial",
                "--no-images",
            ])
            .args(SIZE)
            .arg("--dump")
            .arg(out)
            .args(options),
        0,
    );
}

#[test]
fn the_binary_dumps_compares_and_exits_0_only_when_equal() {
    let dir = scratch("binary");
    let dumps = dir.join("dumps");
    render_dump(&dumps, "mdts,mdts32,abuffer", &[]);
    for scheme in ["mdts", "mdts32", "abuffer"] {
        let out = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(dumps.join(scheme))
                .args(["--json", "--no-images"]),
            0,
        );
        assert_eq!(
            crate::support::json_lines(out.as_bytes())[0]["equal"],
            true,
            "{out}"
        );
    }
    let text = stdout_of(
        fragsim()
            .arg("compare")
            .arg(dumps.join("abuffer"))
            .arg(dumps.join("mdts"))
            .arg("--no-images"),
        0,
    );
    assert!(text.contains("EQUAL (bit-identical)"), "{text}");
    // One corrupted word: exit 1, the verdict, both lists and a difference image.
    let slots = dumps.join("mdts").join("slots.u64");
    let mut bytes = std::fs::read(&slots).unwrap();
    let first = bytes.chunks_exact(8).position(|w| w != [0xff; 8]).unwrap();
    bytes[first * 8] ^= 1;
    std::fs::write(&slots, bytes).unwrap();
    let image = dir.join("diff.png");
    let corrupted_text = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .arg("--image")
            .arg(&image),
        1,
    );
    assert!(
        corrupted_text.contains("missing 1, extra 1"),
        "{corrupted_text}"
    );
    assert!(
        corrupted_text.contains("verdict: DIFFERENT"),
        "{corrupted_text}"
    );
    assert!(image.exists());
    let json = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .args(["--json", "--no-images"]),
        1,
    );
    let records = crate::support::json_lines(json.as_bytes());
    assert_eq!(records[0]["equal"], false, "{json}");
    assert_eq!(records[1]["record"], "difference", "{json}");
    // Nothing to compare, or no dump at all: exit 2.
    stdout_of(fragsim().args(["compare", "oracle", "oracle"]), 2);
    stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("absent")),
        2,
    );
}

/// Runs `fragsim compare oracle DIR --json --no-images` expecting exit code `code`; the records
/// (the `compare` record, then one `difference` record per pixel shown).
pub(super) fn json_report(dir: &Path, code: i32) -> Vec<serde_json::Value> {
    let out = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir)
            .args(["--json", "--no-images"]),
        code,
    );
    crate::support::json_lines(out.as_bytes())
}

#[test]
fn the_binary_calls_a_word_written_after_an_empty_slot_corrupt_never_equal() {
    let dir = scratch("binary-corrupt");
    let dumps = dir.join("dumps");
    render_dump(&dumps, "mdts,mdts-desc,mdts32,kbuffer,abuffer", &[]);
    // (layout, slots file, bytes a word, the empty slot's word, the pixel's verdicts): MDTS reads
    // up to the first empty slot, a k-buffer's resolve every full slot (the copy is extra too).
    let layouts = [
        ("mdts", "slots.u64", 8, u64::MAX, "corrupt"),
        ("mdts-desc", "slots.u64", 8, 0, "corrupt"),
        ("mdts32", "slots.u32", 4, u64::from(u32::MAX), "corrupt"),
        (
            "kbuffer",
            "slots.u64",
            8,
            u64::MAX,
            "extra, misordered, corrupt",
        ),
    ];
    for (scheme, file, width, empty, verdicts) in layouts {
        let path = dumps.join(scheme);
        let k = usize::try_from(json_report(&path, 0)[0]["candidate_k"].as_u64().unwrap()).unwrap();
        let slots = path.join(file);
        let mut bytes = std::fs::read(&slots).unwrap();
        let word = |raw: &[u8], i: usize| {
            let mut le = [0_u8; 8];
            le[..width].copy_from_slice(&raw[i * width..(i + 1) * width]);
            u64::from_le_bytes(le)
        };
        // A pixel whose first slot is full and whose last two are empty; its last slot gets a
        // copy of its first word, a word the pixel really holds.
        let pixel = (0..bytes.len() / width / k)
            .find(|&p| word(&bytes, p * k) != empty && word(&bytes, p * k + k - 2) == empty)
            .unwrap();
        let stray = word(&bytes, pixel * k);
        let last = pixel * k + k - 1;
        bytes[last * width..(last + 1) * width].copy_from_slice(&stray.to_le_bytes()[..width]);
        std::fs::write(&slots, &bytes).unwrap();
        let text = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(&path)
                .arg("--no-images"),
            1,
        );
        let x = pixel % WIDTH as usize;
        let y = pixel / WIDTH as usize;
        for expected in [
            "corrupt 1".to_string(),
            format!("pixel {pixel} (x {x}, y {y}): {verdicts}\n"),
            format!("slot {}: {stray:#x} written after an empty slot", k - 1),
            "verdict: DIFFERENT".to_string(),
        ] {
            assert!(
                text.contains(&expected),
                "{scheme}: {expected:?} not in\n{text}"
            );
        }
        assert!(!text.contains("EQUAL"), "{scheme}: {text}");
        let records = json_report(&path, 1);
        let report = &records[0];
        assert_eq!(report["equal"], false);
        assert_eq!(report["corrupt_pixels"], 1, "{scheme}");
        assert_eq!(report["corrupt_words"], 1);
        let first = &records[1];
        assert_eq!(first["pixel"], pixel);
        let listed: Vec<&str> = verdicts.split(", ").collect();
        assert_eq!(first["verdict"], serde_json::json!(listed));
        assert_eq!(first["corrupt_words"][0]["slot"], k - 1);
    }
    // An A-buffer counter that never stopped: overflow-miscounted, and the overflow by design
    // stays what the oracle predicts (none here) instead of the counter's 4294967295 − n.
    let path = dumps.join("abuffer");
    let counters = path.join("counters.u32");
    let mut bytes = std::fs::read(&counters).unwrap();
    let pixel = bytes.chunks_exact(4).position(|c| c != [0; 4]).unwrap();
    bytes[pixel * 4..pixel * 4 + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&counters, &bytes).unwrap();
    let records = json_report(&path, 1);
    assert_eq!(records[0]["overflow_miscounted_pixels"], 1);
    assert_eq!(records[0]["overflowed"], 0);
    assert_eq!(records[1]["pixel"], pixel);
    assert_eq!(
        records[1]["verdict"],
        // `abuffer` is fixed storage written in full (`filled`): the slots the counter now
        // claims hold the empty marker, which is corrupt too.
        serde_json::json!(["overflow-miscounted", "corrupt"])
    );
    let text = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(&path)
            .arg("--no-images"),
        1,
    );
    assert!(
        text.contains("overflowed by design 0 (counters claim"),
        "{text}"
    );
    assert!(text.contains("overflow-miscounted 1"), "{text}");
}

#[test]
fn the_binary_exports_the_triangles_of_the_view_it_names() {
    let dir = scratch("export");
    let file = dir.join("scene.tri");
    let text = stdout_of(
        fragsim()
            .args([
                "export-scene",
                "--scene",
                SCENE,
                "--view",
                "30",
                "--elevation",
                "15",
            ])
            .args(SIZE)
            .arg("--out")
            .arg(&file),
        0,
    );
    assert!(text.contains("screen triangles"), "{text}");
    let read = TriangleExport::read(&file).unwrap();
    with_view(|view, _| assert_eq!(read, TriangleExport::from_view(view, spec())));
}

/// Issue 36: `export-scene` takes `render`'s convention flags, records them in its scene, and
/// writes the view a backend under them rasterizes (its size in pixels at several samples).
#[test]
fn the_export_takes_renders_conventions() {
    let dir = scratch("export-conventions");
    let export = |name: &str, conventions: &[&str]| {
        let file = dir.join(name);
        let text = stdout_of(
            fragsim()
                .args(["export-scene", "--scene", SCENE])
                .args(SIZE)
                .args(conventions)
                .arg("--out")
                .arg(&file),
            0,
        );
        assert!(text.contains("binary FRAGTRI1"), "{text}");
        TriangleExport::read(&file).unwrap()
    };
    let reference = export("reference.tri", &[]);
    let gl = export(
        "gl.tri",
        &[
            "--window-origin",
            "lower-left",
            "--depth-range",
            "minus-one-to-one",
            "--subpixel-bits",
            "4",
            "--vertex-precision",
            "f32",
            "--samples",
            "4",
        ],
    );
    let declared = gl.scene.conventions;
    assert_eq!(
        serde_json::to_value(declared).unwrap(),
        serde_json::json!({"window_origin": "lower-left", "subpixel_bits": 4,
            "depth_range": "minus-one-to-one", "vertex_precision": "f32", "samples": 4})
    );
    assert_eq!((gl.width, gl.height), (WIDTH, super::HEIGHT));
    let scene = fragsim::raster::Scene::procedural(SCENE).unwrap();
    let view = gl
        .scene
        .view(
            &scene,
            fragsim::raster::Viewport::new(WIDTH, super::HEIGHT).unwrap(),
        )
        .unwrap();
    assert_eq!(
        gl.triangles,
        TriangleExport::from_view(&view, gl.scene.clone()).triangles
    );
    assert_ne!(
        gl.triangles, reference.triangles,
        "the conventions changed nothing"
    );
}

#[test]
fn render_dumps_every_scheme_or_nothing() {
    let dir = scratch("binary-all");
    let dumps = dir.join("dumps");
    let render = |into: &Path| {
        fragsim()
            .args(["render", "--scene", SCENE, "--scheme", "all"])
            .args(SIZE)
            .args(["--no-images", "--dump"])
            .arg(into)
            .output()
            .unwrap()
    };
    let made = render(&dumps);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let mut written: Vec<String> = std::fs::read_dir(&dumps)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    written.sort();
    let mut every: Vec<String> = fragsim::catalog::CATALOG
        .iter()
        .map(|e| e.name.to_string())
        .collect();
    every.sort();
    // One dump a scheme, and no staging directory left.
    assert_eq!(written, every);
    for scheme in ["linked-list", "layer-counter", "peeling", "zbuffer"] {
        let out = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(dumps.join(scheme))
                .args(["--json", "--no-images"]),
            0,
        );
        assert_eq!(
            crate::support::json_lines(out.as_bytes())[0]["equal"],
            true,
            "{scheme}: {out}"
        );
    }
    // A file where one dump goes fails the whole run before anything is moved into place.
    let blocked = dir.join("blocked");
    std::fs::create_dir_all(&blocked).unwrap();
    std::fs::write(blocked.join("loop32"), b"not a dump").unwrap();
    let failed = render(&blocked);
    assert!(!failed.status.success());
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(
        stderr.contains("loop32") && stderr.contains("not a directory"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(&blocked).unwrap().collect();
    assert_eq!(left.len(), 1, "only the file that was there");
}

#[test]
fn a_header_that_disagrees_with_its_arrays_names_the_field_at_fault() {
    // Issue 36: `k: 9` over slots of shape [pixels, 8], or a width one short, was reported as a
    // total of words that named neither `k`, `width` nor `shape`.
    let dir = scratch("binary-header-fields");
    render_dump(
        &dir,
        "mdts,abuffer,linked-list,layer-counter",
        &["--k", "4"],
    );
    let pixels = WIDTH * 36;
    let cases: [(&str, &str, serde_json::Value, &[&str]); 6] = [
        (
            "mdts",
            "k",
            serde_json::json!(5),
            &["\"slots\"", "\"k\" 5", "[1728, 5]"],
        ),
        (
            "mdts",
            "width",
            serde_json::json!(WIDTH - 1),
            &["\"slots\"", "\"width\" 47 × \"height\" 36", "[1692, 4]"],
        ),
        (
            "abuffer",
            "capacity",
            serde_json::json!(3),
            &["\"slots\"", "\"capacity\" 3"],
        ),
        (
            "abuffer",
            "height",
            serde_json::json!(35),
            &["\"counters\"", "\"height\" 35"],
        ),
        (
            "linked-list",
            "pool",
            serde_json::json!(7),
            &["\"nodes\"", "\"pool\" 7"],
        ),
        (
            "layer-counter",
            "k",
            serde_json::json!(3),
            &["\"layers\"", "\"k\" 3", "[3, 1728]"],
        ),
    ];
    assert_eq!(pixels, 1728);
    for (scheme, field, value, reasons) in cases {
        let header_file = dir.join(scheme).join("dump.json");
        let original = std::fs::read(&header_file).unwrap();
        json_report(&dir.join(scheme), 0);
        let mut header: serde_json::Value = serde_json::from_slice(&original).unwrap();
        header[field] = value;
        std::fs::write(&header_file, header.to_string()).unwrap();
        let output = fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join(scheme))
            .arg("--no-image")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{scheme} {field}: {stderr}");
        for reason in reasons
            .iter()
            .chain(&["shape", "disagrees with the header"])
        {
            assert!(
                stderr.contains(reason),
                "{scheme} {field}: {reason:?} not in {stderr}"
            );
        }
        std::fs::write(&header_file, original).unwrap();
    }
}
