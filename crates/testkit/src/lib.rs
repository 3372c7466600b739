//! fragsim's property tests as a product: the proptest strategies its own suite uses, the
//! conformance battery, and backends to run it on, in process or as a command.
//!
//! - [`strategies`]: proptest strategies for viewports, cameras, procedural and random scenes,
//!   closed meshes, planar tilings, capacities, depths and schedules of the scheduled executor,
//!   each documented with what it is for and what it shrinks towards.
//! - [`case`]: the battery's cases, tiny triangle soups on the half-pixel grid ([`case::case`]).
//! - [`backend`]: the [`Backend`] trait (a case in, a dump or per-pixel lists out) and
//!   [`CatalogBackend`], fragsim's own schemes.
//! - [`command`]: [`CommandBackend`], any program that reads a case's files and writes a dump.
//! - [`judge`]: the verdict `fragsim compare` gives, on a backend's output.
//! - [`battery`]: the properties a claim implies, and a shrunk counterexample on a failure.
//! - [`conform`]: `fragsim conform`, the battery against a command, its record and the saved
//!   counterexample.
//!
//! Everything here runs fragsim's own pipeline (`fragsim-raster`), schemes (`fragsim-capture`)
//! and oracle (`fragsim-oracle`); nothing is re-implemented, so a property that holds here holds
//! of the reference itself.
//!
//! The battery in a test of one's own (here on fragsim's MDTS; a backend of one's own implements
//! [`Backend`]):
//!
//! ```
//! use fragsim_capture::executors::Executor;
//! use fragsim_catalog::SchemeName;
//! use fragsim_testkit::{Battery, CatalogBackend, Params};
//!
//! let backend = CatalogBackend::on(Executor::Parallel);
//! let params = Params { scheme: SchemeName::Mdts, k: 2, capacity: 2 };
//! let passed = Battery::new(&backend, params).cases(8).run().expect("MDTS conforms");
//! assert_eq!(passed.cases, 8);
//! ```

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

pub mod backend;
pub mod battery;
pub mod case;
pub mod command;
pub mod conform;
pub mod judge;
pub mod strategies;

pub use backend::{Backend, BackendError, CatalogBackend, GuaranteeError, Input, Output, Params};
pub use battery::{Battery, Counterexample, Event, Exercised, Failure, Passed, Property};
pub use case::{Case, CaseTriangle, Limits};
pub use command::CommandBackend;
