//! Arbitrary fragment streams through every exact scheme, against a sorting oracle; the checks are in `tests/fuzz_support/schemes.rs`, shared with the corpus replay
//! `tests/fuzz_corpus.rs`.
#![no_main]

#[allow(dead_code, reason = "each target uses one check of the shared support")]
#[path = "../../tests/fuzz_support/mod.rs"]
mod support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| support::schemes::check(data));
