//! Building a catalog entry: what its constructor is given ([`Build`]) and what receives the
//! built scheme ([`SchemeVisitor`]).
//!
//! Each entry of the `catalog!` table carries its constructor, so the table is the only place a
//! scheme is named and built. A scheme's type differs per entry, and Rust has no generic
//! closures, so the built scheme is handed to a visitor whose `visit` is generic: the executors'
//! run ([`SchemeRunner::run`](super::SchemeRunner::run)), the dump recorder and reader, the fuzz
//! targets' checks and `explain`'s replays are each one visitor, statically dispatched.

use fragsim_capture::primitive_order::PrimitiveOrder;
use fragsim_capture::{CaptureError, Scheme};
use fragsim_raster::Viewport;

/// The sizes a constructor builds with, every `auto` already resolved.
#[derive(Debug, Clone, Copy)]
pub struct Build<'a> {
    /// The viewport the scheme's storage covers: the sample-expanded framebuffer of a view
    /// rasterizing per sample.
    pub viewport: Viewport,
    /// Samples a pixel of the view (1 without multisampling).
    pub samples: u32,
    /// Slots per pixel of the K-sized schemes.
    pub k: u32,
    /// Slots per pixel of the capacity-sized schemes.
    pub capacity: u32,
    /// The scene's maximum depth complexity (at least 1), for schemes that record every layer.
    pub layers: u32,
    /// Linked lists' node pool, in nodes.
    pub pool: usize,
    /// Refuse storage beyond this many bytes.
    pub memory_cap: u64,
    /// The per-pixel fragment counts of the scheme's own counting pass, where one ran.
    pub counts: Option<&'a [u32]>,
    /// The scene's primitive order, for the entries that follow it
    /// ([`Entry::primitive_order`](super::Entry::primitive_order)); `None`: arrival order.
    pub order: Option<&'a PrimitiveOrder>,
}

impl<'a> Build<'a> {
    /// Sizes without a counting pass: `k` and `capacity` slots, `layers` layers, a pool of
    /// `capacity` nodes per pixel, one sample a pixel.
    #[must_use]
    pub fn fixed(viewport: Viewport, k: u32, capacity: u32, layers: u32, memory_cap: u64) -> Self {
        Build {
            viewport,
            samples: 1,
            k,
            capacity,
            layers: layers.max(1),
            pool: viewport.pixels() * capacity as usize,
            memory_cap,
            counts: None,
            order: None,
        }
    }

    /// The render target in pixels: [`Build::viewport`] less its samples, for a scheme whose
    /// storage is per pixel while its capture is per sample (the masked-node A-buffer).
    ///
    /// # Errors
    /// A viewport whose width is no whole number of pixels of [`Build::samples`] samples.
    pub fn pixel_viewport(&self) -> Result<Viewport, CaptureError> {
        let samples = self.samples.max(1);
        if !self.viewport.width.is_multiple_of(samples) {
            return Err(CaptureError::BadParameter(format!(
                "a framebuffer {} samples wide holds no whole pixels of {samples} samples",
                self.viewport.width
            )));
        }
        Viewport::new(self.viewport.width / samples, self.viewport.height)
            .map_err(|e| CaptureError::BadParameter(e.to_string()))
    }

    /// The counting pass's per-pixel counts, which a scheme sized exactly to the scene needs.
    ///
    /// # Errors
    /// No counting pass ran.
    pub fn counts(&self) -> Result<&'a [u32], CaptureError> {
        self.counts.ok_or_else(|| {
            CaptureError::BadParameter(
                "this scheme is sized by its counting pass, and none ran".to_string(),
            )
        })
    }
}

/// Something done with a built catalog scheme, whatever its type.
pub trait SchemeVisitor {
    /// What the visit returns.
    type Output;
    /// Uses `scheme`, which holds `slots` slots per pixel where it has a fixed number.
    fn visit<S: Scheme>(self, scheme: &S, slots: Option<u32>) -> Self::Output;
}
