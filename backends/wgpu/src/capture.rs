//! One capture on the GPU: a view's geometry drawn through a scheme's WGSL fragment shader, its
//! per-pixel buffers read back as a fragsim dump (`docs/dump-format.md`).
//!
//! Two ways in ([`Mode`]): **replay** draws fragsim's own screen triangles
//! (`View::screen_triangles`: transformed in f64, clipped and snapped to 1/256 pixel) as clip
//! coordinates with `w = 1` that a power-of-two viewport maps back to the same window positions
//! with no rounding, so the GPU scans exactly fragsim's triangles; **engine** draws the mesh with
//! the orbit camera's view-projection matrix rounded to f32 in the vertex shader, as an engine
//! does (Vulkan conventions: upper-left origin, depth in [0, 1], the f32 vertex stage). Depth is
//! the GPU's own interpolation in both modes (`@builtin(position).z`).
//!
//! **Per sample** ([`capture_samples`]): at N > 1 samples a pixel the colour target is
//! multisampled and the scheme's per-sample variant (`schemes/*_samples.wgsl`) draws: its entry
//! points read `@builtin(sample_index)`, so the pipeline shades once per covered sample, and each
//! sample's fragment goes to its own list `pixel · N + sample` with the depth of a varying
//! interpolated at the sample (`@interpolate(linear, sample)` of the clip `z / w`: window depth is
//! affine in the window, so screen-linear interpolation at the sample position is the depth plane
//! there, fragsim's per-sample depth, `docs/semantics.md` §11; `position.z` is the pixel
//! centre's on the H200). The dump is the scheme's single-sample layout over the sample-expanded
//! framebuffer, its scene declaring `conventions.samples` N (`docs/dump-format.md`).
//!
//! A scheme is a list of passes ([`Pass`](crate::shaders::Pass): draws and compute dispatches)
//! over its storage buffers, in one submission, read back at its end (`capture/run.rs`); the
//! exact A-buffer first runs its counting passes in a submission of their own and reads back the
//! prefix sum's total, which sizes its slots (the GPU's count, never the oracle's).
//!
//! Guarantee: the dump holds every word the shader left, bit for bit (nothing is repaired on
//! the way back); bad requests (a replay viewport that is not a power of two, a buffer past the
//! adapter's limits, a feature the adapter lacks) are errors naming the problem.

use std::collections::BTreeMap;

use fragsim_dump::{ArraySpec, Dtype, Dump, Header, Words, FORMAT, VERSION};
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::scene_spec::{SceneSpec, ViewProjection};
use fragsim_raster::{Conventions, View};

use crate::device::{Gpu, GpuError};
use crate::plant::Plant;
use crate::shaders::{GpuScheme, Storage};
use run::execute_geometry;
pub(crate) use run::RunResult;

mod run;

/// How the geometry reaches the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// fragsim's snapped screen triangles (coverage identical to fragsim's by construction).
    Replay,
    /// The mesh and the view-projection matrix in f32 in the vertex shader.
    Engine,
}

impl Mode {
    /// The name used on the command line and in dumps.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Replay => "replay",
            Self::Engine => "engine",
        }
    }
}

/// A capture's dump and what it cost.
#[derive(Debug)]
pub struct Captured {
    /// The dump (header and arrays), ready to write or compare.
    pub dump: Dump,
    /// The passes on the GPU, from the first one's start to the last one's end by timestamps
    /// (when the adapter has them), summed over the submissions.
    pub gpu_ms: Option<f64>,
    /// Each submission to the end of its read-back, on the host, summed.
    pub wall_ms: f64,
    /// Triangles drawn (screen triangles in replay mode, mesh triangles in engine mode).
    pub triangles: u32,
}

/// The vertex and index data of one draw.
struct Geometry {
    vertices: Vec<u8>,
    stride: u64,
    indices: Option<Vec<u32>>,
    count: u32,
    view_projection: [f32; 16],
}

/// Replay vertices: clip `(X / (128 W) − 1, 1 − Y / (128 H), z, 1)` (20 bytes with the primitive
/// id). With `W` and `H` powers of two and `|X|, |Y| ≤ 2^23` both coordinates are exact in f32
/// and the viewport transform `(x + 1) W / 2` gives `X / 256` back exactly.
fn replay_geometry(view: &View<'_>) -> Result<Geometry, GpuError> {
    replay_geometry_of(view, 0..view.triangle_count())
}

/// [`replay_geometry`] of the primitives `prims` of `view` alone (each with all its screen
/// triangles).
fn replay_geometry_of(
    view: &View<'_>,
    prims: impl IntoIterator<Item = u32>,
) -> Result<Geometry, GpuError> {
    let viewport = view.viewport();
    if !viewport.width.is_power_of_two() || !viewport.height.is_power_of_two() {
        return Err(GpuError::Refused(format!(
            "replay mode needs power-of-two viewport sides (exact clip coordinates), not {}x{}",
            viewport.width, viewport.height
        )));
    }
    let (sx, sy) = (
        128.0 * f64::from(viewport.width),
        128.0 * f64::from(viewport.height),
    );
    let mut vertices = Vec::new();
    let mut count = 0_u32;
    for prim in prims {
        view.screen_triangles(prim, &mut |t| {
            for (xy, z) in t.xy.iter().zip(t.z) {
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "vertex positions are f32, as the GPU's vertex buffer holds them"
                )]
                let x = (xy[0] as f64 / sx - 1.0) as f32;
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "vertex positions are f32, as the GPU's vertex buffer holds them"
                )]
                let y = (1.0 - xy[1] as f64 / sy) as f32;
                #[expect(
                    clippy::cast_possible_truncation,
                    reason = "vertex positions are f32, as the GPU's vertex buffer holds them"
                )]
                for v in [x, y, z as f32, 1.0] {
                    vertices.extend_from_slice(&v.to_le_bytes());
                }
                vertices.extend_from_slice(&t.prim.to_le_bytes());
            }
            count += 1;
        });
    }
    Ok(Geometry {
        vertices,
        stride: 20,
        indices: None,
        count,
        view_projection: view.view_projection().as_mat4().to_cols_array(),
    })
}

/// Engine vertices: the mesh's f32 positions and its triangles as an index buffer, so that
/// `primitive_index` is the mesh's primitive id.
fn engine_geometry(view: &View<'_>) -> Geometry {
    let mesh = view.mesh();
    let vertices = mesh
        .positions
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    Geometry {
        vertices,
        stride: 12,
        indices: Some(mesh.triangles.iter().flatten().copied().collect()),
        count: view.triangle_count(),
        view_projection: view.view_projection().as_mat4().to_cols_array(),
    }
}

/// Runs `scheme` over `view` in `mode` and reads its buffers back as a dump naming `scene`.
///
/// # Errors
/// As the module says: a feature the adapter lacks, a replay viewport that is not a power of
/// two, a buffer past the adapter's limits, a shader the device refuses, a failed read-back.
pub fn capture(
    gpu: &Gpu,
    view: &View<'_>,
    scene: SceneSpec,
    scheme: &GpuScheme,
    mode: Mode,
) -> Result<Captured, GpuError> {
    capture_samples(gpu, view, scene, scheme, mode, None, 1)
}

/// [`capture`] with a planted bug's shader variant ([`Plant`]); `None` is the correct shader.
/// The dump names the scheme as the correct one would (its `extra` names the plant), so that
/// `compare` judges it by what it claims to be.
///
/// # Errors
/// As [`capture`], and a plant that does not apply to the scheme ([`Plant::check`]).
pub fn capture_planted(
    gpu: &Gpu,
    view: &View<'_>,
    scene: SceneSpec,
    scheme: &GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
) -> Result<Captured, GpuError> {
    capture_samples(gpu, view, scene, scheme, mode, plant, 1)
}

/// [`capture_planted`] at `samples` a pixel: at more than one, per sample (the module says how),
/// the dump's scene declaring the sample count. `view` is the single-sample view (the geometry
/// drawn); the GPU samples at its own positions, which the verdict takes for Vulkan's standard
/// ones.
///
/// # Errors
/// As [`capture_planted`], and a sample count the adapter's target cannot render at, a scheme
/// without a per-sample variant at more than one sample ([`GpuScheme::captures_at`]), a view that
/// already rasterizes per sample, a plant that cannot show at `samples` ([`Plant::check_at`]).
pub fn capture_samples(
    gpu: &Gpu,
    view: &View<'_>,
    mut scene: SceneSpec,
    scheme: &GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
    samples: u32,
) -> Result<Captured, GpuError> {
    if let GpuScheme::SampleCounts = scheme {
        return Err(GpuError::Refused(format!(
            "{} is a pass, not a capture scheme: it has no dump layout",
            scheme.name()
        )));
    }
    if !scheme.captures_at(samples) {
        return Err(GpuError::Refused(format!(
            "{} has no per-sample variant: it captures at 1 sample a pixel, not {samples}",
            scheme.name()
        )));
    }
    if view.samples().is_some() {
        return Err(GpuError::Refused(
            "a per-sample capture draws a single-sample view into a multisampled target".into(),
        ));
    }
    if let Some(plant) = plant {
        plant.check_at(scheme, samples)?;
    }
    let (run, triangles) = execute(gpu, view, scheme, mode, plant, samples)?;
    let (storages, words, gpu_ms, wall_ms) = run;
    scene.conventions.samples = samples;
    let dump = to_dump(
        gpu, view, scene, scheme, mode, plant, triangles, &storages, words, gpu_ms, wall_ms,
    )?;
    Ok(Captured {
        dump,
        gpu_ms,
        wall_ms,
        triangles,
    })
}

/// Draws `view` into a target of `samples` a pixel in `mode` through `scheme`'s passes (the
/// per-sample variant's draws past one sample, the counting pass's own) and reads its storages
/// back, a list per pixel or per (pixel, sample); with the triangles drawn.
///
/// # Errors
/// As [`capture`]: a feature or sample count the adapter lacks, a replay viewport that is not a
/// power of two, a buffer past the adapter's limits, a shader the device refuses, a failed
/// read-back.
pub(crate) fn execute(
    gpu: &Gpu,
    view: &View<'_>,
    scheme: &GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
    samples: u32,
) -> Result<(RunResult, u32), GpuError> {
    let geometry = match mode {
        Mode::Replay => replay_geometry(view)?,
        Mode::Engine => engine_geometry(view),
    };
    Ok((
        execute_geometry(gpu, view, &geometry, scheme, mode, plant, samples)?,
        geometry.count,
    ))
}

/// [`execute`] in replay mode with only the primitives `prims` of `view` drawn (what the
/// counting pass's diagnosis draws alone, `crate::sample_counts::count_samples_of`).
///
/// # Errors
/// As [`execute`].
pub(crate) fn execute_replay_of(
    gpu: &Gpu,
    view: &View<'_>,
    prims: &[u32],
    scheme: &GpuScheme,
    samples: u32,
) -> Result<RunResult, GpuError> {
    let geometry = replay_geometry_of(view, prims.iter().copied())?;
    execute_geometry(gpu, view, &geometry, scheme, Mode::Replay, None, samples)
}

/// The u64 words of an array read back as (low, high) u32 pairs.
fn pairs_to_u64(words: &[u32]) -> Vec<u64> {
    words
        .chunks_exact(2)
        .map(|p| u64::from(p[0]) | (u64::from(p[1]) << 32))
        .collect()
}

fn to_dump(
    gpu: &Gpu,
    view: &View<'_>,
    scene: SceneSpec,
    scheme: &GpuScheme,
    mode: Mode,
    plant: Option<Plant>,
    triangles: u32,
    storages: &[Storage],
    words: Vec<Vec<u32>>,
    gpu_ms: Option<f64>,
    wall_ms: f64,
) -> Result<Dump, GpuError> {
    let viewport = view.viewport();
    let mut arrays = BTreeMap::new();
    let mut specs = BTreeMap::new();
    #[expect(
        clippy::shadow_unrelated,
        reason = "each dumped storage's own words, of the read-back `words`"
    )]
    for (storage, words) in storages.iter().zip(words).filter(|(s, _)| s.dumped) {
        let (data, ext) = match storage.dtype {
            Dtype::U32 => (Words::U32(words), "u32"),
            Dtype::U64 => (Words::U64(pairs_to_u64(&words)), "u64"),
        };
        specs.insert(
            storage.name.to_string(),
            ArraySpec {
                file: format!("{}.{ext}", storage.name),
                dtype: storage.dtype,
                shape: storage.shape.clone(),
            },
        );
        arrays.insert(storage.name.to_string(), data);
    }
    // The dump names the engine's matrix and conventions, so that compare rebuilds the oracle
    // the engine's way. Replay mode draws fragsim's own snapped triangles: reference.
    let scene = match mode {
        Mode::Engine => engine_scene(scene, view),
        Mode::Replay => scene,
    };
    let scene_samples = scene.conventions.samples;
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        producer: format!(
            "fragsim-wgpu {} ({} mode, {}{})",
            env!("CARGO_PKG_VERSION"),
            mode.name(),
            scheme.name(),
            plant.map_or(String::new(), |p| format!(", planted bug {}", p.name()))
        ),
        scene,
        width: viewport.width,
        height: viewport.height,
        scheme: scheme.layout().into(),
        k: scheme.k(),
        capacity: scheme.capacity(),
        sorted: scheme.sorted(),
        filled: scheme.filled(),
        word: scheme.word().into(),
        pool: scheme.pool(viewport.pixels() as u64 * u64::from(scene_samples)),
        layers: None,
        layout: scheme.layout_spec(),
        arrays: specs,
        extra: serde_json::json!({
            "device": gpu.info.name,
            "driver": format!("{} {}", gpu.info.driver, gpu.info.driver_info),
            "mode": mode.name(),
            "shader": scheme.name(),
            "plant": plant.map(Plant::name),
            "triangles_drawn": triangles,
            "timings": {"gpu_ms": gpu_ms, "wall_ms": wall_ms},
        }),
    };
    Ok(Dump { header, arrays })
}

/// `scene` as engine mode draws `view`: the orbit camera's matrix rounded to f32 (what
/// `vs_engine` multiplies by) and Vulkan's conventions with the f32 vertex stage (upper-left
/// origin, depth in [0, 1]), the sample count kept; the scene fragsim rebuilds an engine
/// capture's oracle from.
#[must_use]
pub fn engine_scene(mut scene: SceneSpec, view: &View<'_>) -> SceneSpec {
    let m = view.view_projection().as_mat4().to_cols_array();
    // Row-major, as a reader writes a matrix down (glam's arrays are column-major).
    scene.view_projection = Some(ViewProjection {
        row_major: std::array::from_fn(|i| f64::from(m[(i % 4) * 4 + i / 4])),
        precision: VertexPrecision::F32,
    });
    scene.conventions = Conventions {
        vertex_precision: VertexPrecision::F32,
        samples: scene.conventions.samples,
        ..Conventions::REFERENCE
    };
    scene
}
