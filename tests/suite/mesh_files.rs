//! Mesh files as users bring them, through the `fragsim` binary: PLY triangle strips
//! (`tristrips`, `-1` restarting a strip, as the common test-model collections store their
//! scans) load, ASCII or binary, into the triangles of the same mesh written as faces; a truncated
//! binary PLY is refused on one line that names no line number (a binary file has no lines); and
//! `--up z` stands a z-up model on the orbit's axis, dumps included.

use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::Command;

/// A fresh directory of this module's group (`crate::support::scratch`).
fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("mesh-files", name)
}

fn fragsim(args: &[&str], mesh: &Path) -> Output {
    Command::cargo_bin("fragsim")
        .unwrap()
        .args([
            "render",
            "--no-images",
            "--width",
            "40",
            "--height",
            "30",
            "--mesh",
        ])
        .arg(mesh)
        .args(args)
        .output()
        .unwrap()
}

/// `render --json` of `mesh` (with `args`): its first record, after checking that it succeeded.
fn record(mesh: &Path, args: &[&str]) -> serde_json::Value {
    let output = fragsim(&[&["--json", "--scheme", "mdts"], args].concat(), mesh);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    crate::support::json_lines(&output.stdout).remove(0)
}

/// Two strips in two planes: the first a band of 4 triangles, the second of 2 plus a degenerate
/// stitch (a repeated vertex), which covers nothing and is left out.
const POSITIONS: [[f32; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [2.0, 0.0, 0.0],
    [2.0, 1.0, 0.0],
    [0.5, -0.5, 0.5],
    [0.5, 1.5, 0.5],
    [1.5, -0.5, 0.5],
    [1.5, 1.5, 0.5],
];
const STRIPS: [i32; 12] = [0, 1, 2, 3, 4, 5, -1, 6, 7, 8, 9, 9];
/// The strips' triangles, each strip's odd ones turned to keep its winding.
const TRIANGLES: [[i32; 3]; 6] = [
    [0, 1, 2],
    [2, 1, 3],
    [2, 3, 4],
    [4, 3, 5],
    [6, 7, 8],
    [8, 7, 9],
];

fn header(format: &str, element: &str, count: usize, list: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement {element} {count}\nproperty list {list} vertex_indices\n\
         end_header\n",
        POSITIONS.len()
    )
}

fn binary_strips() -> Vec<u8> {
    let mut bytes = header("binary_little_endian", "tristrips", 1, "int int").into_bytes();
    for v in POSITIONS.iter().flatten() {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes.extend_from_slice(
        &i32::try_from(STRIPS.len())
            .expect("a few strips")
            .to_le_bytes(),
    );
    for i in STRIPS {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes
}

fn ascii_vertices() -> String {
    POSITIONS
        .iter()
        .map(|[x, y, z]| format!("{x} {y} {z}\n"))
        .collect()
}

#[test]
fn ply_triangle_strips_load_ascii_or_binary_as_their_faces() {
    let dir = scratch("strips");
    let binary = dir.join("strips-binary.ply");
    std::fs::write(&binary, binary_strips()).unwrap();
    let ascii = dir.join("strips-ascii.ply");
    let strip: Vec<String> = STRIPS.iter().map(i32::to_string).collect();
    std::fs::write(
        &ascii,
        format!(
            "{}{}{} {}\n",
            header("ascii", "tristrips", 1, "int int"),
            ascii_vertices(),
            STRIPS.len(),
            strip.join(" ")
        ),
    )
    .unwrap();
    let faces = dir.join("faces.ply");
    let triangles: String = TRIANGLES
        .iter()
        .map(|[a, b, c]| format!("3 {a} {b} {c}\n"))
        .collect();
    std::fs::write(
        &faces,
        format!(
            "{}{}{triangles}",
            header("ascii", "face", TRIANGLES.len(), "uchar int"),
            ascii_vertices()
        ),
    )
    .unwrap();
    let expected = record(&faces, &[]);
    assert_eq!(expected["triangles"], TRIANGLES.len());
    assert!(expected["fragments"].as_u64().unwrap() > 100, "{expected}");
    for strips in [&binary, &ascii] {
        let got = record(strips, &[]);
        for field in ["triangles", "fragments", "max_depth_complexity", "captured"] {
            assert_eq!(
                got[field],
                expected[field],
                "{field} of {}",
                strips.display()
            );
        }
    }
}

#[test]
fn a_truncated_binary_ply_is_refused_on_one_line_without_a_line_number() {
    let dir = scratch("truncated");
    let whole = binary_strips();
    for cut in [
        whole.len() - 3,
        whole.len() - 4 * STRIPS.len(),
        whole.len() - 60,
    ] {
        let path = dir.join(format!("cut-{cut}.ply"));
        std::fs::write(&path, &whole[..cut]).unwrap();
        let output = fragsim(&[], &path);
        let stderr = String::from_utf8(output.stderr).unwrap();
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            !stderr.contains('\t') && !stderr.contains("Line"),
            "{stderr}"
        );
        assert!(
            stderr.contains(path.to_str().unwrap()) && stderr.contains("truncated"),
            "{stderr}"
        );
    }
}

/// The 12 triangles of the box `lo`–`hi`, as OBJ lines (vertices numbered from `base` + 1).
fn obj_box(lo: [f64; 3], hi: [f64; 3], base: usize, turn: fn([f64; 3]) -> [f64; 3]) -> String {
    let mut text = String::new();
    for corner in 0..8 {
        let pick = |axis: usize| {
            if corner >> axis & 1 == 0 {
                lo[axis]
            } else {
                hi[axis]
            }
        };
        let [x, y, z] = turn([pick(0), pick(1), pick(2)]);
        text += &format!("v {x} {y} {z}\n");
    }
    for [a, b, c, d] in [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ] {
        text += &format!(
            "f {} {} {}\nf {} {} {}\n",
            base + a + 1,
            base + b + 1,
            base + c + 1,
            base + a + 1,
            base + c + 1,
            base + d + 1
        );
    }
    text
}

/// A tower with an arm: upright along `y` as written by `turn` = identity.
fn tower(turn: fn([f64; 3]) -> [f64; 3]) -> String {
    obj_box([0.0, 0.0, 0.0], [1.0, 4.0, 1.0], 0, turn)
        + &obj_box([1.0, 3.0, 0.0], [2.5, 3.5, 1.0], 8, turn)
}

#[test]
fn up_z_stands_a_z_up_model_as_its_y_up_twin() {
    let dir = scratch("up");
    let y_up = dir.join("tower-y.obj");
    std::fs::write(&y_up, tower(|p| p)).unwrap();
    // The same tower modelled z up: file (x, −z, y) for the y-up (x, y, z).
    let z_up = dir.join("tower-z.obj");
    std::fs::write(&z_up, tower(|[x, y, z]| [x, -z, y])).unwrap();
    let upright = record(&y_up, &[]);
    let stood = record(&z_up, &["--up", "z"]);
    let lying = record(&z_up, &[]);
    for field in ["fragments", "max_depth_complexity", "captured"] {
        assert_eq!(stood[field], upright[field], "{field}");
    }
    assert_ne!(
        lying["fragments"], upright["fragments"],
        "the z-up file lies otherwise"
    );
    // A dump of the stood model records the turned camera, so compare rebuilds the same oracle.
    let dumps = dir.join("dumps");
    let output = fragsim(
        &[
            "--up",
            "z",
            "--scheme",
            "mdts",
            "--dump",
            dumps.to_str().unwrap(),
        ],
        &z_up,
    );
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let compare = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["compare", "oracle"])
        .arg(dumps.join("mdts"))
        .arg("--no-images")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&compare.stdout);
    assert!(compare.status.success() && text.contains("EQUAL"), "{text}");
    // A bad axis is refused, naming the ones accepted.
    let w_up = fragsim(&["--up", "w"], &z_up);
    let stderr = String::from_utf8(w_up.stderr).unwrap();
    assert_eq!(w_up.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("x, y, z, -x, -y or -z"), "{stderr}");
}
