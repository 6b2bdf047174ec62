//! What `nlvid build`, `nlvid sample` and `nlvid merge` read from a study
//! besides the forward model: `[design]` (training and checking designs)
//! and `[build]` (store, export, admissibility filters). The study's other
//! stages (`[parameters]` of `nlvid simulate`, `[fit]`, …) may share the
//! file; they are left to their commands.

use std::path::{Path, PathBuf};

use nlvid_model::Domain;
use nlvid_study::Study;

use crate::build::{Admissibility, BuildOptions, build, export, load};
use crate::doe::DesignSettings;
use crate::error::{Result, SurrogateError};
use nlvid_model::ForwardModel;

/// A study read for a meta-model build: the forward model of `[forward]`
/// (+ `[protocol]`, crate `nlvid-forward`) and `[design]`, `[build]`.
pub struct BuildStudy {
    /// The forward model.
    pub model: Box<dyn ForwardModel>,
    /// `[design]` and `[build]`.
    pub settings: BuildSettings,
}

/// The largest store plus export one build may write, bytes (each run
/// file holds its response as JSON text, ≈ 24 bytes a value; the export
/// holds it twice more, as CSV text and as f64).
pub const MAX_OUTPUT_BYTES: f64 = 50e9;

/// Refuses a build whose store and export would exceed
/// [`MAX_OUTPUT_BYTES`], with the estimate and the settings to change.
fn check_output_size(path: &Path, runs: usize, points: usize) -> Result<()> {
    let bytes = runs as f64 * (points as f64 * (24.0 + 14.0 + 8.0) + 300.0);
    if bytes <= MAX_OUTPUT_BYTES {
        return Ok(());
    }
    Err(SurrogateError::InvalidSettings(format!(
        "{}: {runs} runs × {points} time points need ≈ {:.0} GB of store and export \
         (limit {:.0} GB): lower design.n_train / n_check or the model's `points`",
        path.display(),
        bytes / 1e9,
        MAX_OUTPUT_BYTES / 1e9
    )))
}

impl BuildStudy {
    /// Reads the study at `path`; sections of other stages are left alone,
    /// unknown ones are errors.
    ///
    /// # Errors
    /// Any study error (file, line, key); settings the model cannot use.
    pub fn load(path: &Path) -> Result<Self> {
        let bad = |e: &dyn std::fmt::Display| SurrogateError::InvalidSettings(e.to_string());
        let mut study = Study::load(path).map_err(|e| bad(&e))?;
        let model = nlvid_forward::ForwardSettings::from_study(&mut study)
            .and_then(|f| f.build())
            .map_err(|e| bad(&e))?;
        let (names, units) = (model.parameter_names(), model.parameter_units());
        let settings = BuildSettings::from_study(study, &names, &units, model.contact_index())
            .map_err(|e| bad(&e))?;
        check_output_size(
            path,
            settings.design.n_train + settings.design.n_check,
            model.time_grid().len(),
        )?;
        Ok(Self { model, settings })
    }

    /// Where a build of this study (file `path`) writes: the store (`store`
    /// from the command line, else `[build] store`) and the export
    /// directory (`export`, else `[build] export`; a shard exports only
    /// when asked, since every task of an array would write it at once).
    ///
    /// # Errors
    /// No store directory anywhere.
    pub fn outputs(
        &self,
        path: &Path,
        store: Option<PathBuf>,
        export: Option<PathBuf>,
        shard: bool,
    ) -> Result<(PathBuf, Option<PathBuf>)> {
        let Some(store) = store.or_else(|| self.settings.store.clone()) else {
            return Err(SurrogateError::InvalidSettings(format!(
                "{}: no store directory: give --store DIR or `store = \"DIR\"` in [build]",
                path.display()
            )));
        };
        let export = match shard {
            true => export,
            false => export.or_else(|| self.settings.export.clone()),
        };
        Ok((store, export))
    }

    /// Builds the training design into `store/train` and the checking
    /// design into `store/check` ([`build_report`]), then exports each to
    /// `export/train`, `export/check` with the study's filters and domain
    /// ([`export_report`]); `say` gets each report as it is done.
    ///
    /// # Errors
    /// As [`build_report`] and [`export_report`]; `say` failing.
    pub fn build_all(
        &self,
        store: &Path,
        export: Option<&Path>,
        opts: &BuildOptions<'_>,
        say: &mut dyn FnMut(&str) -> std::io::Result<()>,
    ) -> Result<()> {
        let said = |r: std::io::Result<()>| r.map_err(crate::error::io_err("stdout"));
        let (train, check) = self.settings.design.designs()?;
        let sets: Vec<_> = [("train", train), ("check", check)]
            .into_iter()
            .filter(|(_, d)| !d.is_empty())
            .collect();
        match &self.settings.design.infill {
            None => {
                for (name, design) in &sets {
                    let text =
                        build_report(name, self.model.as_ref(), design, &store.join(name), opts)?;
                    said(say(&text))?;
                }
            }
            Some(infill) => self.build_infill(infill, &sets, store, opts, say)?,
        }
        for (name, _) in sets.iter().filter(|_| export.is_some()) {
            let dir = export.map(|e| e.join(name)).unwrap_or_default();
            let (filters, domain) = (&self.settings.filters, &self.settings.design.domain);
            said(say(&export_report(
                &store.join(name),
                &dir,
                filters,
                Some(domain),
            )?))?;
        }
        Ok(())
    }
}

impl BuildStudy {
    /// The checking set as usual, then the training set by adaptive infill
    /// ([`crate::infill::run_infill`]) from the starting design of `sets`.
    fn build_infill(
        &self,
        infill: &crate::infill::InfillSettings,
        sets: &[(&str, Vec<Vec<f64>>)],
        store: &Path,
        opts: &BuildOptions<'_>,
        say: &mut dyn FnMut(&str) -> std::io::Result<()>,
    ) -> Result<()> {
        let said = |r: std::io::Result<()>| r.map_err(crate::error::io_err("stdout"));
        let design = &self.settings.design;
        let (mut cx, mut cy) = (Vec::new(), Vec::new());
        if let Some((_, check)) = sets.iter().find(|(n, _)| *n == "check") {
            let dir = store.join("check");
            said(say(&build_report(
                "check",
                self.model.as_ref(),
                check,
                &dir,
                opts,
            )?))?;
            if opts
                .cancel
                .is_some_and(|c| c.load(std::sync::atomic::Ordering::SeqCst))
            {
                return Ok(());
            }
            (cx, cy) = crate::infill::checking_set(&dir, &self.settings.filters)?;
        }
        let initial = sets
            .iter()
            .find(|(n, _)| *n == "train")
            .map(|(_, d)| d.clone())
            .unwrap_or_default();
        crate::infill::run_infill(
            self.model.as_ref(),
            &design.domain,
            infill,
            &initial,
            design.n_train,
            design.seed,
            &self.settings.filters,
            &store.join("train"),
            (&cx, &cy),
            opts,
            &mut |t| said(say(t)),
        )?;
        Ok(())
    }
}

/// Merges the shard stores (each a store, or holding the `train/` and
/// `check/` stores of a study build, [`shard_sets`]) into `out` and
/// exports each merged store to `export` with `filters` and `domain`.
/// Returns what it did, for people.
///
/// # Errors
/// Shard directories of neither kind; as [`merge`] and [`export_report`].
pub fn merge_report(
    shards: &[PathBuf],
    out: &Path,
    export: Option<&Path>,
    filters: &Admissibility,
    domain: Option<&Domain>,
) -> Result<String> {
    let mut text = String::new();
    for set in shard_sets(shards)? {
        let dirs: Vec<PathBuf> = shards.iter().map(|d| set_dir(d, set)).collect();
        let merged = set_dir(out, set);
        let n = crate::store::merge(&dirs, &merged)?;
        text.push_str(&format!(
            "merged {} shards into {} ({n} runs copied)\n",
            dirs.len(),
            merged.display()
        ));
        if let Some(dir) = export {
            text.push_str(&export_report(
                &merged,
                &set_dir(dir, set),
                filters,
                domain,
            )?);
        }
    }
    Ok(text)
}

/// Sections of the other pipeline stages a build study may hold.
const OTHER_STAGES: [&str; 6] = ["parameters", "fit", "probe", "material", "loading", "cell"];

/// `[design]` and `[build]` of a study.
#[derive(Debug, Clone)]
pub struct BuildSettings {
    /// `[design]`.
    pub design: DesignSettings,
    /// `[build] store`.
    pub store: Option<PathBuf>,
    /// `[build] export`.
    pub export: Option<PathBuf>,
    /// `[build]` filters.
    pub filters: Admissibility,
}

impl BuildSettings {
    /// Reads `[design]` for parameters `names` in `units` and `[build]`
    /// (filters look from `contact_index` on), then checks the study for
    /// unknown sections (call after the forward model has read its own).
    ///
    /// # Errors
    /// Missing, unknown or invalid keys (file, line, key).
    pub fn from_study(
        mut study: Study,
        names: &[String],
        units: &[String],
        contact_index: usize,
    ) -> nlvid_study::Result<Self> {
        let _ = study.root().opt_str("title")?;
        let mut ds = study.section("design")?;
        let design = DesignSettings::from_section(&mut ds, names, units)?;
        ds.finish()?;
        let (store, export, filters) = match study.opt_section("build")? {
            Some(mut b) => {
                let store = b.opt_path("store")?;
                let export = b.opt_path("export")?;
                let filters = Admissibility::from_section(&mut b, contact_index)?;
                b.finish()?;
                (store, export, filters)
            }
            None => (
                None,
                None,
                Admissibility {
                    contact_index,
                    ..Default::default()
                },
            ),
        };
        for other in OTHER_STAGES {
            study.root().skip(other);
        }
        study.finish()?;
        Ok(Self {
            design,
            store,
            export,
            filters,
        })
    }
}

/// The stores to merge: `[None]` when every shard directory is a store
/// (`meta.json`), `[Some("train")]` (and `Some("check")`) when every one
/// holds the `train/` (and `check/`) stores of a study build.
///
/// # Errors
/// Shard directories of neither kind.
pub fn shard_sets(shards: &[PathBuf]) -> Result<Vec<Option<&'static str>>> {
    let all = |sub: &str| {
        shards
            .iter()
            .all(|d| d.join(sub).join("meta.json").is_file())
    };
    if shards.iter().all(|d| d.join("meta.json").is_file()) {
        Ok(vec![None])
    } else if all("train") {
        Ok(if all("check") {
            vec![Some("train"), Some("check")]
        } else {
            vec![Some("train")]
        })
    } else {
        Err(SurrogateError::InvalidInput(
            "each shard directory must be a store (meta.json) or hold train/ (and check/) stores"
                .into(),
        ))
    }
}

/// `dir`, or its sub-directory `set`.
pub fn set_dir(dir: &Path, set: Option<&str>) -> PathBuf {
    set.map_or_else(|| dir.to_path_buf(), |s| dir.join(s))
}

/// Builds the set `name` of `design` into `store` ([`build`]) and reports
/// it for people: runs in the shard, done before, run now, failed, time per
/// run, then each failure with its reason.
///
/// # Errors
/// As [`build`]; the store cannot be read back.
pub fn build_report(
    name: &str,
    model: &dyn ForwardModel,
    design: &[Vec<f64>],
    store: &Path,
    opts: &BuildOptions<'_>,
) -> Result<String> {
    let t0 = std::time::Instant::now();
    let s = build(model, design, store, opts)?;
    let secs = t0.elapsed().as_secs_f64();
    let per_run = if s.ran > 0 {
        format!(", {:.3} s per run", secs / s.ran as f64)
    } else {
        String::new()
    };
    let mut text = format!(
        "{name}: {} runs in shard: {} already done, {} run now ({} failed) in {secs:.2} s{per_run}\n",
        s.in_shard, s.skipped, s.ran, s.failed
    );
    if s.by_others > 0 {
        text.push_str(&format!(
            "{name}: {} runs done meanwhile by another build into this store\n",
            s.by_others
        ));
    }
    if s.failed > 0 {
        for (i, status, reason, secs) in &load(store, &Admissibility::default())?.status {
            if status == "failed" {
                text.push_str(&format!("run {i} failed after {secs:.3} s: {reason}\n"));
            }
        }
    }
    Ok(text)
}

/// Exports the admissible runs of `store` to `dir` ([`export`]; `domain`
/// is stored in its `meta.json` for the fits) and says how many each filter
/// removed — and, without a domain, that fits cannot use the export.
///
/// # Errors
/// As [`load`] and [`export`].
pub fn export_report(
    store: &Path,
    dir: &Path,
    filters: &Admissibility,
    domain: Option<&Domain>,
) -> Result<String> {
    let mm = load(store, filters)?;
    export(&mm, dir, domain)?;
    let c = &mm.counts;
    let warning = if domain.is_none() {
        format!(
            "warning: {} has no parameter domain (give --domain FILE, or build from a study): \
             `nlvid fit` and `nlvid cohort` cannot use it\n",
            dir.join("meta.json").display()
        )
    } else {
        String::new()
    };
    Ok(format!(
        "{warning}exported {} of {} runs to {} (failed {}, missing {}, below peak force {}, non-repulsive {})\n",
        c.kept,
        c.design,
        dir.display(),
        c.failed,
        c.missing,
        c.below_peak,
        c.non_repulsive
    ))
}

/// Reads a domain file (the stored form of [`Domain`], checked when read);
/// with `names`, they must be its parameters, in order; every row of
/// `design` must lie inside it.
///
/// # Errors
/// Unreadable or invalid file, parameters other than `names`, a design row
/// outside the domain (naming its CSV line).
pub fn read_domain(path: &Path, names: &[String], design: &[Vec<f64>]) -> Result<Domain> {
    let text = std::fs::read_to_string(path).map_err(crate::error::io_err(path))?;
    let bad = |m: String| SurrogateError::Parse {
        path: path.to_path_buf(),
        message: m,
    };
    let domain: Domain = toml::from_str(&text).map_err(|e| bad(e.to_string()))?;
    if !names.is_empty() {
        domain
            .check_names(names)
            .map_err(|e| bad(format!("the model's parameters: {e}")))?;
    }
    if let Some(i) = design.iter().position(|x| !domain.contains(x, 1e-9)) {
        return Err(bad(format!(
            "design row {} (CSV line) lies outside the domain",
            i + 2
        )));
    }
    Ok(domain)
}
