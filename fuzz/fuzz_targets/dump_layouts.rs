//! Dumps built field by field (slot arrays slot-major or pixel-major with any payload, linked lists, layer-major layers, scheme memory; the header's scene fields) through encoding, parsing, decoding, the word rules and the comparison; the checks are in `tests/fuzz_support/layouts.rs`, shared with the corpus replay
//! `tests/fuzz_corpus.rs`.
#![no_main]

#[allow(dead_code, reason = "each target uses one check of the shared support")]
#[path = "../../tests/fuzz_support/mod.rs"]
mod support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| support::layouts::check(data));
