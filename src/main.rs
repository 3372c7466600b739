//! The `fragsim` command: see `fragsim --help`.

fn main() -> std::process::ExitCode {
    fragsim_cli::main()
}
