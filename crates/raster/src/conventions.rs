//! The rasterization conventions an implementation declares: the parameters of fragsim's pipeline
//! that differ between graphics APIs and hardware generations.
//!
//! fragsim's reference pipeline (`docs/semantics.md`) is one point in this space, the default:
//! upper-left window origin (D3D, Vulkan, WebGPU), 8 subpixel bits, clip-space depth in `[0, 1]`,
//! vertices transformed in f64. An engine's capture names its own point (an OpenGL engine: lower-left
//! origin and depth in `[−1, 1]`; any vertex shader: f32), and the oracle is rebuilt under it, so
//! that a conforming implementation and the oracle disagree only where precision allows
//! (`docs/semantics.md`, "Conventions", gives each rule and the specification it comes from).
//!
//! [`View::with_conventions`](crate::View::with_conventions) rasterizes under any of them;
//! [`View::new`](crate::View::new) keeps [`Conventions::REFERENCE`], bit for bit the pipeline
//! fragsim had before conventions existed. In JSON (a dump header's `scene.conventions`) each
//! field is optional and defaults to the reference's, the enums are spelled in kebab case
//! (`"lower-left"`, `"minus-one-to-one"`, `"f32"`) and an unknown field is refused.
//!
//! The sample count ([`Conventions::samples`]) is one of them: an implementation that renders
//! with N samples a pixel at the standard pattern ([`SamplePattern::standard`]) declares N, and
//! [`View::with_conventions`](crate::View::with_conventions) then rasterizes per sample into the
//! sample-expanded framebuffer (`docs/semantics.md`, "Multisampling"). One sample, the default,
//! is the single-sample pipeline, and a header without the field is written and read as before.

use serde::{Deserialize, Serialize};

use crate::samples::{SampleError, SamplePattern};

/// Why fragsim cannot rasterize a view under some conventions.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConventionsError {
    /// Subpixel bits outside `1..=MAX_SUBPIXEL_BITS`.
    #[error("{bits} subpixel bits: fragsim rasterizes with 1 to {MAX_SUBPIXEL_BITS}")]
    SubpixelBits {
        /// The bits declared.
        bits: u32,
    },
    /// A sample count without a standard pattern.
    #[error(
        "conventions \"samples\" {samples}: the standard sample patterns have 1, 2, 4, 8 or 16 \
         samples a pixel"
    )]
    Samples {
        /// The count declared.
        samples: u32,
    },
    /// Under f32 vertex precision, the view's vertex stage would leave f32's normal range.
    #[error(transparent)]
    F32Range(#[from] F32RangeError),
    /// The sample-expanded framebuffer cannot be made (too wide).
    #[error(transparent)]
    Sampling(#[from] SampleError),
}

/// A view whose f32 vertex stage would leave f32's normal range
/// ([`View::check_f32_range`](crate::View::check_f32_range)): the first entry of the
/// view-projection matrix whose product with a vertex coordinate (or which, as a translation
/// entry, alone) is nonzero and below `f32::MIN_POSITIVE` or above `f32::MAX` in magnitude.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "view_projection.row_major[{index}] is {entry:e}: under an f32 vertex stage its \
     product{times} is {product:e}, outside f32's normal range ({min:e} to {max:e}; a GPU \
     may flush subnormals to zero)",
    times = factor_words(self.vertex),
    min = f32::MIN_POSITIVE,
    max = f32::MAX
)]
pub struct F32RangeError {
    /// The entry's index, row by row.
    pub index: usize,
    /// The entry.
    pub entry: f64,
    /// The vertex whose coordinate the entry multiplies, and that coordinate's name (`x`, `y`
    /// or `z`); `None` for a translation entry, which multiplies no coordinate.
    pub vertex: Option<(usize, &'static str)>,
    /// The product out of range (the entry itself for a translation entry).
    pub product: f64,
}

/// The words naming the vertex coordinate an entry multiplies, for [`F32RangeError`]'s message.
fn factor_words(vertex: Option<(usize, &str)>) -> String {
    vertex.map_or(String::new(), |(v, axis)| {
        format!(" times vertex {v}'s {axis}")
    })
}

/// Where window row 0 lies, which decides which edge the fill rule gives a shared pixel centre.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WindowOrigin {
    /// Row 0 at the top, y grows downwards (D3D, Vulkan, WebGPU, Metal): fragsim's pixel order.
    #[default]
    UpperLeft,
    /// Row 0 at the bottom, y grows upwards (OpenGL's default `glClipControl(GL_LOWER_LEFT, …)`).
    LowerLeft,
}

impl WindowOrigin {
    /// The origin as a dump header spells it (`upper-left`, `lower-left`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::UpperLeft => "upper-left",
            Self::LowerLeft => "lower-left",
        }
    }
}

/// The clip-space depth range that maps to window depth `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthRange {
    /// `0 ≤ z ≤ w`, window depth `z / w` (D3D, Vulkan, WebGPU, Metal).
    #[default]
    ZeroToOne,
    /// `−w ≤ z ≤ w`, window depth `(z / w + 1) / 2` (OpenGL's default `GL_NEGATIVE_ONE_TO_ONE`).
    MinusOneToOne,
}

impl DepthRange {
    /// The range as a dump header spells it (`zero-to-one`, `minus-one-to-one`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::ZeroToOne => "zero-to-one",
            Self::MinusOneToOne => "minus-one-to-one",
        }
    }
}

/// The arithmetic of the vertex stage (transform, perspective divide, viewport mapping).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VertexPrecision {
    /// f64 throughout: fragsim's reference, exact enough that snapping decides alone.
    #[default]
    F64,
    /// f32, as a vertex shader computes: the matrix and positions rounded to f32, each product and
    /// sum rounded to f32.
    F32,
}

impl VertexPrecision {
    /// The arithmetic as a dump header spells it (`f64`, `f32`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::F64 => "f64",
            Self::F32 => "f32",
        }
    }
}

/// Which edges own a sample lying exactly on them (an edge function of 0), in the API's own window
/// (the one [`WindowOrigin`] names: y down for an upper-left origin, y up for a lower-left one).
/// Vulkan and OpenGL leave the choice to the implementation, requiring only that a sample on an
/// edge shared by two triangles belong to exactly one of them; D3D fixes the top-left rule.
/// "Top" is a horizontal edge with the triangle below it in that window, "left" a non-horizontal
/// edge with the triangle to its right.
///
/// fragsim's pipeline rasterizes with the top-left rule of the declared window whatever this says
/// (`docs/semantics.md` §4 and §9); the oracle's verdict owes the declared rule, and where none is
/// declared accepts any one of the four, the same one throughout a capture
/// (`fragsim_oracle::edge_ties`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EdgeTies {
    /// Top and left edges own their samples (D3D's rule, fragsim's pipeline).
    TopLeft,
    /// Top and right edges.
    TopRight,
    /// Bottom and left edges.
    BottomLeft,
    /// Bottom and right edges.
    BottomRight,
}

impl EdgeTies {
    /// The four rules.
    pub const ALL: [Self; 4] = [
        Self::TopLeft,
        Self::TopRight,
        Self::BottomLeft,
        Self::BottomRight,
    ];

    /// Whether horizontal edges with the triangle below them own their samples.
    #[must_use]
    pub fn top(self) -> bool {
        matches!(self, Self::TopLeft | Self::TopRight)
    }

    /// Whether non-horizontal edges with the triangle to their right own their samples.
    #[must_use]
    pub fn left(self) -> bool {
        matches!(self, Self::TopLeft | Self::BottomLeft)
    }

    /// The rule with `top` and `left` as given.
    #[must_use]
    pub fn of(top: bool, left: bool) -> Self {
        match (top, left) {
            (true, true) => Self::TopLeft,
            (true, false) => Self::TopRight,
            (false, true) => Self::BottomLeft,
            (false, false) => Self::BottomRight,
        }
    }

    /// The rule as its JSON spells it (`top-left`, …).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::TopLeft => "top-left",
            Self::TopRight => "top-right",
            Self::BottomLeft => "bottom-left",
            Self::BottomRight => "bottom-right",
        }
    }
}

/// The conventions under which a scene was rasterized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Conventions {
    /// Where row 0 lies.
    pub window_origin: WindowOrigin,
    /// Fractional bits of the snapped vertex grid, 1 to [`MAX_SUBPIXEL_BITS`] (8 on current
    /// hardware and Vulkan's common `subPixelPrecisionBits`, 4 on older hardware).
    pub subpixel_bits: u32,
    /// The clip-space depth range.
    pub depth_range: DepthRange,
    /// The vertex stage's arithmetic.
    pub vertex_precision: VertexPrecision,
    /// Samples a pixel at the standard pattern ([`SamplePattern::COUNTS`]: 1, 2, 4, 8 or 16);
    /// 1: one sample at the pixel centre, the single-sample pipeline. Left out of JSON at 1, so
    /// that a header written without it reads, and is written back, as before.
    #[serde(skip_serializing_if = "is_one")]
    pub samples: u32,
    /// The rule that decides a sample exactly on an edge, when the implementation declares one
    /// ([`EdgeTies`]); absent: undeclared, any one rule for the whole capture.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_ties: Option<EdgeTies>,
}

#[allow(
    clippy::trivially_copy_pass_by_ref,
    reason = "serde's `skip_serializing_if` takes a reference"
)]
fn is_one(samples: &u32) -> bool {
    *samples == 1
}

/// The most subpixel bits fragsim's fixed-point grid holds ([`crate::SUBPIXEL_BITS`]).
pub const MAX_SUBPIXEL_BITS: u32 = crate::viewport::SUBPIXEL_BITS;

impl Conventions {
    /// fragsim's reference conventions: upper-left, 8 subpixel bits, `[0, 1]`, f64.
    pub const REFERENCE: Self = Self {
        window_origin: WindowOrigin::UpperLeft,
        subpixel_bits: MAX_SUBPIXEL_BITS,
        depth_range: DepthRange::ZeroToOne,
        vertex_precision: VertexPrecision::F64,
        samples: 1,
        edge_ties: None,
    };

    /// Whether these are the reference conventions (a header then leaves them out).
    #[must_use]
    pub fn is_reference(&self) -> bool {
        *self == Self::REFERENCE
    }

    /// Refuses conventions fragsim cannot rasterize under.
    ///
    /// # Errors
    /// Subpixel bits outside `1..=MAX_SUBPIXEL_BITS`, or a sample count without a standard
    /// pattern, by value and field name.
    pub fn check(&self) -> Result<(), ConventionsError> {
        if !(1..=MAX_SUBPIXEL_BITS).contains(&self.subpixel_bits) {
            return Err(ConventionsError::SubpixelBits {
                bits: self.subpixel_bits,
            });
        }
        self.pattern().map(|_| ())
    }

    /// The sample pattern of [`Conventions::samples`]: `None` for one sample (the single-sample
    /// scan at pixel centres), else the standard pattern of that count.
    ///
    /// # Errors
    /// A count other than 1, 2, 4, 8 or 16, naming the field `samples`.
    pub fn pattern(&self) -> Result<Option<SamplePattern>, ConventionsError> {
        match self.samples {
            1 => Ok(None),
            samples => SamplePattern::standard(samples)
                .map(Some)
                .map_err(|_| ConventionsError::Samples { samples }),
        }
    }
}

impl Conventions {
    /// The fields that are not the reference's, as a dump header's `conventions` object spells
    /// them (`{"window_origin": "lower-left", "samples": 4}`), so that a report names them in
    /// the words a user writes; `{}` for the reference conventions.
    #[must_use]
    pub fn describe(&self) -> String {
        let reference = Self::REFERENCE;
        let quoted = |name: &str| format!("\"{name}\"");
        let fields = [
            (self.window_origin != reference.window_origin)
                .then(|| ("window_origin", quoted(self.window_origin.name()))),
            (self.subpixel_bits != reference.subpixel_bits)
                .then(|| ("subpixel_bits", self.subpixel_bits.to_string())),
            (self.depth_range != reference.depth_range)
                .then(|| ("depth_range", quoted(self.depth_range.name()))),
            (self.vertex_precision != reference.vertex_precision)
                .then(|| ("vertex_precision", quoted(self.vertex_precision.name()))),
            (self.samples != reference.samples).then(|| ("samples", self.samples.to_string())),
            self.edge_ties
                .map(|rule| ("edge_ties", quoted(rule.name()))),
        ];
        let fields: Vec<String> = fields
            .into_iter()
            .flatten()
            .map(|(field, value)| format!("\"{field}\": {value}"))
            .collect();
        format!("{{{}}}", fields.join(", "))
    }
}

impl Default for Conventions {
    fn default() -> Self {
        Self::REFERENCE
    }
}
