//! The `Scheme` trait: a per-fragment state machine doing one memory operation per step.

use std::fmt::Debug;

use fragsim_raster::Fragment;

use crate::capture::Capture;
use crate::memory::Memory;

/// Default cap on the per-pixel storage a scheme may allocate: 4 GiB.
pub const MEMORY_CAP_DEFAULT: u64 = 4 << 30;

/// The storage a scheme needs: how many words of each width and their initial value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Number of `u32` words.
    pub words32: usize,
    /// Initial value of every `u32` word.
    pub init32: u32,
    /// Number of `u64` words.
    pub words64: usize,
    /// Initial value of every `u64` word.
    pub init64: u64,
    /// Read-only tables the scheme keeps beside the words (e.g. the A-buffer's offsets), in bytes.
    pub table_bytes: usize,
}

impl Layout {
    /// Total bytes: words and tables.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        self.words32 as u64 * 4 + self.words64 as u64 * 8 + self.table_bytes as u64
    }

    /// Fresh storage for this layout.
    #[must_use]
    pub fn allocate<M: Memory>(&self) -> M {
        M::new(self.words32, self.init32, self.words64, self.init64)
    }
}

/// What a step did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The fragment needs more steps.
    Continue,
    /// The fragment (or the value it carried) is stored; its walk is over.
    Stored,
    /// A value was dropped for lack of storage (counted, never hidden); the walk is over.
    Dropped,
}

/// Why a scheme could not be set up.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CaptureError {
    /// A scheme parameter is out of range (K = 0, say).
    #[error("{0}")]
    BadParameter(String),
    /// The storage would exceed the memory cap.
    #[error(
        "{scheme} would need {needed} bytes of per-pixel storage, more than the cap of {cap} bytes"
    )]
    TooMuchMemory {
        /// The scheme.
        scheme: String,
        /// Bytes it would need.
        needed: u64,
        /// The cap.
        cap: u64,
    },
}

/// A capture scheme: how a fragment walks per-pixel memory, and how the memory is read back.
///
/// Contract: [`Scheme::step`] performs **exactly one** operation on `memory` per call. That is the
/// granularity at which GPU atomics are atomic, so executors may interleave steps of different
/// fragments arbitrarily and get every behaviour the GPU could show.
pub trait Scheme: Sync {
    /// A fragment's progress between steps.
    type State: Send + Clone + Debug;

    /// A short name, e.g. `mdts` or `abuffer`.
    fn name(&self) -> String;

    /// The storage the scheme needs.
    fn layout(&self) -> Layout;

    /// The state of a fragment before its first step.
    fn begin(&self, fragment: Fragment) -> Self::State;

    /// One memory operation of the fragment's walk.
    fn step<M: Memory>(&self, state: &mut Self::State, memory: &M) -> Step;

    /// The post pass, after every fragment is done: the per-pixel lists in canonical order.
    fn resolve<M: Memory>(&self, memory: &M) -> Capture;

    /// Runs one fragment's walk to the end on `memory`, counting the steps into `steps`.
    fn insert<M: Memory>(&self, fragment: Fragment, memory: &M, steps: &mut u64) -> Step {
        let mut state = self.begin(fragment);
        loop {
            *steps += 1;
            match self.step(&mut state, memory) {
                Step::Continue => {}
                done => return done,
            }
        }
    }
}

/// Fails with [`CaptureError::TooMuchMemory`] when `layout` exceeds `cap`.
pub(crate) fn check_cap(scheme: &str, layout: &Layout, cap: u64) -> Result<(), CaptureError> {
    let needed = layout.bytes();
    if needed > cap {
        return Err(CaptureError::TooMuchMemory {
            scheme: scheme.into(),
            needed,
            cap,
        });
    }
    Ok(())
}
