//! `fragsim conform --backend 'COMMAND {scene} {out}' --scheme S`: the conformance battery
//! (`fragsim_testkit::battery`) against a backend in any language, run as a command on each
//! generated case's files (`fragsim_testkit::command`).
//!
//! Each case is written as files (the triangle export, the mesh OBJ and its camera JSON, the
//! case's sizes), the command runs on them with a timeout and writes a dump, and the dump is
//! judged with `compare`'s verdict against the oracle, in the case's submission order and in
//! another. On a failure proptest shrinks the case by re-running the command on smaller ones
//! (fewer triangles, a smaller viewport, corners nearer the origin); the smallest failing case is
//! printed and saved: its scene files, the dump the backend wrote, both lists of the first
//! differing pixels, and the commands that replay it. Exit code 0 when every case passes, 1 on
//! a counterexample, 2 on errors (bad arguments, a command that cannot run), as `compare`.
//!
//! Most cases are deep (past K and the capacity: `fragsim_testkit::case`), and the report claims
//! only what the cases exercised: how many overflowed as the oracle predicts, the deepest pixel,
//! the fragments, the cases past K and the capacity, with ties, and empty; a claim no case
//! exercised is said to be so. A backend that fails to run on the smallest case too fails
//! whatever the case: the run stops at once with that, unshrunk.

use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::Args;
use fragsim_capture::catalog::SchemeName;
use fragsim_oracle::PixelMismatch;
use fragsim_raster::scene_spec::{mesh_hash, SceneSpec};
use fragsim_raster::{depth_from_key, Conventions, VertexPrecision};
use fragsim_testkit::command::write_case;
use fragsim_testkit::{
    Battery, Case, CommandBackend, Counterexample, Event, Exercised, Failure, Input, Limits, Params,
};
use serde::Serialize;

use crate::args::Shard;
use crate::record::{self, Context, Slots};

/// Options of `fragsim conform`.
#[derive(Debug, Clone, Args)]
pub struct ConformArgs {
    /// The backend's command line, run by `sh -c` per case: `{scene}` is the case's directory
    /// (scene.tri, mesh.obj, camera.json, case.json), `{out}` the directory to write the dump
    /// into; `{scheme}`, `{k}`, `{capacity}` are replaced too.
    #[arg(long, value_name = "COMMAND")]
    pub backend: String,
    /// The catalog scheme the backend runs (the dump's layout).
    #[arg(long, value_name = "NAME")]
    pub scheme: String,
    /// Slots per pixel of K-sized schemes (MDTS, the k-buffers).
    #[arg(long, value_name = "N", default_value_t = 2,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub k: u32,
    /// Slots per pixel of the fixed A-buffer.
    #[arg(long, value_name = "N", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub capacity: u32,
    /// How many cases to generate.
    #[arg(long, value_name = "N", default_value_t = 100,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub cases: u32,
    /// The seed the cases are generated from (the same seed, the same cases).
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Check only shard I of N of the `--cases` cases (cargo-nextest's `count:I/N`): case `n`
    /// (from 1) when `(n − 1) mod N = I − 1`. Every shard generates the same cases from the
    /// seed, so N machines running shards 1 to N check exactly the unsharded run's cases.
    #[arg(long, value_name = "I/N", value_parser = Shard::parse)]
    pub shard: Option<Shard>,
    /// Seconds one run of the command may take before it is killed (a failing case).
    #[arg(long, value_name = "SECONDS", default_value_t = 30.0, value_parser = positive)]
    pub timeout: f64,
    /// The largest viewport side of a case, in pixels.
    #[arg(long, value_name = "N", default_value_t = 8,
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_side: u32,
    /// The most triangles a case holds (default: 7, or 4 more than the larger of K and the
    /// capacity where that is more, so that most cases overflow both).
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_triangles: Option<u32>,
    /// The most simplifications proptest tries on a failing case before fragsim's own crop to
    /// the differing pixels and triangle dropping finish the shrinking (each one runs the
    /// backend once).
    #[arg(long, value_name = "N", default_value_t = 2048)]
    pub shrink_steps: u32,
    /// Where the smallest failing case is saved (`DIR/case/`, replaced), and the cases are run
    /// (`DIR/work/`, removed at the end).
    #[arg(long, value_name = "DIR", default_value = "out/conform")]
    pub save: PathBuf,
    /// How the backend's vertex stage is judged, as `compare --vertex-precision`: `f64` (the
    /// default) owes the oracle every bit; `f32` (a vertex shader, a GPU's depth interpolation)
    /// judges each case within the bounds derived for an f32 vertex stage against the exact f64
    /// one (`docs/semantics.md`, "Precision of a conforming implementation").
    #[arg(long, value_name = "f64|f32", default_value = "f64", value_parser = ["f64", "f32"])]
    pub vertex_precision: String,
    /// Generate (and shrink to) viewports whose sides are powers of two only, for a backend
    /// that takes no other (the wgpu backend's replay mode).
    #[arg(long)]
    pub power_of_two: bool,
    /// Print JSON Lines instead of the report: one `conform` record, then one
    /// `counterexample_pixel` record per differing pixel shown (`docs/json-schema.md`).
    #[arg(long)]
    pub json: bool,
    /// Write a line to stderr as each case passes (`conform: N of M cases passed`) and at each
    /// shrinking step (`conform: case N failed; shrinking step S`): for a log, where no bar is
    /// drawn, so that a run stopped from outside (a `timeout`) still says how far it got. The
    /// report waits for the end.
    #[arg(long)]
    pub progress_lines: bool,
}

/// A positive, finite number of seconds.
fn positive(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{text} is not a positive number of seconds")),
    }
}

/// A fragment as the report shows it.
#[derive(Debug, Serialize)]
struct Entry {
    key: String,
    depth: f32,
    prim: u32,
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "a word packs the depth key (high 32 bits) and the primitive id (low 32)"
)]
fn entries(words: &[u64]) -> Vec<Entry> {
    words
        .iter()
        .map(|&w| Entry {
            // As `compare` prints keys: 8 hex digits.
            key: format!("{:08x}", w >> 32),
            depth: depth_from_key((w >> 32) as u32),
            prim: w as u32,
        })
        .collect()
}

/// What the checked cases exercised, as the `conform` record carries it.
#[derive(Debug, Serialize)]
struct ExercisedRecord {
    /// Cases counted: those that passed.
    exercised_cases: u32,
    exercised_fragments: u64,
    deepest_pixel: u32,
    k_cut_cases: u32,
    over_capacity_cases: u32,
    overflow_cases: u32,
    overflow_fragments: u64,
    tie_cases: u32,
    empty_cases: u32,
}

impl From<Exercised> for ExercisedRecord {
    fn from(e: Exercised) -> Self {
        Self {
            exercised_cases: e.cases,
            exercised_fragments: e.fragments,
            deepest_pixel: e.deepest_pixel,
            k_cut_cases: e.k_cut_cases,
            over_capacity_cases: e.over_capacity_cases,
            overflow_cases: e.overflow_cases,
            overflow_fragments: e.overflow_fragments,
            tie_cases: e.tie_cases,
            empty_cases: e.empty_cases,
        }
    }
}

/// The `conform` record.
#[derive(Debug, Serialize)]
struct Summary {
    passed: bool,
    backend: String,
    conform_scheme: String,
    cases: u32,
    seed: u64,
    vertex_precision: String,
    /// `I/N` under `--shard` (`null` unsharded).
    shard: Option<String>,
    /// Cases checked (a shard's own).
    cases_run: u32,
    /// The failing case's number among the seed's `cases` (the same in a shard as unsharded).
    case_number: Option<u32>,
    shrink_steps: Option<u32>,
    property: Option<String>,
    message: Option<String>,
    triangles: Option<usize>,
    fragments: Option<usize>,
    saved: Option<String>,
    replay: Option<Vec<String>>,
    /// On a failure, whether the backend failed to run on the smallest case too (not shrunk).
    case_independent: Option<bool>,
    #[serde(flatten)]
    exercised: ExercisedRecord,
}

/// One differing pixel of the counterexample, both lists.
#[derive(Debug, Serialize)]
struct PixelRecord {
    pixel: usize,
    x: u32,
    y: u32,
    reference: Vec<Entry>,
    candidate: Vec<Entry>,
}

/// Runs `conform`; returns whether every case passed.
///
/// # Errors
/// An unknown scheme, a command that cannot run, files that cannot be written.
pub fn conform(args: &ConformArgs) -> Result<bool, String> {
    let scheme = SchemeName::from_name(&args.scheme).ok_or_else(|| {
        let names: Vec<&str> = fragsim_capture::catalog::CATALOG
            .iter()
            .map(|e| e.name)
            .collect();
        format!(
            "unknown scheme {}: one of {}",
            args.scheme,
            names.join(", ")
        )
    })?;
    if !args.backend.contains("{out}") {
        return Err(format!(
            "--backend `{}` has no {{out}}: the command must be told where to write its dump",
            args.backend
        ));
    }
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    // This shard's cases: those numbered `shard.index`, `shard.index + shard.count`, … of all.
    let shard_cases = (args.cases + shard.count - shard.index) / shard.count;
    let params = Params {
        scheme,
        k: args.k,
        capacity: args.capacity,
    };
    let work = args.save.join("work");
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let backend = CommandBackend {
        template: args.backend.clone(),
        timeout: Duration::from_secs_f64(args.timeout),
        work: work.clone(),
        vertex_precision: if args.vertex_precision == "f32" {
            VertexPrecision::F32
        } else {
            VertexPrecision::F64
        },
        power_of_two: args.power_of_two,
    };
    let max_triangles = args
        .max_triangles
        .unwrap_or((args.k.max(args.capacity) + 4).clamp(7, 64));
    let battery = Battery::new(&backend, params)
        .cases(args.cases)
        .seed(args.seed)
        .shard(shard.index, shard.count)
        .shrink_steps(args.shrink_steps)
        .limits(Limits {
            max_side: args.max_side,
            max_triangles: max_triangles as usize,
            power_of_two: args.power_of_two,
            ..Limits::default()
        });
    let bar = crate::progress::bar(u64::from(shard_cases), "conform");
    // Case N starts once case N − 1 has passed; the last case's pass is the run's end.
    let mut cases_started = 0;
    let result = battery.run_with(&mut |event| match event {
        Event::Case(n) => {
            bar.set_position(u64::from(n));
            cases_started = n;
            if args.progress_lines && n > 1 {
                eprintln!("conform: {} of {shard_cases} cases passed", n - 1);
            }
        }
        Event::Shrink(step) => {
            bar.set_message(format!("failed; shrinking (step {step})"));
            if args.progress_lines {
                eprintln!("conform: case {cases_started} failed; shrinking step {step}");
            }
        }
    });
    bar.finish_and_clear();
    if args.progress_lines && result.is_ok() {
        eprintln!("conform: {shard_cases} of {shard_cases} cases passed");
    }
    // The cases' files are scratch; the saved case is written afresh below.
    let _ = std::fs::remove_dir_all(&work);
    let mut summary = Summary {
        passed: true,
        backend: args.backend.clone(),
        conform_scheme: scheme.name().to_string(),
        cases: args.cases,
        seed: args.seed,
        vertex_precision: args.vertex_precision.clone(),
        shard: args.shard.map(|s| s.to_string()),
        cases_run: shard_cases,
        case_number: None,
        shrink_steps: None,
        property: None,
        message: None,
        triangles: None,
        fragments: None,
        saved: None,
        replay: None,
        case_independent: None,
        exercised: Exercised::default().into(),
    };
    let saved = args.save.join("case");
    let found = match result {
        Ok(passed) => {
            // A failing case saved by an earlier run no longer describes this backend.
            if saved.exists() {
                std::fs::remove_dir_all(&saved)
                    .map_err(|e| format!("cannot remove {}: {e}", saved.display()))?;
            }
            let spec = SceneSpec::named("generated", 0.0, 0.0);
            let context = sized(
                Context::new("conform", &spec, args.max_side, args.max_side),
                &params,
            );
            summary.exercised = passed.exercised.into();
            if args.json {
                record::emit("conform", &context, &summary)?;
            } else {
                #[expect(clippy::shadow_unrelated, reason = "the shard the arguments name")]
                let cases = match args.shard {
                    Some(shard) => format!("{shard_cases} cases (shard {shard} of {})", args.cases),
                    None => format!("{} cases", args.cases),
                };
                outln!(
                    "conform: {} passes {cases} of {} (k {}, capacity {}, seed {}, {} vertex \
                     stage):",
                    args.backend,
                    scheme.name(),
                    args.k,
                    args.capacity,
                    args.seed,
                    args.vertex_precision
                );
                for line in exercised_lines(&passed.exercised, args.k, args.capacity) {
                    outln!("  {line}");
                }
            }
            return Ok(true);
        }
        Err(Failure::Refused(message)) => return Err(message),
        Err(Failure::Counterexample(found)) => found,
    };
    let replay = save(&backend, &found, &params, &saved)?;
    summary.exercised = found.exercised.into();
    let spec = Case::scene_and_camera(
        &saved.join("scene").join("mesh.obj").display().to_string(),
        mesh_hash(found.submitted.obj().as_bytes()),
    );
    let viewport = found.submitted.viewport;
    let context = sized(
        Context::new("conform", &spec, viewport.width, viewport.height),
        &params,
    );
    summary = Summary {
        passed: false,
        cases_run: found.cases_run,
        case_number: Some(found.case_number),
        shrink_steps: Some(found.shrink_steps),
        property: Some(found.property.to_string()),
        message: Some(found.message.clone()),
        triangles: Some(found.submitted.triangles.len()),
        fragments: Some(found.fragments),
        saved: Some(saved.display().to_string()),
        replay: Some(replay.clone()),
        case_independent: Some(found.case_independent),
        ..summary
    };
    let pixels: Vec<PixelRecord> = found
        .mismatches()
        .iter()
        .map(|m| pixel_record(m, viewport.width))
        .collect();
    let mut lines = vec![record::line("conform", &context, &summary)?];
    for p in &pixels {
        lines.push(record::line("counterexample_pixel", &context, p)?);
    }
    let report = saved.join("conform.jsonl");
    std::fs::write(&report, lines.join("\n") + "\n")
        .map_err(|e| format!("cannot write {}: {e}", report.display()))?;
    if args.json {
        for line in &lines {
            outln!("{line}");
        }
    } else {
        print_counterexample(args, &found, &pixels, &saved, &replay);
    }
    Ok(false)
}

/// The context with the run's K and capacity.
fn sized(mut context: Context, params: &Params) -> Context {
    context.k = Some(Slots::Fixed(params.k));
    context.capacity = Some(Slots::Fixed(params.capacity));
    context
}

#[expect(
    clippy::cast_possible_truncation,
    reason = "pixel indices fit u32: viewports are at most 16384² pixels (Viewport::new)"
)]
fn pixel_record(m: &PixelMismatch, width: u32) -> PixelRecord {
    PixelRecord {
        pixel: m.pixel,
        x: m.pixel as u32 % width,
        y: m.pixel as u32 / width,
        reference: entries(&m.expected),
        candidate: entries(&m.got),
    }
}

/// Runs the backend once more on the shrunk case inside `dir` (`dir/scene`, `dir/out`), and
/// writes `dir/replay.sh`; returns the replay's command lines.
fn save(
    backend: &CommandBackend,
    found: &Counterexample,
    params: &Params,
    dir: &Path,
) -> Result<Vec<String>, String> {
    let case = &found.submitted;
    let scene = case.scene();
    let view = scene
        .view_under(case.viewport, &Case::camera(), Conventions::REFERENCE)
        .map_err(|e| e.to_string())?;
    let input = Input {
        case,
        view: &view,
        params,
    };
    // The dump may be missing when the failure is the backend's own (a crash, a timeout):
    // the scene files are saved all the same. A backend that fails whatever the case is not run
    // again (a timeout would cost its whole length once more).
    let rerun = if found.case_independent {
        #[expect(
            clippy::shadow_unrelated,
            reason = "the scene file's path in the counterexample's directory"
        )]
        let scene = dir.join("scene");
        if dir.exists() {
            std::fs::remove_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        for d in [&scene, &dir.join("out")] {
            std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
        }
        write_case(case, &view, params, &scene).map_err(|e| e.to_string())?;
        Err(found.message.clone())
    } else {
        backend.run_in(&input, dir).map_err(|e| e.to_string())
    };
    let absolute = std::fs::canonicalize(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // Every path absolute, so that the script runs from any directory: the backend's command
    // from the directory conform ran in (its own paths may be relative to it), and this very
    // fragsim (which need not be on PATH).
    let here = std::env::current_dir().map_err(|e| format!("the working directory: {e}"))?;
    let fragsim = std::env::current_exe().map_err(|e| format!("fragsim's own path: {e}"))?;
    let replay = vec![
        format!("cd {} || exit 2", shell_quoted(&here)),
        backend.command_line(&absolute.join("scene"), &absolute.join("out"), params),
        format!(
            "{} compare oracle {}{}",
            shell_quoted(&fragsim),
            shell_quoted(&absolute.join("out")),
            match backend.vertex_precision {
                VertexPrecision::F32 => " --vertex-precision f32",
                VertexPrecision::F64 => "",
            }
        ),
    ];
    let mut script = String::from(
        "#!/bin/sh\n# Replays fragsim conform's smallest failing case (from any directory).\n",
    );
    if let Err(e) = rerun {
        script.push_str(&if found.case_independent {
            format!("# The backend failed whatever the case, this one too: {e}\n")
        } else {
            format!("# On saving, the backend failed again: {e}\n")
        });
    }
    for line in &replay {
        script.push_str(line);
        script.push('\n');
    }
    let path = dir.join("replay.sh");
    std::fs::write(&path, script).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(replay)
}

/// `path` quoted for `sh`: in single quotes, a quote inside written `'\''`.
fn shell_quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', "'\\''"))
}

fn print_counterexample(
    args: &ConformArgs,
    found: &Counterexample,
    pixels: &[PixelRecord],
    saved: &Path,
    replay: &[String],
) {
    let case = &found.submitted;
    if found.case_independent {
        outln!(
            "conform: {} FAILS `{}` whatever the case: on case {} of {} (seed {}) and on the \
             smallest case, not shrunk:",
            args.backend,
            found.property,
            found.case_number,
            args.cases,
            args.seed,
        );
    } else {
        outln!(
            "conform: {} FAILS `{}` on case {} of {} (seed {}), shrunk in {} steps to:",
            args.backend,
            found.property,
            found.case_number,
            args.cases,
            args.seed,
            found.shrink_steps
        );
    }
    outln!("  {}", found.message);
    outln!(
        "  viewport {}x{}, {} triangles, {} fragments (corners in half pixels, y down: (1, 1) is \
         pixel (0, 0)'s centre):",
        case.viewport.width,
        case.viewport.height,
        case.triangles.len(),
        found.fragments
    );
    for (prim, t) in case.triangles.iter().enumerate() {
        let corners: Vec<String> = t
            .corners
            .iter()
            .zip(t.depths)
            .map(|(c, z)| format!("({}, {}, z {z})", c[0], c[1]))
            .collect();
        outln!("    prim {prim}: {}", corners.join(" "));
    }
    for p in pixels {
        outln!("  pixel ({}, {}):", p.x, p.y);
        let show = |list: &[Entry]| {
            list.iter()
                .map(|e| format!("{} (prim {}, depth {})", e.key, e.prim, e.depth))
                .collect::<Vec<_>>()
                .join(", ")
        };
        outln!("    oracle:  [{}]", show(&p.reference));
        outln!("    backend: [{}]", show(&p.candidate));
    }
    if found.exercised.cases > 0 {
        outln!(
            "  the {} cases that passed before it:",
            found.exercised.cases
        );
        for line in exercised_lines(&found.exercised, args.k, args.capacity) {
            outln!("    {line}");
        }
    }
    outln!(
        "  saved in {} (scene/, out/, conform.jsonl); replay:",
        saved.display()
    );
    for line in replay {
        outln!("    {line}");
    }
}

/// What the cases exercised, in lines: each claim of a pass with the cases that exercised it,
/// or said never to have been exercised.
fn exercised_lines(e: &Exercised, k: u32, capacity: u32) -> Vec<String> {
    let of = |n: u32| format!("{n} of {}", e.cases);
    let mut lines = vec![format!(
        "equal to the oracle and order-independent in {} cases ({} fragments, {} empty cases)",
        e.cases, e.fragments, e.empty_cases
    )];
    lines.push(if e.overflow_cases > 0 {
        format!(
            "overflow as predicted in {} cases ({} fragments overflowed)",
            of(e.overflow_cases),
            e.overflow_fragments
        )
    } else {
        format!(
            "overflow: never exercised (no case exceeded the scheme's storage: deepest pixel {}, \
             k {k}, capacity {capacity})",
            e.deepest_pixel
        )
    });
    lines.push(format!(
        "deepest pixel {} fragments; deeper than K ({k}) in {} cases, than the capacity \
         ({capacity}) in {}",
        e.deepest_pixel,
        of(e.k_cut_cases),
        of(e.over_capacity_cases)
    ));
    lines.push(if e.tie_cases > 0 {
        format!("ties (fragments at one depth) in {} cases", of(e.tie_cases))
    } else {
        "ties: never exercised (no pixel held two fragments at one depth)".to_string()
    });
    lines
}
