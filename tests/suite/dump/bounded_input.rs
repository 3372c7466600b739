//! Input that is not bounded is refused through the binary before it is read or made: a
//! procedural scene a header names is bounded by `--memory-cap` from its name, a link to
//! `/dev/zero` and a FIFO are refused by their kind (never read, never waited on), an array file
//! of another size than its shape is refused from its metadata, and arrays past the cap are
//! refused before any is read. Each test first sees the same dump read and judged, so that it can
//! fail both ways; none allocates more than a few kilobytes.

use std::path::Path;
use std::time::Duration;

use super::binary::{fragsim, stdout_of};
use super::scratch;

/// `fragsim render` of `quads:4` at 64 × 64 with `mdts` at K = 1 (4,096 slots of 8 bytes:
/// 32,768 bytes of arrays), its dump in `out/mdts`.
fn quads_dump(out: &Path) {
    stdout_of(
        fragsim()
            .args([
                "render", "--scene", "quads:4", "--width", "64", "--height", "64",
            ])
            .args(["--scheme", "mdts", "--k", "1", "--executor", "serial"])
            .args(["--no-images", "--quiet", "--dump"])
            .arg(out),
        0,
    );
}

/// `fragsim compare oracle DIR --no-images` with `options`, stopped after 20 s whatever it does
/// (a FIFO waited on would hang the test otherwise).
fn compare(dir: &Path, options: &[&str]) -> assert_cmd::Command {
    let mut command = fragsim();
    command
        .args(["compare", "oracle"])
        .arg(dir)
        .arg("--no-images")
        .args(options)
        .timeout(Duration::from_secs(20));
    command
}

/// Runs `command`, expecting exit 2 and an error of one line that names each of `names`.
pub(super) fn refused(command: &mut assert_cmd::Command, names: &[&str]) -> String {
    let output = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "stderr: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    for name in names {
        assert!(stderr.contains(name), "{name:?} not in {stderr}");
    }
    stderr
}

/// The dump header in `dir` rewritten by `edit`, as JSON.
pub(super) fn edit_header(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join("dump.json");
    let mut header: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut header);
    std::fs::write(&path, header.to_string()).unwrap();
}

/// Names the scene `name` in the dump header in `dir`.
fn name_scene(dir: &Path, name: &str) {
    edit_header(dir, |h| h["scene"]["name"] = name.into());
}

#[test]
fn a_header_naming_a_huge_procedural_scene_is_refused_from_its_name() {
    let out = scratch("bounded-huge-scene");
    quads_dump(&out);
    let dir = out.join("mdts");
    let text = stdout_of(&mut compare(&dir, &[]), 0);
    assert!(text.contains("EQUAL"), "{text}");
    name_scene(&dir, "quads:1000000");
    refused(
        &mut compare(&dir, &[]),
        &["scene quads:1000000", "memory cap", "--memory-cap"],
    );
    name_scene(&dir, "soup:10000000:1");
    refused(
        &mut compare(&dir, &[]),
        &["scene soup:10000000:1", "10000000 triangles", "memory cap"],
    );
    // A cap the arrays fit (32,768 bytes) and the oracle of the small scene does not (24 bytes
    // for each of 4,096 pixels alone): refused by the bound from its triangles.
    name_scene(&dir, "quads:4");
    refused(
        &mut compare(&dir, &["--memory-cap", "50000"]),
        &["scene quads:4", "its oracle", "memory cap of 50000 bytes"],
    );
}

#[cfg(unix)]
#[test]
fn links_to_dev_zero_are_refused_unread_as_array_header_or_mesh() {
    let out = scratch("bounded-dev-zero");
    quads_dump(&out);
    let dir = out.join("mdts");
    let slots = dir.join("slots.u64");
    std::fs::remove_file(&slots).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &slots).unwrap();
    refused(
        &mut compare(&dir, &[]),
        &["slots.u64", "not a regular file but a character device"],
    );
    // The header itself.
    let header = out.join("zero-header");
    std::fs::create_dir_all(&header).unwrap();
    std::os::unix::fs::symlink("/dev/zero", header.join("dump.json")).unwrap();
    refused(
        &mut compare(&header, &[]),
        &["dump.json", "character device"],
    );
    // A mesh the header names, beside the dump.
    let mesh = scratch("bounded-dev-zero-mesh");
    std::fs::write(mesh.join("dump.json"), mesh_header("zero.obj")).unwrap();
    std::fs::write(mesh.join("slots.u64"), [0xFF; 4 * 3 * 8]).unwrap();
    std::os::unix::fs::symlink("/dev/zero", mesh.join("zero.obj")).unwrap();
    refused(&mut compare(&mesh, &[]), &["zero.obj", "character device"]);
    // The control: a regular mesh file there is read and judged (every list empty: DIFFERENT).
    std::fs::remove_file(mesh.join("zero.obj")).unwrap();
    let tetrahedron = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::fs::write(mesh.join("zero.obj"), tetrahedron).unwrap();
    stdout_of(&mut compare(&mesh, &[]), 1);
}

/// The header of an empty `mdts` dump of the mesh `mesh` at 4 × 3, K = 1.
fn mesh_header(mesh: &str) -> String {
    format!(
        r#"{{"format": "fragsim-dump", "version": 1, "scene": {{"mesh": "{mesh}"}},
        "width": 4, "height": 3, "scheme": "mdts", "k": 1,
        "arrays": {{"slots": {{"file": "slots.u64", "dtype": "u64", "shape": [12, 1]}}}}}}"#
    )
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_without_waiting_for_a_writer() {
    let out = scratch("bounded-fifo");
    quads_dump(&out);
    let dir = out.join("mdts");
    let slots = dir.join("slots.u64");
    std::fs::remove_file(&slots).unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(&slots)
        .status()
        .unwrap();
    assert!(made.success(), "mkfifo failed");
    refused(&mut compare(&dir, &[]), &["slots.u64", "a FIFO"]);
}

#[test]
fn an_array_file_of_another_size_than_its_shape_is_refused_from_its_metadata() {
    let out = scratch("bounded-size");
    quads_dump(&out);
    let dir = out.join("mdts");
    let slots = dir.join("slots.u64");
    let mut bytes = std::fs::read(&slots).unwrap();
    let size = bytes.len();
    bytes.extend([0xFF; 8]);
    std::fs::write(&slots, &bytes).unwrap();
    refused(
        &mut compare(&dir, &[]),
        &[
            "slots.u64",
            &format!("{} bytes, more than the {size} bytes", size + 8),
        ],
    );
    // Short by a word: read (it is within the bound) and named by its shape.
    bytes.truncate(size - 8);
    std::fs::write(&slots, &bytes).unwrap();
    refused(&mut compare(&dir, &[]), &["\"slots\"", "shape [4096, 1]"]);
}

#[test]
fn arrays_past_the_memory_cap_are_refused_before_any_is_read() {
    let out = scratch("bounded-cap");
    quads_dump(&out);
    let dir = out.join("mdts");
    // 4,096 pixels × 1 slot × 8 bytes = 32,768 bytes of slots.
    refused(
        &mut compare(&dir, &["--memory-cap", "32767"]),
        &["32768 bytes", "memory cap of 32767 bytes"],
    );
    // A shape past the cap with no file behind it: refused before the file is looked for.
    edit_header(&dir, |h| {
        h["k"] = 4_000_000_000_u32.into();
        h["arrays"]["slots"]["shape"] = serde_json::json!([4096, 4_000_000_000_u32]);
    });
    std::fs::remove_file(dir.join("slots.u64")).unwrap();
    refused(&mut compare(&dir, &[]), &["memory cap"]);
}
