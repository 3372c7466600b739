//! The interchange with GPU backends (`docs/dump-format.md`): the **dump**, what a backend's
//! per-pixel memory held after its passes, and the **triangle export** ([`triangles`]), the
//! scene after fragsim's vertex stage, so that a backend can test its scan and atomics alone.
//! This crate is the format only: headers, layouts, arrays, reading and writing, and the bounds
//! every input is checked against. Judging a dump against a reference is the oracle's
//! (`fragsim-oracle`, built on this crate: raster ← capture ← dump ← oracle), so that a
//! backend or a test kit that writes dumps needs no judge to do so.
//!
//! A dump is a directory: `dump.json` (format, version, the scene and camera that produced it,
//! viewport, scheme, K or capacity, the names, dtypes and shapes of the arrays) and one file of
//! little-endian words per array beside it. [`Dump::capture`] decodes the words into a
//! [`Capture`] through the named scheme's own post pass (`Scheme::resolve`): fragsim's MDTS reads
//! each pixel's slots until the first empty one, the A-buffer reads `min(counter, capacity)` slots
//! and sorts them. A dump whose A-buffer lists were already sorted on the GPU (`"sorted": true`)
//! is taken in stored order, so a broken sort kernel shows up as misordered pixels. Decoding
//! stops where the layout says a list ends, so [`Dump::check_words`] reads every word against
//! the layout's rules (nothing after an empty MDTS slot, no empty marker below an A-buffer
//! counter, no key above 1.0) and the oracle's comparison adds what it finds to its verdict: a
//! corrupt word, and an A-buffer counter other than the pixel's fragment count, which the
//! reference knows.
//!
//! ```
//! use fragsim_dump::{Direction, Dump, DumpScheme};
//! use fragsim_raster::scene_spec::SceneSpec;
//! use fragsim_raster::Viewport;
//!
//! let spec = SceneSpec::named("spheres:2", 30.0, 15.0);
//! let scene = spec.load(None).unwrap();
//! let view = scene.view(Viewport::new(32, 24).unwrap(), &spec.orbit()).unwrap();
//! let scheme = DumpScheme::Mdts { k: 8, direction: Direction::Ascending };
//! let dump = Dump::record(&view, spec, &scheme, "doc").unwrap();
//! let capture = dump.capture().unwrap();
//! assert_eq!(capture.pixels(), 32 * 24);
//! assert_eq!(dump.check_words().unwrap().corrupt_words(), 0);
//! ```
//!
//! Every catalog scheme has a layout: MDTS slots, the A-buffer's counters and slots, a k-buffer's
//! slots (MDTS's, under its own name), linked lists (heads, next, nodes, the pool counter), Bevy's
//! layer-major layers, or, for schemes whose memory is no list per pixel, the scheme's own memory
//! words. Any of them may carry a description
//! ([`LayoutSpec`]: slot arrays pixel-major or slot-major, a list's terminator and node numbering,
//! the payload's u32 or u64 word, f32, unorm24 or unorm16 depth and id bits), so an engine's own
//! buffers can be dumped as they are; [`Dump::in_layout`] writes fragsim's words so
//! (`render --dump-order`, `--dump-payload`, `--dump-list-numbering`).
//!
//! The parts: the header and its words (`header.rs`), the layout description (`spec.rs`), the
//! layouts and their word rules (`layouts.rs`, from the catalog's
//! [`DumpLayout`](fragsim_catalog::DumpLayout), which names each scheme's layout
//! without knowing the format; `word_check.rs`), linked lists and layers turned into fragsim's
//! memory with their links checked (`lists.rs`), slot arrays in an engine's order and payload
//! turned into fragsim's (`slots.rs`), the array shapes a header states (`shapes.rs`), the
//! masked-node A-buffer's arrays (`masked.rs`), parsing and decoding (`read.rs`, `arrays.rs`),
//! recording and writing (`write.rs`); the scene a dump names is [`fragsim_raster::scene_spec`].
//!
//! Unlike the GPU, which leaves its words in device memory, [`Dump::record`] runs fragsim's scheme
//! serially on [`SerialMemory`] and copies every word out; for MDTS the words are the same under
//! any interleaving (the sortedness proof), for the A-buffer the slot order within a pixel is the
//! serial one. [`Dump::of_memory`] records the words another run left instead (`render --dump`
//! writes the memory of the run it reports, on whatever executor, a racy one's included).
//!
//! A header field this format does not name is refused by name (`extra` holds anything else), and
//! an array whose size the header's fields contradict is refused naming the fields at fault.

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]
#![warn(clippy::print_stdout, clippy::print_stderr)]

mod arrays;
mod header;
mod layouts;
mod lists;
mod masked;
mod read;
mod shapes;
mod slots;
mod spec;
pub mod triangles;
mod word_check;
mod write;

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

#[cfg(doc)]
use fragsim_capture::Capture;
use fragsim_capture::CaptureError;
#[cfg(doc)]
use fragsim_memory::SerialMemory;
use fragsim_raster::SceneSpecError;

pub use header::{ArraySpec, Dtype, Header, Words};
pub use layouts::{Direction, DumpScheme};
pub use masked::{masked_spec, MASKED_SCHEME};
pub use read::HEADER_BYTES_LIMIT;
pub use spec::{kebab, DepthFormat, Encoding, LayoutSpec, ListNumbering, Payload, SlotOrder};
pub use word_check::{CorruptWord, Corruption, Counter, WordCheck};

/// The `format` field of every dump header.
pub const FORMAT: &str = "fragsim-dump";
/// The dump format version this code reads and writes.
pub const VERSION: u32 = 1;
/// The header's file name inside a dump directory.
pub const HEADER_FILE: &str = "dump.json";

/// Why a dump or a triangle export could not be read, written or decoded.
///
/// Callers branch on the kind: a file that cannot be read or written ([`DumpError::Io`]: a
/// path to fix) is not a dump that is wrong ([`DumpError::Invalid`]: the backend's bug, or a
/// header to fix), and a scheme that cannot be built for the dump's sizes
/// ([`DumpError::Capture`]) is neither. The messages name the file, field or array at fault.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DumpError {
    /// A file could not be read, written or listed.
    #[error("cannot {action} {}: {reason}", path.display())]
    Io {
        /// What was tried: `read`, `write`, `create`, ….
        action: String,
        /// The file or directory.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
    /// The dump, its header or a triangle export contradicts the format, or the run it names.
    #[error("{0}")]
    Invalid(String),
    /// The scheme the header names cannot be built at the header's sizes.
    #[error(transparent)]
    Capture(#[from] CaptureError),
}

impl From<SceneSpecError> for DumpError {
    /// A scene that cannot be loaded or viewed says it is the dump's scene; the spec's own
    /// errors (the mesh file, the numbers) name their field already.
    fn from(e: SceneSpecError) -> Self {
        match e {
            SceneSpecError::Scene(e) => Self::Invalid(format!("scene: {e}")),
            e => Self::Invalid(e.to_string()),
        }
    }
}

pub(crate) fn err<T>(message: impl Into<String>) -> Result<T, DumpError> {
    Err(DumpError::Invalid(message.into()))
}

pub(crate) fn io_err(action: &str, path: &Path, reason: impl fmt::Display) -> DumpError {
    DumpError::Io {
        action: action.into(),
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// A dump: the header and the arrays it names.
#[derive(Clone, Debug, PartialEq)]
pub struct Dump {
    /// The header.
    pub header: Header,
    /// The arrays by name.
    pub arrays: BTreeMap<String, Words>,
}
