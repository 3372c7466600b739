//! Helpers shared by the suites of this binary (`crate::support`).
//!
//! - [`strategies`]: proptest strategies for viewports, orbit cameras, procedural scenes, random
//!   and closed meshes, planar tilings, capacities `K` and depths.

pub mod strategies;
