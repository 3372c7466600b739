//! Where the f32 verdict judges instead of excusing or refusing, through the binary: a matrix
//! whose f32 products leave f32's normal range is refused by name whatever precision it is
//! declared in (exit 2, one line), and exact duplicate triangles (the same vertex indices, so the
//! same depth in any implementation) at the K cut are judged by their primitive ids under
//! `--vertex-precision f32` as exactly (`docs/semantics.md` §10).

use std::path::{Path, PathBuf};

use crate::support::prim_of;
use assert_cmd::Command;
use serde_json::Value;

fn fragsim() -> Command {
    Command::cargo_bin("fragsim").unwrap()
}

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("f32-verdict", name)
}

/// Runs `cmd`, checks its exit code, returns stdout and stderr.
fn run(cmd: &mut Command, code: i32) -> (String, String) {
    let output = cmd.output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    );
    assert_eq!(
        output.status.code(),
        Some(code),
        "stdout {out}\nstderr {err}"
    );
    (out, err)
}

/// `fragsim render` of `scene` (`--scene NAME` or `--mesh PATH`) with MDTS at K = `k`, dumped
/// into `dir`; the dump's directory.
fn render(dir: &Path, scene: &[&str], k: &str) -> PathBuf {
    run(
        fragsim()
            .arg("render")
            .args(scene)
            .args(["--width", "32", "--height", "24", "--scheme", "mdts"])
            .args(["--k", k, "--no-images", "--dump"])
            .arg(dir),
        0,
    );
    dir.join("mdts")
}

/// The dump's header, to edit.
fn header(dump: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dump.join("dump.json")).unwrap()).unwrap()
}

fn write_header(dump: &Path, header: &Value) {
    std::fs::write(dump.join("dump.json"), header.to_string()).unwrap();
}

/// `fragsim compare oracle DUMP` with `args`.
fn compare(dump: &Path, args: &[&str], code: i32) -> (String, String) {
    run(
        fragsim()
            .args(["compare", "oracle"])
            .arg(dump)
            .args(args)
            .arg("--no-images"),
        code,
    )
}

/// A perspective matrix (depth in [0, 1]) looking down −z from 3 units away, row by row.
const MATRIX: [f64; 16] = [
    1.5, 0.0, 0.0, 0.0, //
    0.0, 2.0, 0.0, 0.0, //
    0.0, 0.0, -1.0, 2.9, //
    0.0, 0.0, -1.0, 3.0,
];

#[test]
fn matrix_entries_whose_f32_products_leave_the_normal_range_are_refused_by_name() {
    let dump = render(&scratch("range"), &["--scene", "spheres:2"], "4");
    let original = header(&dump);
    // The unscaled matrix judges: the control.
    let with_matrix = |scale: f64, precision: &str, stage: &str| {
        let mut h = original.clone();
        h["scene"]["view_projection"] = serde_json::json!({
            "row_major": MATRIX.map(|e| e * scale),
            "precision": precision,
        });
        h["scene"]["conventions"]["vertex_precision"] = stage.into();
        h
    };
    write_header(&dump, &with_matrix(1.0, "f64", "f32"));
    let (out, _) = compare(&dump, &["--vertex-precision", "f32"], 1);
    assert!(out.contains("verdict: DIFFERENT"), "{out}");
    for scale in [1e-39, 1e-300] {
        for precision in ["f64", "f32"] {
            write_header(&dump, &with_matrix(scale, precision, "f32"));
            for args in [&["--vertex-precision", "f32"][..], &[]] {
                let (_, err) = compare(&dump, args, 2);
                let lines: Vec<&str> = err.lines().filter(|l| !l.is_empty()).collect();
                assert_eq!(
                    lines.len(),
                    1,
                    "scale {scale}, {precision}, {args:?}: {err}"
                );
                assert!(
                    lines[0].contains("view_projection.row_major[")
                        && lines[0].contains("normal range"),
                    "{err}"
                );
            }
        }
    }
}

/// A unit square at depth 0 drawn twice from the same four vertices: primitives 0–1 and their
/// twins 2–3.
const TWICE: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
f 1 2 3\nf 1 3 4\nf 1 2 3\nf 1 3 4\n";

#[test]
fn keeping_the_later_of_two_exact_duplicates_at_the_k_cut_is_different_under_f32() {
    let dir = scratch("twins");
    let mesh = dir.join("twice.obj");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(&mesh, TWICE).unwrap();
    let dump = render(&dir, &["--mesh", mesh.to_str().unwrap()], "1");
    // The control: the dump as MDTS stored it (the earlier twin at every pixel) is equal.
    for args in [&["--vertex-precision", "f32"][..], &[]] {
        let (out, _) = compare(&dump, args, 0);
        assert!(out.contains("verdict: EQUAL"), "{out}");
    }
    let slots = dump.join("slots.u64");
    let mut bytes = std::fs::read(&slots).unwrap();
    let mut moved = 0;
    for word in bytes.chunks_mut(8) {
        let w = u64::from_le_bytes(word.try_into().unwrap());
        if w != u64::MAX {
            assert!(prim_of(w) < 2, "the earlier twin is kept");
            word.copy_from_slice(&(w + 2).to_le_bytes());
            moved += 1;
        }
    }
    assert!(moved > 0);
    std::fs::write(&slots, bytes).unwrap();
    for args in [&["--vertex-precision", "f32"][..], &[]] {
        let (out, _) = compare(&dump, args, 1);
        assert!(out.contains("verdict: DIFFERENT"), "{args:?}: {out}");
    }
}
