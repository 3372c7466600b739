//! `fragsim-wgpu msaa-count` (a module of the binary, `main.rs`): its options, and the GPU's
//! per-sample fragment counts against fragsim's per-sample oracle for every view, mode and sample
//! count, with the triangles at differing samples drawn alone on request.

use std::path::PathBuf;

use clap::Args;
use fragsim_dump::DumpError;
use fragsim_raster::conventions::VertexPrecision;
use fragsim_raster::scene_spec::args::{degrees, elevation, side};
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::{SamplePattern, View, Viewport};
use fragsim_wgpu::capture::engine_scene;
use fragsim_wgpu::sample_counts::{
    count_samples, count_samples_of, covering_prims, f32_snap_radius, mirrored, reference_counts,
    CountDiff, NearEdges,
};
use fragsim_wgpu::{Gpu, Mode};

use crate::ModeArg;

/// Options of `fragsim-wgpu msaa-count`: every combination of views, modes and sample counts.
#[derive(Args)]
pub(crate) struct MsaaArgs {
    /// A mesh file (OBJ or PLY, optionally gzipped).
    #[arg(long, conflicts_with = "scene")]
    mesh: Option<PathBuf>,
    /// A named scene (bunny, bunny-spheres, spheres:N, soup, quads).
    #[arg(long, default_value = "bunny")]
    scene: String,
    /// Viewport width (a power of two in replay mode).
    #[arg(long, default_value_t = 512, allow_negative_numbers = true, value_parser = side())]
    width: u32,
    /// Viewport height (a power of two in replay mode).
    #[arg(long, default_value_t = 512, allow_negative_numbers = true, value_parser = side())]
    height: u32,
    /// Orbit angles, degrees, comma-separated.
    #[arg(long, default_value = "30", value_delimiter = ',', allow_negative_numbers = true,
          value_parser = degrees)]
    view: Vec<f64>,
    /// Elevation, degrees, within ±89.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true, value_parser = elevation)]
    elevation: f64,
    /// Samples per pixel, comma-separated: 1 (the control), 2, 4, 8 (Vulkan's standard
    /// patterns; the adapter's target format must render at the count).
    #[arg(long, default_value = "4", value_delimiter = ',')]
    samples: Vec<u32>,
    /// Modes, comma-separated: replay (fragsim's snapped triangles: identity owed), engine (the
    /// mesh and the f32 matrix: differences reported).
    #[arg(long, value_enum, default_value = "replay", value_delimiter = ',')]
    mode: Vec<ModeArg>,
    /// Also compare the GPU's counts with fragsim's at the standard positions mirrored in y
    /// (x, 16 − y): nonzero differences show that the counts tell the positions apart.
    #[arg(long)]
    mirrored: bool,
    /// Differing samples printed per comparison.
    #[arg(long, default_value_t = 5)]
    examples: usize,
    /// Diagnose each printed differing sample of a replay comparison: draw each triangle that
    /// covers it in fragsim's oracle alone, then all of them together, and print the GPU's count
    /// there (does the rasterizer miss the sample by itself, or only beside the rest?).
    #[arg(long)]
    alone: bool,
}

/// Engine mode: at most this many differing samples of a comparison are measured against the
/// nearest triangle boundary (each measure visits every triangle).
const CHECKED: usize = 200;

/// `fragsim-wgpu msaa-count`: the GPU's per-sample counts against fragsim's per-sample oracle for
/// every view, mode and sample count, one verdict line each (with the first differing samples),
/// then a table; `Ok(false)` when any count differs.
pub(crate) fn msaa_count(gpu: &Gpu, args: &MsaaArgs) -> Result<bool, Box<dyn std::error::Error>> {
    let base = match &args.mesh {
        Some(path) => SceneSpec::hashed_mesh(path, 0.0, args.elevation)?,
        None => SceneSpec::named(&args.scene, 0.0, args.elevation),
    };
    let name = match &args.mesh {
        Some(path) => path.file_name().map_or_else(
            || path.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        ),
        None => args.scene.clone(),
    };
    let viewport = Viewport::new(args.width, args.height)?;
    let loaded = base.load(None).map_err(DumpError::from)?;
    let mut rows = Vec::new();
    let (mut identical, mut failed) = (true, 0);
    for &degrees in &args.view {
        let spec = SceneSpec {
            view_degrees: degrees,
            ..base.clone()
        };
        let view = spec.view(&loaded, viewport).map_err(DumpError::from)?;
        // The f32 vertex stage's snap radius on this view (engine mode, when a count differs).
        let mut radius: Option<i64> = None;
        for mode in &args.mode {
            let (mode, reference_view) = match mode {
                ModeArg::Replay => (Mode::Replay, view.clone()),
                ModeArg::Engine => (
                    Mode::Engine,
                    engine_scene(spec.clone(), &view)
                        .view(&loaded, viewport)
                        .map_err(DumpError::from)?,
                ),
            };
            for &samples in &args.samples {
                let what = format!(
                    "{name} {}x{} view {degrees} {} {samples}x",
                    args.width,
                    args.height,
                    mode.name()
                );
                let pattern = SamplePattern::standard(samples)?;
                let counted = match count_samples(gpu, &view, mode, samples) {
                    Ok(counted) => counted,
                    Err(e) => {
                        eprintln!("fragsim-wgpu: {what}: {e}");
                        failed += 1;
                        continue;
                    }
                };
                let reference = reference_counts(&reference_view, pattern)?;
                let diff = CountDiff::of(
                    &counted.counts,
                    &reference,
                    args.width,
                    samples,
                    CHECKED.max(args.examples),
                );
                let ms = counted.gpu_ms.map_or_else(
                    || format!("{:.1} (wall)", counted.wall_ms),
                    |ms| format!("{ms:.3}"),
                );
                println!(
                    "{what}: {} triangles, GPU {ms} ms; {}",
                    counted.triangles,
                    diff.summary()
                );
                // Engine mode: each differing sample's nearest triangle boundaries in fragsim's f32
                // view, against twice the snap radius (src/sample_counts.rs).
                let near_edges = (mode == Mode::Engine && !diff.is_identical())
                    .then(|| -> Result<_, Box<dyn std::error::Error>> {
                        let r = match radius {
                            Some(r) => r,
                            None => {
                                let mut exact = engine_scene(spec.clone(), &view);
                                exact.conventions.vertex_precision = VertexPrecision::F64;
                                *radius.insert(f32_snap_radius(&exact.view(&loaded, viewport)?))
                            }
                        };
                        Ok(NearEdges::of(&reference_view, pattern, &diff, r))
                    })
                    .transpose()?;
                let index =
                    |&[x, y, s, ..]: &[u32; 5]| ((y * args.width + x) * samples + s) as usize;
                for (i, example) in diff.examples.iter().take(args.examples).enumerate() {
                    let [x, y, s, got, want] = *example;
                    let at = index(example);
                    let mut line = format!(
                        "  pixel ({x}, {y}) sample {s}: GPU {got}, fragsim {want}; shader depth outside [0, 1] there: {}",
                        counted.shader_depth_outside[at]
                    );
                    if counted.shader_depth_outside[at] > 0 {
                        line += &format!(
                            " (position.z {:e})",
                            f32::from_bits(counted.shader_depth_bits[at])
                        );
                    }
                    if let Some(near) = &near_edges {
                        let edges: Vec<String> = near.nearest[i]
                            .iter()
                            .map(|b| {
                                format!(
                                    "prim {} at {:.3} ({})",
                                    b.prim,
                                    b.subpixels,
                                    if b.inside { "inside" } else { "outside" }
                                )
                            })
                            .collect();
                        line += &format!("; nearest boundaries (subpixels): {}", edges.join(", "));
                    }
                    println!("{line}");
                }
                if args.alone && mode == Mode::Replay {
                    let shown: Vec<usize> = diff
                        .examples
                        .iter()
                        .take(args.examples)
                        .map(index)
                        .collect();
                    alone(gpu, &view, pattern, &shown)?;
                }
                let outside: u64 = counted
                    .shader_depth_outside
                    .iter()
                    .map(|&c| u64::from(c))
                    .sum();
                if outside > 0 {
                    println!("  counted samples whose shader depth (position.z) lies outside [0, 1] (the depth of another point than the sample): {outside}");
                }
                let explained = near_edges.as_ref().map(|near| {
                    let (within, checked) = (near.within(), near.nearest.len());
                    println!(
                        "  f32 vertex stage: {within} of the {checked} differing samples checked lie within twice the snap radius ({} subpixels) of a triangle boundary (explained by vertex precision)",
                        near.bound_subpixels
                    );
                    format!(" ({within}/{checked} near an edge)")
                });
                let mirror = if args.mirrored && samples > 1 {
                    let other = reference_counts(
                        &reference_view,
                        mirrored(pattern).map_err(|e| e.to_string())?,
                    )?;
                    let against = CountDiff::of(&counted.counts, &other, args.width, samples, 0);
                    println!(
                        "  against the mirrored positions (x, 16 - y): {} of {} samples, {} pixels' sums differ",
                        against.samples_differ, against.samples, against.pixels_differ
                    );
                    against.samples_differ.to_string()
                } else {
                    "-".to_string()
                };
                identical &= diff.is_identical();
                rows.push(format!(
                    "| {name} | {}x{} | {degrees} | {} | {samples} | {} | {} | {} | {} | {} | {mirror} | {ms} | {}{} |",
                    args.width,
                    args.height,
                    mode.name(),
                    counted.triangles,
                    diff.gpu_fragments,
                    diff.reference_fragments,
                    diff.samples_differ,
                    diff.pixels_differ,
                    if diff.is_identical() { "IDENTICAL" } else { "DIFFERENT" },
                    explained.unwrap_or_default()
                ));
            }
        }
    }
    println!("\n| scene | size | view | mode | samples | triangles | GPU sample fragments | fragsim | samples differ | pixel sums differ | mirrored: samples differ | GPU ms | verdict |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for row in &rows {
        println!("{row}");
    }
    if failed > 0 {
        return Err(format!("{failed} counting passes could not run").into());
    }
    Ok(identical)
}

/// `msaa-count --alone`: at each of the samples `shown` (indices into the counts), the GPU's
/// count with each triangle fragsim finds there drawn alone, then with all of them together.
fn alone(
    gpu: &Gpu,
    view: &View<'_>,
    pattern: SamplePattern,
    shown: &[usize],
) -> Result<(), Box<dyn std::error::Error>> {
    let samples = pattern.count();
    for (&at, prims) in shown.iter().zip(covering_prims(view, pattern, shown)?) {
        let mut parts = Vec::new();
        for &prim in &prims {
            let one = count_samples_of(gpu, view, &[prim], samples)?;
            parts.push(format!("prim {prim}: {}", one.counts[at]));
        }
        let together = count_samples_of(gpu, view, &prims, samples)?;
        println!(
            "  sample #{at} drawn alone: {}; all {} together: {}",
            parts.join(", "),
            prims.len(),
            together.counts[at]
        );
    }
    Ok(())
}
