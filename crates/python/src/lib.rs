//! fragsim from Python: the native half of the `fragsim` package (`fragsim._fragsim`), built by
//! maturin into an abi3 wheel for Python 3.10 and later (`pyproject.toml`).
//!
//! Python users write their capture kernels in Warp, `CuPy`, `PyTorch` or Slang and hold the results
//! as arrays. This module lets them judge those arrays with fragsim's oracle without writing a
//! dump directory: a scene ([`scene::SceneCore`]: a named scene, a mesh file or vertex and index
//! arrays, through the orbit camera or an engine's matrix), its screen triangles, its fragment
//! stream and its exact reference as numpy arrays, the oracle's one verdict on arrays in memory
//! (`SceneCore::judge`), dump directories read and written, and the conformance battery
//! run on a Python callable ([`battery`]).
//!
//! The pure-Python half (`python/fragsim/`) holds the public API: it names the keyword
//! arguments, builds the dump header from them (the same JSON as `dump.json`) and turns the
//! verdict into a result object. The split keeps every decision in the library crates: a header
//! is parsed by `fragsim_dump::Dump::parse`, judged by `fragsim_oracle::verdict::judge`,
//! and a battery is `fragsim_testkit::Battery`.
//!
//! The crate is a workspace member like any other: without the `extension-module` feature (which
//! maturin turns on) it builds, lints and documents as an ordinary library.

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod battery;
pub mod errors;
pub mod reference;
pub mod scene;

use pyo3::prelude::*;

/// The native module `fragsim._fragsim`.
///
/// # Errors
/// Registering a class, function or exception fails (Python out of memory).
#[pymodule]
pub fn _fragsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::SceneCore>()?;
    m.add_function(wrap_pyfunction!(scene::read_dump, m)?)?;
    m.add_function(wrap_pyfunction!(battery::run_battery, m)?)?;
    m.add_function(wrap_pyfunction!(reference::verdict_flags, m)?)?;
    m.add_function(wrap_pyfunction!(scene::scheme_names, m)?)?;
    errors::register(m)
}
