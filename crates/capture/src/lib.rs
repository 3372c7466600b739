//! Capture schemes as state machines over per-pixel memory, and the executors that run them.
//!
//! The one idea (see `docs/architecture.md`): every scheme is a per-fragment state machine that
//! performs **exactly one memory operation per step** on a [`Memory`]. The same scheme code then
//! runs on plain memory (the serial executor), on std atomics (the parallel executor) and on loom's
//! atomics (the model-checking suite in `tests/loom.rs`), and whether a scheme is safe under
//! concurrency is a question of where its steps are cut.
//!
//! Schemes: [`mdts`] (FreePipe's multi-depth test scheme) and [`abuffer`] (FreePipe's A-buffer
//! scheme).
//!
//! ```
//! use fragsim_capture::{executor, mdts::Mdts};
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//!
//! let scene = Scene::procedural("quads:3").unwrap();
//! let view = scene.view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default()).unwrap();
//! let scheme = Mdts::<u64>::ascending(view.viewport(), 4).unwrap();
//! let run = executor::run_serial(&view, &scheme);
//! assert_eq!(run.stats.counters.dropped, 0);
//! ```

pub mod abuffer;
pub mod bucket;
mod capture;
pub mod dual_peeling;
pub mod executor;
pub mod kbuffer;
pub mod kbuffer_multipass;
pub mod mdts;
pub mod mdts_packed;
mod memory;
pub mod peeling;
pub mod scheduled;
mod scheme;
pub mod stencil_routed;
pub mod zbuffer;

pub use capture::{Capture, Identity, Keeps};
pub use memory::{AtomicMemory, Memory, SerialMemory, Word, WordMemory};
pub use scheme::{CaptureError, Layout, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};
