//! The `weft` binary: the command line is src/cli/ (one file per subcommand).

#![deny(unsafe_code)]

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
