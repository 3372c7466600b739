//! Executors: who runs which fragment's next step, and when. Every one runs the same frame loop
//! ([`frame`]: begin pass, steps, end pass, resolve, stats); they differ in the order of steps.
//!
//! - [`serial`] ([`run_serial`]): triangles in submission order on one thread, each fragment's
//!   walk run to the end before the next fragment starts: the reference behaviour of a scheme.
//! - [`parallel`] ([`run_parallel`]): FreePipe's model, one logical thread per triangle, on the
//!   current rayon pool with std atomics, triangles in chunks.
//! - [`tiled`]: triangles binned into screen tiles, one thread per tile at a time.
//! - [`scheduled`]: replayable GPU-like interleavings on one thread, with traces.
//! - [`counting`] ([`count_locked_ops`]): an untimed frame that counts locked operations.
//!
//! Multi-pass schemes run one geometry pass after another, with the scheme's between-pass kernel
//! in between, until the scheme asks for no more. Every executor times the passes (storage
//! initialisation, rasterization, capture) and the post pass (resolve) separately, and counts
//! fragments, steps (= memory operations), drops and passes. The serial, parallel and tiled
//! executors keep their storage between frames.

pub mod counting;
pub mod frame;
pub mod parallel;
pub mod scheduled;
pub mod serial;
pub mod tiled;

pub use counting::count_locked_ops;
pub use frame::{Counters, Run, RunStats};
pub use parallel::{run_parallel, ParallelExecutor, TRIANGLES_PER_TASK};
pub use serial::{run_serial, serial_passes, SerialExecutor};
pub use tiled::{run_tiled, TiledExecutor};

/// The executors, by name: what the command line, the catalog and the tests iterate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Executor {
    /// Submission order on one thread: the reference behaviour.
    Serial,
    /// FreePipe's model: triangles in chunks on rayon, std atomics.
    Parallel,
    /// Triangles binned into screen tiles, one thread per tile at a time.
    Tiled,
    /// A replayable GPU-like interleaving on one thread ([`crate::executors::scheduled`]).
    Scheduled,
}

impl Executor {
    /// Every executor.
    pub const EVERY: [Self; 4] = [Self::Serial, Self::Parallel, Self::Tiled, Self::Scheduled];

    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Serial => "serial",
            Self::Parallel => "parallel",
            Self::Tiled => "tiled",
            Self::Scheduled => "scheduled",
        }
    }

    /// Whether each pixel sees its fragments one walk at a time, in primitive order: then no
    /// read–modify–write hazard can happen, and the guarantees that exclude hazards are owed.
    #[must_use]
    pub fn serialises_pixels(self) -> bool {
        matches!(self, Self::Serial | Self::Tiled)
    }
}

impl std::fmt::Display for Executor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
