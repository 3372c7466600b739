//! The render target, the fixed-point grid its vertices snap to, and rectangles of whole pixels.
//!
//! The grid and the viewport are what every stage shares, from the vertex stage's snapping to
//! the sample patterns and the scene's camera, so they sit apart from the pipeline's stages.

/// Fractional bits of the fixed-point vertex grid (Vulkan's common `subPixelPrecisionBits`).
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in grid units.
pub(crate) const ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a pixel in grid units: where a pixel's centre lies from its corner.
pub(crate) const HALF: i64 = ONE / 2;

/// Why a viewport could not be made: a side out of range.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("viewport {side_name} must be between 1 and {max}, got {side}", max = Viewport::MAX_SIDE)]
pub struct ViewportError {
    /// `width` or `height`.
    pub side_name: &'static str,
    /// The side given.
    pub side: u32,
}

/// The size of the render target in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Viewport {
    /// The largest side accepted (the guard band's fixed-point bound is sized for it).
    pub const MAX_SIDE: u32 = 16384;

    /// A viewport of `width × height` pixels.
    ///
    /// # Errors
    /// A zero or larger than [`Viewport::MAX_SIDE`] side, by name.
    pub fn new(width: u32, height: u32) -> Result<Self, ViewportError> {
        for (side_name, side) in [("width", width), ("height", height)] {
            if side == 0 || side > Self::MAX_SIDE {
                return Err(ViewportError { side_name, side });
            }
        }
        Ok(Self { width, height })
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixels(self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Every pixel of the viewport.
    #[must_use]
    pub fn rect(self) -> PixelRect {
        PixelRect {
            x: (0, self.width - 1),
            y: (0, self.height - 1),
        }
    }
}

/// A rectangle of whole pixels, bounds inclusive: the pixels a scan may visit (a screen tile, or
/// the pixels whose centres a triangle's bounding box holds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// First and last column.
    pub x: (u32, u32),
    /// First and last row.
    pub y: (u32, u32),
}

impl PixelRect {
    /// The smallest rectangle holding both.
    #[must_use]
    pub fn union(self, other: Self) -> Self {
        Self {
            x: (self.x.0.min(other.x.0), self.x.1.max(other.x.1)),
            y: (self.y.0.min(other.y.0), self.y.1.max(other.y.1)),
        }
    }

    /// The pixel centres that a bounding box `[lo, hi]` (x and y in 1/256 pixel) holds inside
    /// this rectangle; `None` when there is none.
    #[inline]
    pub(crate) fn centres_within(self, lo: [i64; 2], hi: [i64; 2]) -> Option<Self> {
        let x = pixel_span(lo[0], hi[0], self.x)?;
        let y = pixel_span(lo[1], hi[1], self.y)?;
        Some(Self { x, y })
    }
}

/// The first and last pixel whose centre lies in `[lo, hi]` (1/256 pixel) and in the pixel range
/// `[first, last]`; `None` when there is none.
#[inline]
#[expect(
    clippy::cast_possible_truncation,
    reason = "both lie in [first, last], u32s, when they are ordered"
)]
fn pixel_span(lo: i64, hi: i64, (first, last): (u32, u32)) -> Option<(u32, u32)> {
    // An arithmetic shift is the floor division by `ONE` (a power of two), in fewer instructions
    // than `div_euclid`: this runs for every triangle of the mesh.
    let from = ((lo - HALF + ONE - 1) >> SUBPIXEL_BITS).max(first.into());
    let to = ((hi - HALF) >> SUBPIXEL_BITS).min(last.into());
    // Both lie in [first, last] when they are ordered, so the conversions are lossless.
    (from <= to).then_some((from as u32, to as u32))
}
