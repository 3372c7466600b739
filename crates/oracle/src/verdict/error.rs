//! Why a verdict could not be given: the sides do not describe the same thing, or one of them
//! cannot be read. A verdict that is given is never an error, whatever it says.

use fragsim_raster::{F32RangeError, ViewportError};

use crate::memory_cap::MemoryCapError;
use crate::samples::UnsampledViewError;
use fragsim_dump::{DumpError, MASKED_SCHEME};

/// Why [`super::judge`] or [`super::judge_sides`] gave no verdict. Each message names what is at
/// fault; callers branch on the kind (a dump that cannot be decoded is the backend's or the
/// header's, sides that do not match are the command line's).
// No `Eq`: an f32 range error carries the f64 entry and product it names.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum VerdictError {
    /// A dump could not be read or decoded, or its scene rebuilt.
    #[error(transparent)]
    Dump(#[from] DumpError),
    /// The candidate dump covers another viewport than the reference.
    #[error(
        "the dump covers {}x{} pixels, the reference {}x{}",
        candidate.0, candidate.1, reference.0, reference.1
    )]
    Viewport {
        /// The candidate dump's width and height.
        candidate: (u32, u32),
        /// The reference's width and height.
        reference: (u32, u32),
    },
    /// The candidate holds another number of lists than the reference.
    #[error("the candidate covers {candidate} pixels, the reference {reference}")]
    Lists {
        /// The candidate's lists.
        candidate: usize,
        /// The reference's lists.
        reference: usize,
    },
    /// Something other than a masked-node dump judged against the per-sample oracle's
    /// per-pixel view.
    #[error("the per-pixel view of the per-sample oracle judges masked-node dumps only")]
    MaskedOnly,
    /// Both sides of a comparison are the oracle.
    #[error("compare needs at least one dump: both sides are `oracle`")]
    NoDump,
    /// Two dumps of different viewports.
    #[error("the dumps cover different viewports: {}x{} and {}x{}", a.0, a.1, b.0, b.1)]
    DumpViewports {
        /// The reference dump's width and height.
        a: (u32, u32),
        /// The candidate dump's width and height.
        b: (u32, u32),
    },
    /// Two dumps of different scenes, not allowed.
    #[error(
        "the dumps name different scenes: {a} and {b} (--allow-different-scenes compares them \
         anyway)"
    )]
    DifferentScenes {
        /// The reference dump's scene, described.
        a: String,
        /// The candidate dump's scene, described.
        b: String,
    },
    /// A masked-node dump as the reference, or against another dump.
    #[error(
        "a masked-node dump ({MASKED_SCHEME}) is compared as the candidate against the oracle: \
         `fragsim compare oracle DUMP`"
    )]
    MaskedSide,
    /// An f32 vertex stage judged against a dump, which holds no geometry.
    #[error(
        "--vertex-precision f32 needs the oracle as the reference: a dump holds no geometry to \
         derive bounds from"
    )]
    F32NeedsOracle,
    /// The viewport a dump names is no viewport.
    #[error(transparent)]
    DumpViewport(#[from] ViewportError),
    /// The scene's f32 vertex stage, judged, would leave f32's normal range.
    #[error("scene: {0}")]
    F32Range(#[from] F32RangeError),
    /// The per-sample oracle asked of a view that does not rasterize per sample.
    #[error(transparent)]
    Unsampled(#[from] UnsampledViewError),
    /// The reference (the scene a dump names, its oracle's lists) would need more memory than
    /// the cap allows: refused before it is built, the message naming the bound and the cap.
    #[error(transparent)]
    MemoryCap(#[from] MemoryCapError),
}

impl From<VerdictError> for String {
    /// The command line's errors are their messages.
    fn from(e: VerdictError) -> Self {
        e.to_string()
    }
}

impl From<VerdictError> for DumpError {
    /// A dump's own error as it was; any other as a dump that is not what the reference asks.
    fn from(e: VerdictError) -> Self {
        match e {
            VerdictError::Dump(e) => e,
            e => Self::Invalid(e.to_string()),
        }
    }
}
