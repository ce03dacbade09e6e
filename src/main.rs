//! The `lamina` command line: parses the arguments, runs the command (`cli/`), and maps an
//! error to its message and exit status 1 — nothing else. Argument errors clap reports itself
//! (exit status 2).

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    quiet_on_closed_pipe();
    match cli::run(&cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Output piped into a reader that stops early (`lamina sweep FILE --dry-run | head`) ends the
/// process quietly, as it ends other command-line tools, rather than in a panic of `println!`.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: runs first in `main`, before any thread exists, and SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
