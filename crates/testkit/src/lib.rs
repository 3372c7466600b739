//! fragsim's property tests as a product: the proptest strategies its own suite uses, and
//! generators of scenes small enough to read, for anyone testing a multi-fragment backend.
//!
//! - [`strategies`]: proptest strategies for viewports, cameras, procedural and random scenes,
//!   closed meshes, planar tilings, capacities, depths and schedules of the scheduled executor,
//!   each documented with what it is for and what it shrinks towards.
//!
//! Everything here runs fragsim's own pipeline (`fragsim-raster`), schemes (`fragsim-capture`)
//! and oracle (`fragsim-oracle`); nothing is re-implemented, so a property that holds here holds
//! of the reference itself.

pub mod strategies;
