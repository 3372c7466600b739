//! What the masked-node A-buffer loses at bounded capacity, against the A-buffer run per sample
//! (`docs/results.md`, "Multisampling"): for each scene, sample count and capacity, the sample
//! fragments lost, the samples with a wrong list and the bytes a pixel, every number measured
//! against the per-sample oracle.
//!
//! `cargo run --release -p fragsim-oracle --example masked_loss -- [SIDE] [SCENE|MESH ...]`
//! (default: 512, `bunny-spheres` and `../shared/meshes/dragon_vrip.ply.gz`).

use std::path::Path;

use fragsim_capture::catalog::{Count, Executors, SchemeName, Sizing};
use fragsim_capture::executors::Executor;
use fragsim_capture::schemes::masked_abuffer::MaskedABuffer;
use fragsim_oracle::samples::{SampleError, SampleOracle};
use fragsim_raster::{OrbitCamera, SamplePattern, Scene, Viewport};

fn main() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let side: u32 = match args.next() {
        Some(side) => side.parse().map_err(|e| format!("side {side:?}: {e}"))?,
        None => 512,
    };
    let mut scenes: Vec<String> = args.collect();
    if scenes.is_empty() {
        scenes = vec![
            "bunny-spheres".into(),
            "../shared/meshes/dragon_vrip.ply.gz".into(),
        ];
    }
    println!(
        "| scene | samples | storage | capacity | bytes/pixel | sample fragments lost | samples wrong | of which misordered |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for name in &scenes {
        let scene = if Path::new(name).is_file() {
            Scene::from_file(Path::new(name)).map_err(|e| e.to_string())?
        } else {
            Scene::procedural(name).map_err(|e| e.to_string())?
        };
        let label = Path::new(name)
            .file_name()
            .map_or(name.clone(), |f| f.to_string_lossy().into_owned());
        let view = scene
            .view(Viewport::new(side, side)?, &OrbitCamera::default())
            .map_err(|e| e.to_string())?;
        for count in [4, 8] {
            let sampled = view.clone().with_samples(SamplePattern::standard(count)?)?;
            let oracle = SampleOracle::build(&sampled)?;
            let pixels = view.viewport().pixels() as f64;
            let row = |storage: &str, capacity: String, bytes: u64, error: SampleError| {
                println!(
                    "| {label} | {count} | {storage} | {capacity} | {:.0} | {} of {} ({:.3} %) | {} ({:.3} %) | {} |",
                    bytes as f64 / pixels,
                    error.lost,
                    error.fragments,
                    100.0 * error.lost as f64 / error.fragments as f64,
                    error.wrong_samples,
                    100.0 * error.wrong_samples as f64 / error.samples as f64,
                    error.misordered_samples,
                );
            };
            let per_pixel = oracle.per_pixel();
            let deepest = (0..per_pixel.pixels())
                .map(|p| per_pixel.pixel(p).len() as u32)
                .max()
                .unwrap_or(1)
                .max(1);
            for capacity in [4, 8, 16, 32, deepest] {
                let scheme = MaskedABuffer::new(view.viewport(), count, capacity, u64::MAX)
                    .map_err(|e| e.to_string())?;
                let captured = scheme.capture(&sampled, true)?;
                let label = if capacity == deepest {
                    format!("{capacity} (deepest pixel)")
                } else {
                    capacity.to_string()
                };
                row(
                    "masked nodes",
                    label,
                    scheme.layout().bytes(),
                    oracle.sample_error(&captured.per_sample()),
                );
            }
            let mut executors = Executors::default();
            for capacity in [1, 2, 4, 8] {
                let sizing = Sizing {
                    k: Count::Fixed(capacity),
                    capacity: Count::Fixed(capacity),
                    memory_cap: u64::MAX,
                };
                let named =
                    executors.run(SchemeName::Abuffer, Executor::Parallel, &sampled, &sizing)?;
                row(
                    "per sample",
                    capacity.to_string(),
                    named.run.stats.memory_bytes,
                    oracle.sample_error(&named.run.capture.lists),
                );
            }
        }
    }
    Ok(())
}
