//! Meshes told by content, not by name: the gzipped bunny and PLY load
//! whatever the file is called, and errors name the format, the file and the line.

use super::{assert_obj_refused, assert_refused, fragsim, obj_file, TRIANGLE_VERTICES};

/// `data` gzipped as one stored (uncompressed) deflate block: gzip without a compressor.
fn gzip_stored(data: &[u8]) -> Vec<u8> {
    let crc = !data.iter().fold(!0_u32, |crc, &byte| {
        (0..8).fold(crc ^ u32::from(byte), |c, _| {
            (c >> 1) ^ (0xEDB8_8320 & (c & 1).wrapping_neg())
        })
    });
    let len = u16::try_from(data.len()).expect("one stored block holds 65535 bytes");
    let mut out = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255, 1];
    out.extend(len.to_le_bytes());
    out.extend((!len).to_le_bytes());
    out.extend(data);
    out.extend(crc.to_le_bytes());
    out.extend(
        u32::try_from(data.len())
            .expect("a test file of a few bytes")
            .to_le_bytes(),
    );
    out
}

const QUAD_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
    property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
    end_header\n-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n4 0 1 2 3\n";

/// Renders `path` as a mesh, expecting success and `triangles` triangles.
fn assert_loads(path: &std::path::Path, triangles: u32) {
    let output = fragsim(&["--mesh", path.to_str().unwrap(), "--json"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{}: {stderr}", path.display());
    let rows = crate::support::json_lines(&output.stdout);
    assert!(!rows.is_empty(), "{}: no record", path.display());
    for row in rows {
        assert_eq!(row["triangles"], triangles, "{row}");
    }
}

#[test]
fn the_embedded_gzipped_bunny_loads_from_a_file_whatever_its_name() {
    let gz = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/raster/assets/stanford-bunny.obj.gz"
    ))
    .unwrap();
    for name in ["stanford-bunny.obj.gz", "bunny.obj", "bunny"] {
        assert_loads(&obj_file(name, &gz), 69_451);
    }
}

#[test]
fn ply_is_told_by_content_gzipped_or_not() {
    assert_loads(&obj_file("quad-ply.txt", QUAD_PLY.as_bytes()), 2);
    let gz = gzip_stored(QUAD_PLY.as_bytes());
    assert_loads(&obj_file("quad.ply.gz", &gz), 2);
    assert_loads(&obj_file("quad.ply", &gz), 2);
}

#[test]
fn ply_errors_name_ply_not_obj() {
    let broken = QUAD_PLY.replace("format ascii 1.0", "format zip 9");
    let path = obj_file("broken.ply", broken.as_bytes());
    let path = path.to_str().unwrap();
    let output = fragsim(&["--mesh", path]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("OBJ"), "{stderr}");
    assert_refused(&["--mesh", path], &["malformed PLY", path, "header"]);
    let faceless = QUAD_PLY
        .replace("element face 1", "element face 0")
        .replace("4 0 1 2 3\n", "");
    let faceless_path = obj_file("faceless.ply", faceless.as_bytes());
    let faceless_path = faceless_path.to_str().unwrap();
    assert_refused(
        &["--mesh", faceless_path],
        &[&format!("PLY {faceless_path} has no triangles")],
    );
}

#[test]
fn utf16_and_binary_files_are_refused_saying_what_they_are_not() {
    let text = format!("{TRIANGLE_VERTICES}f 1 2 3\n");
    let mut utf16 = vec![0xFF, 0xFE];
    utf16.extend(text.encode_utf16().flat_map(u16::to_le_bytes));
    let path = obj_file("utf16.obj", &utf16);
    let path = path.to_str().unwrap();
    assert_refused(&["--mesh", path], &[path, "not OBJ text", "UTF-16"]);
    let no_bom: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
    let no_bom_path = obj_file("utf16-no-bom.obj", &no_bom);
    let no_bom_path = no_bom_path.to_str().unwrap();
    assert_refused(
        &["--mesh", no_bom_path],
        &[no_bom_path, "not OBJ text", "UTF-16"],
    );
    let binary_path = obj_file("binary.obj", &[b'v', b' ', 0x00, 0x01, 0x9F, 0x80, b'\n']);
    let binary_path = binary_path.to_str().unwrap();
    assert_refused(
        &["--mesh", binary_path],
        &[binary_path, "not OBJ text", "binary data", "offset 2"],
    );
}

#[test]
fn obj_errors_name_the_format_and_the_line() {
    assert_obj_refused(
        "letters-line.obj",
        &format!("{TRIANGLE_VERTICES}v 1 x 0\nf 1 2 3\n"),
        &["malformed OBJ", "line 4", "position parse error", "\"x\""],
    );
    assert_obj_refused(
        "empty-format.obj",
        TRIANGLE_VERTICES,
        &["OBJ ", "has no triangles"],
    );
}

#[test]
fn a_scene_entirely_outside_the_view_warns_and_exits_0() {
    let path = obj_file(
        "far-outlier.obj",
        format!("{TRIANGLE_VERTICES}v 1e38 0 0\nf 1 2 3\nf 1 2 4\n").as_bytes(),
    );
    let output = fragsim(&["--mesh", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("warning: "), "{stderr}");
    assert!(stderr.contains("covers a pixel"), "{stderr}");
    // A visible scene gets no such warning.
    let quads_output = fragsim(&["--scene", "quads:2"]);
    assert!(!String::from_utf8_lossy(&quads_output.stderr).contains("warning"));
}
