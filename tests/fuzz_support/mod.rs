//! Checks shared by the cargo-fuzz targets in `fuzz/` (each includes this module with
//! `#[path]`) and by `tests/fuzz_corpus.rs`, which replays the checked-in corpus on stable Rust
//! inside `cargo test`. Every check decodes raw bytes itself, so a corpus file means the same to
//! libFuzzer and to the replay.

pub mod camera;
pub mod compare;
pub mod dump;
pub mod input;
pub mod layouts;
pub mod obj_load;
pub mod raster;
pub mod schemes;
pub mod triangles;
