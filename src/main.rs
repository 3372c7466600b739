//! The `fragsim` command: see `fragsim --help`.

#![warn(clippy::cast_possible_truncation, clippy::shadow_unrelated)]

fn main() -> std::process::ExitCode {
    fragsim_cli::main()
}
