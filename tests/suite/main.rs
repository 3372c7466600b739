//! fragsim's integration tests in one binary. Each module is one suite, with its own module docs
//! saying what it checks; one binary means `cargo test` compiles and links the whole of fragsim
//! into a test executable once, not once per suite. Run one suite by its module path:
//! `cargo test --release --test suite bucket::`.
//!
//! Two suites are binaries of their own: the loom models (`tests/loom/`), the longest tests,
//! compile beside this one on another core and can be run alone (`--test loom`); and the fuzz
//! corpus replay (`tests/fuzz_corpus.rs`), which shares `tests/fuzz_support/` with the cargo-fuzz
//! targets by path.
//!
//! proptest keeps the failing seeds of this binary where its default rule puts them for a crate
//! rooted at `tests/suite/main.rs`: `tests/proptest-regressions/<file under suite/>.txt` (the
//! path with `.rs` made `.txt`), replayed before any new case.

mod support;

mod approximate;
mod bucket;
mod cli_errors;
mod conform;
mod conventions;
mod default_scene;
mod dump;
mod effects;
mod explain;
mod extremes;
mod flag_dialect;
mod frame_loop;
mod honest_reports;
mod injected_fault;
mod interlock_ordered;
mod json_lines;
mod kbuffer;
mod locks;
mod loop64;
mod mdts_packed;
mod mesh_files;
mod meshes;
mod multisampling;
mod new_scheme;
mod order_independence;
mod peeling;
mod pictures;
mod precision;
mod precision_cli;
mod progress;
mod properties;
mod readme;
mod reports;
mod scheduled;
mod shards;
mod shipping;
