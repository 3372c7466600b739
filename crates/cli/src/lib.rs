//! The `fragsim` command line: `render` (the default) runs schemes on a scene, checks them
//! against the serial oracle and writes a table, JSON and PNGs. The measurements (`bench`,
//! `sweep`, `hazard`) are `fragsim_measure`'s; their commands here turn the options into the
//! library's parameters and print and write what it returns.

// The Linebender lint set's crate-level lints (https://linebender.org/wiki/canonical-lints/), as
// vello's lib.rs has them: `unused_crate_dependencies` not under `cfg(test)`, whose target also
// links the dev-dependencies that only the integration tests use. Not `print_stdout` and
// `print_stderr`: this crate is the command line, whose job is printing.
#![cfg_attr(not(test), warn(unused_crate_dependencies))]

use std::ffi::OsString;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

/// `println!` for a command's output on stdout: once stdout is closed (`fragsim … | head -1`)
/// the rest of the output is dropped quietly instead of panicking, and the command finishes with
/// its documented exit code.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` with `outln!`'s handling of a closed stdout.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_stdout(format_args!($($arg)*))
    };
}

/// Set when a write to stdout failed: the reader is gone, so nothing more is written.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes to stdout; a closed pipe ends the output silently, any other failure once on stderr.
fn write_stdout(text: std::fmt::Arguments<'_>) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    if let Err(error) = std::io::stdout().lock().write_fmt(text) {
        STDOUT_CLOSED.store(true, Ordering::Relaxed);
        if error.kind() != std::io::ErrorKind::BrokenPipe {
            eprintln!(
                "warning: cannot write to stdout ({error}); the rest of the output is dropped"
            );
        }
    }
}

mod args;
mod bench;
mod compare;
mod conform;
mod explain;
mod export;
mod hazard;
use fragsim_oracle::memory_cap as oracle_memory;
mod progress;
pub mod record;
mod render;
mod schemes;
mod sweep;
use fragsim_measure::table;

use std::process::ExitCode;

use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser, Subcommand};

pub use args::{ConventionsArgs, Count, DumpArgs, ExecutorChoice, SceneArgs, SchemeArgs, Shard};
pub use bench::BenchArgs;
pub use compare::{compare, CompareArgs};
pub use conform::{conform, ConformArgs};
pub use explain::{ExplainArgs, ExplainedScheme, WriteBackArg};
pub use export::ExportArgs;
pub use fragsim_catalog::{SchemeName, Sizing};
pub use hazard::HazardArgs;
pub use render::{RenderArgs, RunSummary, TieChoice};
pub use schemes::SchemeChoice;
pub use sweep::SweepArgs;

/// fragsim: the CPU reference simulator of GPU atomics for multi-fragment rendering.
#[derive(Debug, Parser)]
#[command(
    name = "fragsim",
    version,
    about,
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// What to do; without one, `render` runs with the options below.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Options of the default `render`.
    #[command(flatten)]
    pub render: RenderArgs,
    /// No progress bars on stderr (they are drawn only on a terminal anyway).
    #[arg(long, global = true)]
    pub quiet: bool,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene with capture schemes, check them against the oracle, write images.
    Render(RenderArgs),
    /// Measure every scheme's speed and accuracy (passes, memory, loss, error pixels, time).
    Bench(BenchArgs),
    /// Error-pixel rate per view angle around the model, and the speed/accuracy scatter.
    Sweep(SweepArgs),
    /// Compare a dump (docs/dump-format.md) with fragsim's oracle or another dump, pixel by pixel.
    Compare(CompareArgs),
    /// Run the conformance battery against a backend command on generated cases, shrink a failure.
    Conform(ConformArgs),
    /// Write a view's screen triangles (snapped, clipped, oriented) for a GPU backend.
    ExportScene(ExportArgs),
    /// Find, shrink and print a step-by-step interleaving (k-buffer hazard, MDTS invariant).
    Explain(ExplainArgs),
    /// The k-buffer's hazard rate vs threads in flight and depth complexity (scheduled executor).
    Hazard(HazardArgs),
}

/// Parses the command line and runs it; errors go to stderr with a non-zero exit code.
#[must_use]
pub fn main() -> ExitCode {
    let matches = command().get_matches_from(help_flag_dropped(std::env::args_os().collect()));
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    progress::set_quiet(cli.quiet);
    if let Err(message) = check_flags(&cli, &matches) {
        eprintln!("error: {message}");
        return ExitCode::from(2);
    }
    let args = match cli.command {
        Some(Command::Render(args)) => args,
        Some(Command::Sweep(args)) => return exit_code(sweep::sweep(&args).map(|_| true), ""),
        Some(Command::Explain(args)) => {
            return exit_code(
                explain::explain(&args),
                "no interleaving showed the property",
            )
        }
        Some(Command::Hazard(args)) => return exit_code(hazard::hazard(&args).map(|_| true), ""),
        Some(Command::Bench(args)) => return exit_code(bench::bench(&args).map(|_| true), ""),
        Some(Command::Compare(args)) => {
            return exit_code(
                compare::compare(&args),
                "the candidate differs from the reference",
            )
        }
        Some(Command::Conform(args)) => {
            return exit_code(conform::conform(&args), "the backend fails the battery")
        }
        Some(Command::ExportScene(args)) => {
            return exit_code(export::export_scene(&args).map(|()| true), "")
        }
        None => cli.render,
    };
    match render::render(&args) {
        Ok(summary) => {
            let (code, broken) = render_verdict(&summary);
            for message in broken {
                eprintln!("error: {message}");
            }
            code
        }
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

/// `render`'s exit code for the runs it made, with what it prints on stderr (each after
/// `error: `): success when every run kept its guarantee; 1 and one message for each run that
/// broke it, naming its scheme, executor and guarantee and counting the pixels that show it.
/// Apart from [`main`] so that the unit tests below see a broken guarantee fail `render`
/// without a scheme that breaks one (the integration suite's fault-injecting wrapper shows that
/// the verdict itself can fail: `tests/suite/injected_fault.rs`).
fn render_verdict(summary: &[RunSummary]) -> (ExitCode, Vec<String>) {
    let broken: Vec<String> = summary
        .iter()
        .filter(|run| !run.keeps_guarantee)
        .map(|run| {
            format!(
                "{} on the {} executor breaks its guarantee `{}` ({} mismatched pixels, {} with a miscounted overflow)",
                run.scheme,
                run.executor,
                run.guarantee,
                run.mismatched_pixels,
                run.overflow_miscounted_pixels
            )
        })
        .collect();
    let code = if broken.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    };
    (code, broken)
}

/// The command line's definition: the derived one, with `sweep --view` hidden from `sweep
/// --help` (the sweep sets the angle itself; the flag stays parsed so that [`check_flags`] can
/// refuse it saying why, rather than clap's bare "unexpected argument").
fn command() -> clap::Command {
    Cli::command().mut_subcommand("sweep", |sweep| {
        sweep.mut_arg("view", |view| view.hide(true))
    })
}

/// `fragsim help … --help` as `fragsim help …`: clap's `help` subcommand takes no flags, so
/// the `--help` a user adds out of habit would otherwise be an "unrecognized subcommand" error.
fn help_flag_dropped(mut argv: Vec<OsString>) -> Vec<OsString> {
    if argv.get(1).is_some_and(|word| word == "help") {
        let rest = argv.split_off(2);
        argv.extend(
            rest.into_iter()
                .filter(|word| word != "--help" && word != "-h"),
        );
    }
    argv
}

/// Flags given where they do nothing: an error where the command would contradict them, a
/// warning on stderr where they are merely unused.
///
/// # Errors
/// `sweep --view` (the sweep sets the angle itself).
fn check_flags(cli: &Cli, matches: &ArgMatches) -> Result<(), String> {
    let (schemes, sub) = match &cli.command {
        None => (&cli.render.schemes, matches),
        Some(Command::Render(args)) => (&args.schemes, sub_matches(matches, "render")),
        Some(Command::Bench(args)) => (&args.schemes, sub_matches(matches, "bench")),
        Some(Command::Sweep(args)) => {
            let sub = sub_matches(matches, "sweep");
            if sub.value_source("view") == Some(ValueSource::CommandLine) {
                return Err(format!(
                    "sweep sets the view angle itself ({} angles over a full turn: --angles); \
                     --view {} would be ignored",
                    args.angles, args.scene.view
                ));
            }
            (&args.schemes, sub)
        }
        Some(_) => return Ok(()),
    };
    if sub.value_source("threads") == Some(ValueSource::CommandLine)
        && matches!(
            schemes.executor,
            ExecutorChoice::Serial | ExecutorChoice::Scheduled
        )
    {
        let executor = if schemes.executor == ExecutorChoice::Serial {
            "serial"
        } else {
            "scheduled"
        };
        eprintln!(
            "warning: --threads has no effect on the {executor} executor, which captures on one \
             thread (it sets the parallel and tiled executors' threads)"
        );
    }
    Ok(())
}

/// The matches of subcommand `name`, which clap has just parsed.
fn sub_matches<'a>(matches: &'a ArgMatches, name: &str) -> &'a ArgMatches {
    matches.subcommand_matches(name).unwrap_or(matches)
}

/// 0 when `result` is `Ok(true)`, 1 (after `failure` on stderr) when `Ok(false)`, 2 on errors.
fn exit_code(result: Result<bool, String>, failure: &str) -> ExitCode {
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => {
            eprintln!("error: {failure}");
            ExitCode::from(1)
        }
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of `scheme` on `executor` whose run kept its guarantee or not, the rest of it what
    /// an A-buffer of capacity 2 that miscounted one pixel's overflow reports.
    fn row(scheme: &str, executor: &str, keeps_guarantee: bool) -> RunSummary {
        RunSummary {
            scheme: scheme.into(),
            guarantee: "exact-within-capacity(2)".into(),
            keeps_guarantee,
            guarantee_owed: true,
            executor: executor.into(),
            threads: 1,
            triangles: 8,
            fragments: 40,
            reference_fragments: 40,
            passes: 1,
            count_pass_ms: None,
            max_depth_complexity: 4,
            memory_ops: 80,
            captured: 32,
            overflowed: 8,
            reported_overflow: 8 + u64::from(!keeps_guarantee),
            overflow_miscounted_pixels: u64::from(!keeps_guarantee),
            lost: 0,
            extra: 0,
            mismatched_pixels: u64::from(!keeps_guarantee),
            time_ms: 0.0,
            pass_ms: 0.0,
            resolve_ms: 0.0,
            memory_bytes: 0,
            allocated_bytes: 0,
            slots_per_pixel: Some(2),
        }
    }

    #[test]
    fn render_succeeds_when_every_run_keeps_its_guarantee() {
        let summary = [
            row("abuffer", "serial", true),
            row("abuffer", "parallel", true),
        ];
        let (code, broken) = render_verdict(&summary);
        assert_eq!(code, ExitCode::SUCCESS, "{broken:?}");
        assert!(broken.is_empty(), "nothing is printed: {broken:?}");
        assert_eq!(
            render_verdict(&[]).0,
            ExitCode::SUCCESS,
            "no runs, nothing broken"
        );
    }

    #[test]
    fn render_exits_1_naming_each_run_that_breaks_its_guarantee() {
        let summary = [
            row("abuffer", "serial", true),
            row("abuffer-exact", "parallel", false),
        ];
        let (code, broken) = render_verdict(&summary);
        assert_eq!(code, ExitCode::from(1), "{broken:?}");
        assert_eq!(
            broken,
            [
                "abuffer-exact on the parallel executor breaks its guarantee \
              `exact-within-capacity(2)` (1 mismatched pixels, 1 with a miscounted overflow)"
            ],
            "one message, for the run that broke its guarantee only"
        );
    }
}
