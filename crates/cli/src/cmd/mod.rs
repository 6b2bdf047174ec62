//! Command-line surface: one module per subcommand.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod build;
pub mod sample;
pub mod surrogate;

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
    /// Latin-hypercube training and checking designs in a parameter domain.
    Sample(sample::SampleArgs),
    /// Run a forward model over a design: parallel, resumable, shardable.
    Build(build::BuildArgs),
    /// Merge shard stores of one build.
    Merge(build::MergeArgs),
    /// Kriging surrogates: fit, predict, check.
    #[command(subcommand)]
    Surrogate(surrogate::SurrogateCmd),
}

impl Command {
    /// Run the chosen subcommand.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        match self {
            Command::Version => {
                println!("nlvid {}", env!("CARGO_PKG_VERSION"));
                Ok(ExitCode::SUCCESS)
            }
            Command::Sample(a) => a.run(),
            Command::Build(a) => a.run(),
            Command::Merge(a) => a.run(),
            Command::Surrogate(c) => c.run(),
        }
    }
}
