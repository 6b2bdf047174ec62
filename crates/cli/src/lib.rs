//! The library behind the `nlvid` binary: subcommands, argument handling and
//! shared output helpers. The binary (`main.rs`) only calls [`run`].
//!
//! Conventions every subcommand follows:
//! - two-stage arguments: raw clap `Args` → validated `Config` ([`cmd::Run`]);
//! - `--json`: stdout carries exactly one JSON document ([`output::print_json`]);
//! - curves as CSV with unit-suffixed headers, written atomically
//!   ([`output::Table`], [`output::write_atomic`]);
//! - progress bars on stderr, hidden off-terminal and in CI ([`progress::bar`]);
//! - logs on stderr via `tracing` (`-v`, `NLVID_LOG`);
//! - `--shard i/n` for batches split over a cluster (`nlvid_surrogate::Shard`);
//! - outputs record the study hash ([`output::provenance`]).
//!
//! Cost: negligible; the work is in the pipeline crates.
//!
//! ```
//! use nlvid_cli::output::{Column, Table};
//! let mut t = Table::new(vec![Column::new("time", "s"), Column::new("sigma_1", "Pa")]);
//! t.push_row(&[0.0, 2940.0])?;
//! assert_eq!(t.to_csv()?, "time_s,sigma_1_Pa\n0,2940\n");
//! # Ok::<(), anyhow::Error>(())
//! ```
#![warn(missing_docs)]

use std::process::ExitCode;

use clap::Parser;

pub mod args;
pub mod cmd;
pub mod output;
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
pub fn report(err: &anyhow::Error) -> ExitCode {
    let broken_pipe = err.chain().any(|e| {
        e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    });
    if broken_pipe {
        return ExitCode::SUCCESS;
    }
    eprintln!("error: {err:#}");
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
