//! Frames of one scheme on one executor, and nothing else: what an instruction-count profiler
//! (`valgrind --tool=callgrind`) should see when a change to the frame is measured. `fragsim
//! bench` also parses the mesh, builds the oracle and judges the capture, which under callgrind
//! cost several times the frames themselves; here the frames run inside one function,
//! [`profiled_frames`], on a pool of one thread, so that callgrind can collect that function
//! alone (`--collect-atstart=no --toggle-collect='*profiled_frames*'`).
//!
//! A mesh file is parsed once into a raw cache (`.bin`: vertex and triangle counts, then the
//! positions and the indices, little-endian), which later runs read in a moment:
//!
//! ```text
//! cargo bench --bench frame_profile --no-run   # prints the binary's path
//! BIN cache dragon_vrip.ply.gz /tmp/dragon.bin
//! valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*profiled_frames*' \
//!     BIN run /tmp/dragon.bin 512 512 mdts parallel 2
//! ```
//!
//! `run` runs one untimed frame first (storage allocated, pages faulted in), then the frames
//! measured: the vertex stage, the geometry passes and the post pass, as `fragsim bench` times a
//! frame. It prints the fragments and wall-clock times; callgrind's total is the instructions.

use std::path::Path;
use std::time::Instant;

use fragsim::capture::executors::Run;
use fragsim::capture::executors::{ParallelExecutor, TiledExecutor};
use fragsim::capture::MEMORY_CAP_DEFAULT;
use fragsim::raster::{Mesh, OrbitCamera, Scene, View, Viewport};
use fragsim::schemes::abuffer::{ABuffer, PostSort};
use fragsim::schemes::mdts::Mdts;

/// FreePipe's configuration, as `fragsim bench` runs it: K = 20 slots, 20 per A-buffer pixel.
const SLOTS: u32 = 20;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let words: Vec<&str> = args.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["cache", mesh, out] => cache(Path::new(mesh), Path::new(out)),
        ["run", cache, width, height, scheme, executor, frames] => {
            let number = |text: &str| text.parse::<u32>().map_err(|e| format!("{text}: {e}"));
            let viewport =
                Viewport::new(number(width)?, number(height)?).map_err(|e| e.to_string())?;
            run(
                Path::new(cache),
                viewport,
                scheme,
                executor,
                number(frames)?,
            )
        }
        // `cargo bench` runs every bench target with `--bench`: nothing to do without a mesh.
        ["--bench", ..] => Ok(()),
        _ => Err(
            "usage: frame_profile cache MESH OUT.bin | run OUT.bin WIDTH HEIGHT mdts|abuffer \
             parallel|tiled FRAMES"
                .into(),
        ),
    }
}

/// Parses `mesh` (any file `fragsim` reads) and writes its raw cache to `out`.
fn cache(mesh: &Path, out: &Path) -> Result<(), String> {
    let scene = Scene::from_file(mesh).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    for count in [scene.mesh.positions.len(), scene.mesh.triangles.len()] {
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a mesh's indices are u32, so its vertex and triangle counts fit"
        )]
        bytes.extend_from_slice(&(count as u32).to_le_bytes());
    }
    for value in scene.mesh.positions.iter().flatten() {
        bytes.extend_from_slice(&value.to_le_bytes());
    }
    for index in scene.mesh.triangles.iter().flatten() {
        bytes.extend_from_slice(&index.to_le_bytes());
    }
    std::fs::write(out, bytes).map_err(|e| format!("{}: {e}", out.display()))
}

/// Reads a raw cache written by [`cache`].
fn read_cache(path: &Path) -> Result<Mesh, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut words = bytes
        .chunks_exact(4)
        .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
    let mut next = || words.next().ok_or("truncated mesh cache");
    let (vertices, triangles) = (next()? as usize, next()? as usize);
    let mut positions = Vec::with_capacity(vertices);
    for _ in 0..vertices {
        positions.push([next()?, next()?, next()?].map(f32::from_bits));
    }
    let mut indices = Vec::with_capacity(triangles);
    for _ in 0..triangles {
        indices.push([next()?, next()?, next()?]);
    }
    let mesh = Mesh {
        positions,
        triangles: indices,
    };
    mesh.validate(&path.display().to_string())
        .map_err(|e| e.to_string())?;
    Ok(mesh)
}

fn run(
    cache: &Path,
    viewport: Viewport,
    scheme: &str,
    executor: &str,
    frames: u32,
) -> Result<(), String> {
    let scene = Scene {
        name: cache.display().to_string(),
        mesh: read_cache(cache)?,
    };
    let orbit = OrbitCamera::default().at_angle(30.0);
    let camera = scene.orbit_camera(viewport, &orbit, Default::default());
    let mut view = scene.view(viewport, &orbit).map_err(|e| e.to_string())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| e.to_string())?;
    let error = |e: fragsim::capture::CaptureError| e.to_string();
    let mut parallel = ParallelExecutor::default();
    let mut tiled = TiledExecutor::default();
    #[expect(
        clippy::shadow_unrelated,
        reason = "the closure's view is the one each call passes"
    )]
    let mut frame = |view: &View<'_>| -> Result<Run, String> {
        Ok(match (scheme, executor) {
            ("mdts", "parallel") => parallel.run(
                view,
                &Mdts::<u64>::ascending(viewport, SLOTS).map_err(error)?,
            ),
            ("mdts", "tiled") => tiled.run(
                view,
                &Mdts::<u64>::ascending(viewport, SLOTS).map_err(error)?,
            ),
            ("abuffer", "parallel") => parallel.run(view, &abuffer(viewport)?),
            ("abuffer", "tiled") => tiled.run(view, &abuffer(viewport)?),
            _ => return Err(format!("unknown scheme {scheme} or executor {executor}")),
        })
    };
    pool.install(|| {
        let warm = frame(&view)?;
        println!(
            "{}: {} fragments, {} stored, {} dropped",
            scene.name,
            warm.stats.counters.fragments,
            warm.stats.counters.stored,
            warm.stats.counters.dropped
        );
        profiled_frames(&mut view, &camera, frames, &mut frame)
    })
}

fn abuffer(viewport: Viewport) -> Result<ABuffer, String> {
    ABuffer::fixed(viewport, SLOTS, PostSort::Insertion, MEMORY_CAP_DEFAULT)
        .map_err(|e| e.to_string())
}

/// The frames measured: vertex stage, then the executor's frame. Not inlined, so that callgrind
/// can toggle collection on it.
#[inline(never)]
fn profiled_frames(
    view: &mut View<'_>,
    camera: &fragsim::raster::Camera,
    frames: u32,
    frame: &mut dyn FnMut(&View<'_>) -> Result<Run, String>,
) -> Result<(), String> {
    for index in 0..frames {
        let start = Instant::now();
        view.set_camera(camera);
        let vertex = start.elapsed();
        let run = frame(view)?;
        println!(
            "frame {index}: vertex {:.2} ms, passes {:.2} ms, post {:.2} ms, {} fragments",
            vertex.as_secs_f64() * 1e3,
            run.stats.pass_time.as_secs_f64() * 1e3,
            run.stats.resolve_time.as_secs_f64() * 1e3,
            run.stats.counters.fragments
        );
    }
    Ok(())
}
