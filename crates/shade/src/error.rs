//! Why a figure could not be drawn, or an image or chart saved.

use std::path::PathBuf;

use plotters::drawing::DrawingAreaErrorKind;

/// Why plotters could not draw a figure (a font error, say): its message. plotters' error is
/// generic over its drawing backend, so only the message is kept.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct DrawError {
    /// What plotters said.
    pub message: String,
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        Self {
            message: e.to_string(),
        }
    }
}

/// Why an image or a chart could not be saved to a file.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The file's directory could not be created.
    #[error("cannot create {}: {source}", dir.display())]
    CreateDir {
        /// The directory.
        dir: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The image could not be encoded or written.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the encoder or the system said.
        source: image::ImageError,
    },
    /// The chart could not be drawn (an SVG chart is written as it is drawn).
    #[error("cannot draw {}: {source}", path.display())]
    Draw {
        /// The file.
        path: PathBuf,
        /// What plotters said.
        source: DrawError,
    },
}
