//! Two arbitrary dumps through `fragsim compare`; the checks are in `tests/fuzz_support/compare.rs`, shared with the corpus replay
//! `tests/fuzz_corpus.rs`.
#![no_main]

#[allow(dead_code, reason = "each target uses one check of the shared support")]
#[path = "../../tests/fuzz_support/mod.rs"]
mod support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| support::compare::check(data));
