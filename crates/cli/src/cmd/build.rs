//! `nlvid build`: run a forward model over a design (parallel, resumable,
//! shardable) and `nlvid merge`: join shard stores.
//!
//! Two ways to call `build`:
//! * `nlvid build study.toml`: forward model from `[forward]` (+
//!   `[protocol]`), training and checking designs from `[design]`, store,
//!   export and admissibility filters from `[build]`; the training set goes
//!   to `<store>/train`, the checking set to `<store>/check`.
//! * flags only (as before): `--design X.csv --model hertz-prony --store DIR`
//!   (`--domain FILE`: the domain the design was sampled in, stored in the
//!   export's `meta.json` for `nlvid fit`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Args;
use nlvid_surrogate::{Admissibility, BuildOptions, BuildStudy, Shard, merge_report};

use crate::output::print_text;

/// Arguments of `build`.
#[derive(Debug, Args)]
pub struct BuildArgs {
    /// Study file with `[forward]`, `[design]` and `[build]` sections
    /// (docs/study-format.md). Without it, give `--design` and `--store`.
    pub study: Option<PathBuf>,
    /// Design CSV (from `nlvid sample`); flag-only use.
    #[arg(long, conflicts_with = "study")]
    pub design: Option<PathBuf>,
    /// Domain file the design was sampled in (as for `nlvid sample
    /// --domain`); flag-only use. The export's `meta.json` stores it, and
    /// `nlvid fit` needs it there.
    #[arg(long, conflicts_with = "study")]
    pub domain: Option<PathBuf>,
    /// Forward model for flag-only use: `hertz-prony` (analytic LV Hertz
    /// ramp-hold, R = 5 µm, 1 µm/s for 1 s, then hold to 10 s; parameters
    /// G0, g1, g2, tau1, tau2). Study files choose any model in `[forward]`.
    #[arg(long, default_value = "hertz-prony", conflicts_with = "study")]
    pub model: String,
    /// Store directory (created; re-running resumes). Overrides `[build] store`.
    #[arg(long)]
    pub store: Option<PathBuf>,
    /// Build only slice i/n (1-based), e.g. `--shard $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT`.
    /// A malformed slice is a usage error (exit status 2).
    #[arg(long, value_parser = |s: &str| Shard::parse(s).map(|_| s.to_string()).map_err(|e| e.to_string()))]
    pub shard: Option<String>,
    /// Export X, Y (npy + CSV) and a JSON sidecar to this directory when
    /// done. Overrides `[build] export`.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Admissibility filters (flag-only use).
    #[command(flatten)]
    pub filters: Filters,
    /// hertz-prony (flag-only use): time points.
    #[arg(long, default_value_t = 200, conflicts_with = "study")]
    pub points: usize,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Shard store directories (each a store, or holding `train/` and `check/` stores).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Merged store directory.
    #[arg(long, short)]
    pub out: PathBuf,
    /// Export X, Y after merging.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Take the admissibility filters from this study's `[build]` section.
    #[arg(long)]
    pub study: Option<PathBuf>,
    /// Admissibility filters (without --study).
    #[command(flatten)]
    pub filters: Filters,
}

/// Admissibility filters given as flags (thesis §5.4.1, App. A.2).
#[derive(Debug, Args)]
pub struct Filters {
    /// Admissibility: remove runs whose peak force is below this [N].
    #[arg(long, conflicts_with = "study")]
    pub min_peak_force: Option<f64>,
    /// Admissibility: remove runs with any non-positive force after contact.
    #[arg(long, conflicts_with = "study")]
    pub reject_non_repulsive: bool,
}

impl Filters {
    fn admissibility(&self) -> Admissibility {
        Admissibility {
            min_peak_force: self.min_peak_force,
            reject_non_repulsive: self.reject_non_repulsive,
            contact_index: 0,
        }
    }
}

/// Checks that the store and the export directory can be written.
fn check_dirs(store: &Path, export: Option<&Path>) -> anyhow::Result<()> {
    for d in std::iter::once(store).chain(export) {
        nlvid_study::check_output_dir(d)?;
    }
    Ok(())
}

impl BuildArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let opts = BuildOptions {
            shard: self.shard.as_deref().map(Shard::parse).transpose()?,
            progress: !self.quiet && crate::progress::progress_enabled(),
            cancel: None,
        };
        let say = &mut |t: &str| std::io::Write::write_all(&mut std::io::stdout(), t.as_bytes());
        if let Some(path) = &self.study {
            let st = BuildStudy::load(path)?;
            let shard = opts.shard.is_some();
            let (store, export) = st.outputs(path, self.store, self.export, shard)?;
            check_dirs(&store, export.as_deref())?;
            st.build_all(&store, export.as_deref(), &opts, say)?;
            return Ok(ExitCode::SUCCESS);
        }
        let (Some(design), Some(store)) = (&self.design, &self.store) else {
            bail!("give a study file, or --design X.csv and --store DIR");
        };
        check_dirs(store, self.export.as_deref())?;
        let build = nlvid_surrogate::FlagBuild {
            design,
            domain: self.domain.as_deref(),
            model: &self.model,
            points: self.points,
            store,
            export: self.export.as_deref(),
            filters: self.filters.admissibility(),
        };
        build.run(&opts, say)?;
        Ok(ExitCode::SUCCESS)
    }
}

impl MergeArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let (filt, domain) = match &self.study {
            Some(p) => {
                let st = BuildStudy::load(p).with_context(|| format!("--study {}", p.display()))?;
                (st.settings.filters, Some(st.settings.design.domain))
            }
            None => (self.filters.admissibility(), None),
        };
        let export = self.export.as_deref();
        print_text(&merge_report(
            &self.shards,
            &self.out,
            export,
            &filt,
            domain.as_ref(),
        )?)?;
        Ok(ExitCode::SUCCESS)
    }
}
