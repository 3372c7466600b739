//! The capture schemes, one module each, named after the scheme (the catalog's spelling where
//! there is one), every one stating its algorithm, guarantee, passes and memory; [`common`] holds
//! what several of them share.

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
