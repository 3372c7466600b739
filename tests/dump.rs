//! The interchange with GPU backends (`docs/dump-format.md`): dumps round-trip through files,
//! decode to exactly what the scheme captured, and `compare` names every kind of difference; the
//! triangle export carries everything a backend needs to reproduce the oracle. CI has no GPU:
//! these tests are the host side of `backends/cuda`.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use fragsim::capture::mdts::Direction;
use fragsim::capture::Identity;
use fragsim::oracle::dump::{
    self, verdict, Dtype, Dump, DumpScheme, SceneSpec, TriangleExport, Words,
};
use fragsim::oracle::Oracle;
use fragsim::raster::{OrbitCamera, Scene, Viewport};

/// A fresh directory under cargo's per-test-target temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("dump-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SCENE: &str = "spheres:3";
/// Not square, so that a width/height mix-up cannot pass.
const WIDTH: u32 = 48;
const HEIGHT: u32 = 36;

fn spec() -> SceneSpec {
    SceneSpec::named(SCENE, 30.0, 15.0)
}

fn with_view<R>(f: impl FnOnce(&fragsim::raster::View<'_>, &Oracle) -> R) -> R {
    let scene = Scene::procedural(SCENE).unwrap();
    let view = scene
        .view(Viewport::new(WIDTH, HEIGHT).unwrap(), &spec().orbit())
        .unwrap();
    let oracle = Oracle::build(&view);
    f(&view, &oracle)
}

fn every_layout(oracle: &Oracle) -> Vec<DumpScheme> {
    let k = oracle.max_depth_complexity();
    assert!(k >= 4, "the scene must have several layers, got {k}");
    vec![
        DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        },
        DumpScheme::Mdts {
            k: 2,
            direction: Direction::Descending,
        },
        DumpScheme::Mdts32 { k: 3 },
        DumpScheme::ABufferFixed {
            capacity: k,
            sorted: true,
        },
        DumpScheme::ABufferFixed {
            capacity: 2,
            sorted: false,
        },
        DumpScheme::ABufferExact {
            counts: oracle.depth_complexity(),
            sorted: false,
        },
    ]
}

fn u64_slots(dump: &mut Dump) -> &mut Vec<u64> {
    match dump.arrays.get_mut("slots") {
        Some(Words::U64(w)) => w,
        _ => panic!("no u64 slots"),
    }
}

#[test]
fn every_layout_round_trips_through_files_and_decodes_to_what_its_scheme_promises() {
    with_view(|view, oracle| {
        for (i, scheme) in every_layout(oracle).iter().enumerate() {
            let dump = Dump::record(view, spec(), scheme, "test").unwrap();
            let dir = scratch(&format!("round-trip-{i}"));
            dump.write(&dir).unwrap();
            let back = Dump::read(&dir).unwrap();
            assert_eq!(back, dump, "{scheme:?}");
            assert_eq!(Dump::read(&dir.join("dump.json")).unwrap(), dump);
            assert_eq!(back.scheme().unwrap(), *scheme);
            let capture = back.capture().unwrap();
            let diff = oracle.diff(&capture);
            assert!(diff.is_exact(), "{scheme:?}: {diff:?}");
            let comparison = dump::compare(oracle, &capture, 0, 4);
            assert!(comparison.is_equal());
            assert_eq!(comparison.diff.captured, diff.captured);
            assert_eq!(comparison.diff.overflowed, diff.overflowed);
            assert_eq!(comparison.counts.equal, u64::from(WIDTH * HEIGHT));
        }
    });
}

#[test]
fn a_dump_written_by_hand_as_a_gpu_backend_writes_it_is_read_and_judged() {
    with_view(|_, oracle| {
        // What a CUDA or NumPy writer produces: the MDTS words of every pixel, K slots, empty = all
        // ones, raw little-endian, and a header typed by hand (NumPy dtype names, an extra field).
        let k = oracle.max_depth_complexity() as usize;
        let pixels = (WIDTH * HEIGHT) as usize;
        let mut bytes = Vec::new();
        for p in 0..pixels {
            let list = oracle.pixel(p);
            for slot in 0..k {
                bytes.extend_from_slice(&list.get(slot).copied().unwrap_or(u64::MAX).to_le_bytes());
            }
        }
        let dir = scratch("by-hand");
        std::fs::write(dir.join("words.bin"), &bytes).unwrap();
        let header = format!(
            r#"{{"format": "fragsim-dump", "version": 1, "producer": "numpy",
                "scene": {{"name": "{SCENE}", "view_degrees": 30, "elevation_degrees": 15}},
                "width": {WIDTH}, "height": {HEIGHT}, "scheme": "mdts", "k": {k},
                "arrays": {{"slots": {{"file": "words.bin", "dtype": "<u8", "shape": [{pixels}, {k}]}}}},
                "extra": {{"kernel_ms": 0.25}}, "something_new": true}}"#
        );
        std::fs::write(dir.join("dump.json"), header).unwrap();
        let dump = Dump::read(&dir).unwrap();
        assert_eq!(dump.header.arrays["slots"].dtype, Dtype::U64);
        assert_eq!(dump.header.scene, spec(), "defaults fill the camera");
        assert!(oracle.diff(&dump.capture().unwrap()).is_exact());
    });
}

#[test]
fn compare_names_missing_extra_and_misordered_pixels_and_agrees_with_the_diff() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        let deep: Vec<usize> = (0..oracle.pixels())
            .filter(|&p| oracle.pixel(p).len() >= 3)
            .take(3)
            .collect();
        let [swapped, renamed, holed] = [deep[0], deep[1], deep[2]];
        let k = k as usize;
        let slots = u64_slots(&mut dump);
        slots.swap(swapped * k, swapped * k + 1);
        slots[renamed * k] ^= 1; // another primitive id
        slots[holed * k + 1] = u64::MAX; // an empty slot: what follows is unreachable
        let capture = dump.capture().unwrap();
        let comparison = dump::compare(oracle, &capture, 0, 8);
        let flags = |p: usize| comparison.verdicts[p];
        assert_eq!(flags(swapped), verdict::MISORDERED);
        assert_eq!(flags(renamed), verdict::MISSING | verdict::EXTRA);
        assert_eq!(flags(holed), verdict::MISSING);
        let lost_behind_hole = oracle.pixel(holed).len() as u64 - 1;
        assert_eq!(comparison.diff.lost, 1 + lost_behind_hole);
        assert_eq!(comparison.diff.extra, 1);
        assert_eq!(
            (
                comparison.counts.missing,
                comparison.counts.extra,
                comparison.counts.misordered
            ),
            (2, 1, 1)
        );
        assert_eq!(
            comparison.counts.equal,
            u64::from(WIDTH * HEIGHT) - 3,
            "every other pixel is equal"
        );
        let whole = oracle.diff(&capture);
        assert_eq!(
            (
                whole.lost,
                whole.extra,
                whole.misordered_pixels,
                whole.mismatched_pixels
            ),
            (
                comparison.diff.lost,
                comparison.diff.extra,
                comparison.diff.misordered_pixels,
                comparison.diff.mismatched_pixels
            )
        );
        let shown: Vec<usize> = comparison
            .diff
            .first_mismatches
            .iter()
            .map(|m| m.pixel)
            .collect();
        let mut expected = vec![swapped, renamed, holed];
        expected.sort_unstable();
        assert_eq!(shown, expected);
    });
}

#[test]
fn abuffer_overflow_by_design_is_equal_but_an_overstated_counter_is_caught() {
    with_view(|view, oracle| {
        let scheme = DumpScheme::ABufferFixed {
            capacity: 2,
            sorted: true,
        };
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
        assert!(comparison.is_equal());
        assert!(comparison.counts.overflowed > 0);
        assert!(comparison.diff.overflowed > 0);
        let deep = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() >= 3)
            .unwrap();
        match dump.arrays.get_mut("counters") {
            Some(Words::U32(c)) => c[deep] += 1,
            _ => panic!("no counters"),
        }
        let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
        assert!(!comparison.is_equal());
        assert_eq!(
            comparison.verdicts[deep] & verdict::MISCOUNTED,
            verdict::MISCOUNTED
        );
        assert_eq!(comparison.counts.miscounted, 1);
    });
}

#[test]
fn a_sorted_abuffer_dump_is_judged_in_stored_order_an_unsorted_one_is_sorted_first() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let deep = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() >= 2)
            .unwrap();
        for sorted in [true, false] {
            let scheme = DumpScheme::ABufferFixed {
                capacity: k,
                sorted,
            };
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            let base = deep * k as usize;
            let slots = u64_slots(&mut dump);
            slots.swap(base, base + 1);
            let comparison = dump::compare(oracle, &dump.capture().unwrap(), 0, 8);
            if sorted {
                assert_eq!(comparison.verdicts[deep], verdict::MISORDERED);
            } else {
                assert!(
                    comparison.is_equal(),
                    "the post pass sorts an unsorted dump"
                );
            }
        }
    });
}

#[test]
fn depth_ulps_accepts_keys_within_the_tolerance_and_no_further() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        // Closed spheres: two layers far apart, so a nudged front key stays in front.
        let pixel = (0..oracle.pixels())
            .find(|&p| oracle.pixel(p).len() == 2)
            .unwrap();
        for (nudge, tolerance, equal) in [
            (1u64, 0u32, false),
            (1, 1, true),
            (3, 2, false),
            (3, 3, true),
        ] {
            let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
            u64_slots(&mut dump)[pixel * k as usize] += nudge << 32;
            let comparison = dump::compare(oracle, &dump.capture().unwrap(), tolerance, 8);
            assert_eq!(
                comparison.is_equal(),
                equal,
                "nudge {nudge} ulps, tolerance {tolerance}"
            );
        }
        // A different primitive is never a tolerance match.
        let mut dump = Dump::record(view, spec(), &scheme, "test").unwrap();
        u64_slots(&mut dump)[pixel * k as usize] += (1 << 32) + 1;
        assert!(!dump::compare(oracle, &dump.capture().unwrap(), 5, 8).is_equal());
    });
}

#[test]
fn a_key_only_reference_compares_keys_only() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let reference = Dump::record(view, spec(), &DumpScheme::Mdts32 { k }, "test").unwrap();
        let reference = reference.capture().unwrap();
        assert_eq!(reference.identity, Identity::KeyOnly);
        let candidate = Dump::record(
            view,
            spec(),
            &DumpScheme::Mdts {
                k,
                direction: Direction::Ascending,
            },
            "test",
        )
        .unwrap()
        .capture()
        .unwrap();
        let as_oracle = Oracle::from_capture(&reference);
        assert!(!dump::compare(&as_oracle, &candidate, 0, 1).is_equal());
        let coarse = dump::with_identity(&candidate, Identity::KeyOnly);
        assert!(dump::compare(&as_oracle, &coarse, 0, 1).is_equal());
    });
}

#[test]
fn malformed_dumps_are_clear_errors() {
    with_view(|view, oracle| {
        let k = oracle.max_depth_complexity();
        let scheme = DumpScheme::Mdts {
            k,
            direction: Direction::Ascending,
        };
        let good = Dump::record(view, spec(), &scheme, "test").unwrap();
        let cases: Vec<(&str, Breaker)> = vec![
            (
                "version",
                Box::new(|d: &Path| edit_header(d, "\"version\": 1", "\"version\": 9")),
            ),
            (
                "elements",
                Box::new(|d: &Path| {
                    let f = d.join("slots.u64");
                    let mut b = std::fs::read(&f).unwrap();
                    b.truncate(b.len() - 8);
                    std::fs::write(f, b).unwrap();
                }),
            ),
            (
                "cannot read",
                Box::new(|d: &Path| std::fs::remove_file(d.join("slots.u64")).unwrap()),
            ),
            (
                "unknown scheme",
                Box::new(|d: &Path| edit_header(d, "\"scheme\": \"mdts\"", "\"scheme\": \"zbuf\"")),
            ),
            (
                "needs \"k\"",
                Box::new(|d: &Path| edit_header(d, &format!("\"k\": {k}"), "\"k\": 0")),
            ),
            (
                "holds",
                Box::new(|d: &Path| edit_header(d, "\"width\": 48", "\"width\": 24")),
            ),
        ];
        for (i, (message, break_it)) in cases.iter().enumerate() {
            let dir = scratch(&format!("malformed-{i}"));
            good.write(&dir).unwrap();
            break_it(&dir);
            let error = Dump::read(&dir)
                .and_then(|d| d.capture())
                .expect_err(message)
                .to_string();
            assert!(error.contains(message), "{message:?} not in {error:?}");
        }
    });
}

/// Damages a dump directory in one way.
type Breaker<'a> = Box<dyn Fn(&Path) + 'a>;

fn edit_header(dir: &Path, from: &str, to: &str) {
    let path = dir.join("dump.json");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from:?} not in {text}");
    std::fs::write(path, text.replace(from, to)).unwrap();
}

#[test]
fn the_triangle_export_round_trips_and_rescanning_it_reproduces_the_oracle() {
    for (scene, camera) in [
        (SCENE, OrbitCamera::default().at_angle(30.0)),
        // Close enough that triangles cross the near plane: clipped pieces keep their prim.
        (
            "quads:3",
            OrbitCamera {
                distance_scale: 0.3,
                ..OrbitCamera::default()
            },
        ),
    ] {
        let mesh = Scene::procedural(scene).unwrap();
        let view = mesh
            .view(Viewport::new(WIDTH, HEIGHT).unwrap(), &camera)
            .unwrap();
        let oracle = Oracle::build(&view);
        let export =
            TriangleExport::from_view(&view, SceneSpec::named(scene, camera.angle_degrees, 15.0));
        let bytes = export.to_bytes().unwrap();
        assert_eq!(&bytes[..8], b"FRAGTRI1");
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), WIDTH);
        assert_eq!(
            u32::from_le_bytes(bytes[16..20].try_into().unwrap()),
            HEIGHT
        );
        let count = u32::from_le_bytes(bytes[28..32].try_into().unwrap()) as usize;
        assert_eq!(count, export.triangles.len());
        assert_eq!((bytes.len() - 40) % 8, 0);
        assert_eq!(TriangleExport::from_bytes(&bytes).unwrap(), export);
        let mut lists = vec![Vec::new(); oracle.pixels()];
        for t in &export.triangles {
            view.scan(t, &mut |f| lists[f.pixel as usize].push(f.packed()));
        }
        for (p, list) in lists.iter_mut().enumerate() {
            list.sort_unstable();
            assert_eq!(list.as_slice(), oracle.pixel(p), "{scene}: pixel {p}");
        }
        assert!(TriangleExport::from_bytes(&bytes[..bytes.len() - 1]).is_err());
    }
}

fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

fn stdout_of(cmd: &mut Command, code: i32) -> String {
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

#[test]
fn the_binary_dumps_compares_and_exits_0_only_when_equal() {
    let dir = scratch("binary");
    let dumps = dir.join("dumps");
    stdout_of(
        fragsim()
            .args([
                "render",
                "--scene",
                SCENE,
                "--scheme",
                "mdts,mdts32,abuffer",
            ])
            .args(SIZE)
            .args(["--no-images", "--dump"])
            .arg(&dumps),
        0,
    );
    for scheme in ["mdts", "mdts32", "abuffer"] {
        let out = stdout_of(
            fragsim()
                .args(["compare", "oracle"])
                .arg(dumps.join(scheme))
                .args(["--json", "--no-image"]),
            0,
        );
        assert!(out.contains("\"equal\": true"), "{out}");
    }
    let text = stdout_of(
        fragsim()
            .arg("compare")
            .arg(dumps.join("abuffer"))
            .arg(dumps.join("mdts"))
            .arg("--no-image"),
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
    let text = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .arg("--image")
            .arg(&image),
        1,
    );
    assert!(text.contains("missing 1, extra 1"), "{text}");
    assert!(text.contains("verdict: DIFFERENT"), "{text}");
    assert!(image.exists());
    let json = stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dumps.join("mdts"))
            .args(["--json", "--no-image"]),
        1,
    );
    assert!(json.contains("\"equal\": false") && json.contains("\"first_differences\""));
    // Nothing to compare, or no dump at all: exit 2.
    stdout_of(fragsim().args(["compare", "oracle", "oracle"]), 2);
    stdout_of(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dir.join("absent")),
        2,
    );
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

/// A 2 × 2 MDTS dump header (K = 2) whose `slots` array has this file name and shape (JSON).
fn mdts_header(file: &str, shape: &str) -> String {
    format!(
        r#"{{"format": "fragsim-dump", "version": 1, "scene": {{"name": "quads:2",
            "view_degrees": 30.0, "elevation_degrees": 15.0}}, "width": 2, "height": 2,
            "scheme": "mdts", "k": 2,
            "arrays": {{"slots": {{"file": {file:?}, "dtype": "u64", "shape": {shape}}}}}}}"#
    )
}

/// Parses `header` from memory with a reader that records every file name it is asked for and
/// returns eight empty slots.
fn parse_recording(header: &str) -> (Result<Dump, String>, Vec<String>) {
    let mut asked = Vec::new();
    let parsed = Dump::parse("dump.json", header.as_bytes(), |file| {
        asked.push(file.to_string());
        Ok(vec![0xFF; 8 * 8])
    });
    (parsed.map_err(|e| e.to_string()), asked)
}

#[test]
fn dump_parse_reads_a_dump_from_memory_as_read_does_from_files() {
    let (parsed, asked) = parse_recording(&mdts_header("slots.u64", "[4, 2]"));
    let dump = parsed.unwrap();
    assert_eq!(asked, ["slots.u64"]);
    let capture = dump.capture().unwrap();
    assert_eq!(capture.pixels(), 4);
    assert!(
        (0..4).all(|p| capture.pixel(p).is_empty()),
        "every slot empty"
    );
    let (text, files) = dump.encode().unwrap();
    let dir = scratch("parse-vs-read");
    std::fs::write(dir.join("dump.json"), text).unwrap();
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).unwrap();
    }
    assert_eq!(Dump::read(&dir).unwrap(), dump);
}

#[test]
fn regression_dump_parse_refuses_array_file_names_that_leave_the_dump_directory() {
    for file in [
        "../slots.u64",
        "/etc/passwd",
        "sub/slots.u64",
        "..",
        ".",
        "",
        "C:slots",
        "a\\b",
    ] {
        let header = mdts_header(file, "[4, 2]");
        let (parsed, asked) = parse_recording(&header);
        let error = parsed.expect_err(file);
        assert!(
            error.contains("must be a plain file name"),
            "{file:?}: {error}"
        );
        assert!(
            asked.is_empty(),
            "{file:?}: the reader was asked for {asked:?}"
        );
        let dir = scratch("bad-file-name");
        std::fs::write(dir.join("dump.json"), header).unwrap();
        let error = Dump::read(&dir).unwrap_err().to_string();
        assert!(
            error.contains("must be a plain file name"),
            "{file:?}: {error}"
        );
    }
}

#[test]
fn regression_dump_parse_refuses_a_shape_whose_element_count_overflows() {
    let header = mdts_header("slots.u64", "[4294967296, 4294967296, 2]");
    let (parsed, asked) = parse_recording(&header);
    let error = parsed.unwrap_err();
    assert!(error.contains("more than 2^64 elements"), "{error}");
    assert!(asked.is_empty(), "the reader was asked for {asked:?}");
}
