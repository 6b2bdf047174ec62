//! The study's `[fit]` section — one reader for `nlvid fit` and
//! `nlvid cohort` ([`FitSettings`]) — and what a cohort reads besides it
//! ([`CohortSettings`]: title and `[probe]`). Format: docs/cli/fit.md.
//!
//! ```toml
//! title = "demo"
//! [probe]                      # cohort: Lee–Radok model and Hertz baseline
//! radius = "2.5 um"
//! poisson = 0.5
//! [fit]
//! model = "surrogate"          # default: "surrogate" when `surrogate` is given, else "lee-radok"
//! surrogate = "metamodel/model.json"  # model file of `nlvid surrogate fit`
//! meta = "metamodel/meta.json"        # sidecar of `nlvid build --export`
//! check = "metamodel/model.check.json" # default: <surrogate>.check.json if present
//! constraint_epsilon = 0.01    # g1 + g2 <= 1 - eps (Table 5.3; model = "lee-radok" only:
//!                              # a meta-model brings the domain stored in its meta.json)
//! inputs = "physical"          # or "unit": coordinates the surrogate was fitted on
//! data = "afm"                 # or "compression"
//! starts = 64                  # multistart starts (default 64)
//! seed = 1
//! ramp = "1 s"                 # cohort: end of the loading ramp (Hertz baseline)
//! hold_end = "52 s"            # cohort: end of the fitted window
//! suspicious_misfit = 0.05     # cohort: eq. 5.3 misfit above which a cell is `suspicious`
//! [fit.columns]                # defaults shown (AFM)
//! time = "time"
//! piezo = "piezo"
//! deflection = "deflection"
//! [fit.calibration]            # CSV data only: JPK/.ibw files carry their own
//! spring_constant = "0.12 N/m" # k, F = k d (§5.2.2); replaces a file's if given
//! deflection_sensitivity = "50 nm/V"  # only if the deflection is in volts
//! ```
//!
//! Both read `[fit.protocol]` the same way (optional; where given, checked
//! against every data file: [`Protocol`]). `nlvid fit` also reads
//! `[[fit.segment]]`, `[fit.real_model]`, `[[fit.experiment]]` and
//! `modulus_times`; a cohort
//! also `ramp_points`, `hold_points`, `first_hold_step` (Lee–Radok grid).
//! Keys of the former second schema are errors naming the key to use.

use std::path::{Path, PathBuf};

use nlvid_inverse::posterior::RidgeTime;
use nlvid_inverse::{
    AfmColumns, Calibration, CompressionColumns, Coordinates, PosteriorSettings, ProtocolTolerance,
    Segment,
};
use nlvid_study::{Bounds, Dimension, FromSection, Section, Study, StudyError};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{ReportError, Result};

/// The model every curve is fitted with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FitModel {
    /// Small-strain Lee–Radok linear-viscoelastic Hertz contact, rigid
    /// sphere, run with each cell's measured indentation.
    LeeRadok,
    /// A pre-built Kriging meta-model of a forward model (thesis §4.4.1,
    /// §5.4.1): `nlvid surrogate fit` model file + `meta.json`.
    Surrogate,
}

impl FitModel {
    /// One-line description shown in outputs and the report.
    pub fn describe(&self) -> &'static str {
        match self {
            FitModel::LeeRadok => {
                "small-strain Lee–Radok (linear-viscoelastic Hertz, rigid sphere), \
                 run with each cell's measured indentation; no surrogate"
            }
            FitModel::Surrogate => {
                "Kriging meta-model (nlvid surrogate fit) of the forward model named in \
                 the study, on the nominal protocol of each experiment"
            }
        }
    }
}

/// What kind of measured data the files hold.
#[derive(Debug, Clone, PartialEq)]
pub enum DataColumns {
    /// AFM: time, piezo Z, deflection (V, m or N) of CSV files, with the
    /// calibration of `[fit.calibration]` (required for CSV files; instrument
    /// files carry their own, which a given calibration replaces).
    Afm(AfmColumns, Option<Calibration>),
    /// Plate compression: time, displacement, force, optional contact area.
    Compression(CompressionColumns),
}

/// Shape of the expected controlled displacement of [`Protocol`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ProtocolKind {
    /// Ramp at `rate` to `amplitude`, then hold to the end of the time grid
    /// (AFM relaxation, §5.2.2; capsule RH, §4.2).
    RampHold,
    /// Ramp at `rate` to `amplitude`, then back at the same rate to the end
    /// of the time grid (capsule RR, §4.2).
    RampReverse,
}

/// Expected controlled displacement: ramp at `rate` to `amplitude`, then
/// hold (`kind` ramp-hold) or go back at the same rate (ramp-reverse) to
/// the end of the surrogate's time grid (`[fit.protocol]`).
///
/// One rule for `nlvid fit` and `nlvid cohort`: `[fit.protocol]` is
/// optional in both; where given, both check every data file against it
/// ([`crate::fit::check_protocol`]) and refuse the same invalid sections.
/// (Requiring it with a meta-model would refuse the committed demo study,
/// whose cohort cuts every cell at `ramp` and `hold_end` instead.)
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Protocol {
    /// Ramp-hold or ramp-reverse.
    pub kind: ProtocolKind,
    /// Ramp rate (m/s).
    pub rate: f64,
    /// Ramp amplitude (m).
    pub amplitude: f64,
    /// Tolerances of the protocol check.
    pub tolerance: ProtocolTolerance,
}

/// The real forward model that re-checks the optimum.
#[derive(Debug, Clone, PartialEq)]
pub enum RealModelSpec {
    /// Analytic Lee–Radok Hertz, run with each curve's measured indentation.
    LeeRadok {
        /// Probe radius (m).
        radius: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
    /// The model of a study's `[forward]` section (`nlvid_forward`),
    /// run on its own grid and interpolated onto the surrogate's.
    Forward {
        /// The study file holding `[forward]` (default: the fit study).
        study: PathBuf,
    },
}

/// One experiment: which surrogate predicts it, under which protocol.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentSettings {
    /// Label (default: the data file's stem).
    pub label: Option<String>,
    /// Model file of `nlvid surrogate fit` (`None` with `model = "lee-radok"`).
    pub surrogate: Option<PathBuf>,
    /// `meta.json` of `nlvid build --export` (names, time grid).
    pub meta: Option<PathBuf>,
    /// Summary of `nlvid surrogate check` (its `max` is the checking
    /// error); `None`: `<model>.check.json` if it exists.
    pub check: Option<PathBuf>,
    /// Expected loading, checked against each data file.
    pub protocol: Option<Protocol>,
    /// Eq. 5.3 weights per time segment.
    pub segments: Vec<Segment>,
    /// Real model for the re-check.
    pub real: Option<RealModelSpec>,
}

impl ExperimentSettings {
    /// Where the checking summary is: `check`, else `<surrogate>.check.json`
    /// (where `nlvid surrogate check` saves it) when that file exists.
    pub fn check_file(&self) -> Option<PathBuf> {
        self.check.clone().or_else(|| {
            self.surrogate
                .as_deref()
                .map(nlvid_surrogate::check::summary_path)
                .filter(|p| p.is_file())
        })
    }
}

/// Everything `[fit]` says.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings {
    /// The study file.
    pub study: PathBuf,
    /// Surrogate or analytic Lee–Radok.
    pub model: FitModel,
    /// ε of g1 + g2 ≤ 1 − ε of the Table 5.3 domain of the analytic
    /// Lee–Radok model; a meta-model brings the domain stored in its
    /// `meta.json` instead.
    pub constraint_epsilon: f64,
    /// Coordinates the surrogates were fitted on.
    pub inputs: Coordinates,
    /// Columns and calibration of the data files.
    pub columns: DataColumns,
    /// Multistart starts.
    pub starts: usize,
    /// Multistart seed (the same for every curve).
    pub seed: u64,
    /// Times of the printed G(t), E(t).
    pub modulus_times: Vec<f64>,
    /// End of the loading ramp and of the hold, s (the fitted window of a
    /// cohort), when given.
    pub window: Option<(f64, f64)>,
    /// Lee–Radok model grid: uniform intervals on the ramp.
    pub ramp_points: usize,
    /// Lee–Radok model grid: log-spaced points on the hold.
    pub hold_points: usize,
    /// Lee–Radok model grid: first step of the hold, s.
    pub first_hold_step: f64,
    /// Misfit (eq. 5.3) above which a cohort cell is marked suspicious.
    pub suspicious_misfit: f64,
    /// Experiments; `repeat` says whether the single one applies to every file.
    pub experiments: Vec<ExperimentSettings>,
    /// True when the experiment settings sit directly in `[fit]`.
    pub repeat: bool,
}

/// Keys of earlier `[fit]` schemas, with what to do instead.
const RENAMED: [(&str, &str); 4] = [
    (
        "checking",
        "this key is now `check` (the summary of `nlvid surrogate check`)",
    ),
    (
        "checking_error",
        "this key is now `check = \"model.check.json\"` (the output of `nlvid --json surrogate check`)",
    ),
    (
        "domain",
        "the parameter domain (bounds, g1 + g2 <= 1 - epsilon) is now read from the \
         meta-model's meta.json, written by `nlvid build --export` from the build study's \
         [design] section: remove `domain` from [fit]",
    ),
    (
        "epsilon",
        "the parameter domain (bounds, g1 + g2 <= 1 - epsilon) is now read from the \
         meta-model's meta.json, written by `nlvid build --export` from the build study's \
         [design] section: remove `epsilon` from [fit] (the Table 5.3 domain of \
         model = \"lee-radok\" takes `constraint_epsilon`)",
    ),
];

fn renamed(s: &Section) -> std::result::Result<(), StudyError> {
    for (old, why) in RENAMED {
        if s.has(old) {
            return Err(s.invalid(old, why));
        }
    }
    Ok(())
}

impl FitSettings {
    /// Reads `[fit]` of the study at `path` (other sections belong to other
    /// commands and are not checked here).
    ///
    /// # Errors
    /// Any missing, unknown or invalid key, with the file, line and key.
    pub fn load(path: &Path) -> Result<Self> {
        let mut study = Study::load(path)?;
        Self::from_study(&mut study, path)
    }

    /// Reads `[fit]` of a parsed study (the study is not finished).
    ///
    /// # Errors
    /// As [`FitSettings::load`].
    pub fn from_study(study: &mut Study, path: &Path) -> Result<Self> {
        let mut s = study.section("fit")?;
        let settings = Self::from_section(&mut s, path)?;
        s.finish()?;
        Ok(settings)
    }

    fn from_section(s: &mut Section, path: &Path) -> Result<Self> {
        renamed(s)?;
        let model = s.enum_or(
            "model",
            &[
                ("lee-radok", FitModel::LeeRadok),
                ("surrogate", FitModel::Surrogate),
            ],
            if s.has("surrogate") || s.has("experiment") {
                FitModel::Surrogate
            } else {
                FitModel::LeeRadok
            },
        )?;
        let inputs = s.enum_or(
            "inputs",
            &[
                ("physical", Coordinates::Physical),
                ("unit", Coordinates::Unit),
            ],
            Coordinates::Physical,
        )?;
        let constraint_epsilon =
            s.f64_or("constraint_epsilon", Bounds::closed_open(0.0, 0.98), 0.01)?;
        let columns = read_columns(s)?;
        let window = match (s.has("ramp"), s.has("hold_end")) {
            (false, false) => None,
            _ => {
                let ramp = s.req_quantity("ramp", Dimension::TIME, Bounds::positive())?;
                let hold_end = s.req_quantity("hold_end", Dimension::TIME, Bounds::positive())?;
                if hold_end <= ramp {
                    return Err(s.invalid("hold_end", "must be later than `ramp`").into());
                }
                Some((ramp, hold_end))
            }
        };
        let settings = Self {
            study: path.to_path_buf(),
            model,
            constraint_epsilon,
            inputs,
            columns,
            starts: s.usize_or(
                "starts",
                Bounds::closed(1.0, 1000.0),
                nlvid_inverse::DEFAULT_STARTS,
            )?,
            seed: s.opt_u64("seed")?.unwrap_or(1),
            modulus_times: s
                .opt_quantities("modulus_times", Dimension::TIME, Bounds::non_negative())?
                .unwrap_or_else(|| vec![0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 52.0]),
            window,
            ramp_points: s.usize_or("ramp_points", Bounds::closed(1.0, 10000.0), 40)?,
            hold_points: s.usize_or("hold_points", Bounds::closed(2.0, 100000.0), 120)?,
            first_hold_step: s.quantity_or(
                "first_hold_step",
                Dimension::TIME,
                Bounds::positive(),
                1e-3,
            )?,
            suspicious_misfit: s.f64_or("suspicious_misfit", Bounds::positive(), 0.05)?,
            experiments: Vec::new(),
            repeat: true,
        };
        let tables = s.tables("experiment")?;
        let (experiments, repeat) = if tables.is_empty() {
            (vec![read_experiment(s, model, path)?], true)
        } else {
            let mut out = Vec::with_capacity(tables.len());
            for mut t in tables {
                renamed(&t)?;
                out.push(read_experiment(&mut t, model, path)?);
                t.finish()?;
            }
            (out, false)
        };
        Ok(Self {
            experiments,
            repeat,
            ..settings
        })
    }
}

fn read_columns(s: &mut Section) -> Result<DataColumns> {
    #[derive(Clone, Copy)]
    enum Kind {
        Afm,
        Compression,
    }
    let kind = s.enum_or(
        "data",
        &[("afm", Kind::Afm), ("compression", Kind::Compression)],
        Kind::Afm,
    )?;
    let mut cols = s.opt_subsection("columns")?;
    let mut name = |key: &str, default: &str| -> std::result::Result<String, StudyError> {
        match cols.as_mut() {
            Some(c) => Ok(c.opt_str(key)?.unwrap_or_else(|| default.to_string())),
            None => Ok(default.to_string()),
        }
    };
    let time = name("time", "time")?;
    let out = match kind {
        Kind::Afm => {
            let names = AfmColumns {
                time,
                piezo: name("piezo", "piezo")?,
                deflection: name("deflection", "deflection")?,
            };
            let cal = match s.opt_subsection("calibration")? {
                Some(mut c) => {
                    let cal = Calibration {
                        spring_constant: c.req_quantity(
                            "spring_constant",
                            Dimension::STIFFNESS,
                            Bounds::positive(),
                        )?,
                        deflection_sensitivity: c.opt_quantity(
                            "deflection_sensitivity",
                            Dimension::LENGTH_PER_VOLTAGE,
                            Bounds::positive(),
                        )?,
                    };
                    c.finish()?;
                    Some(cal)
                }
                None => None,
            };
            DataColumns::Afm(names, cal)
        }
        Kind::Compression => {
            let Some(c) = cols.as_mut() else {
                return Err(s
                    .invalid(
                        "columns",
                        "data = \"compression\" needs [fit.columns] with displacement and force",
                    )
                    .into());
            };
            DataColumns::Compression(CompressionColumns {
                time,
                displacement: c.req_str("displacement")?,
                force: c.req_str("force")?,
                contact_area: c.opt_str("contact_area")?,
            })
        }
    };
    if let Some(c) = cols {
        c.finish()?;
    }
    Ok(out)
}

/// One experiment's keys, from `[fit]` itself or a `[[fit.experiment]]`.
fn read_experiment(s: &mut Section, model: FitModel, study: &Path) -> Result<ExperimentSettings> {
    let label = s.opt_str("label")?;
    let (surrogate, meta, check) = match model {
        FitModel::Surrogate => {
            let check = match s.opt_path("check")? {
                Some(p) if !p.is_file() => {
                    return Err(s
                        .invalid("check", format!("no such file: {}", p.display()))
                        .into());
                }
                other => other,
            };
            (
                Some(s.req_input_file("surrogate")?),
                Some(s.req_input_file("meta")?),
                check,
            )
        }
        FitModel::LeeRadok => {
            for key in ["surrogate", "meta", "check"] {
                if s.has(key) {
                    return Err(s.invalid(key, "only with model = \"surrogate\"").into());
                }
            }
            (None, None, None)
        }
    };
    let protocol = match s.opt_subsection("protocol")? {
        None => None,
        Some(mut p) => {
            let v = Protocol {
                kind: p.enum_or(
                    "kind",
                    &[
                        ("ramp-hold", ProtocolKind::RampHold),
                        ("ramp-reverse", ProtocolKind::RampReverse),
                    ],
                    ProtocolKind::RampHold,
                )?,
                rate: p.req_quantity("rate", Dimension::VELOCITY, Bounds::positive())?,
                amplitude: p.req_quantity("amplitude", Dimension::LENGTH, Bounds::positive())?,
                tolerance: ProtocolTolerance {
                    duration: p.f64_or("duration_tolerance", Bounds::closed(0.0, 1.0), 0.02)?,
                    displacement: p.f64_or(
                        "displacement_tolerance",
                        Bounds::closed(0.0, 1.0),
                        0.05,
                    )?,
                },
            };
            p.finish()?;
            Some(v)
        }
    };
    let mut segments = Vec::new();
    for mut t in s.tables("segment")? {
        let seg = Segment {
            start: t.req_quantity("start", Dimension::TIME, Bounds::non_negative())?,
            end: t.req_quantity("end", Dimension::TIME, Bounds::non_negative())?,
            weight: t.req_f64("weight", Bounds::non_negative())?,
        };
        if seg.end <= seg.start {
            return Err(t
                .invalid("end", "a segment must end after it starts")
                .into());
        }
        t.finish()?;
        segments.push(seg);
    }
    let real = match s.opt_subsection("real_model")? {
        None => None,
        Some(mut r) => {
            let spec = match r.req_str("model")?.as_str() {
                "lee-radok" => RealModelSpec::LeeRadok {
                    radius: r.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?,
                    poisson: r.f64_or("poisson", Bounds::closed(0.0, 0.5), 0.5)?,
                },
                "forward" => RealModelSpec::Forward {
                    study: r.opt_path("study")?.unwrap_or_else(|| study.to_path_buf()),
                },
                other => {
                    return Err(r
                        .invalid(
                            "model",
                            format!(
                                "unknown real model `{other}` (available: lee-radok; forward = \
                                 the [forward] section of `study`, default this file)"
                            ),
                        )
                        .into());
                }
            };
            r.finish()?;
            Some(spec)
        }
    };
    Ok(ExperimentSettings {
        label,
        surrogate,
        meta,
        check,
        protocol,
        segments,
        real,
    })
}

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

impl SurrogateFiles {
    /// The forward model's name: [`SurrogateFiles::forward`] up to its
    /// first `(` (`afm-fe`, `HertzProny`). The full identity of an FE
    /// model lists every setting and output time (pages of text).
    pub fn forward_name(&self) -> &str {
        self.forward.split('(').next().unwrap_or_default().trim()
    }
}

/// Cohort settings, all in SI: the study's title, `[probe]` and `[fit]`
/// ([`FitSettings`]) as one serialisable record (written to `cohort.json`).
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
    /// Cantilever spring constant k, N/m (`[fit.calibration]`: required for CSV
    /// cells; replaces an instrument file's own when given).
    pub spring_constant: Option<f64>,
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
    pub model: FitModel,
    /// The meta-model's files (when `model` is [`FitModel::Surrogate`]).
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
    /// Per-cell posteriors (`[posterior]`, opt-in; meta-model fits only).
    #[serde(default)]
    pub posterior: Option<PosteriorStudy>,
    /// `[fit.protocol]`: every cell's curve is checked against it, as by
    /// `nlvid fit`.
    #[serde(default)]
    pub protocol: Option<Protocol>,
}

/// The study's `[posterior]` section: sample each cell's posterior on the
/// meta-model after its fit (issue 17; docs/cli/cohort.md). Absent, or
/// `enabled = false`: no posteriors (the thesis's point estimates only).
///
/// ```toml
/// [posterior]
/// ensembles = 4     # independent ensembles (>= 2; R-hat compares them)
/// walkers = 16      # walkers per ensemble (>= 12)
/// burn = 200        # burn-in steps per walker
/// steps = 250       # kept steps per walker per round; rounds are added
/// max_steps = 1000  #   until R-hat <= 1.01 or max_steps kept steps
/// level = 0.9       # credible level of intervals and bands
/// keep = 200        # thinned draws kept per cell (group bands, p(t) over draws)
/// seed = 1          # default: fit.seed
/// rungs = 4         # temperature rungs of the restart of a slow cell (1: none)
/// temper_after = 500  # kept steps after which a cell with R-hat > 1.01 restarts tempered
/// # temper_rhat = 1.05  # opt-in: restart tempered at a round's end with R-hat above this
/// temper_burn = 100    # burn-in steps of the tempered restart
/// hot_starts = false   # true: hot rungs start from the pooled proposal, widened
/// check_every = 50  # after the first round, R-hat checked every this many kept steps
/// delayed_acceptance = true  # screen proposals on the Kriging mean first (exact)
/// heavy_tails = false  # true: surrogate error Student-t (nu from the meta-model's LOO)
/// direction_scales = false  # true: a Gaussian surrogate error scale per direction (LOO)
/// ridge_starts = false      # true: half the ensembles start at the ends of the weakest direction
/// ridge_time = "kept"       # "viscous": half the ridge steps move τ1 at fixed G0·g1·τ1
/// mode_starts = true        # half the ensembles start at the fit's other optima within 6 in ln L
/// variance_at_fit = false   # true: the surrogate error's variance held at the fit (approximate, faster)
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PosteriorStudy {
    /// Independent ensembles.
    #[serde(default = "default_ensembles")]
    pub ensembles: usize,
    /// Walkers of each ensemble.
    pub walkers: usize,
    /// Burn-in steps.
    pub burn: usize,
    /// Kept steps per round.
    pub steps: usize,
    /// Most kept steps.
    #[serde(default)]
    pub max_steps: usize,
    /// Credible level.
    pub level: f64,
    /// Thinned draws kept per cell.
    pub keep: usize,
    /// Seed (None: the fit's).
    pub seed: Option<u64>,
    /// Rungs of a tempered restart (`PosteriorSettings::rungs`).
    #[serde(default = "default_rungs")]
    pub rungs: usize,
    /// Kept steps before a tempered restart
    /// (`PosteriorSettings::temper_after`).
    #[serde(default = "default_temper_after")]
    pub temper_after: usize,
    /// R̂ at a round's end above which a cell restarts tempered before
    /// `temper_after` (`PosteriorSettings::temper_rhat`; None, the
    /// default: only after `temper_after`).
    #[serde(default)]
    pub temper_rhat: Option<f64>,
    /// Burn-in steps of the tempered restart
    /// (`PosteriorSettings::temper_burn`).
    #[serde(default = "default_temper_burn")]
    pub temper_burn: usize,
    /// Hot rungs started from the independence proposal
    /// (`PosteriorSettings::hot_starts`).
    #[serde(default)]
    pub hot_starts: bool,
    /// Kept steps between R̂ checks after the first round
    /// (`PosteriorSettings::check_every`).
    #[serde(default = "default_check_every")]
    pub check_every: usize,
    /// Delayed acceptance (`PosteriorSettings::delayed_acceptance`).
    #[serde(default = "default_delayed_acceptance")]
    pub delayed_acceptance: bool,
    /// Student-t surrogate error (`PosteriorSettings::heavy_tails`).
    #[serde(default = "default_heavy_tails")]
    pub heavy_tails: bool,
    /// A surrogate error scale per direction
    /// (`PosteriorSettings::direction_scales`).
    #[serde(default)]
    pub direction_scales: bool,
    /// Half the ensembles started at the ridge's ends
    /// (`PosteriorSettings::ridge_starts`).
    #[serde(default)]
    pub ridge_starts: bool,
    /// What the ridge steps do with τ1 (`PosteriorSettings::ridge_time`).
    #[serde(default)]
    pub ridge_time: RidgeTime,
    /// Half the ensembles started at the fit's other optima
    /// (`PosteriorSettings::mode_starts`).
    #[serde(default = "default_mode_starts")]
    pub mode_starts: bool,
    /// The surrogate error's variance held at the fit
    /// (`PosteriorSettings::variance_at_fit`).
    #[serde(default)]
    pub variance_at_fit: bool,
}

fn default_mode_starts() -> bool {
    PosteriorSettings::new(1.0).mode_starts
}

fn default_heavy_tails() -> bool {
    PosteriorSettings::new(1.0).heavy_tails
}

fn default_check_every() -> usize {
    PosteriorSettings::new(1.0).check_every
}

fn default_delayed_acceptance() -> bool {
    PosteriorSettings::new(1.0).delayed_acceptance
}

fn default_ensembles() -> usize {
    4
}

fn default_rungs() -> usize {
    PosteriorSettings::new(1.0).rungs
}

fn default_temper_after() -> usize {
    PosteriorSettings::new(1.0).temper_after
}

fn default_temper_burn() -> usize {
    PosteriorSettings::new(1.0).temper_burn
}

struct PosteriorSection(Option<PosteriorStudy>);

impl FromSection for PosteriorSection {
    fn from_section(s: &mut Section) -> std::result::Result<Self, StudyError> {
        let enabled = s.opt_bool("enabled")?.unwrap_or(true);
        let steps = s.usize_or("steps", Bounds::closed(20.0, 1e7), 250)?;
        let p = PosteriorStudy {
            ensembles: s.usize_or("ensembles", Bounds::closed(2.0, 64.0), 4)?,
            walkers: s.usize_or("walkers", Bounds::closed(12.0, 10000.0), 16)?,
            burn: s.usize_or("burn", Bounds::closed(0.0, 1e6), 200)?,
            steps,
            max_steps: s.usize_or("max_steps", Bounds::closed(20.0, 1e8), 4 * steps)?,
            level: s.f64_or("level", Bounds::closed(0.5, 0.999), 0.9)?,
            keep: s.usize_or("keep", Bounds::closed(10.0, 1e5), 200)?,
            seed: s.opt_u64("seed")?,
            rungs: s.usize_or("rungs", Bounds::closed(1.0, 16.0), default_rungs())?,
            temper_after: s.usize_or(
                "temper_after",
                Bounds::closed(0.0, 1e8),
                default_temper_after(),
            )?,
            temper_rhat: s.opt_f64("temper_rhat", Bounds::closed(1.0, 100.0))?,
            temper_burn: s.usize_or(
                "temper_burn",
                Bounds::closed(0.0, 1e6),
                default_temper_burn(),
            )?,
            hot_starts: s.opt_bool("hot_starts")?.unwrap_or(false),
            check_every: s.usize_or(
                "check_every",
                Bounds::closed(1.0, 1e8),
                default_check_every(),
            )?,
            delayed_acceptance: s
                .opt_bool("delayed_acceptance")?
                .unwrap_or_else(default_delayed_acceptance),
            heavy_tails: s
                .opt_bool("heavy_tails")?
                .unwrap_or_else(default_heavy_tails),
            direction_scales: s.opt_bool("direction_scales")?.unwrap_or(false),
            ridge_starts: s.opt_bool("ridge_starts")?.unwrap_or(false),
            ridge_time: s
                .opt_enum(
                    "ridge_time",
                    &[
                        ("kept", RidgeTime::Kept),
                        ("redrawn", RidgeTime::Redrawn),
                        ("viscous", RidgeTime::Viscous),
                    ],
                )?
                .unwrap_or_default(),
            mode_starts: s
                .opt_bool("mode_starts")?
                .unwrap_or_else(default_mode_starts),
            variance_at_fit: s.opt_bool("variance_at_fit")?.unwrap_or(false),
        };
        Ok(Self(enabled.then_some(p)))
    }
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

/// Sections of the other pipeline stages in a shared study file: the
/// cohort leaves them to their commands.
const OTHER_STAGES: [&str; 7] = [
    "forward",
    "protocol",
    "design",
    "build",
    "parameters",
    "material",
    "loading",
];

impl CohortSettings {
    /// Reads the settings from a study file; unknown sections or keys are
    /// errors naming file, line and key.
    ///
    /// # Errors
    /// [`crate::ReportError::Study`].
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_study(Study::load(path)?, path)
    }

    /// Reads the settings from a parsed study (its file is `path`), which
    /// is then checked for unknown sections.
    ///
    /// # Errors
    /// [`crate::ReportError::Study`].
    pub fn from_study(mut study: Study, path: &Path) -> Result<Self> {
        let name = study.name().to_string();
        let title = study
            .root()
            .opt_str("title")?
            .unwrap_or_else(|| name.clone());
        if study.root().has("seed") {
            return Err(study
                .root()
                .invalid("seed", "this key is now `seed` in [fit]")
                .into());
        }
        if study.has("afm") {
            return Err(study
                .root()
                .invalid(
                    "afm",
                    "[afm] is now [fit.calibration] (spring_constant, deflection_sensitivity) and \
                 [fit.columns] (time, piezo, deflection)",
                )
                .into());
        }
        if let Some(p) = study.opt_section("protocol")? {
            for key in ["ramp", "hold_end"] {
                if p.has(key) {
                    return Err(p
                        .invalid(key, format!("this key is now `{key}` in [fit]"))
                        .into());
                }
            }
        }
        let probe: Probe = study.read("probe")?;
        let fit = FitSettings::from_study(&mut study, path)?;
        let posterior = study
            .opt_read::<PosteriorSection>("posterior")?
            .and_then(|p| p.0);
        if posterior.is_some() && fit.model != FitModel::Surrogate {
            return Err(ReportError::InvalidSetting(format!(
                "{name}: [posterior] samples on a meta-model: it needs fit.model = \"surrogate\""
            )));
        }
        for other in OTHER_STAGES {
            study.root().skip(other);
        }
        let fail = |what: String| ReportError::InvalidSetting(format!("{name}: {what}"));
        let Some((ramp, hold_end)) = fit.window else {
            return Err(fail(
                "[fit]: a cohort needs `ramp` (end of the loading ramp) and `hold_end` (end of \
                 the fitted window)"
                    .into(),
            ));
        };
        let DataColumns::Afm(cols, cal) = &fit.columns else {
            return Err(fail(
                "[fit]: a cohort fits AFM curves (data = \"afm\")".into(),
            ));
        };
        let [exp] = fit.experiments.as_slice() else {
            return Err(fail(
                "[fit]: a cohort fits each cell as one experiment; [[fit.experiment]] tables \
                 are for `nlvid fit`"
                    .into(),
            ));
        };
        if exp.real.is_some() || !exp.segments.is_empty() {
            return Err(fail(
                "[fit]: real_model and segment are read by `nlvid fit` only".into(),
            ));
        }
        if ramp + fit.first_hold_step >= hold_end {
            return Err(fail(format!(
                "fit.first_hold_step ({} s) does not fit between fit.ramp and fit.hold_end",
                fit.first_hold_step
            )));
        }
        let surrogate = match (&exp.surrogate, &exp.meta) {
            (Some(model), Some(meta)) => Some(SurrogateFiles {
                forward: forward_of_meta(meta)?,
                model: model.clone(),
                meta: meta.clone(),
                check: exp.check_file(),
            }),
            _ => None,
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
            seed: fit.seed,
            radius: probe.radius,
            poisson: probe.poisson,
            spring_constant: cal.as_ref().map(|c| c.spring_constant),
            deflection_sensitivity: cal.as_ref().and_then(|c| c.deflection_sensitivity),
            time_column: cols.time.clone(),
            piezo_column: cols.piezo.clone(),
            deflection_column: cols.deflection.clone(),
            ramp,
            hold_end,
            model: fit.model,
            surrogate,
            starts: fit.starts,
            ramp_points: fit.ramp_points,
            hold_points: fit.hold_points,
            first_hold_step: fit.first_hold_step,
            constraint_epsilon: fit.constraint_epsilon,
            suspicious_misfit: fit.suspicious_misfit,
            posterior,
            protocol: exp.protocol,
        })
    }
}
