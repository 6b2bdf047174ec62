//! `nlvid build`: run a forward model over a design (parallel, resumable,
//! shardable) and `nlvid merge`: join shard stores.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use clap::Args;
use nlvid_surrogate::{Admissibility, BuildOptions, HertzProny, Shard, build, export, load, merge};

use super::surrogate::read_table;

/// Arguments of `build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Design CSV (from `nlvid sample`).
    #[arg(long)]
    pub design: PathBuf,
    /// Forward model. Available now: `hertz-prony` (analytic LV Hertz ramp-hold,
    /// parameters G0, g1, g2, tau1, tau2). Membrane and FE models plug in here.
    #[arg(long, default_value = "hertz-prony")]
    pub model: String,
    /// Store directory (created; re-running resumes).
    #[arg(long)]
    pub store: PathBuf,
    /// Build only slice i/n (1-based), e.g. `--shard $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT`.
    #[arg(long)]
    pub shard: Option<String>,
    /// Export X, Y (npy + CSV) and a JSON sidecar to this directory when done.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Admissibility: remove runs whose peak force is below this [N].
    #[arg(long)]
    pub min_peak_force: Option<f64>,
    /// Admissibility: remove runs with any non-positive force after contact.
    #[arg(long)]
    pub reject_non_repulsive: bool,
    /// hertz-prony: time points.
    #[arg(long, default_value_t = 200)]
    pub points: usize,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard store directories.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Merged store directory.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Export X, Y after merging.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Admissibility: peak-force threshold [N].
    #[arg(long)]
    pub min_peak_force: Option<f64>,
    /// Admissibility: remove non-repulsive runs.
    #[arg(long)]
    pub reject_non_repulsive: bool,
}

fn do_export(
    store: &std::path::Path,
    dir: &std::path::Path,
    filt: &Admissibility,
) -> anyhow::Result<()> {
    let mm = load(store, filt)?;
    export(&mm, dir)?;
    let c = &mm.counts;
    println!(
        "exported {} of {} runs to {} (failed {}, missing {}, below peak force {}, non-repulsive {})",
        c.kept,
        c.design,
        dir.display(),
        c.failed,
        c.missing,
        c.below_peak,
        c.non_repulsive
    );
    Ok(())
}

impl BuildArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let model = match self.model.as_str() {
            "hertz-prony" => HertzProny::new(5e-6, 1e-6, 1.0, 10.0, self.points),
            other => bail!("--model {other}: unknown forward model (available: hertz-prony)"),
        };
        let design = read_table(&self.design)?;
        if design.header.len() != 5 {
            bail!(
                "{}: hertz-prony needs 5 columns (G0, g1, g2, tau1, tau2), found {}",
                self.design.display(),
                design.header.len()
            );
        }
        let shard = self.shard.as_deref().map(Shard::parse).transpose()?;
        let opts = BuildOptions {
            shard,
            progress: !self.quiet,
            cancel: None,
        };
        let s = build(&model, &design.rows, &self.store, &opts)?;
        println!(
            "{} runs in shard: {} already done, {} run now ({} failed)",
            s.in_shard, s.skipped, s.ran, s.failed
        );
        if let Some(dir) = &self.export {
            let filt = Admissibility {
                min_peak_force: self.min_peak_force,
                reject_non_repulsive: self.reject_non_repulsive,
                contact_index: 0,
            };
            do_export(&self.store, dir, &filt)?;
        }
        Ok(ExitCode::SUCCESS)
    }
}

impl MergeArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let n = merge(&self.shards, &self.out)?;
        println!(
            "merged {} shards into {} ({n} runs copied)",
            self.shards.len(),
            self.out.display()
        );
        if let Some(dir) = &self.export {
            let filt = Admissibility {
                min_peak_force: self.min_peak_force,
                reject_non_repulsive: self.reject_non_repulsive,
                contact_index: 0,
            };
            do_export(&self.out, dir, &filt)?;
        }
        Ok(ExitCode::SUCCESS)
    }
}
