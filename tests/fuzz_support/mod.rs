//! Checks shared by the cargo-fuzz targets in `fuzz/` (each includes this module with
//! `#[path]`) and by `tests/fuzz_corpus.rs`, which replays the checked-in corpus on stable Rust
//! inside `cargo test`. Every check decodes raw bytes itself, so a corpus file means the same to
//! libFuzzer and to the replay.

pub(crate) mod camera;
pub(crate) mod compare;
pub(crate) mod dump;
pub(crate) mod input;
pub(crate) mod layouts;
pub(crate) mod obj_load;
pub(crate) mod raster;
pub(crate) mod schemes;
pub(crate) mod triangles;
