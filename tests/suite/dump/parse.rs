//! `dump_parse` reads a dump from memory as `read` does from files, and the regressions the
//! `dump_parse` fuzz target found.

use fragsim::dump::Dump;

use super::{mdts_header, parse_recording, scratch};

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
        let read_error = Dump::read(&dir).unwrap_err().to_string();
        assert!(
            read_error.contains("must be a plain file name"),
            "{file:?}: {read_error}"
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

#[test]
fn regression_dump_parse_refuses_two_arrays_naming_the_same_file() {
    // `dump_parse` found it (seed `regression-two-arrays-one-file`): an A-buffer whose
    // `offsets` and `slots` both named `slots.u64` parsed, then encoded one array's words under
    // both names and failed to parse back.
    let header = r#"{"format": "fragsim-dump", "version": 1, "scene": {"name": "quads:2",
        "view_degrees": 30.0, "elevation_degrees": 15.0}, "width": 2, "height": 2,
        "scheme": "abuffer", "arrays": {
        "counters": {"file": "counters.u32", "dtype": "u32", "shape": [4]},
        "offsets": {"file": "slots.u64", "dtype": "u32", "shape": [5]},
        "slots": {"file": "slots.u64", "dtype": "u64", "shape": [4]}}}"#;
    let (parsed, asked) = parse_recording(header);
    let error = parsed.unwrap_err();
    assert!(
        error.contains(r#"arrays "offsets" and "slots" both name file "slots.u64""#),
        "{error}"
    );
    assert!(asked.is_empty(), "the reader was asked for {asked:?}");
}
