//! The capture model and the frame loop: what a scheme is, what it hands back, and the executors
//! that run it.
//!
//! The one idea (see `docs/architecture.md`): every scheme is a per-fragment state machine that
//! performs **exactly one memory operation per step** on a [`Memory`], the seam of the crate
//! below this one (`fragsim-memory`: words, operations, the serial and atomic memories). The
//! same scheme code then runs on plain memory (the serial executor), on std atomics (the
//! parallel executor) and on loom's atomics (the model-checking suite in `tests/loom/`), and
//! whether a scheme is safe under concurrency is a question of where its steps are cut.
//!
//! This crate holds that contract and what runs it; the schemes themselves are the crate above
//! (`fragsim-schemes`, one module a scheme), and the catalog that names them the one above that
//! (`fragsim-catalog`). Executors: [`executors`] (serial and parallel, storage kept between
//! frames), [`tiled`](executors::tiled) (triangles binned into screen tiles, one thread per tile
//! at a time) and [`scheduled`](executors::scheduled) (replayable GPU-like interleavings with
//! traces), all running one frame loop ([`executors::frame`]).
//!
//! # The tree
//!
//! ```text
//! lib.rs          this map, and the re-exports of the core types (Scheme, Capture, ...)
//! scheme.rs       the Scheme trait: begin, step, end pass, resolve; the Descriptor each scheme
//!                 builds once; Step, Promise, Simt, CaptureError
//! guarantee.rs    what a scheme guarantees against the oracle
//! capture.rs      the per-pixel lists a run returns, and what they keep
//! masked.rs       the masked nodes (one a primitive and pixel, with its coverage mask) and
//!                 their lists: the capture of multisampled node storage
//! depth_count.rs  the counting pass that sizes exact storage
//! walk_input.rs   what a walk starts from: a fragment, or what a scheme gathers from a triangle's
//!                 fragments (a masked node)
//! post_pass.rs    the post pass of every executor: empty pixels skipped in bulk, in parallel
//! primitive_order.rs  each pixel's primitives in submission order (the ordered interlock's)
//! executors/      frame.rs (the one frame loop: passes, resolve, stats), serial.rs,
//!                 parallel.rs, tiled.rs, scheduled.rs, counting.rs (the counted frame)
//! ```
//!
//! Imports go one way: the memory is a crate of its own (`fragsim-memory`); `scheme` needs it,
//! `capture` and `guarantee` (and `post_pass`, whose serial form its default `resolve` runs: the
//! one circle left, explained in `post_pass.rs`); the executors need `scheme` and the memory. The
//! frame loop's tests that need real schemes are in `tests/suite/frame_loop.rs`.
//!
//! [`Memory`]: fragsim_memory::Memory
//!
//! ```
//! use fragsim_capture::{executors, depth_count::DepthCount};
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//!
//! // The counting pass, itself a scheme: one `fetch_add` a fragment.
//! let scene = Scene::procedural("quads:3").unwrap();
//! let view = scene.view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default()).unwrap();
//! let run = executors::run_serial(&view, &DepthCount::new(view.viewport()));
//! assert_eq!(run.stats.counters.dropped, 0);
//! assert!(run.stats.counters.fragments > 0);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

mod capture;
pub mod depth_count;
pub mod executors;
mod guarantee;
mod masked;
mod post_pass;
pub mod primitive_order;
mod scheme;
mod walk_input;

pub use capture::{Capacity, Capture, Identity, Keeps, PixelLists};
pub use guarantee::Guarantee;
pub use masked::{merge_samples, MaskedLists, MaskedNode};
pub use scheme::{
    walk_to_end, CaptureError, Descriptor, PixelRun, Promise, Scheme, Simt, Step,
    MEMORY_CAP_DEFAULT,
};
pub use walk_input::{inputs_of, WalkInput};
