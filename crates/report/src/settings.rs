//! What `nlvid cohort` reads from the study file: probe, cantilever and
//! CSV columns, the ramp-hold window that is fitted, and the fit settings.
//!
//! ```toml
//! title = "demo"
//! seed = 7
//! [probe]
//! radius = "2.5 um"            # sphere radius R (5 um diameter in §5.2.2)
//! poisson = 0.5
//! [afm]
//! spring_constant = "0.12 N/m" # k, F = k d (§5.2.2)
//! deflection_sensitivity = "50 nm/V"  # only if the deflection is in volts
//! time_column = "time"         # defaults shown
//! piezo_column = "piezo"
//! deflection_column = "deflection"
//! [protocol]
//! ramp = "0.2 s"               # end of the loading ramp
//! hold_end = "52 s"            # end of the hold = end of the fitted window
//! # (or `ramp`, `hold_end` in [fit]: then [protocol] is the forward model's,
//! # nlvid-protocol format, and the cohort does not read it)
//! [fit]
//! model = "surrogate"          # or "lee-radok" (analytic, no surrogate)
//! surrogate = "metamodel/model.json"  # model file of `nlvid surrogate fit`
//! meta = "metamodel/meta.json"        # sidecar of `nlvid build --export`
//! check = "metamodel/check.json"      # optional: `nlvid --json surrogate check` output
//! starts = 8
//! ramp_points = 40
//! hold_points = 120
//! first_hold_step = "1 ms"
//! constraint_epsilon = 0.01    # g1 + g2 <= 1 - eps (Table 5.3; model = "lee-radok" only:
//!                              # a meta-model brings the domain stored in its meta.json)
//! suspicious_misfit = 0.05     # eq. 5.3 misfit above which a cell is `suspicious`
//! ```

use std::path::{Path, PathBuf};

use nlvid_study::{Bounds, Dimension, FromSection, Section, Study, StudyError};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{ReportError, Result};

/// The `model` key of a `meta.json` (the forward model's identity), if any.
fn forward_of_meta(meta: &Path) -> Result<String> {
    let bytes = std::fs::read(meta).map_err(|e| ReportError::io(meta, e))?;
    let v: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| ReportError::Data {
        path: meta.to_path_buf(),
        line: e.line() as u64,
        message: format!("not JSON: {e}"),
    })?;
    Ok(v.get("model")
        .and_then(|m| m.as_str())
        .unwrap_or("(meta.json names no model)")
        .to_string())
}

/// The forward model used to fit each cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ForwardModel {
    /// Small-strain Lee–Radok linear-viscoelastic Hertz contact, rigid
    /// sphere, run with each cell's measured indentation.
    LeeRadok,
    /// A pre-built Kriging meta-model of a forward model (thesis §4.4.1,
    /// §5.4.1): `nlvid surrogate fit` model file + `meta.json`.
    Surrogate,
}

impl ForwardModel {
    /// One-line description shown in outputs and the report.
    pub fn describe(&self) -> &'static str {
        match self {
            ForwardModel::LeeRadok => {
                "small-strain Lee–Radok (linear-viscoelastic Hertz, rigid sphere), \
                 run with each cell's measured indentation; no surrogate"
            }
            ForwardModel::Surrogate => {
                "Kriging meta-model (nlvid surrogate fit) of the forward model named in \
                 the study, on the nominal ramp-hold protocol"
            }
        }
    }
}

/// The files of a pre-built meta-model (paths resolved against the study's
/// directory).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurrogateFiles {
    /// Model file of `nlvid surrogate fit`.
    pub model: PathBuf,
    /// `meta.json` of `nlvid build --export` (input names, time grid).
    pub meta: PathBuf,
    /// Optional checking-error summary (`nlvid --json surrogate check`).
    pub check: Option<PathBuf>,
    /// Text describing the forward model the surrogate stands for (from
    /// `meta.json`'s `model` key when present).
    pub forward: String,
}

/// Cohort settings, all in SI.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CohortSettings {
    /// Study title.
    pub title: String,
    /// SHA-256 of the study's canonical content (provenance; a finished
    /// cell is reused on a re-run only if this matches).
    pub study_hash: String,
    /// Seed of the multistart fit (the same for every cell: a cell's result
    /// does not depend on which other cells are in the cohort).
    pub seed: u64,
    /// Sphere radius R, m.
    pub radius: f64,
    /// Poisson ratio ν.
    pub poisson: f64,
    /// Cantilever spring constant k, N/m.
    pub spring_constant: f64,
    /// Deflection sensitivity, m/V (only for a deflection in volts).
    pub deflection_sensitivity: Option<f64>,
    /// Time column name.
    pub time_column: String,
    /// Piezo column name.
    pub piezo_column: String,
    /// Deflection column name.
    pub deflection_column: String,
    /// End of the loading ramp, s.
    pub ramp: f64,
    /// End of the hold (end of the fitted window), s.
    pub hold_end: f64,
    /// Forward model.
    pub model: ForwardModel,
    /// The meta-model's files (when `model` is [`ForwardModel::Surrogate`]).
    pub surrogate: Option<SurrogateFiles>,
    /// Multistart starts per cell.
    pub starts: usize,
    /// Uniform intervals of the model grid on the ramp.
    pub ramp_points: usize,
    /// Log-spaced points of the model grid on the hold.
    pub hold_points: usize,
    /// First step of the hold grid, s.
    pub first_hold_step: f64,
    /// ε of g1 + g2 ≤ 1 − ε of the Table 5.3 domain of the analytic
    /// Lee–Radok model; a meta-model fit uses the domain stored in its
    /// `meta.json` instead.
    pub constraint_epsilon: f64,
    /// Misfit (eq. 5.3) above which a cell is marked suspicious.
    pub suspicious_misfit: f64,
}

struct Probe {
    radius: f64,
    poisson: f64,
}

impl FromSection for Probe {
    fn from_section(s: &mut Section) -> std::result::Result<Self, StudyError> {
        Ok(Self {
            radius: s.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?,
            poisson: s.f64_or("poisson", Bounds::closed(0.0, 0.5), 0.5)?,
        })
    }
}

struct Afm {
    k: f64,
    sensitivity: Option<f64>,
    time: String,
    piezo: String,
    deflection: String,
}

impl FromSection for Afm {
    fn from_section(s: &mut Section) -> std::result::Result<Self, StudyError> {
        Ok(Self {
            k: s.req_quantity("spring_constant", Dimension::STIFFNESS, Bounds::positive())?,
            sensitivity: s.opt_quantity(
                "deflection_sensitivity",
                Dimension::LENGTH_PER_VOLTAGE,
                Bounds::positive(),
            )?,
            time: s.opt_str("time_column")?.unwrap_or_else(|| "time".into()),
            piezo: s.opt_str("piezo_column")?.unwrap_or_else(|| "piezo".into()),
            deflection: s
                .opt_str("deflection_column")?
                .unwrap_or_else(|| "deflection".into()),
        })
    }
}

#[derive(Clone, Copy)]
struct Window {
    ramp: f64,
    hold_end: f64,
}

impl FromSection for Window {
    fn from_section(s: &mut Section) -> std::result::Result<Self, StudyError> {
        let ramp = s.req_quantity("ramp", Dimension::TIME, Bounds::positive())?;
        let hold_end = s.req_quantity("hold_end", Dimension::TIME, Bounds::positive())?;
        if hold_end <= ramp {
            return Err(s.invalid("hold_end", "must be later than `ramp`"));
        }
        Ok(Self { ramp, hold_end })
    }
}

/// The fitted window from `[fit]` (`ramp`, `hold_end`) when given there:
/// then `[protocol]` belongs to the forward model (nlvid-protocol format).
fn fit_window(s: &mut Section) -> std::result::Result<Option<Window>, StudyError> {
    match (s.has("ramp"), s.has("hold_end")) {
        (false, false) => Ok(None),
        _ => Window::from_section(s).map(Some),
    }
}

struct Fit {
    window: Option<Window>,
    model: ForwardModel,
    surrogate: Option<(PathBuf, PathBuf, Option<PathBuf>)>,
    starts: usize,
    ramp_points: usize,
    hold_points: usize,
    first_hold_step: f64,
    eps: f64,
    suspicious: f64,
}

impl FromSection for Fit {
    fn from_section(s: &mut Section) -> std::result::Result<Self, StudyError> {
        let model = s.enum_or(
            "model",
            &[
                ("lee-radok", ForwardModel::LeeRadok),
                ("surrogate", ForwardModel::Surrogate),
            ],
            ForwardModel::LeeRadok,
        )?;
        let surrogate = match model {
            ForwardModel::Surrogate => Some((
                s.req_input_file("surrogate")?,
                s.req_input_file("meta")?,
                match s.opt_path("check")? {
                    Some(p) if !p.is_file() => {
                        return Err(s.invalid("check", format!("no such file: {}", p.display())));
                    }
                    other => other,
                },
            )),
            ForwardModel::LeeRadok => {
                for key in ["surrogate", "meta", "check"] {
                    if s.has(key) {
                        return Err(s.invalid(key, "only with model = \"surrogate\""));
                    }
                }
                None
            }
        };
        Ok(Self {
            window: fit_window(s)?,
            model,
            surrogate,
            starts: s
                .opt_usize("starts", Bounds::closed(1.0, 1000.0))?
                .unwrap_or(8),
            ramp_points: s
                .opt_usize("ramp_points", Bounds::closed(1.0, 10000.0))?
                .unwrap_or(40),
            hold_points: s
                .opt_usize("hold_points", Bounds::closed(2.0, 100000.0))?
                .unwrap_or(120),
            first_hold_step: s.quantity_or(
                "first_hold_step",
                Dimension::TIME,
                Bounds::positive(),
                1e-3,
            )?,
            eps: s.f64_or("constraint_epsilon", Bounds::closed_open(0.0, 0.98), 0.01)?,
            suspicious: s.f64_or("suspicious_misfit", Bounds::positive(), 0.05)?,
        })
    }
}

impl CohortSettings {
    /// Reads the settings from a study file; unknown sections or keys are
    /// errors naming file, line and key.
    ///
    /// # Errors
    /// [`crate::ReportError::Study`].
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_study(Study::load(path)?)
    }

    /// Reads the settings from a parsed study, which is then checked for
    /// unknown sections.
    ///
    /// # Errors
    /// [`crate::ReportError::Study`].
    pub fn from_study(mut study: Study) -> Result<Self> {
        let title = study
            .root()
            .opt_str("title")?
            .unwrap_or_else(|| study.name().to_string());
        let seed = study.root().opt_u64("seed")?.unwrap_or(0);
        let probe: Probe = study.read("probe")?;
        let afm: Afm = study.read("afm")?;
        // Sections of the meta-model build (`nlvid sample/build`): not the
        // cohort's business, but part of the same study file.
        for other in ["forward", "design", "build"] {
            study.root().skip(other);
        }
        let fit: Fit = study.opt_read("fit")?.unwrap_or(Fit {
            window: None,
            model: ForwardModel::LeeRadok,
            surrogate: None,
            starts: 8,
            ramp_points: 40,
            hold_points: 120,
            first_hold_step: 1e-3,
            eps: 0.01,
            suspicious: 0.05,
        });
        let window = match fit.window {
            Some(w) => {
                study.root().skip("protocol");
                w
            }
            None => study.read("protocol")?,
        };
        if window.ramp + fit.first_hold_step >= window.hold_end {
            return Err(crate::ReportError::InvalidSetting(format!(
                "{}: fit.first_hold_step ({} s) does not fit between protocol.ramp and protocol.hold_end",
                study.name(),
                fit.first_hold_step
            )));
        }
        let surrogate = match fit.surrogate {
            Some((model, meta, check)) => Some(SurrogateFiles {
                forward: forward_of_meta(&meta)?,
                model,
                meta,
                check,
            }),
            None => None,
        };
        // A rebuilt meta-model must not reuse cells fitted on the old one.
        let study_hash = match &surrogate {
            Some(f) => {
                let mut h = Sha256::new();
                h.update(study.hash().to_string().as_bytes());
                for p in [&f.model, &f.meta] {
                    let bytes = std::fs::read(p).map_err(|e| ReportError::io(p, e))?;
                    h.update(Sha256::digest(&bytes));
                }
                h.finalize().iter().map(|b| format!("{b:02x}")).collect()
            }
            None => study.hash().to_string(),
        };
        study.finish()?;
        Ok(Self {
            title,
            study_hash,
            seed,
            radius: probe.radius,
            poisson: probe.poisson,
            spring_constant: afm.k,
            deflection_sensitivity: afm.sensitivity,
            time_column: afm.time,
            piezo_column: afm.piezo,
            deflection_column: afm.deflection,
            ramp: window.ramp,
            hold_end: window.hold_end,
            model: fit.model,
            surrogate,
            starts: fit.starts,
            ramp_points: fit.ramp_points,
            hold_points: fit.hold_points,
            first_hold_step: fit.first_hold_step,
            constraint_epsilon: fit.eps,
            suspicious_misfit: fit.suspicious,
        })
    }
}
