//! Command-line surface: one module per subcommand.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod inspect;

/// Identify non-linear viscoelastic properties of capsules and cells from
/// force–time experiments.
#[derive(Debug, Parser)]
#[command(name = "nlvid", version, about, long_about = None)]
pub struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); NLVID_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,

    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands, in pipeline order.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print the version and the crates that make up this build.
    Version,
    /// Show what an AFM instrument file holds (segments, channels, calibration); export CSV, plot, quick fits.
    Inspect(inspect::Args),
}

impl Command {
    /// Run the chosen subcommand.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        match self {
            Command::Version => {
                println!("nlvid {}", env!("CARGO_PKG_VERSION"));
                Ok(ExitCode::SUCCESS)
            }
            Command::Inspect(args) => args.run(),
        }
    }
}
