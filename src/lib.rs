//! fragsim: the CPU reference simulator of GPU atomics for multi-fragment rendering.
//!
//! This facade re-exports the workspace's crates so that the integration tests in `tests/` and
//! users see one library:
//! - [`raster`]: scenes, camera and the exact rasterizer that produces fragments;
//! - [`memory`]: the simulated GPU's memory, the `Memory` seam the schemes step on;
//! - [`capture`]: the `Scheme` trait, the captures a run returns and the executors that run a
//!   frame;
//! - [`schemes`]: the capture schemes, one module each (MDTS, the A-buffer, the baselines the
//!   papers measure, the OIT backends engines ship);
//! - [`catalog`]: every scheme by name, built and run on any executor;
//! - [`dump`]: the dump format GPU backends write, and the triangle export;
//! - [`oracle`]: the serial reference lists, the per-pixel diff and the verdict;
//! - [`shade`]: images of the results.
//!
//! ```
//! use fragsim::capture::executors;
//! use fragsim::schemes::mdts::Mdts;
//! use fragsim::raster::{OrbitCamera, Scene, Viewport};
//! use fragsim::oracle::Oracle;
//!
//! let scene = Scene::procedural("spheres:2").unwrap();
//! let view = scene.view(Viewport::new(48, 48).unwrap(), &OrbitCamera::default()).unwrap();
//! let oracle = Oracle::build(&view);
//! let scheme = Mdts::<u64>::ascending(view.viewport(), oracle.max_depth_complexity().max(1)).unwrap();
//! let run = executors::run_parallel(&view, &scheme);
//! assert!(oracle.diff(&run.capture).is_exact());
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

// The command (`src/main.rs`) is fragsim-cli's; the facade does not re-export it.
use fragsim_cli as _;

pub use fragsim_capture as capture;
pub use fragsim_catalog as catalog;
pub use fragsim_dump as dump;
pub use fragsim_memory as memory;
pub use fragsim_oracle as oracle;
pub use fragsim_raster as raster;
pub use fragsim_schemes as schemes;
pub use fragsim_shade as shade;
