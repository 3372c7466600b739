//! The `fragsim` command line: `render` (the default) runs schemes on a scene, checks them
//! against the serial oracle and writes a table, JSON and PNGs.

mod args;
mod bench;
mod compare;
mod explain;
mod export;
mod hazard;
mod judge;
mod render;
mod schemes;
mod sweep;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub use args::{Count, ExecutorChoice, SceneArgs, SchemeArgs};
pub use bench::{BenchArgs, BenchReport, BenchRow};
pub use compare::CompareArgs;
pub use explain::{ExplainArgs, ExplainScheme, WriteBackArg};
pub use export::ExportArgs;
pub use hazard::{BaselineRow, HazardArgs, HazardReport, HazardRow};
pub use judge::{AttributePass, EffectName};
pub use render::{RenderArgs, RunSummary, TieChoice};
pub use schemes::{Fault, SchemeChoice, SchemeName, Sizing};
pub use sweep::{SweepArgs, SweepSeries};

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
    let cli = Cli::parse();
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
        Some(Command::ExportScene(args)) => {
            return exit_code(export::export_scene(&args).map(|()| true), "")
        }
        None => cli.render,
    };
    match render::render(&args) {
        Ok(summary) if summary.iter().all(|run| run.keeps_guarantee) => ExitCode::SUCCESS,
        Ok(summary) => {
            for run in summary.iter().filter(|run| !run.keeps_guarantee) {
                eprintln!(
                    "error: {} on the {} executor breaks its guarantee `{}` ({} mismatched pixels, {} with a miscounted overflow)",
                    run.scheme,
                    run.executor,
                    run.guarantee,
                    run.mismatches,
                    run.overflow_miscounted_pixels
                );
            }
            ExitCode::from(1)
        }
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
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
