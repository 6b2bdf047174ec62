//! The `nlvid` binary: a thin layer over the pipeline crates.
//!
//! `main` only turns [`nlvid_cli::run`]'s result into an exit code; every
//! subcommand lives in its own module under `cmd/`.

use std::process::ExitCode;

fn main() -> ExitCode {
    match nlvid_cli::run() {
        Ok(code) => code,
        Err(err) => nlvid_cli::report(&err),
    }
}
