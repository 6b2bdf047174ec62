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
use nlvid_surrogate::doe::DesignSettings;
use nlvid_surrogate::{Admissibility, BuildOptions, Shard, build, export, load, merge};

use super::surrogate::read_table;

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

/// A study file read for a meta-model build.
pub struct BuildStudy {
    /// The forward model.
    pub model: Box<dyn ForwardModel>,
    /// `[design]`.
    pub design: DesignSettings,
    /// `[build] store`.
    pub store: Option<PathBuf>,
    /// `[build] export`.
    pub export: Option<PathBuf>,
    /// `[build]` filters.
    pub filters: Admissibility,
}

/// Reads `[forward]` (+ `[protocol]`), `[design]` and `[build]`; unknown
/// sections or keys are errors naming file and line.
///
/// # Errors
/// Any study error.
pub fn read_study(path: &Path) -> anyhow::Result<BuildStudy> {
    let mut study = Study::load(path)?;
    let _ = study.root().opt_str("title")?;
    let model = ForwardSettings::from_study(&mut study)?.build()?;
    let mut ds = study.section("design")?;
    let design =
        DesignSettings::from_section(&mut ds, &model.parameter_names(), &model.parameter_units())?;
    ds.finish()?;
    let (store, export, filters) = match study.opt_section("build")? {
        Some(mut b) => {
            let store = b.opt_path("store")?;
            let export = b.opt_path("export")?;
            let filters = Admissibility::from_section(&mut b, model.contact_index())?;
            b.finish()?;
            (store, export, filters)
        }
        None => (
            None,
            None,
            Admissibility {
                contact_index: model.contact_index(),
                ..Default::default()
            },
        ),
    };
    study.finish()?;
    Ok(BuildStudy {
        model,
        design,
        store,
        export,
        filters,
    })
}

fn do_export(
    store: &Path,
    dir: &Path,
    filt: &Admissibility,
    domain: Option<&Domain>,
) -> anyhow::Result<()> {
    let mm = load(store, filt)?;
    export(&mm, dir, domain)?;
    if domain.is_none() {
        eprintln!(
            "warning: {} has no parameter domain (give --domain FILE, or build from a study): \
             `nlvid fit` and `nlvid cohort` cannot use it",
            dir.join("meta.json").display()
        );
    }
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

fn report_failures(store: &Path) -> anyhow::Result<()> {
    let mm = load(store, &Admissibility::default())?;
    for (i, status, reason, secs) in &mm.status {
        if status == "failed" {
            eprintln!("run {i} failed after {secs:.3} s: {reason}");
        }
    }
    Ok(())
}

fn run_set(
    name: &str,
    model: &dyn ForwardModel,
    design: &[Vec<f64>],
    store: &Path,
    shard: Option<Shard>,
    quiet: bool,
) -> anyhow::Result<()> {
    let hide = std::env::var_os("NLVID_NO_PROGRESS").is_some() || std::env::var_os("CI").is_some();
    let opts = BuildOptions {
        shard,
        progress: !quiet && !hide,
        cancel: None,
    };
    let t0 = std::time::Instant::now();
    let s = build(model, design, store, &opts)?;
    let secs = t0.elapsed().as_secs_f64();
    let per_run = if s.ran > 0 {
        format!(", {:.3} s per run", secs / s.ran as f64)
    } else {
        String::new()
    };
    println!(
        "{name}: {} runs in shard: {} already done, {} run now ({} failed) in {secs:.2} s{per_run}",
        s.in_shard, s.skipped, s.ran, s.failed
    );
    if s.failed > 0 {
        report_failures(store)?;
    }
    Ok(())
}

impl BuildArgs {
    /// Run.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let shard = self.shard.as_deref().map(Shard::parse).transpose()?;
        if let Some(path) = &self.study {
            let st = read_study(path)?;
            let Some(store) = self.store.clone().or(st.store.clone()) else {
                bail!(
                    "{}: no store directory: give --store DIR or `store = \"DIR\"` in [build]",
                    path.display()
                );
            };
            // The tasks of an array would all write `[build] export` at
            // once: a shard exports only when asked with --export.
            let export_dir = match shard {
                Some(_) => self.export.clone(),
                None => self.export.clone().or(st.export.clone()),
            };
            let (train, check) = st.design.designs()?;
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
                    do_export(
                        &store.join(name),
                        &dir.join(name),
                        &st.filters,
                        Some(&st.design.domain),
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
        let domain = self
            .domain
            .as_deref()
            .map(|p| super::sample::read_domain(p, &model.parameter_names()))
            .transpose()?;
        if let Some(d) = &domain
            && let Some((i, _)) = design
                .rows
                .iter()
                .enumerate()
                .find(|(_, x)| !d.contains(x, 1e-9))
        {
            bail!(
                "{}: design row {} lies outside the domain of {}",
                design_path.display(),
                i + 2,
                self.domain.as_deref().unwrap_or(Path::new("")).display()
            );
        }
        run_set("design", &model, &design.rows, store, shard, self.quiet)?;
        if let Some(dir) = &self.export {
            let filt = Admissibility {
                min_peak_force: self.min_peak_force,
                reject_non_repulsive: self.reject_non_repulsive,
                contact_index: 0,
            };
            do_export(store, dir, &filt, domain.as_ref())?;
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
                (st.filters, Some(st.design.domain))
            }
            None => (
                Admissibility {
                    min_peak_force: self.min_peak_force,
                    reject_non_repulsive: self.reject_non_repulsive,
                    contact_index: 0,
                },
                None,
            ),
        };
        // A study build's shards hold `train/` (and `check/`) stores.
        let sets: Vec<Option<&str>> = if self.shards.iter().all(|d| d.join("meta.json").is_file()) {
            vec![None]
        } else if self
            .shards
            .iter()
            .all(|d| d.join("train/meta.json").is_file())
        {
            let mut v = vec![Some("train")];
            if self
                .shards
                .iter()
                .all(|d| d.join("check/meta.json").is_file())
            {
                v.push(Some("check"));
            }
            v
        } else {
            bail!(
                "each shard directory must be a store (meta.json) or hold train/ (and check/) stores"
            );
        };
        for set in sets {
            let sub = |d: &Path| set.map_or_else(|| d.to_path_buf(), |s| d.join(s));
            let dirs: Vec<PathBuf> = self.shards.iter().map(|d| sub(d)).collect();
            let out = sub(&self.out);
            let n = merge(&dirs, &out)?;
            println!(
                "merged {} shards into {} ({n} runs copied)",
                dirs.len(),
                out.display()
            );
            if let Some(dir) = &self.export {
                do_export(&out, &sub(dir), &filt, domain.as_ref())?;
            }
        }
        Ok(ExitCode::SUCCESS)
    }
}
