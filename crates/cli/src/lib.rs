//! The library behind the `nlvid` binary: subcommands, argument handling and
//! shared output helpers. The binary (`main.rs`) only calls [`run`].
//!
//! Conventions every subcommand follows:
//! - two-stage arguments: raw clap `Args` → validated `Config` ([`cmd::Run`]);
//!   then one call into a library crate, then output;
//! - `--json`: stdout carries exactly one JSON document ([`output::print_json`]);
//! - curves as CSV and JSON with unit-suffixed headers (`force_N`), written
//!   atomically (`nlvid_model::Curve::to_json`, [`output::write_atomic`]);
//! - stdout written with [`say!`] / [`output::print_text`]: a closed pipe
//!   (`nlvid … | head`) ends the command quietly, never a panic;
//! - progress bars on stderr, hidden off-terminal and in CI ([`progress::bar`]);
//! - logs on stderr via `tracing` (`-v`, `NLVID_LOG`);
//! - `--shard i/n` for batches split over a cluster (`nlvid_surrogate::Shard`);
//! - outputs record the study hash (`nlvid_study::Study::provenance`).
//!
//! Cost: negligible; the work is in the pipeline crates.

#![warn(missing_docs)]

use std::process::ExitCode;

use clap::Parser;

pub mod args;
#[macro_use]
pub mod output;
pub mod cmd;
pub mod embedded_demo;
pub mod progress;

/// Parses the command line, sets up logging and runs the subcommand.
///
/// # Errors
/// Any error of the subcommand; `main` prints it and exits with status 1.
pub fn run() -> anyhow::Result<ExitCode> {
    let cli = cmd::Cli::parse();
    init_logging(cli.verbose);
    let ctx = cmd::Context { json: cli.json };
    cli.command.run(&ctx)
}

/// Reports a failed run on stderr and gives the exit status: 1 for errors;
/// a closed stdout pipe (`nlvid ... | head`) ends quietly with status 0.
/// The error and its causes are `: `-joined, each cause text once (an OS
/// error wrapped by two layers that both quote it appears once;
/// [`nlvid_study::error_message`], also the Python exceptions' text).
pub fn report(err: &anyhow::Error) -> ExitCode {
    let broken_pipe = err.chain().any(|e| {
        e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || e.downcast_ref::<serde_json::Error>()
                .is_some_and(|j| j.io_error_kind() == Some(std::io::ErrorKind::BrokenPipe))
            || e.to_string().contains("Broken pipe (os error 32)")
    });
    if broken_pipe {
        return ExitCode::SUCCESS;
    }
    eprintln!("error: {}", nlvid_study::error_message(err.as_ref()));
    ExitCode::FAILURE
}

/// Logs to stderr; `-v` raises the level, `NLVID_LOG` (an `EnvFilter`
/// directive such as `nlvid_fem=debug`) overrides it.
pub fn init_logging(verbosity: u8) {
    let default = match verbosity {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("NLVID_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    // A second initialisation (tests) is harmless; ignore it.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}
