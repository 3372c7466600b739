//! Bad input through the `fragsim` binary: malformed OBJ files and bad command-line
//! values each give a clear error naming the reason and exit with status 2, never a panic. Mesh
//! formats told by content are in `mesh_formats`, flags that do nothing in their context in
//! `context_flags`.

use std::path::PathBuf;
use std::process::Output;

use assert_cmd::Command;

mod context_flags;
mod mesh_formats;

/// A small, fast render of whatever the arguments name (16 × 16 unless they give a size).
fn fragsim(args: &[&str]) -> Output {
    let mut command = Command::cargo_bin("fragsim").unwrap();
    command.arg("--no-images");
    for side in ["--width", "--height"] {
        if !args.iter().any(|a| a.starts_with(side)) {
            command.args([side, "16"]);
        }
    }
    command.args(args).output().unwrap()
}

/// Asserts that `fragsim args` fails with status 2 and an error containing every one of
/// `reasons`, without panicking.
fn assert_refused(args: &[&str], reasons: &[&str]) {
    let output = fragsim(args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
    for reason in reasons {
        assert!(
            stderr.contains(reason),
            "{args:?}: {reason:?} not in {stderr}"
        );
    }
}

/// Writes `contents` to a fresh file in the temporary directory, named after the test.
fn obj_file(name: &str, contents: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fragsim-cli-errors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// Asserts that rendering `contents` as an OBJ file fails naming the file and every reason.
fn assert_obj_refused(name: &str, contents: &str, reasons: &[&str]) {
    let path = obj_file(name, contents.as_bytes());
    let path = path.to_str().unwrap();
    let mut all = vec![path];
    all.extend_from_slice(reasons);
    assert_refused(&["--mesh", path], &all);
}

const TRIANGLE_VERTICES: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\n";

// ---------------------------------------------------------------------------------------------
// Malformed OBJ

#[test]
fn a_missing_mesh_file_is_refused_naming_it() {
    let path = std::env::temp_dir().join("fragsim-cli-errors-no-such-file.obj");
    let path = path.to_str().unwrap();
    assert_refused(&["--mesh", path], &["cannot read mesh file", path]);
}

#[test]
fn an_empty_obj_file_is_refused_as_having_no_triangles() {
    assert_obj_refused("empty.obj", "", &["has no triangles"]);
}

#[test]
fn an_obj_file_without_faces_is_refused_as_having_no_triangles() {
    assert_obj_refused("points.obj", TRIANGLE_VERTICES, &["has no triangles"]);
}

#[test]
fn an_obj_face_beyond_the_last_vertex_is_refused() {
    assert_obj_refused(
        "bad-index.obj",
        &format!("{TRIANGLE_VERTICES}f 1 2 9\n"),
        &["line 4", "vertex 9, but 3 vertices are defined"],
    );
}

#[test]
fn an_obj_face_with_index_zero_is_refused() {
    assert_obj_refused(
        "zero-index.obj",
        &format!("{TRIANGLE_VERTICES}f 0 1 2\n"),
        &["vertex 0"],
    );
}

#[test]
fn an_obj_relative_index_before_the_first_vertex_is_refused() {
    assert_obj_refused(
        "relative.obj",
        &format!("{TRIANGLE_VERTICES}f -1 -2 -4\n"),
        &["vertex -4, but 3 vertices are defined before it"],
    );
    assert_obj_refused(
        "relative-texcoord.obj",
        &format!("{TRIANGLE_VERTICES}vt 0 0\nvt 1 0\nf 1/-11 2/-1 3/-1\n"),
        &["texture coordinate -11"],
    );
}

#[test]
fn non_finite_obj_coordinates_are_refused() {
    for (name, value, shown) in [
        ("nan.obj", "nan", "NaN"),
        ("inf.obj", "inf", "inf"),
        ("overflow.obj", "1e39", "inf"),
    ] {
        assert_obj_refused(
            name,
            &format!("v 0 {value} 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"),
            &["vertex 0 has a non-finite coordinate", shown],
        );
    }
}

#[test]
fn an_unparsable_obj_coordinate_is_refused() {
    assert_obj_refused(
        "letters.obj",
        "v a b c\nv 1 0 0\nv 1 1 0\nf 1 2 3\n",
        &["malformed OBJ", "position parse error"],
    );
}

#[test]
fn an_obj_face_of_two_vertices_is_refused() {
    assert_obj_refused(
        "two-vertices.obj",
        &format!("{TRIANGLE_VERTICES}f 1 2\n"),
        &["line 4: a face needs at least 3 vertices, got 2"],
    );
}

#[test]
fn an_obj_face_referring_to_a_normal_the_file_lacks_is_refused() {
    // A file with no normals at all (0 bytes of them): tobj would drop the reference unchecked.
    assert_obj_refused(
        "no-normals.obj",
        &format!("{TRIANGLE_VERTICES}f 1//5 2//5 3//5\n"),
        &["line 4", "normal 5, but 0 normals are defined"],
    );
    // A file with one normal, referring to the second.
    assert_obj_refused(
        "one-normal.obj",
        &format!("{TRIANGLE_VERTICES}vn 0 0 1\nf 1//1 2//1 3//2\n"),
        &["normal 2, but 1 normals are defined"],
    );
}

#[test]
fn an_obj_normal_without_numbers_is_refused() {
    assert_obj_refused(
        "empty-normal.obj",
        &format!("{TRIANGLE_VERTICES}vn\nf 1//1 2//1 3//1\n"),
        &["normal parse error"],
    );
}

#[test]
fn an_obj_of_binary_garbage_is_refused() {
    let path = obj_file("garbage.obj", &[0xFF, 0xFE, 0x00, 0x80, b'\n', 0xC3, 0x28]);
    let path = path.to_str().unwrap();
    assert_refused(&["--mesh", path], &["malformed OBJ", path]);
}

#[test]
fn non_triangular_obj_faces_are_triangulated_not_refused() {
    // A quad (2 triangles) and a pentagon (3), fanned from their first vertex.
    let path = obj_file(
        "polygons.obj",
        b"v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 1.5 0.5\nf 1 2 3 4\nf 1 2 3 5 4\n",
    );
    let output = fragsim(&["--mesh", path.to_str().unwrap(), "--json"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    for row in crate::support::json_lines(&output.stdout) {
        assert_eq!(row["triangles"], 5, "{stdout}");
        assert_eq!(row["mismatched_pixels"], 0, "{stdout}");
    }
}

// ---------------------------------------------------------------------------------------------
// Bad command-line values

#[test]
fn k_zero_is_refused_with_the_reason() {
    assert_refused(
        &["--scene", "quads:2", "--k", "0"],
        &["--k", "must be at least 1"],
    );
    assert_refused(
        &["--scene", "quads:2", "--capacity", "0"],
        &["--capacity", "must be at least 1"],
    );
}

#[test]
fn negative_and_non_numeric_counts_are_refused_with_the_reason() {
    for args in [["--k", "-3"], ["--capacity", "-1"], ["--k", "many"]] {
        assert_refused(&args, &[args[0], "expected a positive integer"]);
    }
}

#[test]
fn negative_sizes_are_refused_with_the_range() {
    assert_refused(&["--width", "-5"], &["--width", "-5 is not in 1..=16384"]);
    assert_refused(&["--height=-1"], &["--height", "-1 is not in 1..=16384"]);
    assert_refused(&["--width", "0"], &["--width", "0 is not in 1..=16384"]);
    assert_refused(
        &["--height", "16385"],
        &["--height", "16385 is not in 1..=16384"],
    );
}

#[test]
fn a_negative_memory_cap_is_refused_with_the_reason() {
    assert_refused(
        &["--memory-cap", "-1"],
        &["--memory-cap", "cannot be negative, got -1"],
    );
}

#[test]
fn zero_or_negative_threads_are_refused_with_the_range() {
    assert_refused(&["--threads", "0"], &["--threads", "0 is not in 1..=1024"]);
    assert_refused(
        &["--threads", "-2"],
        &["--threads", "-2 is not in 1..=1024"],
    );
}

#[test]
fn an_unknown_scheme_is_refused_listing_the_known_ones() {
    assert_refused(
        &["--scheme", "bogus"],
        &[
            "invalid value 'bogus'",
            "possible values",
            "mdts",
            "abuffer",
        ],
    );
}

#[test]
fn an_unknown_scene_is_refused_listing_the_known_ones() {
    assert_refused(
        &["--scene", "cubes"],
        &["unknown scene \"cubes\"", "spheres", "quads"],
    );
}

#[test]
fn scene_parameters_out_of_range_are_refused_with_the_reason() {
    assert_refused(
        &["--scene", "spheres:0"],
        &["spheres:0", "must be between 1 and 256, got 0"],
    );
    assert_refused(
        &["--scene", "soup:5:-1"],
        &["soup:5:-1", "not a non-negative integer"],
    );
}

#[test]
fn non_finite_camera_angles_are_refused() {
    for (flag, value) in [("--view", "nan"), ("--elevation", "inf")] {
        assert_refused(
            &[flag, value],
            &[flag, "expected a finite number of degrees"],
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Issue 20, item 2: a closed stdout

/// `fragsim args` with its stdout closed before it writes: the exit code must be the one the
/// same command gives when its output is read, and no panic.
fn assert_quiet_on_a_closed_pipe(args: &[&str]) {
    use std::process::Stdio;
    let binary = assert_cmd::cargo::cargo_bin("fragsim");
    let read = std::process::Command::new(&binary)
        .args(args)
        .output()
        .unwrap();
    let mut child = std::process::Command::new(&binary)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Closed before the child's first line: the embedded bunny alone takes it milliseconds.
    drop(child.stdout.take());
    let closed = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&closed.stderr);
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        !read.stdout.is_empty(),
        "{args:?} prints nothing to close on"
    );
    assert_eq!(
        closed.status.code(),
        read.status.code(),
        "{args:?}: {stderr}"
    );
}

#[test]
fn a_closed_stdout_ends_the_output_quietly_keeping_the_exit_code() {
    let size = ["--width", "16", "--height", "16"];
    let mut render = vec!["--scheme", "all", "--no-images"];
    render.extend(size);
    assert_quiet_on_a_closed_pipe(&render);
    let mut json = vec![
        "render",
        "--scheme",
        "mdts,abuffer",
        "--no-images",
        "--json",
    ];
    json.extend(size);
    assert_quiet_on_a_closed_pipe(&json);
    assert_quiet_on_a_closed_pipe(&["explain", "--depths", "0.3,0.5,0.1,0.7"]);
    let dumps = std::env::temp_dir().join(format!("fragsim-cli-pipe-{}", std::process::id()));
    let dumps = dumps.to_str().unwrap();
    let made = fragsim(&["--scene", "quads:3", "--scheme", "mdts", "--dump", dumps]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let dump = format!("{dumps}/mdts");
    assert_quiet_on_a_closed_pipe(&["compare", "oracle", dump.as_str(), "--no-images"]);
}

// ---------------------------------------------------------------------------------------------
// Output paths

#[test]
fn export_scene_into_a_missing_folder_is_refused_and_creates_nothing() {
    let dir = crate::support::scratch("cli-errors", "export-missing-folder");
    let missing = dir.join("no-such-folder");
    let out = missing.join("scene.tri");
    let output = Command::cargo_bin("fragsim")
        .unwrap()
        .args(["export-scene", "--width", "16", "--height", "16", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.starts_with("error: ") && stderr.contains("does not exist"),
        "{stderr}"
    );
    assert!(stderr.contains(&missing.display().to_string()), "{stderr}");
    assert!(!missing.exists(), "the missing folder was created");
}
