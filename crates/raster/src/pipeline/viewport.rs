//! The render target and rectangles of whole pixels.

use super::scan::pixel_span;

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
    /// A zero or larger than [`Viewport::MAX_SIDE`] side, named in the message.
    pub fn new(width: u32, height: u32) -> Result<Self, String> {
        for (name, side) in [("width", width), ("height", height)] {
            if side == 0 || side > Self::MAX_SIDE {
                return Err(format!(
                    "viewport {name} must be between 1 and {}, got {side}",
                    Self::MAX_SIDE
                ));
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
    pub(super) fn centres_within(self, lo: [i64; 2], hi: [i64; 2]) -> Option<Self> {
        let x = pixel_span(lo[0], hi[0], self.x)?;
        let y = pixel_span(lo[1], hi[1], self.y)?;
        Some(Self { x, y })
    }
}
