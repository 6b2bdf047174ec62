//! The `nlvid` binary: a thin layer over the pipeline crates.
//!
//! `main` only turns [`run`]'s result into an exit code; every subcommand
//! lives in its own module under `cmd/`.

use std::process::ExitCode;

use clap::Parser;

mod cmd;

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<ExitCode> {
    let cli = cmd::Cli::parse();
    init_logging(cli.verbose);
    cli.command.run()
}

fn init_logging(verbosity: u8) {
    let default = match verbosity {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_env("NLVID_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
}
