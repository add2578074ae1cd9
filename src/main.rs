//! The `graspmap` binary: parse flags, run, print errors as one line and exit 2.

use std::process::ExitCode;

fn main() -> ExitCode {
    match graspmap::cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::from(2)
        }
    }
}
