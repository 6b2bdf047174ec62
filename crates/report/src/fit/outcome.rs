//! What a fit reports: parameters with units, G(t) and E(t) = 3G(t)
//! (eq. 5.1), per experiment the surrogate and real-model misfits (eq. 5.3)
//! and whether they agree within the surrogate's checking error, the flags
//! of the fit (parameter on a bound, alternatives that fit almost as well,
//! failed starts), and SVG figures of data vs fitted curve (Figs 4.9, 5.13).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nlvid_inverse::{
    Experiment, FigureCurve, FitFigure, FitResult, Identifiability, Misfit, Model, Rerun,
    SensitivityScaling, Z95, identifiability, range_normalised_rmse,
};
use nlvid_model::ModulusPoint;
use serde_json::json;

use super::data::LoadedExperiment;
use crate::error::{ReportError, Result};
use crate::settings::FitSettings;

/// Whether the surrogate and real-model misfits agree within the checking
/// error (issue 6): `yes`, `no`, or `unknown` (no real model or no
/// measured checking error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Agreement {
    /// |e_surrogate − e_real| ≤ checking error.
    Yes,
    /// |e_surrogate − e_real| > checking error.
    No,
    /// Not decidable.
    Unknown,
}

impl Agreement {
    fn word(self) -> &'static str {
        match self {
            Agreement::Yes => "yes",
            Agreement::No => "no",
            Agreement::Unknown => "unknown",
        }
    }
}

/// One experiment's part of the outcome.
#[derive(Debug, Clone)]
pub struct ExperimentOutcome {
    /// Label.
    pub label: String,
    /// Data file.
    pub file: PathBuf,
    /// Surrogate model file.
    pub surrogate: PathBuf,
    /// Eq. 5.3 misfit of the surrogate's curve at the optimum.
    pub misfit_surrogate: f64,
    /// Eq. 5.3 misfit of the real model re-run at the optimum.
    pub misfit_real: Option<f64>,
    /// Why the re-run failed, if it did.
    pub rerun_error: Option<String>,
    /// Max eq. 4.4 checking error of the surrogate (from `checking_file`).
    pub checking_error: Option<f64>,
    /// Where the checking error came from.
    pub checking_file: Option<PathBuf>,
    /// |misfit_surrogate − misfit_real| ≤ checking_error?
    pub agree: Agreement,
    /// Why the agreement is unknown, if it is.
    pub agree_note: Option<String>,
    /// SVG figure, if written.
    pub plot: Option<PathBuf>,
    /// The meta-model domain checks of this curve (what differs from what the
    /// meta-model was built for, and by how much).
    pub domain_checks: Vec<String>,
    fitted: Vec<f64>,
    real: Option<Vec<f64>>,
}

impl ExperimentOutcome {
    fn to_json(&self) -> serde_json::Value {
        json!({
            "label": self.label,
            "file": self.file,
            "surrogate": self.surrogate,
            "misfit_surrogate": self.misfit_surrogate,
            "misfit_real": self.misfit_real,
            "rerun_error": self.rerun_error,
            "checking_error": self.checking_error,
            "checking_file": self.checking_file,
            "misfit_difference": self.misfit_real.map(|r| (self.misfit_surrogate - r).abs()),
            "agree": self.agree.word(),
            "agree_note": self.agree_note,
            "domain_checks": self.domain_checks,
            "plot": self.plot,
        })
    }
}

/// Everything `nlvid fit` prints.
pub struct Outcome {
    study: PathBuf,
    fit: FitResult,
    experiments: Vec<ExperimentOutcome>,
    modulus: Vec<ModulusPoint>,
    /// Local identifiability on the surrogates at the optimum, or why not.
    identifiability: std::result::Result<Identifiability, String>,
    seconds: f64,
}

impl Outcome {
    /// Scores the optimum of `fit` on every experiment.
    ///
    /// # Errors
    /// Surrogate evaluation failures; a domain without Prony terms.
    pub fn new(
        settings: &FitSettings,
        experiments: &[LoadedExperiment],
        fit: FitResult,
        reruns: Vec<std::result::Result<Option<Rerun>, String>>,
        seconds: f64,
    ) -> Result<Self> {
        let x = &fit.best.x;
        let mut out = Vec::with_capacity(experiments.len());
        for (e, result) in experiments.iter().zip(reruns) {
            // A failed re-run (e.g. FE non-convergence) is reported, not fatal.
            let (rerun, rerun_error) = match result {
                Ok(r) => (r, None),
                Err(msg) => (None, Some(msg)),
            };
            let fitted = e.surrogate.model.response(x)?;
            let misfit_surrogate = range_normalised_rmse(&fitted, &e.force, e.weights.as_deref())?;
            let checking = e.surrogate.checking.clone();
            let (agree, agree_note) = match (&rerun, &checking) {
                (Some(r), Some((c, _))) => {
                    if (misfit_surrogate - r.misfit).abs() <= *c {
                        (Agreement::Yes, None)
                    } else {
                        (Agreement::No, None)
                    }
                }
                (None, _) => (
                    Agreement::Unknown,
                    Some(match &rerun_error {
                        Some(msg) => format!("the real model re-run failed: {msg}"),
                        None => "no [fit.real_model]: the optimum was not re-run".to_string(),
                    }),
                ),
                (Some(_), None) => (
                    Agreement::Unknown,
                    Some(format!(
                        "no checking error: run `nlvid surrogate check {} --x X.csv --y Y.csv` \
                         on independent checking runs (it saves {}), or set `checking` in [fit]",
                        e.surrogate.path.display(),
                        nlvid_surrogate::check::summary_path(&e.surrogate.path).display()
                    )),
                ),
            };
            out.push(ExperimentOutcome {
                label: e.label.clone(),
                file: e.curve.path.clone(),
                surrogate: e.surrogate.path.clone(),
                misfit_surrogate,
                misfit_real: rerun.as_ref().map(|r| r.misfit),
                rerun_error,
                checking_error: checking.as_ref().map(|c| c.0),
                checking_file: checking.map(|c| c.1),
                agree,
                agree_note,
                plot: None,
                domain_checks: e.domain_notes.clone(),
                fitted,
                real: rerun.map(|r| r.response),
            });
        }
        let modulus = fit.modulus(&settings.modulus_times)?;
        let identifiability = local_identifiability(experiments, x).map_err(|e| e.to_string());
        Ok(Self {
            study: settings.study.clone(),
            fit,
            experiments: out,
            modulus,
            identifiability,
            seconds,
        })
    }

    /// Writes `fit-<label>.svg` into `dir` for every experiment.
    ///
    /// # Errors
    /// The directory or a figure cannot be written.
    pub fn with_plots(mut self, experiments: &[LoadedExperiment], dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .map_err(|e| ReportError::io(dir, format!("cannot create: {e}")))?;
        for (o, e) in self.experiments.iter_mut().zip(experiments) {
            let path = dir.join(format!("fit-{}.svg", file_safe(&o.label)));
            let title = format!(
                "{}: data vs fit (misfit {:.2} %)",
                o.label,
                100.0 * o.misfit_surrogate
            );
            FitFigure {
                title: &title,
                times: e.surrogate.model.times(),
                data: FigureCurve {
                    label: "data",
                    values: &e.force,
                },
                fitted: FigureCurve {
                    label: "surrogate at the optimum",
                    values: &o.fitted,
                },
                rerun: o.real.as_deref().map(|v| FigureCurve {
                    label: "real model re-run",
                    values: v,
                }),
            }
            .write(&path)?;
            o.plot = Some(path);
        }
        Ok(self)
    }

    /// Overall agreement: `no` if any experiment disagrees, `yes` if all
    /// agree, `unknown` otherwise.
    pub fn agreement(&self) -> Agreement {
        let a: Vec<Agreement> = self.experiments.iter().map(|e| e.agree).collect();
        if a.contains(&Agreement::No) {
            Agreement::No
        } else if !a.is_empty() && a.iter().all(|v| *v == Agreement::Yes) {
            Agreement::Yes
        } else {
            Agreement::Unknown
        }
    }

    /// The parameter-domain check: one note per parameter on a bound of the
    /// meta-model's domain ([`super::domain::bound_notes`]).
    pub fn bound_notes(&self) -> Vec<String> {
        super::domain::bound_notes(&self.fit.domain, &self.fit.best.on_bounds, &self.fit.best.x)
    }

    /// The `--json` document.
    ///
    /// # Errors
    /// Never for a result of a fit (parameter count mismatch otherwise).
    pub fn to_json(&self) -> Result<serde_json::Value> {
        let params = self.fit.parameters()?;
        Ok(json!({
            "study": self.study,
            "parameters": params.rows.iter()
                .map(|(n, v, u)| json!({"name": n, "value": v, "unit": u}))
                .collect::<Vec<_>>(),
            "experiments": self.experiments.iter().map(ExperimentOutcome::to_json).collect::<Vec<_>>(),
            "misfit_surrogate": self.experiments.iter().map(|e| e.misfit_surrogate).collect::<Vec<_>>(),
            "misfit_real": self.experiments.iter().map(|e| e.misfit_real).collect::<Vec<_>>(),
            "surrogate_and_real_agree": self.agreement().word(),
            "domain_checks": self.bound_notes(),
            "flags": {
                "on_bound": self.fit.best.on_bounds,
                "active_constraints": self.fit.best.active_constraints,
                "alternatives": self.fit.alternatives.len(),
                "failed_starts": self.fit.failed_starts.len(),
            },
            "identifiability": match &self.identifiability {
                Ok(i) => json!({
                    "singular_values": i.singular_values,
                    "condition_number": i.condition_number,
                    "std_errors": i.std_errors,
                    "intervals_95": i.intervals,
                    "relative_half_widths_95": i.relative_half_widths(),
                    "note": "value-scaled sensitivities on the surrogate; Gauss-Newton, bounds ignored",
                }),
                Err(e) => json!({"error": e}),
            },
            "modulus_units": {"time": "s", "shear": "Pa", "young": "Pa"},
            "modulus": self.modulus,
            "fit": self.fit,
            "seconds": self.seconds,
            "plots": self.experiments.iter().filter_map(|e| e.plot.clone()).collect::<Vec<_>>(),
        }))
    }

    /// The human-readable report.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "fit of {} curve(s) on the surrogate ({:.3} s):",
            self.experiments.len(),
            self.seconds
        );
        let _ = write!(s, "{}", self.fit);
        for e in &self.experiments {
            let _ = match e.misfit_real {
                Some(r) => writeln!(
                    s,
                    "{}: misfit surrogate {:.4} %, real model re-run {:.4} %",
                    e.label,
                    100.0 * e.misfit_surrogate,
                    100.0 * r
                ),
                None => writeln!(
                    s,
                    "{}: misfit surrogate {:.4} % (not re-checked{})",
                    e.label,
                    100.0 * e.misfit_surrogate,
                    if e.rerun_error.is_some() {
                        ": the real model failed"
                    } else {
                        ""
                    }
                ),
            };
            let _ = match (e.agree, e.checking_error) {
                (Agreement::Unknown, _) => writeln!(
                    s,
                    "  surrogate misfit vs real misfit agree within the checking error: unknown ({})",
                    e.agree_note.as_deref().unwrap_or("")
                ),
                (a, Some(c)) => writeln!(
                    s,
                    "  surrogate misfit vs real misfit agree within the checking error ({:.4} %): {}{} \
                     (|difference| {:.4} %)",
                    100.0 * c,
                    a.word(),
                    if a == Agreement::No {
                        " — the surrogate is off near the optimum: refine it there"
                    } else {
                        ""
                    },
                    100.0
                        * e.misfit_real
                            .map_or(f64::NAN, |r| (e.misfit_surrogate - r).abs())
                ),
                (a, None) => writeln!(s, "  agreement: {}", a.word()),
            };
            for n in &e.domain_checks {
                let _ = writeln!(s, "  meta-model domain: {n}");
            }
        }
        for n in self.bound_notes() {
            let _ = writeln!(s, "meta-model domain: {n}");
        }
        match &self.identifiability {
            Ok(i) => {
                let sv: Vec<String> = i
                    .singular_values
                    .iter()
                    .map(|v| format!("{v:.3}"))
                    .collect();
                let _ = writeln!(
                    s,
                    "identifiability (surrogate, value-scaled): singular values {}; condition {:.3e}",
                    sv.join(", "),
                    i.condition_number
                );
                for ((n, x), (se, (lo, hi))) in i
                    .names
                    .iter()
                    .zip(&i.x)
                    .zip(i.std_errors.iter().zip(&i.intervals))
                {
                    let _ = writeln!(
                        s,
                        "  {n:>8}: 95 % interval {lo:.4e} … {hi:.4e} (±{:.1} %)",
                        100.0 * Z95 * se / x.abs()
                    );
                }
            }
            Err(e) => {
                let _ = writeln!(s, "identifiability: not computed ({e})");
            }
        }
        let _ = writeln!(
            s,
            "{:>10} {:>14} {:>14}",
            "t [s]", "G(t) [Pa]", "E(t)=3G [Pa]"
        );
        for p in &self.modulus {
            let _ = writeln!(s, "{:>10.4} {:>14.6e} {:>14.6e}", p.time, p.shear, p.young);
        }
        for e in &self.experiments {
            if let Some(p) = &e.plot {
                let _ = writeln!(s, "plot written to {}", p.display());
            }
        }
        s
    }
}

/// Identifiability of the stacked experiments on their surrogates at `x`
/// (analytic surrogate Jacobians, value-scaled).
fn local_identifiability(
    experiments: &[LoadedExperiment],
    x: &[f64],
) -> nlvid_inverse::Result<Identifiability> {
    let parts = experiments
        .iter()
        .map(|e| {
            Experiment::new(
                &e.label,
                &e.surrogate.model,
                e.force.clone(),
                e.weights.clone(),
            )
        })
        .collect::<nlvid_inverse::Result<Vec<_>>>()?;
    identifiability(&Misfit::new(parts)?, x, SensitivityScaling::Value)
}

/// A label as a file-name part: anything but letters, digits, `-`, `_`,
/// `.` becomes `_`.
fn file_safe(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect()
}
