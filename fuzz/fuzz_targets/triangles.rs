//! Arbitrary bytes through the FRAGTRI1 triangle export reader; the checks are in `tests/fuzz_support/triangles.rs`, shared with the corpus replay
//! `tests/fuzz_corpus.rs`.
#![no_main]

#[allow(dead_code, reason = "each target uses one check of the shared support")]
#[path = "../../tests/fuzz_support/mod.rs"]
mod support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| support::triangles::check(data));
