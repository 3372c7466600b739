//! fragsim's wgpu backend: the capture schemes as WGSL fragment shaders with storage-buffer
//! atomics, rasterized by the GPU's own rasterizer through Vulkan (Mesa's lavapipe in CI, the
//! NVIDIA driver on the H200), their buffers read back as dumps that `fragsim compare` judges
//! (`docs/dump-format.md`).
//!
//! The parts: the headless device and its adapter report ([`device`]), the shaders, their passes
//! and buffers ([`shaders`], the WGSL files in `backends/wgpu/schemes/`), the planted bugs
//! ([`plant`]), one capture in replay or engine mode ([`mod@capture`]), the judgement of a
//! capture against fragsim's oracle ([`judge`]), the backend as the conformance battery's
//! [`fragsim_testkit::Backend`] ([`mod@conform`]), per-sample captures of a multisampled target
//! ([`capture_samples`]), and the per-sample counting pass of a
//! multisampled target against fragsim's per-sample oracle ([`sample_counts`]). The command is `fragsim-wgpu` (`src/main.rs`).

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

// The command (`src/main.rs`) parses its arguments with clap; the library itself does not.
use clap as _;

pub mod capture;
pub mod conform;
pub mod device;
pub mod judge;
pub mod plant;
pub mod sample_counts;
pub mod shaders;

pub use capture::{capture, capture_planted, capture_samples, Captured, Mode};
pub use conform::WgpuBackend;
pub use device::{adapter_or_skip, say_skipped, Gpu, GpuError};
pub use plant::Plant;
pub use shaders::GpuScheme;
