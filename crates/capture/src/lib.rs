//! Capture schemes as state machines over per-pixel memory, and the executors that run them.
//!
//! The one idea (see `docs/architecture.md`): every scheme is a per-fragment state machine that
//! performs **exactly one memory operation per step** on a [`Memory`], the seam of the crate
//! below this one (`fragsim-memory`: words, operations, the serial and atomic memories). The
//! same scheme code then runs on plain memory (the serial executor), on std atomics (the
//! parallel executor) and on loom's atomics (the model-checking suite in `tests/loom/`), and
//! whether a scheme is safe under concurrency is a question of where its steps are cut.
//!
//! Schemes, one module each, every one stating its algorithm, guarantee, passes and memory:
//! - FreePipe (Liu et al., I3D 2010): [`mdts`](schemes::mdts) (the multi-depth test scheme, §4.1.1),
//!   [`mdts_packed`](schemes::mdts_packed) (depth and colour packed in 32-bit words, §4.1.2), [`abuffer`](schemes::abuffer) (§4.2), and
//!   [`abuffer_atomic_inc`](schemes::abuffer_atomic_inc) (its counter as CUDA's wrapping `atomicInc`: a model of the silent
//!   overwrite on overflow, not a scheme to use);
//! - the baselines the papers measure: [`zbuffer`](schemes::zbuffer) (opaque), [`peeling`](schemes::peeling) (Everitt 2001),
//!   [`dual_peeling`](schemes::dual_peeling) (Bavoil & Myers 2008), [`kbuffer`](schemes::kbuffer) (Bavoil et al. 2007),
//!   [`kbuffer::interlock`](schemes::kbuffer::interlock) (the k-buffer inside a fragment-shader
//!   interlock: nvpro-samples' interlock mode, exact under any interleaving),
//!   [`kbuffer::multipass`](schemes::kbuffer::multipass) (Liu et al. 2006), [`stencil_routed`](schemes::stencil_routed) (Myers & Bavoil 2007) and
//!   [`bucket`](schemes::bucket) (bucket depth peeling, Liu et al. HPG 2009: uniform, two-pass, adaptive);
//! - shipping OIT backends (`docs/baselines/shipping.md`): [`loop32`](schemes::loop32) (nvpro-samples, equal
//!   depths merge), [`layer_counter`](schemes::layer_counter) (Bevy 0.15) and [`linked_list`](schemes::linked_list) (per-pixel linked lists,
//!   Yang et al. 2010, with the resolve policies the samples ship).
//!
//! The [`catalog`] lists every scheme by name, with its passes, its sizing and a constructor
//! that builds and runs it on any executor.
//!
//! Executors: [`executors`] (serial and parallel, storage kept between frames), [`tiled`](executors::tiled)
//! (triangles binned into screen tiles, one thread per tile at a time) and [`scheduled`](executors::scheduled)
//! (replayable GPU-like interleavings with traces), all running one frame loop
//! ([`executors::frame`]).
//!
//! # The tree
//!
//! ```text
//! lib.rs          this map, and the re-exports of the core types (Scheme, Capture, ...)
//! scheme.rs       the Scheme trait: begin, step, end pass, resolve; the Descriptor each scheme
//!                 builds once; Step, Promise, Simt, CaptureError
//! guarantee.rs    what a scheme guarantees against the oracle
//! capture.rs      the per-pixel lists a run returns, and what they keep
//! depth_count.rs  the counting pass that sizes exact storage
//! walk_input.rs   what a walk starts from: a fragment, or what a scheme gathers from a triangle's
//!                 fragments (a masked node)
//! post_pass.rs    the post pass of every executor: empty pixels skipped in bulk, in parallel
//! primitive_order.rs  each pixel's primitives in submission order (the ordered interlock's)
//! catalog/        every scheme by name: passes, sizing, dump layout, its constructor (mod.rs),
//!                 building it for a visitor (build.rs), running it (run.rs), dump layouts
//! schemes/        one file per scheme, named after it; bucket/ holds bucket peeling's three,
//!                 kbuffer/ the k-buffer (mod.rs), its shared slots (slots.rs) and its four siblings
//!   common/       what several schemes share: the fragment words (MdtsWord), the post passes'
//!                 sorts, the peeling schemes' layer storage and depth test
//! executors/      frame.rs (the one frame loop: passes, resolve, stats), serial.rs,
//!                 parallel.rs, tiled.rs, scheduled.rs, counting.rs (the counted frame)
//! ```
//!
//! Imports go one way: the memory is a crate of its own (`fragsim-memory`); `scheme` needs it,
//! `capture` and `guarantee` (and `post_pass`, whose serial form its default `resolve` runs: the
//! one circle left, explained in `post_pass.rs`); `schemes` need those and `schemes::common`, never
//! another scheme's module (a scheme built on another, as the packed MDTS on MDTS's walks, names
//! it; a family's members share their folder's common part, as `kbuffer/slots.rs`); the executors
//! need `scheme` and the memory; the catalog needs everything.
//!
//! [`Memory`]: fragsim_memory::Memory
//!
//! ```
//! use fragsim_capture::{executors, schemes::mdts::Mdts};
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//!
//! let scene = Scene::procedural("quads:3").unwrap();
//! let view = scene.view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default()).unwrap();
//! let scheme = Mdts::<u64>::ascending(view.viewport(), 4).unwrap();
//! let run = executors::run_serial(&view, &scheme);
//! assert_eq!(run.stats.counters.dropped, 0);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

mod capture;
pub mod catalog;
pub mod depth_count;
pub mod executors;
mod guarantee;
mod post_pass;
pub mod primitive_order;
mod scheme;
pub mod schemes;
mod walk_input;

pub use capture::{Capacity, Capture, Identity, Keeps, PixelLists};
pub use guarantee::Guarantee;
pub use scheme::{
    CaptureError, Descriptor, PixelRun, Promise, Scheme, Simt, Step, MEMORY_CAP_DEFAULT,
};
pub use walk_input::{inputs_of, WalkInput};
