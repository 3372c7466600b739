//! The `triangles` target: arbitrary bytes through the `FRAGTRI1` triangle export reader
//! ([`TriangleExport::from_bytes`], `docs/dump-format.md`), never a panic. Checked: a refused
//! file gets an error that says what is wrong with it; an accepted file has exactly the header,
//! the scene's JSON and one 56-byte record per triangle it declares, and writing back what was
//! read gives the same records (less the pad word, written 0) and reads back the same, or the
//! writer refuses a scene number it cannot encode.

use fragsim::dump::triangles::{TriangleExport, TRIANGLE_RECORD_BYTES};

/// Bytes of the fixed header before the scene's JSON.
const HEADER_BYTES: usize = 40;
/// Where the pad word lies in a record (after the prim id and six coordinates).
const PAD: std::ops::Range<usize> = 28..32;

fn u32_at(bytes: &[u8], at: usize) -> usize {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes")) as usize
}

/// Reads `data` as a triangle export and checks the outcome.
pub(crate) fn check(data: &[u8]) {
    let export = match TriangleExport::from_bytes(data) {
        Ok(export) => export,
        Err(error) => {
            let message = error.to_string();
            assert!(
                ["triangle export", "magic", "subpixel bits", "record size"]
                    .iter()
                    .any(|what| message.contains(what)),
                "the error does not say what is wrong: {message}"
            );
            return;
        }
    };
    let count = u32_at(data, 28);
    let start = HEADER_BYTES + u32_at(data, 32).next_multiple_of(8);
    assert_eq!(export.triangles.len(), count, "the declared triangle count");
    assert_eq!(
        data.len(),
        start + count * TRIANGLE_RECORD_BYTES,
        "an accepted file holds exactly its declared records"
    );
    let bytes = match export.to_bytes() {
        Ok(bytes) => bytes,
        Err(error) => {
            assert!(
                export.scene.check_finite().is_err(),
                "the writer refused a finite scene: {error}"
            );
            return;
        }
    };
    // The scene's JSON may be written otherwise (spacing, field order); the records not.
    let written = &bytes[bytes.len() - count * TRIANGLE_RECORD_BYTES..];
    for (i, (read, wrote)) in data[start..]
        .chunks_exact(TRIANGLE_RECORD_BYTES)
        .zip(written.chunks_exact(TRIANGLE_RECORD_BYTES))
        .enumerate()
    {
        let mut expected = read.to_vec();
        expected[PAD].fill(0);
        assert_eq!(
            wrote,
            &expected[..],
            "record {i} changed through the reader"
        );
    }
    let again = TriangleExport::from_bytes(&bytes).expect("a written export reads back");
    assert_eq!(
        again.to_bytes().expect("it was written once"),
        bytes,
        "a written export reads back otherwise"
    );
}
