//! Replays the checked-in fuzz corpus (`fuzz/corpus/<target>/`) through the fuzz targets' own
//! checks (`tests/fuzz_support/`), on stable Rust inside `cargo test`, so CI exercises every
//! target without a nightly toolchain or cargo-fuzz. A proptest adds fresh random inputs.
//! `compare` prints its report for each pair of seeds that decode (it is the command's own code).

#[path = "fuzz_support/mod.rs"]
mod fuzz_support;

use std::path::PathBuf;

use proptest::prelude::*;

/// Every file of `fuzz/corpus/<target>/`, with its name.
fn corpus(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()))
        .map(|entry| {
            let path = entry.expect("a readable directory entry").path();
            let bytes = std::fs::read(&path)
                .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
            (path, bytes)
        })
        .collect();
    files.sort();
    assert!(!files.is_empty(), "the corpus {} is empty", dir.display());
    files
}

/// Runs `check` on every corpus file of `target`, naming the file that fails.
fn replay(target: &str, check: fn(&[u8])) -> usize {
    let files = corpus(target);
    for (path, bytes) in &files {
        if std::panic::catch_unwind(|| check(bytes)).is_err() {
            panic!("{target}: corpus file {} fails its check", path.display());
        }
    }
    files.len()
}

#[test]
fn obj_load_corpus_loads_or_fails_cleanly() {
    replay("obj_load", fuzz_support::obj_load::check);
}

#[test]
fn rasterize_corpus_stays_in_the_viewport_and_matches_the_reference_coverage() {
    replay("rasterize", fuzz_support::raster::check);
}

#[test]
fn schemes_vs_oracle_corpus_equals_the_sorting_oracle() {
    replay("schemes_vs_oracle", fuzz_support::schemes::check);
}

#[test]
fn dump_parse_corpus_parses_round_trips_or_fails_cleanly() {
    replay("dump_parse", fuzz_support::dump::check);
}

#[test]
fn dump_layouts_corpus_decodes_as_the_layout_rules_say_or_fails_naming_the_fault() {
    replay("dump_layouts", fuzz_support::layouts::check);
}

#[test]
fn triangles_corpus_reads_back_its_records_or_fails_cleanly() {
    replay("triangles", fuzz_support::triangles::check);
}

#[test]
fn compare_corpus_keeps_the_exit_codes_meaning() {
    replay("compare", fuzz_support::compare::check);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_pass_every_fuzz_check(data in proptest::collection::vec(any::<u8>(), 0..400)) {
        fuzz_support::obj_load::check(&data);
        fuzz_support::raster::check(&data);
        fuzz_support::schemes::check(&data);
        fuzz_support::dump::check(&data);
        fuzz_support::layouts::check(&data);
        fuzz_support::triangles::check(&data);
        fuzz_support::compare::check(&data);
    }
}
