//! Capture schemes as state machines over per-pixel memory, and the executors that run them.
//!
//! The one idea (see `docs/architecture.md`): every scheme is a per-fragment state machine that
//! performs **exactly one memory operation per step** on a [`Memory`]. The same scheme code then
//! runs on plain memory (the serial executor), on std atomics (the parallel executor) and on loom's
//! atomics (the model-checking suite in `tests/loom.rs`), and whether a scheme is safe under
//! concurrency is a question of where its steps are cut.
//!
//! Schemes, one module each, every one stating its algorithm, guarantee, passes and memory:
//! - FreePipe (Liu et al., I3D 2010): [`mdts`] (the multi-depth test scheme, §4.1.1),
//!   [`mdts_packed`] (depth and colour packed in 32-bit words, §4.1.2), [`abuffer`] (§4.2), and
//!   [`abuffer_atomic_inc`] (its counter as CUDA's wrapping `atomicInc`: a model of the silent
//!   overwrite on overflow, not a scheme to use);
//! - the baselines the papers measure: [`zbuffer`] (opaque), [`peeling`] (Everitt 2001),
//!   [`dual_peeling`] (Bavoil & Myers 2008), [`kbuffer`] (Bavoil et al. 2007),
//!   [`kbuffer_multipass`] (Liu et al. 2006), [`stencil_routed`] (Myers & Bavoil 2007) and
//!   [`bucket`] (bucket depth peeling, Liu et al. HPG 2009: uniform, two-pass, adaptive);
//! - shipping OIT backends (`docs/baselines/shipping.md`): [`loop32`] (nvpro-samples, equal
//!   depths merge), [`layer_counter`] (Bevy 0.15) and [`linked_list`] (per-pixel linked lists,
//!   Yang et al. 2010, with the resolve policies the samples ship).
//!
//! The [`catalog`] lists every scheme by name, with its passes, its sizing and a constructor
//! that builds and runs it on any executor.
//!
//! Executors: [`executor`] (serial and parallel, storage kept between frames), [`tiled`]
//! (triangles binned into screen tiles, one thread per tile at a time) and [`scheduled`]
//! (replayable GPU-like interleavings with traces).
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
pub mod abuffer_atomic_inc;
pub mod bucket;
mod capture;
pub mod catalog;
mod counting;
pub mod depth_count;
pub mod dual_peeling;
pub mod executor;
mod guarantee;
pub mod kbuffer;
pub mod kbuffer_multipass;
pub mod layer_counter;
pub mod linked_list;
pub mod loop32;
pub mod mdts;
pub mod mdts_packed;
mod memory;
pub mod peeling;
pub mod scheduled;
mod scheme;
pub mod stencil_routed;
pub mod tiled;
pub mod zbuffer;

pub use capture::{Capacity, Capture, Identity, Keeps, PixelLists};
pub use counting::CountingMemory;
pub use guarantee::Guarantee;
pub use memory::{AtomicMemory, Memory, SerialMemory, Word, WordMemory};
pub use scheme::{CaptureError, Layout, Promise, Scheme, Step, MEMORY_CAP_DEFAULT};
