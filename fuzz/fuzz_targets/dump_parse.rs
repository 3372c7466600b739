//! Arbitrary bytes as a dump (header and array files) through `Dump::parse`, `Dump::capture` and
//! `compare`; the checks are in `tests/fuzz_support/dump.rs`, shared with the corpus replay
//! `tests/fuzz_corpus.rs`.
#![no_main]

#[allow(dead_code, reason = "each target uses one check of the shared support")]
#[path = "../../tests/fuzz_support/mod.rs"]
mod support;

libfuzzer_sys::fuzz_target!(|data: &[u8]| support::dump::check(data));
