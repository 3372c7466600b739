//! Multisampling semantics: the standard sample patterns of Vulkan and Direct3D, and the
//! sample-expanded framebuffer a sampled [`View`](crate::View) rasterizes into.
//!
//! **Patterns.** [`SamplePattern::standard`] gives the fixed positions of 1, 2, 4, 8 and 16
//! samples a pixel, in 1/16 pixel from the pixel's upper-left corner, y down. They are the
//! Vulkan specification's table "Standard sample locations" (chapter Rasterization, section
//! Multisampling; used when `VkPhysicalDeviceLimits::standardSampleLocations` is true), which
//! are also Direct3D's fixed `D3D11_STANDARD_MULTISAMPLE_PATTERN` positions, and the default
//! positions Metal documents for 1, 2, 4 and 8 samples. Every position lies on the 1/16 grid, so
//! in fragsim's 1/256-pixel fixed point it is exact (a multiple of 16).
//!
//! **Coverage and depth** (`docs/semantics.md`, "Multisampling"). A sample is covered by exactly
//! the rule that decides a pixel centre (rule 6): the three integer edge functions, evaluated at
//! the sample's fixed-point position, are positive or zero on an owned edge (the fill rule of the
//! view's window origin). Its depth is interpolated at the sample from the same integer
//! barycentrics in f64 and rounded once to f32 (rule 7), as hardware evaluates depth per sample for
//! the depth test. One sample at the centre ([`SamplePattern::CENTRE`]) is therefore today's
//! single-sample rasterization, bit for bit.
//!
//! **The expanded framebuffer.** A view with a pattern of `n` samples emits one
//! [`Fragment`](crate::Fragment) per covered sample, whose `pixel` is the *sample index*
//! `(y * width + x) * n + s`: row-major in a viewport of `width * n` columns, where sample `s` of
//! pixel `(x, y)` is column `x * n + s`. Every consumer of a view (the oracle, every scheme, every
//! executor, tiles included) then works per sample unchanged, with `n` times the storage.

use crate::viewport::{Viewport, ViewportError};

/// Why a sample pattern, or the framebuffer it expands, could not be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SampleError {
    /// No standard pattern has this many samples.
    #[error("{count} samples per pixel: the standard patterns have 1, 2, 4, 8 or 16")]
    NotStandard {
        /// The count asked for.
        count: u32,
    },
    /// A custom pattern of no position, or of more than 16.
    #[error("{count} sample positions: a pattern has 1 to 16")]
    PositionCount {
        /// How many positions were given.
        count: usize,
    },
    /// A custom position outside the pixel's 16 × 16 grid.
    #[error("sample position {position:?}: coordinates are 0 to 15 (1/16 pixel)")]
    OutsidePixel {
        /// The position, in 1/16 pixel.
        position: [u8; 2],
    },
    /// A custom position given twice.
    #[error("sample position {position:?} is repeated")]
    Repeated {
        /// The position, in 1/16 pixel.
        position: [u8; 2],
    },
    /// The sample-expanded framebuffer would be wider than [`Viewport::MAX_SIDE`].
    #[error(
        "{width} pixels wide at {samples} samples is {columns} sample columns, more than {max}",
        max = Viewport::MAX_SIDE
    )]
    TooWide {
        /// The viewport's width in pixels.
        width: u32,
        /// Samples a pixel.
        samples: u32,
        /// The expanded width in sample columns.
        columns: u64,
    },
    /// The sample-expanded framebuffer is no viewport (a side of the pixels' viewport out of
    /// range).
    #[error(transparent)]
    Viewport(#[from] ViewportError),
}

/// A fixed set of sample positions per pixel, each in 1/16 pixel from the pixel's upper-left
/// corner (x right, y down).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SamplePattern {
    positions: &'static [[u8; 2]],
}

/// One sample at the pixel centre.
const POSITIONS_1: [[u8; 2]; 1] = [[8, 8]];
const POSITIONS_2: [[u8; 2]; 2] = [[12, 12], [4, 4]];
const POSITIONS_4: [[u8; 2]; 4] = [[6, 2], [14, 6], [2, 10], [10, 14]];
const POSITIONS_8: [[u8; 2]; 8] = [
    [9, 5],
    [7, 11],
    [13, 9],
    [5, 3],
    [3, 13],
    [1, 7],
    [11, 15],
    [15, 1],
];
const POSITIONS_16: [[u8; 2]; 16] = [
    [9, 9],
    [7, 5],
    [5, 10],
    [12, 7],
    [3, 6],
    [10, 13],
    [13, 11],
    [11, 3],
    [6, 14],
    [8, 1],
    [4, 2],
    [2, 12],
    [0, 8],
    [15, 4],
    [14, 15],
    [1, 0],
];

impl SamplePattern {
    /// One sample at the pixel centre: single-sample rasterization.
    pub const CENTRE: Self = Self {
        positions: &POSITIONS_1,
    };

    /// The sample counts with a standard pattern.
    pub const COUNTS: [u32; 5] = [1, 2, 4, 8, 16];

    /// The standard pattern of `count` samples (Vulkan's "Standard sample locations").
    ///
    /// # Errors
    /// A count other than 1, 2, 4, 8 or 16, named in the message.
    pub fn standard(count: u32) -> Result<Self, SampleError> {
        let positions: &'static [[u8; 2]] = match count {
            1 => &POSITIONS_1,
            2 => &POSITIONS_2,
            4 => &POSITIONS_4,
            8 => &POSITIONS_8,
            16 => &POSITIONS_16,
            _ => return Err(SampleError::NotStandard { count }),
        };
        Ok(Self { positions })
    }

    /// A pattern of other positions (1/16 pixel from the pixel's upper-left corner, y down, in
    /// sample-index order): not a standard pattern, for checks that a rasterizer's coverage
    /// tells patterns apart (the wgpu backend's counting pass compares the GPU against a
    /// mirrored pattern too).
    ///
    /// # Errors
    /// No position or more than 16, a coordinate past 15, or a position repeated.
    pub fn custom(positions: &'static [[u8; 2]]) -> Result<Self, SampleError> {
        if positions.is_empty() || positions.len() > 16 {
            return Err(SampleError::PositionCount {
                count: positions.len(),
            });
        }
        if let Some(&position) = positions.iter().find(|p| p[0] > 15 || p[1] > 15) {
            return Err(SampleError::OutsidePixel { position });
        }
        let mut sorted = positions.to_vec();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(SampleError::Repeated { position: w[0] });
        }
        Ok(Self { positions })
    }

    /// Samples per pixel.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "a pattern has at most 16 positions (SamplePattern::custom)"
    )]
    pub fn count(self) -> u32 {
        self.positions.len() as u32
    }

    /// Sample positions in 1/16 pixel from the pixel's upper-left corner, in sample-index order.
    #[must_use]
    pub fn positions(self) -> &'static [[u8; 2]] {
        self.positions
    }

    /// Sample `index`'s offset from the pixel's upper-left corner in fragsim's fixed point (1/256
    /// pixel, [`SUBPIXEL_BITS`](crate::SUBPIXEL_BITS) fractional bits).
    #[must_use]
    pub fn fixed_offset(self, index: usize) -> [i64; 2] {
        let [x, y] = self.positions[index];
        [i64::from(x) << 4, i64::from(y) << 4]
    }

    /// The smallest and largest fixed-point offset along each axis: `[[min_x, min_y], [max_x,
    /// max_y]]` (what bounds the pixels a triangle's box can reach).
    #[must_use]
    pub fn fixed_extent(self) -> [[i64; 2]; 2] {
        let offsets = (0..self.positions.len()).map(|i| self.fixed_offset(i));
        offsets.fold([[i64::MAX; 2], [i64::MIN; 2]], |[lo, hi], o| {
            [
                [lo[0].min(o[0]), lo[1].min(o[1])],
                [hi[0].max(o[0]), hi[1].max(o[1])],
            ]
        })
    }

    /// The sample-expanded framebuffer of `pixels`: `count` columns a pixel.
    ///
    /// # Errors
    /// An expanded width beyond [`Viewport::MAX_SIDE`] ([`SampleError::TooWide`]).
    pub fn expand(self, pixels: Viewport) -> Result<Viewport, SampleError> {
        let columns = u64::from(pixels.width) * u64::from(self.count());
        let width = u32::try_from(columns)
            .ok()
            .filter(|&w| w <= Viewport::MAX_SIDE)
            .ok_or(SampleError::TooWide {
                width: pixels.width,
                samples: self.count(),
                columns,
            })?;
        Ok(Viewport::new(width, pixels.height)?)
    }
}

impl Default for SamplePattern {
    fn default() -> Self {
        Self::CENTRE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_standard_pattern_has_distinct_positions_inside_the_pixel() {
        for count in SamplePattern::COUNTS {
            let pattern = SamplePattern::standard(count).unwrap();
            assert_eq!(pattern.count(), count);
            let mut seen = pattern.positions().to_vec();
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen.len(), count as usize, "{count}: repeated position");
            assert!(pattern.positions().iter().all(|p| p[0] < 16 && p[1] < 16));
        }
    }

    #[test]
    fn one_sample_is_the_pixel_centre_and_other_counts_are_refused_by_name() {
        assert_eq!(SamplePattern::standard(1).unwrap(), SamplePattern::CENTRE);
        assert_eq!(SamplePattern::CENTRE.fixed_offset(0), [128, 128]);
        for bad in [0, 3, 32] {
            let error = SamplePattern::standard(bad).unwrap_err();
            assert_eq!(error, SampleError::NotStandard { count: bad });
            assert!(error.to_string().contains(&bad.to_string()), "{error}");
        }
    }

    #[test]
    fn custom_patterns_are_checked() {
        static MIRRORED_4: [[u8; 2]; 4] = [[6, 14], [14, 10], [2, 6], [10, 2]];
        assert_eq!(SamplePattern::custom(&MIRRORED_4).unwrap().count(), 4);
        assert!(SamplePattern::custom(&[]).is_err());
        assert!(SamplePattern::custom(&[[16, 0]]).is_err());
        assert!(SamplePattern::custom(&[[3, 3], [3, 3]]).is_err());
    }

    #[test]
    fn expansion_multiplies_the_width_and_refuses_past_the_largest_side() {
        let four = SamplePattern::standard(4).unwrap();
        let expanded = four.expand(Viewport::new(10, 3).unwrap()).unwrap();
        assert_eq!((expanded.width, expanded.height), (40, 3));
        let sixteen = SamplePattern::standard(16).unwrap();
        assert!(sixteen.expand(Viewport::new(2048, 1).unwrap()).is_err());
        assert_eq!(four.fixed_extent(), [[32, 32], [224, 224]]);
    }
}
