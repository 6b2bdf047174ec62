//! One cell: read its AFM curve, fit the five Prony parameters (G0, g1,
//! g2, τ1, τ2; eq. 5.1: the domain stored with the meta-model, or Table 5.3
//! for the analytic model) with the misfit of eq. 5.3 on the
//! study's forward model ([`CellModel`]: a pre-built Kriging meta-model or
//! the analytic Lee–Radok model), fit the Hertz baseline (eq. 1.1) to the
//! loading ramp, read the cell's geometry (App. B.2) when the manifest gives
//! it, and keep everything the results table and the report need.
//!
//! A cell never makes the cohort fail: unreadable data, a curve that does
//! not cover the fitted window, or a fit that does not converge give a
//! [`CellResult`] with status `failed` and the reason.

use std::path::Path;

use nlvid_inverse::{
    AfmColumns, Calibration, Coordinates, Experiment, FitResult, FixedInputs, LeeRadokHertz,
    MeasuredCurve, Misfit, Model, MultiStart, Posterior, PosteriorSettings, SurrogateFitter,
    load_kriging_surrogate, ramp_hold_grid, sample_posterior_fixed,
};
use nlvid_model::{BoundSide, Domain};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::input::{CellInput, Geometry};
use crate::settings::{CohortSettings, FitModel, PosteriorStudy};

/// Outcome class of a cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CellStatus {
    /// Fitted; flags may still carry warnings.
    Ok,
    /// Fitted, but the fit is poor (misfit above `fit.suspicious_misfit`):
    /// listed, excluded from group statistics.
    Suspicious,
    /// Not fitted (bad data or no convergence): listed with the reason.
    Failed,
}

impl CellStatus {
    /// The word written in the `status` column.
    pub fn as_str(&self) -> &'static str {
        match self {
            CellStatus::Ok => "ok",
            CellStatus::Suspicious => "suspicious",
            CellStatus::Failed => "failed",
        }
    }
}

/// A fitted parameter with its SI unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamValue {
    /// Name (`G0`, `g1`, `tau1`, …).
    pub name: String,
    /// SI unit (`Pa`, `s`, `1` for dimensionless; empty in results
    /// written before the domain carried units).
    pub unit: String,
    /// Value in SI.
    pub value: f64,
}

/// Everything known about one cell after its fit (also the per-cell result
/// file of a cohort run, as JSON).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellResult {
    /// Group name.
    pub group: String,
    /// Data file, relative to the cohort input (folder or manifest).
    pub file: String,
    /// Cell identifier (the file stem).
    pub cell: String,
    /// Hash of the study the cell was fitted with.
    pub study_hash: String,
    /// Outcome.
    pub status: CellStatus,
    /// Why the cell is suspicious or failed (empty when ok).
    pub reason: String,
    /// Warnings: parameters on a bound, alternative optima, failed starts.
    pub flags: Vec<String>,
    /// Best parameters (empty when failed).
    pub parameters: Vec<ParamValue>,
    /// Misfit of eq. 5.3 at the best parameters.
    pub misfit: Option<f64>,
    /// Distinct optima within the misfit tolerance besides the best.
    pub alternatives: usize,
    /// Peak measured force in the fitted window, N.
    pub peak_force: Option<f64>,
    /// Relaxation at the end of the hold of the peak-normalised measured
    /// curve, 1 − F(t_end)/F_peak (fraction; Figs. 5.6–5.8).
    pub relaxation: Option<f64>,
    /// Model time grid, s (empty if the data could not be read).
    pub times: Vec<f64>,
    /// Measured force resampled on the grid, N.
    pub data: Vec<f64>,
    /// Fitted force on the grid, N (empty when failed).
    pub fit: Vec<f64>,
    /// Hertz baseline (eq. 1.1) on the loading ramp, when it could be fitted.
    #[serde(default)]
    pub hertz: Option<HertzBaseline>,
    /// Cell height H from curves on the cell and on glass (eq. B.1), m.
    #[serde(default)]
    pub cell_height: Option<f64>,
    /// Base diameter √(d1·d2) from two image distances (App. B.2), m.
    #[serde(default)]
    pub base_diameter: Option<f64>,
    /// Posterior on the meta-model (study `[posterior]`), when sampled.
    #[serde(default)]
    pub posterior: Option<Posterior>,
    /// The fit's other local optima (free parameters, `FitResult::
    /// other_optima`): where the posterior starts some ensembles. Not
    /// written (the posterior is sampled right after the fit).
    #[serde(skip)]
    pub other_optima: Vec<Vec<f64>>,
}

/// The familiar Hertz fit (eq. 1.1, rigid sphere on an elastic half-space,
/// E* = E/(1 − ν²)) of the loading ramp: an apparent Young's modulus to
/// compare with what users know. For a viscoelastic cell it lies between
/// 3·G(t_ramp) and 3·G(0) (ν = 0.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HertzBaseline {
    /// Young's modulus E, Pa.
    pub youngs_modulus: f64,
    /// The fitted window (time span and largest indentation).
    pub window: String,
    /// RMSE divided by the range of the fitted force (eq. 4.4 convention).
    pub misfit: f64,
}

impl CellResult {
    /// A failed cell: no parameters, no curves, `reason` (also the base of
    /// test cells built with `..CellResult::failed(…)`).
    pub(crate) fn failed(group: &str, file: &str, cell: &str, hash: &str, reason: String) -> Self {
        Self {
            group: group.into(),
            file: file.into(),
            cell: cell.into(),
            study_hash: hash.into(),
            status: CellStatus::Failed,
            reason,
            flags: Vec::new(),
            parameters: Vec::new(),
            misfit: None,
            alternatives: 0,
            peak_force: None,
            relaxation: None,
            times: Vec::new(),
            data: Vec::new(),
            fit: Vec::new(),
            hertz: None,
            cell_height: None,
            base_diameter: None,
            posterior: None,
            other_optima: Vec::new(),
        }
    }

    /// Value of a named parameter.
    pub fn parameter(&self, name: &str) -> Option<f64> {
        self.parameters
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.value)
    }
}

/// The parameter domain of the analytic Lee–Radok model (Table 5.3 with
/// g1 + g2 ≤ 1 − `fit.constraint_epsilon`); a meta-model brings its own
/// (stored in its `meta.json`, [`CellModel::load`]).
///
/// # Errors
/// An ε outside [0, 0.98).
pub fn domain(settings: &CohortSettings) -> Result<Domain> {
    Ok(Domain::table_5_3(settings.constraint_epsilon)?)
}

/// The forward model every cell is fitted with, prepared once per cohort
/// (the meta-model is read and its Gram matrix computed once, then shared
/// by every thread).
#[derive(Debug, Clone)]
pub enum CellModel {
    /// Analytic Lee–Radok: built per cell from its measured indentation.
    LeeRadok(Domain),
    /// A pre-built Kriging meta-model on the nominal protocol, on the
    /// domain its `meta.json` stores.
    Surrogate(Box<SurrogateFitter>, Box<BuiltFor>),
}

/// What a cohort's meta-model was built for ([`nlvid_model::BuildConditions`] from its
/// `meta.json`), for the domain checks of [`crate::fit::domain`].
#[derive(Debug, Clone)]
pub struct BuiltFor {
    /// The build conditions, if the meta-model stores them.
    pub conditions: Option<nlvid_model::BuildConditions>,
    /// Its `meta.json`.
    pub meta: std::path::PathBuf,
}

impl CellModel {
    /// Prepares the model named by the settings.
    ///
    /// # Errors
    /// Bad ε; unreadable or mismatched meta-model files (naming them).
    pub fn load(settings: &CohortSettings) -> Result<Self> {
        match (&settings.model, &settings.surrogate) {
            (FitModel::LeeRadok, _) => Ok(Self::LeeRadok(domain(settings)?)),
            (FitModel::Surrogate, Some(f)) => {
                let s = load_kriging_surrogate(&f.model, &f.meta, Coordinates::Physical)?;
                let conditions = nlvid_inverse::read_meta(&f.meta)?.conditions;
                Ok(Self::Surrogate(
                    Box::new(SurrogateFitter::new(s, None)?),
                    Box::new(BuiltFor {
                        conditions,
                        meta: f.meta.clone(),
                    }),
                ))
            }
            (FitModel::Surrogate, None) => Err(crate::ReportError::InvalidSetting(
                "fit.model = \"surrogate\" needs fit.surrogate and fit.meta".into(),
            )),
        }
    }

    /// The time grid the misfit is evaluated on, s.
    ///
    /// # Errors
    /// Inconsistent durations (Lee–Radok grid).
    pub fn grid(&self, settings: &CohortSettings) -> nlvid_inverse::Result<Vec<f64>> {
        match self {
            Self::LeeRadok(_) => model_grid(settings),
            Self::Surrogate(f, _) => Ok(f.times().to_vec()),
        }
    }
}

/// The model time grid: the ramp in `ramp_points` uniform steps, then the
/// hold log-spaced (dense where fast relaxation shows).
///
/// # Errors
/// Inconsistent durations (checked when the settings are read).
pub fn model_grid(settings: &CohortSettings) -> nlvid_inverse::Result<Vec<f64>> {
    ramp_hold_grid(
        settings.ramp,
        settings.ramp_points,
        settings.hold_end,
        settings.hold_points,
        settings.first_hold_step,
    )
}

/// The measured curve of a cell: a CSV file with the study's columns and
/// `[fit.calibration]`, or an instrument file (curve `input.curve` of a map) with
/// its own calibration, replaced by `[fit.calibration]` when given, cut at the
/// contact (`nlvid_afm::read_ramp_hold_curve`).
fn read_cell_curve(
    settings: &CohortSettings,
    input: &CellInput,
) -> std::result::Result<nlvid_inverse::MeasuredCurve, String> {
    if nlvid_afm::batch::is_afm_file(&input.path) {
        let options = nlvid_afm::ReadOptions {
            spring_constant: settings.spring_constant,
            sensitivity: settings.deflection_sensitivity,
        };
        let c = nlvid_afm::read_ramp_hold_curve(&input.path, input.curve, &options)
            .map_err(|e| e.to_string())?;
        let lines = (1..=c.len()).collect();
        return nlvid_inverse::MeasuredCurve::new(&input.path, lines, c).map_err(|e| e.to_string());
    }
    let Some(spring_constant) = settings.spring_constant else {
        return Err(format!(
            "{}: a CSV curve needs [fit.calibration] spring_constant (instrument files \
             such as .jpk-force carry their own)",
            input.path.display()
        ));
    };
    let cols = AfmColumns {
        time: settings.time_column.clone(),
        piezo: settings.piezo_column.clone(),
        deflection: settings.deflection_column.clone(),
    };
    let cal = Calibration {
        deflection_sensitivity: settings.deflection_sensitivity,
        spring_constant,
    };
    nlvid_inverse::read_afm_csv(&input.path, &cols, &cal).map_err(|e| e.to_string())
}

/// Reads and fits one cell. Never fails: problems become a `failed` cell.
pub fn fit_cell(settings: &CohortSettings, model: &CellModel, input: &CellInput) -> CellResult {
    let (group, file) = (input.group.as_str(), input.file.as_str());
    let cell = Path::new(file)
        .file_stem()
        .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
    let hash = settings.study_hash.as_str();
    let fail = |reason: String| CellResult::failed(group, file, &cell, hash, reason);

    let curve = match read_cell_curve(settings, input) {
        Ok(c) => c,
        Err(e) => return fail(format!("cannot read the curve: {e}")),
    };
    let implausible = curve.implausible();
    if !implausible.is_empty() {
        let all: Vec<String> = implausible.iter().map(ToString::to_string).collect();
        return fail(format!("implausible data: {}", all.join("; ")));
    }
    let Some(indentation) = curve.indentation().map(<[f64]>::to_vec) else {
        return fail("no indentation in the curve".into());
    };
    let (Some(&t_first), Some(&t_last)) = (curve.time().first(), curve.time().last()) else {
        return fail("the curve has no samples".into());
    };
    let grid = match model.grid(settings) {
        Ok(g) => g,
        Err(e) => return fail(format!("model grid: {e}")),
    };
    let mut base = fail(String::new());
    geometry(&input.geometry, &mut base);
    // meta-model domain checks: protocol, time span, geometry (data ending before the
    // grid are fitted on the overlap: the later grid points weigh 0)
    let mut used = grid.len();
    if let CellModel::Surrogate(_, built) = model {
        let facts = crate::fit::domain::DataFacts {
            end_time_s: t_last - t_first,
            ramp_time_s: Some(settings.ramp),
            depth_m: Some(indentation.iter().fold(0.0f64, |a, d| a.max(d.abs()))),
            probe_radius_m: Some(settings.radius),
            cell_height_m: base.cell_height,
            cell_diameter_m: base.base_diameter,
        };
        let meta = built.meta.display().to_string();
        match crate::fit::domain::check(&facts, built.conditions.as_ref(), &grid, &meta) {
            Ok(found) => {
                if let Some(te) = found.overlap_end {
                    used = grid.iter().filter(|t| **t <= te).count();
                }
                base.flags.extend(
                    found
                        .notes
                        .into_iter()
                        .map(|n| format!("meta-model domain: {n}")),
                );
            }
            Err(e) => {
                base.reason = format!("meta-model domain: {e}");
                return base;
            }
        }
    }
    if let Some(p) = &settings.protocol {
        let t_end = grid[..used].last().copied().unwrap_or(0.0);
        let checked =
            crate::fit::check_protocol(&curve, p, t_end, &input.path, "model's time grid");
        if let Err(e) = checked {
            return fail(format!("protocol: {e}"));
        }
    }
    let needed = if used < grid.len() {
        grid[used - 1]
    } else {
        settings.hold_end.max(grid.last().copied().unwrap_or(0.0))
    };
    if t_last - t_first < needed * (1.0 - 1e-9) {
        return fail(format!(
            "the curve covers {:.4} s but the fitted window needs {needed} s \
             (fit.hold_end / the model's time grid)",
            t_last - t_first,
        ));
    }
    let (mut force, delta) = match (
        curve.resample(curve.force(), &grid[..used]),
        curve.resample(&indentation, &grid[..used]),
    ) {
        (Ok(f), Ok(d)) => (f, d),
        (Err(e), _) | (_, Err(e)) => {
            base.reason = format!("resampling: {e}");
            return base;
        }
    };
    // past the data's end (overlap fit): held at the last value, with weight 0
    let last = force.last().copied().unwrap_or(0.0);
    force.resize(grid.len(), last);
    match hertz_baseline(settings, &curve, &indentation) {
        Ok(h) => base.hertz = Some(h),
        Err(e) => base.flags.push(format!("Hertz baseline not fitted: {e}")),
    }
    // Peak of the measured samples inside the fitted window.
    let peak = curve
        .time()
        .iter()
        .zip(curve.force())
        .filter(|(t, _)| **t - t_first <= settings.hold_end * (1.0 + 1e-12))
        .map(|(_, f)| *f)
        .fold(f64::NEG_INFINITY, f64::max);
    let end_force = match curve.resample(curve.force(), &[settings.hold_end]) {
        Ok(v) => v[0],
        Err(e) => {
            base.reason = format!("resampling: {e}");
            return base;
        }
    };
    base.times = grid.clone();
    base.data = force.clone();
    if peak.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        base.reason = "no positive force in the fitted window".into();
        return base;
    }
    base.peak_force = Some(peak);
    base.relaxation = Some(1.0 - end_force / peak);

    // a meta-model with the cell's shape as inputs: held at this cell's
    let fixed = match model {
        CellModel::Surrogate(f, _) => {
            match shape_inputs(nlvid_inverse::Model::domain(f.surrogate()), &base) {
                Ok((fixed, flag)) => {
                    base.flags.extend(flag);
                    fixed
                }
                Err(e) => {
                    base.reason = e;
                    return base;
                }
            }
        }
        CellModel::LeeRadok(d) => FixedInputs::none(d),
    };
    let multistart = MultiStart::new()
        .with_starts(settings.starts)
        .map(|m| m.with_seed(settings.seed));
    let fitted = match model {
        CellModel::LeeRadok(d) => multistart.and_then(|ms| {
            let m = LeeRadokHertz::new(d.clone(), grid, &delta, settings.radius, settings.poisson)?;
            let misfit = Misfit::new(vec![Experiment::new(&cell, m, force, None)?])?;
            let fit = ms.fit(&misfit)?;
            let y = misfit.experiments()[0].model.response(&fit.best.x)?;
            Ok((fit, y))
        }),
        CellModel::Surrogate(f, _) if used < grid.len() => multistart
            .and_then(|ms| {
                let mut w = vec![1.0; grid.len()];
                w[used..].iter_mut().for_each(|x| *x = 0.0);
                let overlap = SurrogateFitter::new(f.surrogate().clone(), Some(w))?;
                overlap.fit_fixed(&[(cell.as_str(), force.as_slice())], &ms, &fixed)
            })
            .map(|r| (r.fit, r.response)),
        CellModel::Surrogate(f, _) => multistart
            .and_then(|ms| f.fit_fixed(&[(cell.as_str(), force.as_slice())], &ms, &fixed))
            .map(|r| (r.fit, r.response)),
    };
    match fitted {
        Ok((fit, y)) => {
            record_fit(settings, &mut base, &fit, y);
            if let (CellModel::Surrogate(f, _), Some(p)) = (model, &settings.posterior) {
                posterior(settings, p, f, &fixed, &fit.best.x, &mut base);
            }
        }
        Err(e) => base.reason = format!("fit: {e}"),
    }
    base
}

/// The posterior of a fitted cell on the meta-model (study `[posterior]`),
/// seeded per study (not per cell order). A sampler problem is a flag; R̂
/// above 1.01 is flagged too.
fn posterior(
    settings: &CohortSettings,
    p: &PosteriorStudy,
    fitter: &SurrogateFitter,
    fixed: &FixedInputs,
    x_hat: &[f64],
    base: &mut CellResult,
) {
    let ps = PosteriorSettings {
        ensembles: p.ensembles,
        walkers: p.walkers,
        burn: p.burn,
        steps: p.steps,
        max_steps: p.max_steps,
        seed: p.seed.unwrap_or(settings.seed),
        level: p.level,
        keep: p.keep,
        rungs: p.rungs,
        temper_after: p.temper_after,
        temper_rhat: p.temper_rhat,
        temper_burn: p.temper_burn,
        hot_starts: p.hot_starts,
        check_every: p.check_every,
        delayed_acceptance: p.delayed_acceptance,
        heavy_tails: p.heavy_tails,
        direction_scales: p.direction_scales,
        ridge_starts: p.ridge_starts,
        ridge_time: p.ridge_time,
        mode_starts: p.mode_starts,
        variance_at_fit: p.variance_at_fit,
        ..PosteriorSettings::new(settings.hold_end)
    };
    let optima = (x_hat, base.other_optima.as_slice());
    match sample_posterior_fixed(fitter.surrogate(), fixed, &base.data, optima, &ps) {
        Ok(post) => {
            if !(post.rhat_max <= 1.01) {
                base.flags.push(format!(
                    "posterior not converged: R-hat {:.3} > 1.01 (raise posterior.max_steps)",
                    post.rhat_max
                ));
            }
            base.posterior = Some(post);
        }
        Err(e) => base.flags.push(format!("posterior not sampled: {e}")),
    }
}

/// Parameters, misfit, flags and status of a finished fit.
fn record_fit(settings: &CohortSettings, base: &mut CellResult, fit: &FitResult, y: Vec<f64>) {
    base.parameters = fit
        .domain
        .params()
        .iter()
        .zip(&fit.best.x)
        .map(|(p, &value)| ParamValue {
            name: p.name.clone(),
            unit: p.unit.clone(),
            value,
        })
        .collect();
    base.fit = y;
    base.misfit = Some(fit.best.misfit);
    base.alternatives = fit.alternatives.len();
    base.other_optima = fit.other_optima();
    for hit in &fit.best.on_bounds {
        let side = match hit.side {
            BoundSide::Lower => "lower",
            BoundSide::Upper => "upper",
        };
        base.flags.push(format!(
            "{} at its {side} bound (widen the domain)",
            hit.name
        ));
    }
    if !fit.alternatives.is_empty() {
        base.flags.push(format!(
            "{} alternative optimum/optima within the misfit tolerance",
            fit.alternatives.len()
        ));
    }
    if !fit.failed_starts.is_empty() {
        base.flags.push(format!(
            "{} of {} starts failed",
            fit.failed_starts.len(),
            fit.starts
        ));
    }
    if fit.best.misfit > settings.suspicious_misfit {
        base.status = CellStatus::Suspicious;
        base.reason = format!(
            "misfit {:.4} above fit.suspicious_misfit = {}",
            fit.best.misfit, settings.suspicious_misfit
        );
    } else {
        base.status = CellStatus::Ok;
        base.reason.clear();
    }
}

/// Hertz fit (eq. 1.1 with E* = E/(1 − ν²), eq. 1.3) of the loading ramp
/// 0 ≤ t − t₀ ≤ `protocol.ramp`: tip–sample separation s = −δ, contact
/// point and force offset fitted (`nlvid_afm::fit_hertz`).
///
/// # Errors
/// Too few samples on the ramp; the fit does not converge.
pub fn hertz_baseline(
    settings: &CohortSettings,
    curve: &MeasuredCurve,
    indentation: &[f64],
) -> std::result::Result<HertzBaseline, String> {
    let t0 = curve.time().first().copied().unwrap_or(0.0);
    let (mut sep, mut f) = (Vec::new(), Vec::new());
    for ((t, d), fv) in curve.time().iter().zip(indentation).zip(curve.force()) {
        if t - t0 <= settings.ramp * (1.0 + 1e-9) {
            sep.push(-d);
            f.push(*fv);
        }
    }
    let hs = nlvid_afm::HertzSettings::new(settings.radius, settings.poisson);
    let h = nlvid_afm::fit_hertz(&sep, &f, &hs).map_err(|e| e.to_string())?;
    let t_end = curve
        .time()
        .get(sep.len().saturating_sub(1))
        .map_or(0.0, |t| t - t0);
    Ok(HertzBaseline {
        youngs_modulus: h.youngs_modulus,
        window: format!(
            "0-{t_end:.3} s (loading ramp, {} samples), indentation <= {:.3} um",
            h.n_points,
            h.max_indentation * 1e6
        ),
        misfit: h.range_normalised_rmse,
    })
}

/// The inputs a meta-model with the cell's shape as inputs (`H`, `D`,
/// `[forward] geometry = "inputs"`) holds fixed while the cell's material
/// parameters are fitted: the cell's measured height and diameter, or,
/// where the manifest gives none, the centre of the meta-model's range
/// (its mean shape — the thesis's one geometry per setup, §5.4.2), with a
/// flag saying so. A meta-model without those inputs fixes nothing.
///
/// # Errors
/// A measured shape outside the meta-model's range (the reason of a failed
/// cell).
fn shape_inputs(
    domain: &Domain,
    cell: &CellResult,
) -> std::result::Result<(FixedInputs, Option<String>), String> {
    use nlvid_model::names::{DIAMETER, HEIGHT};
    let mut fixed = Vec::new();
    let mut mean = Vec::new();
    for (name, measured, what) in [
        (HEIGHT, cell.cell_height, "height"),
        (DIAMETER, cell.base_diameter, "diameter"),
    ] {
        let Some(i) = domain.index_of(name) else {
            continue;
        };
        let p = &domain.params()[i];
        let value = measured.unwrap_or_else(|| {
            let centre = 0.5 * (p.lower + p.upper);
            mean.push(format!("{what} {name} = {:.2} um", centre * 1e6));
            centre
        });
        fixed.push((name, value));
    }
    let inputs = FixedInputs::new(domain, &fixed)
        .map_err(|e| format!("cell shape vs the meta-model: {e}"))?;
    let flag = (!mean.is_empty()).then(|| {
        format!(
            "shape not measured: fitted with the mean shape ({}, the centre of the \
             meta-model's range; give the manifest columns height, diameter)",
            mean.join(", ")
        )
    });
    Ok((inputs, flag))
}

/// Height (eq. B.1, from curves on the cell and on glass, or the manifest's
/// `height`) and base diameter (√(d1·d2), or the manifest's `diameter`) of
/// a cell, when its manifest row gives them; a problem is a flag.
fn geometry(g: &Geometry, out: &mut CellResult) {
    if let Some((cell, glass)) = &g.height_curves {
        let read =
            |p: &Path| nlvid_afm::read_force_curve(p).map_err(|e| format!("{}: {e}", p.display()));
        match read(cell).and_then(|c| {
            let gl = read(glass)?;
            nlvid_afm::geometry::cell_height_from_curves(
                &c,
                &gl,
                nlvid_afm::ContactMethod::default(),
            )
            .map_err(|e| e.to_string())
        }) {
            Ok(h) => out.cell_height = Some(h),
            Err(e) => out.flags.push(format!("cell height not measured: {e}")),
        }
    }
    if let Some(h) = g.height {
        out.cell_height = Some(h);
    }
    if let Some(d) = g.diameter {
        out.base_diameter = Some(d);
    }
    if let Some((d1, d2)) = g.image_distances {
        match nlvid_afm::geometry::base_diameter(d1, d2) {
            Ok(d) => out.base_diameter = Some(d),
            Err(e) => out.flags.push(format!("base diameter not measured: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(dir: &Path) -> CohortSettings {
        let study = dir.join("study.toml");
        std::fs::write(
            &study,
            "[probe]\nradius = \"2.5 um\"\npoisson = 0.5\n[fit]\nramp = \"1 s\"\n\
             hold_end = \"3 s\"\n[fit.calibration]\nspring_constant = \"0.1 N/m\"\n",
        )
        .unwrap();
        CohortSettings::load(&study).unwrap()
    }

    /// An elastic half-space under a sphere: F = (4/3) E/(1 − ν²) √R δ^{3/2}
    /// (eq. 1.1), written here from the closed form; the Hertz baseline must
    /// return that E.
    #[test]
    fn hertz_baseline_recovers_the_modulus_of_an_elastic_curve() {
        let dir = std::env::temp_dir().join(format!("nlvid-report-hertz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let s = settings(&dir);
        let (e, r, nu, k, rate): (f64, f64, f64, f64, f64) = (1500.0, 2.5e-6, 0.5, 0.1, 2e-6);
        let mut csv = String::from("time [s],piezo [um],deflection [nm]\n");
        for i in 0..=300 {
            let t = i as f64 * 0.01;
            let d: f64 = rate * t.min(1.0);
            let f = 4.0 / 3.0 * e / (1.0 - nu * nu) * r.sqrt() * d.powf(1.5);
            csv.push_str(&format!("{t},{},{}\n", (d + f / k) * 1e6, f / k * 1e9));
        }
        let path = dir.join("elastic.csv");
        std::fs::write(&path, csv).unwrap();
        let cols = AfmColumns {
            time: "time".into(),
            piezo: "piezo".into(),
            deflection: "deflection".into(),
        };
        let cal = Calibration {
            deflection_sensitivity: None,
            spring_constant: k,
        };
        let curve = nlvid_inverse::read_afm_csv(&path, &cols, &cal).unwrap();
        let delta = curve.indentation().map(<[f64]>::to_vec).unwrap();
        let h = hertz_baseline(&s, &curve, &delta).unwrap();
        assert!(
            (h.youngs_modulus / e - 1.0).abs() < 1e-3,
            "E = {} vs {e}",
            h.youngs_modulus
        );
        assert!(h.misfit < 1e-3, "misfit {}", h.misfit);
        assert!(h.window.contains("0-1.000 s"), "{}", h.window);
    }

    /// Table 5.3 with the shape inputs H, D over 12.22 µm, 28.88 µm ± 25 %.
    fn shape_domain() -> Domain {
        use nlvid_model::{Parameter, Scale};
        let mut p = Domain::table_5_3(0.01).unwrap().params().to_vec();
        p.push(Parameter::new("H", "m", 9.165e-6, 15.275e-6, Scale::Linear));
        p.push(Parameter::new("D", "m", 21.66e-6, 36.1e-6, Scale::Linear));
        Domain::new(p)
            .unwrap()
            .with_sum_constraint(&["g1", "g2"], 0.99)
            .unwrap()
    }

    #[test]
    fn a_shape_meta_model_fits_each_cell_with_its_own_shape_or_the_flagged_mean() {
        let d = shape_domain();
        let mut cell = CellResult::failed("g", "f", "c", "h", String::new());
        cell.cell_height = Some(11e-6);
        cell.base_diameter = Some(30e-6);
        let (own, flag) = shape_inputs(&d, &cell).unwrap();
        assert_eq!(flag, None);
        assert_eq!(own.free_domain().names(), nlvid_model::names::PRONY2);
        let x = own.expand(&[900.0, 0.3, 0.2, 0.1, 5.0]);
        assert_eq!(&x[5..], &[11e-6, 30e-6]);
        // no diameter: the centre of its range (the mean shape), flagged
        cell.base_diameter = None;
        let (mean, flag) = shape_inputs(&d, &cell).unwrap();
        let x = mean.expand(&[900.0, 0.3, 0.2, 0.1, 5.0]);
        assert!((x[6] - 28.88e-6).abs() < 1e-12, "{}", x[6]);
        assert_eq!(x[5], 11e-6);
        let flag = flag.unwrap();
        assert!(
            flag.contains("mean shape") && flag.contains("D = 28.88 um"),
            "{flag}"
        );
        // a shape the meta-model does not cover fails the cell, saying why
        cell.cell_height = Some(20e-6);
        let e = shape_inputs(&d, &cell).unwrap_err();
        assert!(e.contains("H = 2e-5") && e.contains("outside"), "{e}");
        // a meta-model without shape inputs fixes nothing
        let t = Domain::table_5_3(0.01).unwrap();
        let (none, flag) = shape_inputs(&t, &cell).unwrap();
        assert_eq!((none.free_domain(), flag), (&t, None));
    }

    #[test]
    fn geometry_is_taken_from_the_manifest_values() {
        let mut out = CellResult::failed("g", "f", "c", "h", String::new());
        geometry(
            &Geometry {
                height_curves: None,
                image_distances: Some((12e-6, 27e-6)),
                ..Geometry::default()
            },
            &mut out,
        );
        // √(12 · 27) = 18 µm.
        assert!((out.base_diameter.unwrap() - 18e-6).abs() < 1e-18);
        let mut given = CellResult::failed("g", "f", "c", "h", String::new());
        geometry(
            &Geometry {
                height: Some(11e-6),
                diameter: Some(29e-6),
                ..Geometry::default()
            },
            &mut given,
        );
        assert_eq!(
            (given.cell_height, given.base_diameter),
            (Some(11e-6), Some(29e-6))
        );
        let mut bad = CellResult::failed("g", "f", "c", "h", String::new());
        geometry(
            &Geometry {
                height_curves: None,
                image_distances: Some((12e-6, -1e-6)),
                ..Geometry::default()
            },
            &mut bad,
        );
        assert!(bad.base_diameter.is_none());
        assert!(bad.flags[0].contains("base diameter"), "{:?}", bad.flags);
    }
}
