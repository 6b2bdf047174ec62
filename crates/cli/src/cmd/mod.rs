//! Command-line surface: one module per subcommand (`Args` → validated
//! `Config` → one library call → output; how to add one: docs/cli/README.md).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub mod build;
mod check;
mod cohort;
mod compare;
mod demo;
mod fit;
mod inspect;
mod material;
pub mod membrane;
mod report;
pub mod sample;
mod simulate;
mod slurm;
pub mod surrogate;

/// Identify non-linear viscoelastic properties of capsules and cells from
/// force–time experiments.
#[derive(Debug, Parser)]
#[command(name = "nlvid", version, about, long_about = None)]
pub struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); NLVID_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,

    /// Print results as one JSON document on stdout instead of text.
    #[arg(long, global = true)]
    pub json: bool,

    /// The subcommand to run.
    #[command(subcommand)]
    pub command: Command,
}

/// Options every subcommand sees.
#[derive(Clone, Copy, Debug)]
pub struct Context {
    /// `--json`: stdout carries exactly one JSON document.
    pub json: bool,
}

/// A subcommand: raw clap arguments that validate into a configuration,
/// which then runs. Two stages, so that every check on user input happens
/// before any work starts.
pub trait Run: Sized {
    /// The validated configuration.
    type Config;
    /// Checks the raw arguments (and any study file they name).
    ///
    /// # Errors
    /// Any invalid input, with a message naming where it is.
    fn validate(self, ctx: &Context) -> anyhow::Result<Self::Config>;
    /// Does the work.
    ///
    /// # Errors
    /// Failures of the work itself (I/O, non-convergence, ...).
    fn execute(config: Self::Config, ctx: &Context) -> anyhow::Result<ExitCode>;

    /// `validate` then `execute`.
    ///
    /// # Errors
    /// As `validate` and `execute`.
    fn run(self, ctx: &Context) -> anyhow::Result<ExitCode> {
        let config = self.validate(ctx)?;
        Self::execute(config, ctx)
    }
}

/// The subcommands, in pipeline order.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print the version and the crates that make up this build.
    Version,
    /// Validate a study file and print every value as the program reads it, in SI.
    Check(check::Args),
    /// Drive one material through uniaxial, equibiaxial or simple-shear loading; CSV of stresses.
    Material(material::Args),
    /// Fluid-filled NLV membrane squeezed between plates (ch. II, semi-analytical).
    Membrane(membrane::MembraneArgs),
    /// One finite-element run of the AFM cell-indentation model (force, deflection, indentation vs time).
    Simulate(simulate::Args),
    /// Show what an AFM instrument file holds (segments, channels, calibration); export CSV, plot, quick fits.
    Inspect(inspect::Args),
    /// Latin-hypercube training and checking designs in a parameter domain.
    Sample(sample::SampleArgs),
    /// Run a forward model over a design: parallel, resumable, shardable.
    Build(build::BuildArgs),
    /// Merge shard stores of one build.
    Merge(build::MergeArgs),
    /// A build as a Slurm job array plus a merge job; `--status DIR` reports it.
    Slurm(slurm::Args),
    /// Kriging surrogates: fit, predict, check.
    #[command(subcommand)]
    Surrogate(surrogate::SurrogateCmd),
    /// Fit NLV parameters to measured curves on a surrogate; re-check with the real model.
    Fit(fit::Args),
    /// Fit every cell of a cohort (parallel, resumable) into a results table.
    Cohort(cohort::Args),
    /// Group G(t) (mean ± sd) and rank-sum p(t) between two groups of cells.
    Compare(compare::Args),
    /// Self-contained HTML report (SVG figures) of a cohort output directory.
    Report(report::Args),
    /// Run the bundled synthetic two-group example end to end.
    Demo(demo::Args),
}

impl Command {
    /// Run the chosen subcommand.
    pub fn run(self, ctx: &Context) -> anyhow::Result<ExitCode> {
        match self {
            Command::Version => {
                let v = env!("CARGO_PKG_VERSION");
                let doc = serde_json::json!({"name": "nlvid", "version": v});
                crate::output::emit(ctx.json, &doc, &format!("nlvid {v}\n"))?;
                Ok(ExitCode::SUCCESS)
            }
            Command::Check(a) => a.run(ctx),
            Command::Material(a) => a.run(ctx),
            Command::Membrane(args) => membrane::run(args, ctx.json),
            Command::Simulate(a) => a.run(ctx),
            Command::Inspect(args) => args.run(ctx.json),
            Command::Sample(a) => a.run(),
            Command::Build(a) => a.run(),
            Command::Merge(a) => a.run(),
            Command::Slurm(a) => a.run(ctx),
            Command::Surrogate(c) => c.run(ctx.json),
            Command::Cohort(a) => a.run(ctx),
            Command::Compare(a) => a.run(ctx),
            Command::Report(a) => a.run(ctx),
            Command::Demo(a) => a.run(ctx),
            Command::Fit(a) => a.run(ctx),
        }
    }
}
