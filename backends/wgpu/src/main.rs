//! `fragsim-wgpu`: captures through the wgpu backend, written as dumps that `fragsim compare`
//! judges, optionally judged in place.
//!
//! ```text
//! fragsim-wgpu adapter
//! fragsim-wgpu capture --scheme abuffer,mdts --scene bunny --width 512 --height 512 \
//!     --view 30 --mode replay --out out/wgpu --judge
//! fragsim-wgpu capture --scheme linked-list --plant lost-node --scene bunny --out out/wgpu
//! fragsim-wgpu capture --case DIR --scheme mdts --k 2 --mode engine --out OUT
//! fragsim-wgpu capture --scheme abuffer,mdts --samples 4 --mode engine --precision --out OUT
//! fragsim-wgpu msaa-count --scene bunny --samples 1,4,8 --view 30,120 --width 512 \
//!     --height 512 --mode replay,engine --mirrored
//! ```
//!
//! `--case` reads a case directory of `fragsim conform` (its `camera.json` and `case.json`), so
//! that the command is conform's `--backend` (`docs/testing.md`).
//!
//! Exit status: 0 on success (`capture`: whatever the verdicts; `msaa-count`: every count
//! identical), 1 when `msaa-count` found differing counts, 2 on an error (no adapter, bad input,
//! a sample count the adapter lacks).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};
use fragsim_dump::DumpError;
use fragsim_oracle::Oracle;
use fragsim_raster::scene_spec::args::SceneArgs;
use fragsim_raster::scene_spec::SceneSpec;
use fragsim_raster::{Conventions, Viewport};
use fragsim_wgpu::judge::{Within, WithinJudgement};
use fragsim_wgpu::shaders::NAMES;
use fragsim_wgpu::{capture_samples, judge, Gpu, GpuScheme, Mode, Plant};
use msaa_count::{msaa_count, MsaaArgs};

mod msaa_count;

#[derive(Parser)]
#[command(
    name = "fragsim-wgpu",
    about = "fragsim's schemes as WGSL fragment shaders on a Vulkan GPU"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    Replay,
    Engine,
}

#[derive(Subcommand)]
enum Command {
    /// Print the adapter and the features the shaders use.
    Adapter,
    /// Capture a scene with one or more schemes; one dump per scheme in OUT/<scheme>/.
    Capture(Box<CaptureArgs>),
    /// Count the GPU's fragments per sample of a multisampled target and compare them with
    /// fragsim's per-sample oracle; a summary table at the end.
    MsaaCount(MsaaArgs),
}

/// Options of `fragsim-wgpu capture`.
#[derive(Args)]
#[command(group(clap::ArgGroup::new("verdicts").args(["judge", "precision"]).multiple(true)))]
struct CaptureArgs {
    /// Schemes, comma-separated: abuffer, abuffer-exact, mdts, mdts32, kbuffer,
    /// linked-list, linked-list-nearest, kbuffer-spinlock-fixed; or all.
    #[arg(long, default_value = "abuffer,mdts,mdts32")]
    scheme: String,
    /// The scene and the camera, as `fragsim render` takes them.
    #[command(flatten)]
    scene: SceneArgs,
    /// A case directory of `fragsim conform` instead of a scene: the scene object of its
    /// `camera.json` (the case's mesh, the identity matrix) on the viewport of its
    /// `case.json`, in place of --mesh, --scene, --width, --height, --view, --elevation and --up.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["mesh", "scene", "width", "height", "up"])]
    case: Option<PathBuf>,
    /// replay: fragsim's snapped triangles; engine: the mesh and the f32 matrix.
    #[arg(long, value_enum, default_value = "replay")]
    mode: ModeArg,
    /// MDTS and k-buffer slots per pixel; linked lists: the nodes the resolve keeps.
    #[arg(long, default_value_t = 8)]
    k: u32,
    /// A-buffer slots per pixel (FreePipe's 20); linked lists: pool nodes per pixel.
    #[arg(long, default_value_t = 20)]
    capacity: u32,
    /// Planted bugs' shader variants, comma-separated: dropped, wrong-id,
    /// off-by-one-capacity, unsorted, lost-node, or none (the correct shader); each scheme
    /// runs once per plant (dumps in OUT/<scheme>-planted-<plant>/). `all`: the correct
    /// shader and every plant that applies to the scheme, the others skipped.
    #[arg(long, default_value = "none", value_delimiter = ',')]
    plant: Vec<String>,
    /// Judge without writing the dumps (a device run whose dumps would not come back).
    #[arg(long, requires = "verdicts")]
    discard: bool,
    /// Output directory.
    #[arg(long, default_value = "out/wgpu")]
    out: PathBuf,
    /// Also judge each dump against fragsim's oracle here and print the verdict.
    #[arg(long)]
    judge: bool,
    /// With --judge: as `fragsim compare --depth-ulps`; a comma-separated list gives one
    /// verdict per value.
    #[arg(long, default_value = "0", value_delimiter = ',')]
    depth_ulps: Vec<u32>,
    /// Also judge each dump within the precision of an f32 vertex stage (the precision verdict:
    /// `fragsim compare oracle DIR --vertex-precision f32`) and print it.
    #[arg(long)]
    precision: bool,
    /// Samples a pixel: 1, or a per-sample capture at 2, 4, 8 (a list per (pixel, sample), the
    /// depth at the sample; the adapter's target must render at the count; abuffer,
    /// abuffer-exact, mdts, mdts32 and the linked lists). Judged by --precision only.
    #[arg(long, default_value_t = 1)]
    samples: u32,
}

fn main() -> ExitCode {
    // Mesa warns when XDG_RUNTIME_DIR is unset; the warning is harmless but noisy.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    match run(Cli::parse()) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("fragsim-wgpu: {e}");
            ExitCode::from(2)
        }
    }
}

/// The command; `Ok(false)`: `msaa-count` found differing counts.
fn run(cli: Cli) -> Result<bool, Box<dyn std::error::Error>> {
    let gpu = Gpu::open()?;
    println!("{}", gpu.report());
    match cli.command {
        Command::Adapter => Ok(true),
        Command::Capture(args) => capture_command(&gpu, *args).map(|()| true),
        Command::MsaaCount(args) => msaa_count(&gpu, &args),
    }
}

fn capture_command(gpu: &Gpu, args: CaptureArgs) -> Result<(), Box<dyn std::error::Error>> {
    let CaptureArgs {
        scheme,
        scene,
        case,
        mode,
        k,
        capacity,
        plant,
        discard,
        out,
        judge: judge_it,
        depth_ulps,
        precision,
        samples,
    } = args;
    if samples > 1 && judge_it {
        return Err(
            "--judge compares with the single-sample oracle: judge a per-sample capture with \
             --precision (fragsim compare oracle DIR --vertex-precision f32)"
                .into(),
        );
    }
    let names: Vec<&str> = if scheme == "all" {
        NAMES.to_vec()
    } else {
        scheme.split(',').map(str::trim).collect()
    };
    let schemes = names
        .into_iter()
        .map(|s| GpuScheme::parse(s, k, capacity))
        .collect::<Result<Vec<_>, _>>()?;
    // `all` skips the plants a scheme cannot show; a plant named is an error where it does not
    // apply.
    let every = plant.iter().any(|p| p == "all");
    let plants: Vec<Option<Plant>> = if every {
        std::iter::once(None).chain(Plant::ALL.map(Some)).collect()
    } else {
        plant
            .iter()
            .map(|p| match p.as_str() {
                "none" => Ok(None),
                name => Plant::parse(name).map(Some),
            })
            .collect::<Result<Vec<_>, _>>()?
    };
    let (spec, viewport) = match &case {
        Some(dir) => conform_case(dir)?,
        None => (
            scene.spec(Conventions::REFERENCE).hashed()?,
            scene.viewport()?,
        ),
    };
    let (width, height) = (viewport.width, viewport.height);
    // Worded as the oracle words a dump's scene (`scene: …`), as fragsim compare says it.
    let loaded = spec.load(None).map_err(DumpError::from)?;
    let fragsim_view = spec.view(&loaded, viewport).map_err(DumpError::from)?;
    // An orbit around another up axis is recorded as its matrix: the dumps name the view captured.
    let spec = spec.recorded(&fragsim_view);
    let mode = match mode {
        ModeArg::Replay => Mode::Replay,
        ModeArg::Engine => Mode::Engine,
    };
    let oracle = judge_it.then(|| Oracle::build(&fragsim_view));
    // The precision verdict's reference, built for the first dump and kept while the dumps name
    // its scene (one view and mode: every dump of this command).
    let mut within: Option<Within> = None;
    let mut failed = 0;
    let mut runs = 0;
    #[expect(
        clippy::shadow_unrelated,
        reason = "each run's scheme and plant, of the lists named for them"
    )]
    for scheme in &schemes {
        for &plant in &plants {
            if every && plant.is_some_and(|p| !p.applies_at(scheme, samples)) {
                continue;
            }
            runs += 1;
            // One scheme the adapter cannot run (a buffer past its limits, a missing feature)
            // does not stop the others: it is reported and the command exits 2 at the end.
            let captured = match capture_samples(
                gpu,
                &fragsim_view,
                spec.clone(),
                scheme,
                mode,
                plant,
                samples,
            ) {
                Ok(captured) => captured,
                Err(e) => {
                    eprintln!("fragsim-wgpu: {e}");
                    failed += 1;
                    continue;
                }
            };
            let dir = match plant {
                Some(p) => out.join(format!("{}-planted-{}", scheme.name(), p.name())),
                None => out.join(scheme.name()),
            };
            if !discard {
                captured.dump.write(&dir)?;
            }
            let gpu_ms = captured
                .gpu_ms
                .map_or_else(|| "n/a".to_string(), |ms| format!("{ms:.3} ms"));
            println!(
                "{}{} {} {}x{}{} {}: {} triangles, GPU {gpu_ms}, wall {:.1} ms -> {}",
                scheme.name(),
                plant.map_or(String::new(), |p| format!(" (planted: {})", p.name())),
                mode.name(),
                width,
                height,
                if samples > 1 {
                    format!(" {samples}x")
                } else {
                    String::new()
                },
                spec.describe(),
                captured.triangles,
                captured.wall_ms,
                if discard {
                    "(not written)".to_string()
                } else {
                    dir.display().to_string()
                }
            );
            if let Some(oracle) = &oracle {
                for &ulps in &depth_ulps {
                    let judgement = judge::judge(&captured.dump, oracle, ulps)?;
                    println!("  verdict (depth ulps {ulps}): {}", judgement.summary());
                }
            }
            if precision {
                if !within.as_ref().is_some_and(|w| w.fits(&captured.dump)) {
                    within = Some(Within::of(&captured.dump)?);
                }
                if let Some(reference) = &within {
                    let verdict = reference.verdict(&captured.dump)?;
                    let per_sample = verdict.per_sample;
                    // One line of figures (what wgpu-captures.sh reads), per sample its "pixels"
                    // the samples, then the samples and pixels that differ.
                    let judgement = WithinJudgement {
                        comparison: verdict.comparison,
                        bounds: verdict.bounds.unwrap_or_default(),
                        covered: reference.covered(),
                    };
                    println!(
                        "  precision verdict (f32 vertex stage): {}",
                        judgement.summary()
                    );
                    if let Some(c) = per_sample.filter(|_| samples > 1) {
                        println!(
                            "  per sample ({samples} a pixel): {} of {} samples differ, in {} of {} pixels",
                            c.differing_samples,
                            c.compared,
                            c.differing_pixels,
                            c.compared / u64::from(samples)
                        );
                    }
                }
            }
        }
    }
    if failed > 0 {
        return Err(format!("{failed} of {runs} captures could not run").into());
    }
    Ok(())
}

/// The scene object and viewport of a `fragsim conform` case directory: `camera.json` (a dump
/// header's scene object, naming the case's mesh by its absolute path) and `case.json` (its
/// `width` and `height`).
fn conform_case(dir: &Path) -> Result<(SceneSpec, Viewport), Box<dyn std::error::Error>> {
    let read = |name: &str| {
        let path = dir.join(name);
        std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))
    };
    let spec: SceneSpec = serde_json::from_str(&read("camera.json")?)
        .map_err(|e| format!("{}: {e}", dir.join("camera.json").display()))?;
    let about: serde_json::Value = serde_json::from_str(&read("case.json")?)
        .map_err(|e| format!("{}: {e}", dir.join("case.json").display()))?;
    let side = |key: &str| {
        about[key]
            .as_u64()
            .and_then(|v| u32::try_from(v).ok())
            .ok_or_else(|| format!("{}: no {key}", dir.join("case.json").display()))
    };
    Ok((spec, Viewport::new(side("width")?, side("height")?)?))
}
