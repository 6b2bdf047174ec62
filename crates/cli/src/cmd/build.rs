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
use nlvid_forward::{ForwardSettings, HertzPronySpec};
use nlvid_model::{Domain, ForwardModel};
use nlvid_study::Study;
use nlvid_surrogate::{
    Admissibility, BuildOptions, BuildSettings, Shard, build_report, export_report, merge,
    read_domain, read_table, set_dir, shard_sets,
};

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
    #[arg(long)]
    pub shard: Option<String>,
    /// Export X, Y (npy + CSV) and a JSON sidecar to this directory when
    /// done. Overrides `[build] export`.
    #[arg(long)]
    pub export: Option<PathBuf>,
    /// Admissibility: remove runs whose peak force is below this [N] (flag-only use).
    #[arg(long, conflicts_with = "study")]
    pub min_peak_force: Option<f64>,
    /// Admissibility: remove runs with any non-positive force after contact (flag-only use).
    #[arg(long, conflicts_with = "study")]
    pub reject_non_repulsive: bool,
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
    #[arg(long, conflicts_with_all = ["min_peak_force", "reject_non_repulsive"])]
    pub study: Option<PathBuf>,
    /// Admissibility: peak-force threshold [N].
    #[arg(long)]
    pub min_peak_force: Option<f64>,
    /// Admissibility: remove non-repulsive runs.
    #[arg(long)]
    pub reject_non_repulsive: bool,
}

/// A study read for a meta-model build: the forward model of `[forward]`
/// and the `[design]` and `[build]` sections (library calls only).
pub struct BuildStudy {
    /// The forward model.
    pub model: Box<dyn ForwardModel>,
    /// `[design]` and `[build]`.
    pub settings: BuildSettings,
}

/// Reads `[forward]` (+ `[protocol]`), `[design]` and `[build]`; sections
/// of other stages are left alone, unknown ones are errors.
///
/// # Errors
/// Any study error (file, line, key).
pub fn read_study(path: &Path) -> anyhow::Result<BuildStudy> {
    let mut study = Study::load(path)?;
    let model = ForwardSettings::from_study(&mut study)?.build()?;
    let (names, units) = (model.parameter_names(), model.parameter_units());
    let settings = BuildSettings::from_study(study, &names, &units, model.contact_index())?;
    Ok(BuildStudy { model, settings })
}

/// The admissibility filters of the flags.
fn filters(min_peak_force: Option<f64>, reject_non_repulsive: bool) -> Admissibility {
    Admissibility {
        min_peak_force,
        reject_non_repulsive,
        contact_index: 0,
    }
}

fn do_export(
    store: &Path,
    dir: &Path,
    filters: &Admissibility,
    domain: Option<&Domain>,
) -> anyhow::Result<()> {
    print_text(&export_report(store, dir, filters, domain)?)
}

fn run_set(
    name: &str,
    model: &dyn ForwardModel,
    design: &[Vec<f64>],
    store: &Path,
    shard: Option<Shard>,
    quiet: bool,
) -> anyhow::Result<()> {
    let opts = BuildOptions {
        shard,
        progress: !quiet && crate::progress::progress_enabled(),
        cancel: None,
    };
    print_text(&build_report(name, model, design, store, &opts)?)
}

impl BuildArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let shard = self.shard.as_deref().map(Shard::parse).transpose()?;
        if let Some(path) = &self.study {
            let st = read_study(path)?;
            let Some(store) = self.store.clone().or(st.settings.store.clone()) else {
                bail!(
                    "{}: no store directory: give --store DIR or `store = \"DIR\"` in [build]",
                    path.display()
                );
            };
            // The tasks of an array would all write `[build] export` at
            // once: a shard exports only when asked with --export.
            let export_dir = match shard {
                Some(_) => self.export.clone(),
                None => self.export.clone().or(st.settings.export.clone()),
            };
            let (train, check) = st.settings.design.designs()?;
            let mut sets = vec![("train", train)];
            if !check.is_empty() {
                sets.push(("check", check));
            }
            for (name, design) in &sets {
                run_set(
                    name,
                    st.model.as_ref(),
                    design,
                    &store.join(name),
                    shard,
                    self.quiet,
                )?;
            }
            if let Some(dir) = &export_dir {
                for (name, _) in &sets {
                    let domain = Some(&st.settings.design.domain);
                    do_export(
                        &store.join(name),
                        &dir.join(name),
                        &st.settings.filters,
                        domain,
                    )?;
                }
            }
            return Ok(ExitCode::SUCCESS);
        }
        let (Some(design_path), Some(store)) = (&self.design, &self.store) else {
            bail!("give a study file, or --design X.csv and --store DIR");
        };
        let model = match self.model.as_str() {
            "hertz-prony" => HertzPronySpec::flag_defaults(self.points).build()?,
            other => bail!(
                "--model {other}: unknown forward model for flag-only use (available: hertz-prony; \
                 afm-fe and membrane are set up in a study file's [forward] section)"
            ),
        };
        let design = read_table(design_path)?;
        if design.header.len() != 5 {
            bail!(
                "{}: hertz-prony needs 5 columns (G0, g1, g2, tau1, tau2), found {}",
                design_path.display(),
                design.header.len()
            );
        }
        let names = model.parameter_names();
        let domain = (self.domain.as_deref())
            .map(|p| read_domain(p, &names, &design.rows))
            .transpose()
            .with_context(|| format!("--domain for --design {}", design_path.display()))?;
        run_set("design", &model, &design.rows, store, shard, self.quiet)?;
        if let Some(dir) = &self.export {
            let filters = filters(self.min_peak_force, self.reject_non_repulsive);
            do_export(store, dir, &filters, domain.as_ref())?;
        }
        Ok(ExitCode::SUCCESS)
    }
}

impl MergeArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let (filt, domain) = match &self.study {
            Some(p) => {
                let st = read_study(p).with_context(|| format!("--study {}", p.display()))?;
                (st.settings.filters, Some(st.settings.design.domain))
            }
            None => (
                filters(self.min_peak_force, self.reject_non_repulsive),
                None,
            ),
        };
        for set in shard_sets(&self.shards)? {
            let dirs: Vec<PathBuf> = self.shards.iter().map(|d| set_dir(d, set)).collect();
            let out = set_dir(&self.out, set);
            let n = merge(&dirs, &out)?;
            say!(
                "merged {} shards into {} ({n} runs copied)",
                dirs.len(),
                out.display()
            )?;
            if let Some(dir) = &self.export {
                do_export(&out, &set_dir(dir, set), &filt, domain.as_ref())?;
            }
        }
        Ok(ExitCode::SUCCESS)
    }
}
