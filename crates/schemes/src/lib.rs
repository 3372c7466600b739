//! The capture schemes, one module each, named after the scheme (the catalog's spelling where
//! there is one), every one stating its algorithm, guarantee, passes and memory; [`common`] holds
//! what several of them share.
//!
//! Each is a `fragsim_capture::Scheme`: a per-fragment state machine of one memory operation a
//! step, run by any of `fragsim_capture`'s executors. The catalog that names them and builds them
//! by name is the crate above (`fragsim-catalog`).
//!
//! - FreePipe (Liu et al., I3D 2010): [`mdts`] (the multi-depth test scheme, §4.1.1),
//!   [`mdts_packed`] (depth and colour packed in 32-bit words, §4.1.2), [`mdts_emulated64`] (MDTS's
//!   64-bit words emulated with 32-bit memory, where 64-bit atomics are missing: the torn
//!   emulation and a correct one), [`abuffer`] (§4.2), [`abuffer_atomic_inc`]
//!   (its counter as CUDA's wrapping `atomicInc`: a model of the silent overwrite on overflow, not
//!   a scheme to use) and [`masked_abuffer`] (the A-buffer of multisampled targets, one node a
//!   primitive and pixel with its coverage mask);
//! - the baselines the papers measure: [`zbuffer`] (opaque), [`peeling`] (Everitt 2001),
//!   [`dual_peeling`] (Bavoil & Myers 2008), [`kbuffer`] (Bavoil et al. 2007, with its siblings:
//!   [`kbuffer::interlock`], nvpro-samples' interlock mode, exact under any interleaving, and
//!   [`kbuffer::multipass`], Liu et al. 2006), [`stencil_routed`] (Myers & Bavoil 2007) and
//!   [`bucket`] (bucket depth peeling, Liu et al. HPG 2009: uniform, two-pass, adaptive);
//! - shipping OIT backends (`docs/baselines/shipping.md`): [`loop32`] and [`loop64`]
//!   (nvpro-samples), [`layer_counter`] (Bevy 0.15), [`linked_list`] (per-pixel linked lists,
//!   Yang et al. 2010, with the resolve policies the samples ship) and [`mlab`] (multi-layer
//!   alpha blending, Salvi & Vaidyanathan 2014: its node structure, the capture half).
//!
//! Imports go one way: a scheme needs `fragsim_capture` (the trait, the captures, the executors
//! where it runs itself) and [`common`], never another scheme's module, except where it is built
//! on one (the packed MDTS on MDTS's walks) or shares its family's folder (`kbuffer/slots.rs`).
//!
//! ```
//! use fragsim_capture::executors;
//! use fragsim_raster::{OrbitCamera, Scene, Viewport};
//! use fragsim_schemes::mdts::Mdts;
//!
//! let scene = Scene::procedural("quads:3").unwrap();
//! let view = scene.view(Viewport::new(16, 16).unwrap(), &OrbitCamera::default()).unwrap();
//! let scheme = Mdts::<u64>::ascending(view.viewport(), 4).unwrap();
//! let run = executors::run_serial(&view, &scheme);
//! assert_eq!(run.stats.counters.dropped, 0);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/).
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod abuffer;
pub mod abuffer_atomic_inc;
pub mod bucket;
pub mod common;
pub mod dual_peeling;
pub mod kbuffer;
pub mod layer_counter;
pub mod linked_list;
pub mod loop32;
pub mod loop64;
pub mod masked_abuffer;
pub mod mdts;
pub mod mdts_emulated64;
pub mod mdts_packed;
pub mod mlab;
pub mod peeling;
pub mod stencil_routed;
pub mod zbuffer;
