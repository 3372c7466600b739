//! Headers that say two things, or a thing their layout cannot mean, are refused by name through
//! the binary (exit 2, one line naming the field) instead of one of the two silently winning:
//! arrays the layout does not use, `capacity` beside `offsets`, a scene with both `name` and
//! `mesh`, `--mesh` on a named scene unless `--mesh-replaces-scene` says so, a shape that fits
//! only transposed, list numbering out of range. A UTF-8 byte-order mark is read past, and a
//! dump's mesh is looked up beside the dump before the working directory. Each test first sees
//! the unedited dump judged EQUAL, so that it can fail both ways.

use std::path::Path;

use serde_json::json;

use super::binary::{fragsim, render_dump, stdout_of};
use super::bounded_input::{edit_header, refused};
use super::scratch;

/// `fragsim compare oracle DIR --no-images` with `options`.
fn compare(dir: &Path, options: &[&str]) -> assert_cmd::Command {
    let mut command = fragsim();
    command
        .args(["compare", "oracle"])
        .arg(dir)
        .arg("--no-images")
        .args(options);
    command
}

/// Checks that the dump in `dir` is EQUAL to the oracle.
fn equal(dir: &Path) {
    let text = stdout_of(&mut compare(dir, &[]), 0);
    assert!(text.contains("EQUAL"), "{text}");
}

/// A dump of the test scene by `scheme` with render's `options`, checked EQUAL: its directory.
fn dumped(name: &str, scheme: &str, options: &[&str]) -> std::path::PathBuf {
    let out = scratch(name);
    render_dump(&out, scheme, options);
    let dir = out.join(scheme);
    equal(&dir);
    dir
}

#[test]
fn arrays_the_layout_does_not_use_are_refused_by_name() {
    let dir = dumped("lies-unused", "mdts", &[]);
    std::fs::write(dir.join("junk.u32"), [0; 4]).unwrap();
    edit_header(&dir, |h| {
        h["arrays"]["junk"] = json!({"file": "junk.u32", "dtype": "u32", "shape": [1]});
    });
    refused(
        &mut compare(&dir, &[]),
        &["array \"junk\"", "mdts dump has no such array"],
    );
    edit_header(&dir, |h| {
        let junk = h["arrays"]["junk"].take();
        h["arrays"]["heads"] = junk;
        h["arrays"].as_object_mut().unwrap().remove("junk");
    });
    refused(
        &mut compare(&dir, &[]),
        &["array \"heads\"", "its arrays: slots"],
    );
}

#[test]
fn capacity_beside_offsets_is_refused_by_name() {
    // `abuffer-exact` storage: offsets, no capacity. Add one.
    let exact = dumped("lies-capacity-offsets", "abuffer-exact", &[]);
    let text = std::fs::read_to_string(exact.join("dump.json")).unwrap();
    assert!(
        text.contains("offsets") && !text.contains("capacity"),
        "{text}"
    );
    edit_header(&exact, |h| h["capacity"] = 3.into());
    refused(
        &mut compare(&exact, &[]),
        &["\"capacity\" 3", "\"offsets\"", "not both"],
    );
}

#[test]
fn a_scene_with_both_a_name_and_a_mesh_is_refused_by_name() {
    let dir = dumped("lies-name-mesh", "mdts", &[]);
    edit_header(&dir, |h| h["scene"]["mesh"] = "bunny.obj".into());
    refused(
        &mut compare(&dir, &[]),
        &["both \"name\"", "\"mesh\" \"bunny.obj\""],
    );
}

#[test]
fn mesh_on_a_named_scene_dump_is_refused_unless_it_replaces_the_scene() {
    let dir = dumped("lies-mesh-flag", "mdts", &[]);
    let mesh = dir.parent().unwrap().join("tetra.obj");
    std::fs::write(
        &mesh,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let mesh = mesh.to_str().unwrap();
    refused(
        &mut compare(&dir, &["--mesh", mesh]),
        &[
            "--mesh",
            "named scene \"spheres:3\"",
            "--mesh-replaces-scene",
        ],
    );
    // Said: the file replaces the spheres, whose lists it does not have.
    stdout_of(
        &mut compare(&dir, &["--mesh", mesh, "--mesh-replaces-scene"]),
        1,
    );
}

#[test]
fn a_shape_that_fits_only_transposed_is_named_so() {
    let dir = dumped("lies-transposed", "mdts", &["--dump-order", "slot-major"]);
    let shape = |at: &Path| -> serde_json::Value {
        let text = std::fs::read_to_string(at.join("dump.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()["arrays"]["slots"]["shape"]
            .clone()
    };
    let [k, pixels] = [0, 1].map(|i| shape(&dir)[i].as_u64().unwrap());
    assert_eq!(pixels, 48 * 36, "slot-major: [k, pixels]");
    // The layout lost: slot-major words under a pixel-major reading.
    edit_header(&dir, |h| {
        h.as_object_mut().unwrap().remove("layout");
    });
    refused(
        &mut compare(&dir, &[]),
        &[
            &format!("shape [{k}, {pixels}] looks transposed"),
            "did you mean layout slot-major?",
        ],
    );
    // Declared slot-major over a pixel-major shape: the other hint.
    let pixel_major = dumped("lies-transposed-pixel-major", "mdts", &[]);
    edit_header(&pixel_major, |h| {
        h["layout"] = json!({"kind": "slots", "order": "slot-major"});
    });
    refused(
        &mut compare(&pixel_major, &[]),
        &["looks transposed", "did you mean layout pixel-major?"],
    );
}

#[test]
fn list_numbering_out_of_range_is_refused_by_name() {
    let dir = dumped(
        "lies-numbering",
        "linked-list-nearest",
        &[
            "--capacity",
            "auto",
            "--dump-list-numbering",
            "4294967295:0",
        ],
    );
    // The fuzzer's crash: `null` 0 with nodes numbered from 0 ends a list at node 0, and the
    // dump compared with itself was DIFFERENT.
    edit_header(&dir, |h| h["layout"]["null"] = 0.into());
    refused(
        &mut compare(&dir, &[]),
        &["\"null\" 0 is the number of a node", "\"node_base\" 0"],
    );
    edit_header(&dir, |h| {
        h["layout"]["null"] = 0.into();
        h["layout"]["node_base"] = u32::MAX.into();
    });
    refused(
        &mut compare(&dir, &[]),
        &["\"node_base\" 4294967295 pass 2^32"],
    );
}

#[test]
fn a_utf8_byte_order_mark_is_read_past() {
    let dir = dumped("lies-bom", "mdts", &[]);
    let path = dir.join("dump.json");
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend(std::fs::read(&path).unwrap());
    std::fs::write(&path, bytes).unwrap();
    equal(&dir);
}

#[test]
fn a_dumps_mesh_is_looked_up_beside_it_before_the_working_directory() {
    const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    let dir = scratch("lies-mesh-beside");
    std::fs::write(dir.join("tetra.obj"), TETRA).unwrap();
    let out = dir.join("dumps");
    stdout_of(
        fragsim()
            .current_dir(&dir)
            .args(["render", "--mesh", "tetra.obj", "--scheme", "mdts"])
            .args(["--width", "24", "--height", "16", "--no-images", "--dump"])
            .arg(&out),
        0,
    );
    let dump = out.join("mdts");
    // The dump travels with its mesh beside it; the header names it by a relative path, without
    // a hash, and the working directory holds another file of that name.
    std::fs::rename(dir.join("tetra.obj"), dump.join("tetra.obj")).unwrap();
    edit_header(&dump, |h| {
        h["scene"].as_object_mut().unwrap().remove("mesh_hash");
    });
    std::fs::write(dir.join("tetra.obj"), TETRA.replace("v 0 0 1", "v 0 0 3")).unwrap();
    let text = stdout_of(
        fragsim()
            .current_dir(&dir)
            .args(["compare", "oracle"])
            .arg(&dump)
            .arg("--no-images"),
        0,
    );
    assert!(text.contains("EQUAL"), "{text}");
    // The control: without the file beside it, the working directory's other mesh is DIFFERENT.
    std::fs::remove_file(dump.join("tetra.obj")).unwrap();
    stdout_of(
        fragsim()
            .current_dir(&dir)
            .args(["compare", "oracle"])
            .arg(&dump)
            .arg("--no-images"),
        1,
    );
}
