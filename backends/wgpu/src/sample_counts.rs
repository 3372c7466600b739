//! The per-sample counting pass on the GPU and its comparison with fragsim's per-sample oracle
//! (per-pixel sample counts identical to the hardware's).
//!
//! **The pass** ([`count_samples`]): a single-sample view drawn, in replay or engine mode as
//! every capture, into a colour target of `n` samples a pixel through
//! `schemes/sample_counts.wgsl`. Its fragment shader reads `@builtin(sample_index)`, which makes
//! the pipeline shade per sample (Vulkan: a shader using `SampleId` runs with sample shading at
//! `minSampleShading` 1.0), so every covered sample of every primitive is one invocation, which
//! adds 1 at `counts[pixel * n + sample]`. That is per-(pixel, sample) counting by construction.
//! The depth-range test is made on the depth interpolated at the sample (a varying with sample
//! interpolation), as fragsim makes it, not on `@builtin(position).z`: under sample shading the
//! H200 gives the shader the depth at the pixel centre, which for a sliver triangle beside the
//! centre lies far outside `[0, 1]` (measured: `docs/results-gpu.md`, "MSAA"), so a test on it
//! dropped covered samples. The pass counts those (`shader_depth_outside`), the evidence of that
//! convention. A per-pixel invocation counting the bits of `@builtin(sample_mask)` would cost
//! fewer invocations but sees the centre's depth too.
//!
//! **The reference** ([`reference_counts`]): fragsim's per-sample oracle
//! ([`SampleOracle`]) of the same view with a sample pattern: in replay mode the view itself
//! (the GPU scans fragsim's own snapped triangles), in engine mode the view of
//! [`engine_scene`](crate::capture::engine_scene) (the f32 matrix and the f32 vertex stage, where
//! the GPU's own vertex arithmetic may move an edge past a sample: identity is not owed there).
//!
//! **Engine mode's differences** ([`nearest_boundaries`]): a sample whose count differs there
//! must lie near a triangle's boundary, as the GPU's f32 vertex stage and fragsim's place each
//! vertex within the snap radius of its exact position ([`Precision`]'s bound), so within twice
//! that radius of each other, and an edge moves no further than its vertices. The command
//! measures each differing sample's distance to the nearest boundary in fragsim's view and
//! counts those within twice the radius: explained by vertex precision.
//!
//! **Sample positions.** wgpu neither sets nor reports sample positions (nor Vulkan's
//! `standardSampleLocations`, which only `unsafe` code could read through its raw handle). The
//! reference takes Vulkan's standard ones ([`SamplePattern::standard`]), which a driver uses when
//! `standardSampleLocations` is true. That the GPU uses them is checked by the counts
//! themselves: [`mirrored`] gives the standard
//! positions mirrored in y (a y-up rasterizer's `(x, 16 − y)`), and a scene's counts against
//! that pattern differ at the samples edges pass between the two positions
//! (`tests/msaa.rs` asserts it), so identity with the standard pattern tells the patterns apart.
//!
//! Guarantee: [`count_samples`] returns the words the shader left, bit for bit; a sample count
//! the adapter's target format lacks, or a view that already rasterizes per sample, is an error
//! naming it.

use fragsim_oracle::precision::Precision;
use fragsim_oracle::samples::SampleOracle;
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::{SampleError, SamplePattern, View, SUBPIXEL_BITS};

use crate::capture::{execute, execute_replay_of, Mode};
use crate::device::{Gpu, GpuError};
use crate::shaders::GpuScheme;

/// The GPU's fragment count at every sample of a view.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleCounts {
    /// Samples per pixel.
    pub samples: u32,
    /// Fragments at sample `s` of pixel `p` at `p * samples + s`, pixels row-major (the
    /// sample-expanded framebuffer's order, `docs/semantics.md`, "Multisampling").
    pub counts: Vec<u32>,
    /// Per sample as `counts`, the counted fragments whose shader-visible depth
    /// (`@builtin(position).z`) lies outside `[0, 1]` though the depth interpolated at the
    /// sample is inside: the GPU gives the shader the depth of another point than the sample
    /// (the H200: the pixel centre's).
    pub shader_depth_outside: Vec<u32>,
    /// Per sample as `counts`, the bits of the largest such shader-visible depth (0 where none).
    pub shader_depth_bits: Vec<u32>,
    /// The draw on the GPU, by timestamps where the adapter has them.
    pub gpu_ms: Option<f64>,
    /// The submission to the end of the read-back, on the host.
    pub wall_ms: f64,
    /// Triangles drawn (screen triangles in replay mode, mesh triangles in engine mode).
    pub triangles: u32,
}

/// Draws `view` in `mode` into a target of `samples` samples a pixel and counts the fragments of
/// every sample.
///
/// # Errors
/// A view that rasterizes per sample (the GPU target is the pixel viewport), a sample count the
/// adapter cannot render at, and [`capture()`](crate::capture())'s errors.
pub fn count_samples(
    gpu: &Gpu,
    view: &View<'_>,
    mode: Mode,
    samples: u32,
) -> Result<SampleCounts, GpuError> {
    if view.samples().is_some() {
        return Err(GpuError::Refused(
            "the counting pass draws a single-sample view into a multisampled target".into(),
        ));
    }
    let ((_, words, gpu_ms, wall_ms), triangles) =
        execute(gpu, view, &GpuScheme::SampleCounts, mode, None, samples)?;
    SampleCounts::read(samples, words, gpu_ms, wall_ms, triangles)
}

/// [`count_samples`] in replay mode with only the primitives `prims` of `view` drawn: the
/// diagnosis of a differing sample, whose covering triangles are drawn alone, each by itself,
/// to tell a rasterizer that misses the sample from one whose result depends on the rest of
/// the scene.
///
/// # Errors
/// As [`count_samples`].
#[expect(
    clippy::cast_possible_truncation,
    reason = "a replay's triangles are below View::triangle_count, a u32"
)]
pub fn count_samples_of(
    gpu: &Gpu,
    view: &View<'_>,
    prims: &[u32],
    samples: u32,
) -> Result<SampleCounts, GpuError> {
    let (_, words, gpu_ms, wall_ms) =
        execute_replay_of(gpu, view, prims, &GpuScheme::SampleCounts, samples)?;
    SampleCounts::read(samples, words, gpu_ms, wall_ms, prims.len() as u32)
}

impl SampleCounts {
    /// The counting pass's one storage (three arrays of samples, `sample_counts.wgsl`) split.
    fn read(
        samples: u32,
        mut words: Vec<Vec<u32>>,
        gpu_ms: Option<f64>,
        wall_ms: f64,
        triangles: u32,
    ) -> Result<Self, GpuError> {
        let mut counts = words
            .pop()
            .ok_or_else(|| GpuError::Device("the counting pass read nothing back".into()))?;
        let n = counts.len() / 3;
        let shader_depth_bits = counts.split_off(2 * n);
        let shader_depth_outside = counts.split_off(n);
        Ok(Self {
            samples,
            counts,
            shader_depth_outside,
            shader_depth_bits,
            gpu_ms,
            wall_ms,
            triangles,
        })
    }
}

/// fragsim's fragment count at every sample of `view` rasterized at `pattern` (the per-sample
/// oracle's depth complexity), indexed as [`SampleCounts::counts`].
///
/// # Errors
/// An expanded framebuffer past fragsim's largest side.
pub fn reference_counts(view: &View<'_>, pattern: SamplePattern) -> Result<Vec<u32>, String> {
    let sampled = view
        .clone()
        .with_samples(pattern)
        .map_err(|e| e.to_string())?;
    Ok(SampleOracle::build(&sampled)
        .map_err(|e| e.to_string())?
        .oracle()
        .depth_complexity())
}

/// The primitives whose fragments fragsim's per-sample oracle of `view` at `pattern` holds at
/// each of `samples` (indices as [`SampleCounts::counts`]), nearest first.
///
/// # Errors
/// As [`reference_counts`].
#[expect(
    clippy::cast_possible_truncation,
    reason = "a word's low half is its primitive id"
)]
pub fn covering_prims(
    view: &View<'_>,
    pattern: SamplePattern,
    samples: &[usize],
) -> Result<Vec<Vec<u32>>, String> {
    let oracle = SampleOracle::build(
        &view
            .clone()
            .with_samples(pattern)
            .map_err(|e| e.to_string())?,
    )
    .map_err(|e| e.to_string())?;
    Ok(samples
        .iter()
        .map(|&i| oracle.oracle().pixel(i).iter().map(|&w| w as u32).collect())
        .collect())
}

/// `pattern`'s positions mirrored in y, `(x, 16 − y)`: where a rasterizer that took the standard
/// positions in y-up rows would sample. Each call leaks its positions (16 bytes at most for 8
/// samples; a pattern's positions are `'static`).
///
/// # Errors
/// A pattern with a position at `y = 0`, whose mirror would lie on the next pixel's edge.
pub fn mirrored(pattern: SamplePattern) -> Result<SamplePattern, SampleError> {
    let positions: Vec<[u8; 2]> = pattern
        .positions()
        .iter()
        .map(|&[x, y]| [x, 16 - y])
        .collect();
    SamplePattern::custom(Box::leak(positions.into_boxed_slice()))
}

/// A triangle boundary near a sample ([`nearest_boundaries`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Boundary {
    /// The triangle's primitive id.
    pub prim: u32,
    /// The distance from the sample to the triangle's boundary, in subpixels (1/256 pixel).
    pub subpixels: f64,
    /// Whether the sample lies inside the triangle.
    pub inside: bool,
}

/// The `count` triangle pieces of `view` whose boundaries pass nearest to sample `sample` of
/// pixel `(x, y)` at `pattern`'s position, nearest first (every piece, culled ones included:
/// distance is geometry, not coverage).
#[must_use]
pub fn nearest_boundaries(
    view: &View<'_>,
    pattern: SamplePattern,
    [x, y]: [u32; 2],
    sample: usize,
    count: usize,
) -> Vec<Boundary> {
    let one = f64::from(1_u32 << SUBPIXEL_BITS);
    let [ox, oy] = pattern.fixed_offset(sample);
    let p = [
        f64::from(x) * one + ox as f64,
        f64::from(y) * one + oy as f64,
    ];
    let mut near: Vec<Boundary> = Vec::new();
    for prim in 0..view.triangle_count() {
        view.screen_triangles(prim, &mut |tri| {
            let v = tri.xy.map(|[vx, vy]| [vx as f64, vy as f64]);
            let edges = [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])];
            let subpixels = edges
                .iter()
                .map(|&(a, b)| segment_distance(p, a, b))
                .fold(f64::INFINITY, f64::min);
            let sides =
                edges.map(|(a, b)| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]));
            let inside = sides.iter().all(|&e| e >= 0.0) || sides.iter().all(|&e| e <= 0.0);
            near.push(Boundary {
                prim: tri.prim,
                subpixels,
                inside,
            });
        });
        // Keep the list short: the nearest `count` so far.
        if near.len() > 4 * count.max(1) {
            near.sort_by(|a, b| a.subpixels.total_cmp(&b.subpixels));
            near.truncate(count);
        }
    }
    near.sort_by(|a, b| a.subpixels.total_cmp(&b.subpixels));
    near.truncate(count);
    near
}

/// Engine mode's differing samples against vertex precision: each one's nearest triangle
/// boundaries in fragsim's f32 view and the bound they are held to, twice the f32 snap radius
/// (the module's documentation says why).
#[derive(Clone, Debug, PartialEq)]
pub struct NearEdges {
    /// Twice the snap radius, in subpixels.
    pub bound_subpixels: f64,
    /// Per differing sample of the [`CountDiff`] (its examples, in order), the three nearest
    /// boundaries, nearest first.
    pub nearest: Vec<Vec<Boundary>>,
}

impl NearEdges {
    /// The examples of `diff` measured in `reference` (fragsim's f32 view, at `pattern`) against
    /// twice `snap_radius` ([`f32_snap_radius`]).
    #[must_use]
    pub fn of(
        reference: &View<'_>,
        pattern: SamplePattern,
        diff: &CountDiff,
        snap_radius: i64,
    ) -> Self {
        let nearest = diff
            .examples
            .iter()
            .map(|&[x, y, s, ..]| nearest_boundaries(reference, pattern, [x, y], s as usize, 3))
            .collect();
        Self {
            bound_subpixels: 2.0 * snap_radius as f64,
            nearest,
        }
    }

    /// The samples measured whose nearest boundary lies within the bound: explained by vertex
    /// precision.
    #[must_use]
    pub fn within(&self) -> usize {
        self.nearest
            .iter()
            .filter(|n| {
                n.first()
                    .is_some_and(|b| b.subpixels <= self.bound_subpixels)
            })
            .count()
    }
}

/// The distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length2 = dx * dx + dy * dy;
    let t = if length2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// The largest snap radius of an f32 vertex stage on `view`'s scene, in subpixels: how far the
/// GPU's snapped vertices (and fragsim's f32 ones) may lie from the exact ones ([`Precision`]'s
/// bound). `exact` is the view under the f64 vertex stage.
#[must_use]
pub fn f32_snap_radius(exact: &View<'_>) -> i64 {
    let f32_stage = fragsim_raster::Conventions {
        vertex_precision: VertexPrecision::F32,
        ..exact.conventions()
    };
    Precision::derive(exact, &f32_stage)
        .bounds()
        .max_snap_radius_subpixels
}

/// Where two per-sample counts of one view differ.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CountDiff {
    /// Samples compared.
    pub samples: u64,
    /// Samples whose counts differ.
    pub samples_differ: u64,
    /// Pixels compared.
    pub pixels: u64,
    /// Pixels whose sums over their samples differ.
    pub pixels_differ: u64,
    /// Sample fragments the GPU counted.
    pub gpu_fragments: u64,
    /// Sample fragments of the reference.
    pub reference_fragments: u64,
    /// The first differing samples: (x, y, sample, GPU count, reference count).
    pub examples: Vec<[u32; 5]>,
}

impl CountDiff {
    /// `gpu` against `reference` (both indexed as [`SampleCounts::counts`]) over a target
    /// `width` pixels wide at `samples` a pixel, keeping the first `examples` differing samples.
    ///
    /// # Panics
    /// If the two cover different numbers of samples, or not whole pixels.
    #[must_use]
    #[expect(
        clippy::cast_possible_truncation,
        reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new); sample indices are below 16"
    )]
    pub fn of(gpu: &[u32], reference: &[u32], width: u32, samples: u32, examples: usize) -> Self {
        assert_eq!(gpu.len(), reference.len(), "sample counts differ");
        let n = samples as usize;
        assert_eq!(gpu.len() % n, 0, "not whole pixels");
        let mut diff = Self {
            samples: gpu.len() as u64,
            pixels: (gpu.len() / n) as u64,
            gpu_fragments: gpu.iter().map(|&c| u64::from(c)).sum(),
            reference_fragments: reference.iter().map(|&c| u64::from(c)).sum(),
            ..Self::default()
        };
        for (pixel, (got, want)) in gpu.chunks(n).zip(reference.chunks(n)).enumerate() {
            let sum = |c: &[u32]| c.iter().map(|&v| u64::from(v)).sum::<u64>();
            diff.pixels_differ += u64::from(sum(got) != sum(want));
            for (s, (&g, &w)) in got.iter().zip(want).enumerate() {
                if g == w {
                    continue;
                }
                diff.samples_differ += 1;
                if diff.examples.len() < examples {
                    let p = pixel as u32;
                    diff.examples.push([p % width, p / width, s as u32, g, w]);
                }
            }
        }
        diff
    }

    /// Whether every sample's count is the same.
    #[must_use]
    pub fn is_identical(&self) -> bool {
        self.samples_differ == 0
    }

    /// One line: the totals and the differing samples and pixels.
    #[must_use]
    pub fn summary(&self) -> String {
        format!(
            "{}: {} of {} samples differ, {} of {} pixels' sums differ; sample fragments: GPU {}, fragsim {}",
            if self.is_identical() {
                "IDENTICAL"
            } else {
                "DIFFERENT"
            },
            self.samples_differ,
            self.samples,
            self.pixels_differ,
            self.pixels,
            self.gpu_fragments,
            self.reference_fragments
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_are_counted_per_sample_and_per_pixel_sum() {
        // Two pixels of 4 samples, 2 wide: pixel 1's samples 0 and 1 trade a fragment (its sum
        // is unchanged), pixel 0's sample 3 loses one.
        let reference = [1, 1, 1, 1, 2, 0, 1, 1];
        let gpu = [1, 1, 1, 0, 1, 1, 1, 1];
        let diff = CountDiff::of(&gpu, &reference, 2, 4, 1);
        assert_eq!((diff.samples, diff.samples_differ), (8, 3));
        assert_eq!((diff.pixels, diff.pixels_differ), (2, 1));
        assert_eq!((diff.gpu_fragments, diff.reference_fragments), (7, 8));
        assert_eq!(diff.examples, [[0, 0, 3, 0, 1]]);
        assert!(!diff.is_identical());
        assert!(CountDiff::of(&gpu, &gpu, 2, 4, 1).is_identical());
    }

    #[test]
    fn near_edges_count_the_samples_within_twice_the_radius() {
        let at = |subpixels| {
            vec![Boundary {
                prim: 0,
                subpixels,
                inside: true,
            }]
        };
        let near = NearEdges {
            bound_subpixels: 2.0,
            nearest: vec![at(0.5), at(2.0), at(2.5), Vec::new()],
        };
        assert_eq!(near.within(), 2);
    }

    #[test]
    fn distances_to_a_segment_are_to_its_nearest_point() {
        let (a, b) = ([0.0, 0.0], [4.0, 0.0]);
        assert_eq!(segment_distance([2.0, 3.0], a, b), 3.0);
        assert_eq!(segment_distance([7.0, 4.0], a, b), 5.0);
        assert_eq!(segment_distance([1.0, 1.0], a, a), 2_f64.sqrt());
    }

    #[test]
    fn the_mirrored_patterns_are_other_positions() {
        for count in [2, 4, 8] {
            let standard = SamplePattern::standard(count).unwrap();
            let mirror = mirrored(standard).unwrap();
            assert_eq!(mirror.count(), count);
            let mut a = standard.positions().to_vec();
            let mut b = mirror.positions().to_vec();
            a.sort_unstable();
            b.sort_unstable();
            assert_ne!(a, b, "{count} samples: the mirror is the same set");
        }
    }
}
