//! Helpers shared by the top-level integration tests; include with `mod support;`.
//!
//! - [`strategies`]: proptest strategies for viewports, orbit cameras, procedural scenes, random
//!   and closed meshes, planar tilings, capacities `K` and depths.

// Each test binary uses a different subset of the helpers.
#![allow(dead_code)]

pub mod strategies;
