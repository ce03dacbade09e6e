//! The `lamina` command line: parses the arguments, runs the command (`cli/`), and maps an
//! error to its message and exit status 1 — nothing else. Argument errors clap reports itself
//! (exit status 2).

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    match cli::run(&cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
