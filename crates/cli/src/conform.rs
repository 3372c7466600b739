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
//!
//! The run, the record and the saved case are `fragsim_testkit::conform`'s; this module holds
//! the options, the progress and what is printed.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use fragsim_raster::scene_spec::{mesh_hash, SceneSpec};
use fragsim_raster::VertexPrecision;
use fragsim_testkit::conform::{ConformParams, Conformance, Entry, Found};
use fragsim_testkit::{Case, Event, Params};

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

/// Runs `conform`; returns whether every case passed.
///
/// # Errors
/// An unknown scheme, a command that cannot run, files that cannot be written.
pub fn conform(args: &ConformArgs) -> Result<bool, String> {
    let params = ConformParams {
        backend: args.backend.clone(),
        scheme: args.scheme.clone(),
        k: args.k,
        capacity: args.capacity,
        cases: args.cases,
        seed: args.seed,
        shard: args.shard.map(|s| (s.index, s.count)),
        timeout: Duration::from_secs_f64(args.timeout),
        max_side: args.max_side,
        max_triangles: args.max_triangles,
        shrink_steps: args.shrink_steps,
        save: args.save.clone(),
        vertex_precision: if args.vertex_precision == "f32" {
            VertexPrecision::F32
        } else {
            VertexPrecision::F64
        },
        power_of_two: args.power_of_two,
        fragsim: std::env::current_exe().map_err(|e| format!("fragsim's own path: {e}"))?,
    };
    let shard_cases = params.shard_cases();
    let bar = crate::progress::bar(u64::from(shard_cases), "conform");
    // Case N starts once case N − 1 has passed; the last case's pass is the run's end.
    let mut cases_started = 0;
    let result = fragsim_testkit::conform::conform(&params, &mut |event| match event {
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
    let conformance = result?;
    let Some(found) = &conformance.found else {
        if args.progress_lines {
            eprintln!("conform: {shard_cases} of {shard_cases} cases passed");
        }
        print_pass(args, &conformance, shard_cases)?;
        return Ok(true);
    };
    let counterexample = &found.counterexample;
    let mesh = found.saved.join("scene").join("mesh.obj");
    let spec = Case::scene_and_camera(
        &mesh.display().to_string(),
        mesh_hash(counterexample.submitted.obj().as_bytes()),
    );
    let viewport = counterexample.submitted.viewport;
    let context = sized(
        Context::new("conform", &spec, viewport.width, viewport.height),
        &conformance.params,
    );
    let mut lines = vec![record::line("conform", &context, &conformance.record)?];
    for p in &found.pixels {
        lines.push(record::line("counterexample_pixel", &context, p)?);
    }
    let report = found.saved.join("conform.jsonl");
    std::fs::write(&report, lines.join("\n") + "\n")
        .map_err(|e| format!("cannot write {}: {e}", report.display()))?;
    if args.json {
        for line in &lines {
            outln!("{line}");
        }
    } else {
        print_counterexample(args, found);
    }
    Ok(false)
}

/// Prints a pass: the `conform` record, or the claims the cases exercised.
fn print_pass(args: &ConformArgs, passed: &Conformance, shard_cases: u32) -> Result<(), String> {
    if args.json {
        let spec = SceneSpec::named("generated", 0.0, 0.0);
        let context = sized(
            Context::new("conform", &spec, args.max_side, args.max_side),
            &passed.params,
        );
        return record::emit("conform", &context, &passed.record);
    }
    let cases = match args.shard {
        Some(shard) => format!("{shard_cases} cases (shard {shard} of {})", args.cases),
        None => format!("{} cases", args.cases),
    };
    outln!(
        "conform: {} passes {cases} of {} (k {}, capacity {}, seed {}, {} vertex stage):",
        args.backend,
        passed.scheme.name(),
        args.k,
        args.capacity,
        args.seed,
        args.vertex_precision
    );
    for line in passed.exercised.claims(args.k, args.capacity) {
        outln!("  {line}");
    }
    Ok(())
}

/// The context with the run's K and capacity.
fn sized(mut context: Context, params: &Params) -> Context {
    context.k = Some(Slots::Fixed(params.k));
    context.capacity = Some(Slots::Fixed(params.capacity));
    context
}

/// Prints the smallest failing case, its differing pixels, and where it is saved.
fn print_counterexample(args: &ConformArgs, found: &Found) {
    let counterexample = &found.counterexample;
    let case = &counterexample.submitted;
    if counterexample.case_independent {
        outln!(
            "conform: {} FAILS `{}` whatever the case: on case {} of {} (seed {}) and on the \
             smallest case, not shrunk:",
            args.backend,
            counterexample.property,
            counterexample.case_number,
            args.cases,
            args.seed,
        );
    } else {
        outln!(
            "conform: {} FAILS `{}` on case {} of {} (seed {}), shrunk in {} steps to:",
            args.backend,
            counterexample.property,
            counterexample.case_number,
            args.cases,
            args.seed,
            counterexample.shrink_steps
        );
    }
    outln!("  {}", counterexample.message);
    outln!(
        "  viewport {}x{}, {} triangles, {} fragments (corners in half pixels, y down: (1, 1) is \
         pixel (0, 0)'s centre):",
        case.viewport.width,
        case.viewport.height,
        case.triangles.len(),
        counterexample.fragments
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
    for p in &found.pixels {
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
    if counterexample.exercised.cases > 0 {
        outln!(
            "  the {} cases that passed before it:",
            counterexample.exercised.cases
        );
        for line in counterexample.exercised.claims(args.k, args.capacity) {
            outln!("    {line}");
        }
    }
    outln!(
        "  saved in {} (scene/, out/, conform.jsonl); replay:",
        found.saved.display()
    );
    for line in &found.replay {
        outln!("    {line}");
    }
}
