//! Creep (force clamp): a Prony creep-compliance fit of the indentation under a
//! constant-force pause, through the Lee–Radok hereditary integral in force control.
//!
//! For a rigid paraboloid of radius R on an incompressible (ν = ½) linear-viscoelastic
//! half-space whose contact grows monotonically (Lee & Radok 1960), the relaxation form
//! `F = (16/3)√R ∫ G(t − s) d(δ^{3/2})/ds ds` (see [`crate::fit_lee_radok`]) inverts to
//!
//! ```text
//! δ(t)^{3/2} = 3/(16√R) ∫₀ᵗ J(t − s) dF/ds ds,
//! J(t) = J₀ + Σₖ Jₖ (1 − e^{−t/τₖ})                  (Prony shear creep compliance)
//! ```
//!
//! with J₀ = 1/G(0) and J(∞) = J₀ + Σ Jₖ = 1/G∞ (elastic limit: J = 1/G gives Hertz,
//! eq. 1.1 with E = 3G). Non-negative J₀, Jₖ make J(t) non-decreasing. Since
//! `∫ Jₖ(1 − e^{−(t−s)/τ}) dF = Jₖ (F(t) − hₖ(t))` with `hₖ(t) = ∫ e^{−(t−s)/τₖ} dF(s)`,
//! the compliances enter linearly: for given τₖ, non-negative least squares in
//! `u = δ^{3/2}` gives J₀, Jₖ (variable projection). hₖ is the exponential convolution
//! of the Lee–Radok kernel, applied here to the force history (piecewise linear between
//! samples): `h(t_{n+1}) = e^{−Δ/τ} h(t_n) + (ΔF/Δ) τ (1 − e^{−Δ/τ})`, the shared
//! kernel's `nlvid_forward::exp_convolution` with the force as the history.
//!
//! The τₖ are searched globally as in the relaxation fit (`varpro.rs`: every
//! combination of a log-spaced grid, then Nelder–Mead from the best combinations,
//! log-spaced and seeded random starts). Terms whose Jₖ is 0 at the optimum are
//! reported as collapsed.

use nlvid_forward::{exp_convolution, exp_convolutions};

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::hertz::prepare_approach;
use crate::prepare::{Baseline, ContactMethod, ContactPoint, tip_sample_separation};
use crate::varpro::{Multistart, Separable};

/// A creep experiment from the contact on: extend after the contact, then the
/// constant-force pause.
#[derive(Debug, Clone, PartialEq)]
pub struct Creep {
    /// Time since the contact, s.
    pub time: Vec<f64>,
    /// Indentation δ = s_c − s, m.
    pub indentation: Vec<f64>,
    /// Force minus the baseline, N.
    pub force: Vec<f64>,
    /// Index of the first sample of the pause in the arrays above.
    pub pause_start: usize,
    /// Contact point on the extend.
    pub contact: ContactPoint,
    /// Baseline that was subtracted.
    pub baseline: Baseline,
}

/// Cut the extend (from the contact) and the constant-force pause right after it out of
/// `curve`; contact and baseline as in [`prepare_approach`].
///
/// # Errors
/// [`AfmError::MissingSegment`] without a creep segment right after the extend; as
/// [`prepare_approach`].
pub fn prepare_creep(curve: &ForceCurve, method: ContactMethod) -> Result<Creep> {
    let (ext_i, pause) = curve.extend_then(
        SegmentKind::Creep,
        "creep (constant-force pause right after the extend)",
    )?;
    let approach = prepare_approach(curve, method)?;
    let ext = &curve.segments[ext_i];
    let k = curve.calibration.spring_constant;
    let c = approach.contact;
    let t_c = ext.time[c.index];
    let mut time = Vec::new();
    let mut indentation = Vec::new();
    let mut force = Vec::new();
    // The approach is cut at the force maximum; the rest of the extend belongs too.
    let fe = ext.force()?;
    let se = tip_sample_separation(ext.height()?, fe, k)?;
    for i in c.index..ext.len() {
        time.push(ext.time[i] - t_c);
        indentation.push(c.separation - se[i]);
        force.push(fe[i] - approach.baseline.at(se[i]));
    }
    let pause_start = time.len();
    let fp = pause.force()?;
    let sp = tip_sample_separation(pause.height()?, fp, k)?;
    for i in 0..pause.len() {
        time.push(pause.time[i] - t_c);
        indentation.push(c.separation - sp[i]);
        force.push(fp[i] - approach.baseline.at(sp[i]));
    }
    Ok(Creep {
        time,
        indentation,
        force,
        pause_start,
        contact: c,
        baseline: approach.baseline,
    })
}

/// A Prony shear creep compliance `J(t) = J₀ + Σ Jₖ (1 − e^{−t/τₖ})`, in 1/Pa.
#[derive(Debug, Clone, PartialEq)]
pub struct Compliance {
    /// Instantaneous compliance J₀ = 1/G(0), 1/Pa.
    pub j0: f64,
    /// Terms (Jₖ in 1/Pa, τₖ in s), ordered by τ.
    pub terms: Vec<(f64, f64)>,
}

impl Compliance {
    /// J(t), 1/Pa.
    pub fn at(&self, t: f64) -> f64 {
        self.j0
            + self
                .terms
                .iter()
                .map(|(j, tau)| j * (1.0 - (-t / tau).exp()))
                .sum::<f64>()
    }

    /// Instantaneous shear modulus G(0) = 1/J₀, Pa.
    pub fn g0(&self) -> f64 {
        1.0 / self.j0
    }

    /// Long-term shear modulus G∞ = 1/(J₀ + Σ Jₖ), Pa.
    pub fn g_inf(&self) -> f64 {
        1.0 / (self.j0 + self.terms.iter().map(|t| t.0).sum::<f64>())
    }
}

/// `hₖ(t) = ∫₀ᵗ e^{−(t−s)/τ} dF(s)` for F piecewise linear between the samples (F jumps
/// from 0 to F(t₀) at the first sample): the Lee–Radok kernel's convolution.
fn hereditary(time: &[f64], force: &[f64], tau: f64) -> Vec<f64> {
    exp_convolution(time, force, tau, false).0
}

/// `u = δ^{3/2}` (m^{3/2}) of the model, unclipped: `3/(16√R) [J₀ F + Σ Jₖ (F − hₖ)]`.
fn model_u(time: &[f64], force: &[f64], j: &Compliance, r: f64) -> Vec<f64> {
    let c = 3.0 / (16.0 * r.sqrt());
    let mut u: Vec<f64> = force.iter().map(|f| j.j0 * f).collect();
    for &(jk, tau) in &j.terms {
        let h = hereditary(time, force, tau);
        for ((u, f), h) in u.iter_mut().zip(force).zip(&h) {
            *u += jk * (f - h);
        }
    }
    u.iter().map(|u| c * u).collect()
}

/// Indentation δ(t) (m) of a paraboloid of radius `r` under the force history `force`
/// (N, from the contact) for the compliance `j` (ν = ½): the forward model of the fit.
pub fn creep_indentation(time: &[f64], force: &[f64], j: &Compliance, r: f64) -> Vec<f64> {
    model_u(time, force, j, r)
        .iter()
        .map(|u| u.max(0.0).powf(2.0 / 3.0))
        .collect()
}

/// Settings of a creep fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CreepSettings {
    /// Probe radius R, m.
    pub tip_radius: f64,
    /// Prony terms, 1 to 3.
    pub terms: usize,
    /// The global τ search (grid points, starts, seed).
    pub multistart: Multistart,
}

impl CreepSettings {
    /// `terms` Prony terms for a probe of radius `tip_radius`, default global search.
    pub fn new(tip_radius: f64, terms: usize) -> Self {
        CreepSettings {
            tip_radius,
            terms,
            multistart: Multistart::default(),
        }
    }
}

/// Result of a creep fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CreepFit {
    /// The fitted compliance.
    pub compliance: Compliance,
    /// Root-mean-square residual of δ^{3/2}, m^{3/2} (the fitted quantity).
    pub rmse_u: f64,
    /// Root-mean-square residual of δ, m.
    pub rmse: f64,
    /// RMSE of δ divided by the range of the fitted δ.
    pub range_normalised_rmse: f64,
    /// Samples fitted.
    pub n_points: usize,
    /// Terms whose compliance came out 0 (the data support fewer terms).
    pub collapsed: usize,
}

/// Fit a Prony creep compliance to a creep experiment (all samples from the contact on).
///
/// # Errors
/// [`AfmError::InvalidInput`] for bad settings or data (fewer than 20 samples, time not
/// increasing, non-finite values); [`AfmError::NotConverged`] if no positive instantaneous
/// compliance fits or Nelder–Mead fails.
pub fn fit_creep(data: &Creep, settings: &CreepSettings) -> Result<CreepFit> {
    let (t, d, f) = (&data.time, &data.indentation, &data.force);
    let n = t.len();
    if !(settings.tip_radius.is_finite() && settings.tip_radius > 0.0) {
        return Err(AfmError::InvalidInput(format!(
            "tip radius must be positive, got {} m",
            settings.tip_radius
        )));
    }
    if !(1..=3).contains(&settings.terms) || settings.multistart.grid < 4 {
        return Err(AfmError::InvalidInput(format!(
            "creep fit takes 1 to 3 terms and a grid of ≥ 4 points (got {}, {})",
            settings.terms, settings.multistart.grid
        )));
    }
    if n < 20 || d.len() != n || f.len() != n {
        return Err(AfmError::InvalidInput(format!(
            "creep fit needs ≥ 20 samples of time, indentation and force (got {n}, {}, {})",
            d.len(),
            f.len()
        )));
    }
    if t.iter().chain(d).chain(f).any(|v| !v.is_finite()) || t.windows(2).any(|w| w[1] <= w[0]) {
        return Err(AfmError::InvalidInput(
            "creep data must be finite with increasing time".into(),
        ));
    }
    let span = t[n - 1] - t[0];
    let dt_min = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let ln_tau = ((2.0 * dt_min).ln(), (10.0 * span).ln());
    let u: Vec<f64> = d.iter().map(|x| x.max(0.0).powf(1.5)).collect();
    if !u.iter().any(|v| *v > 0.0) {
        return Err(AfmError::InvalidInput(
            "no positive indentation in the creep data".into(),
        ));
    }
    let c = 3.0 / (16.0 * settings.tip_radius.sqrt());
    let columns = |taus: &[f64]| {
        exp_convolutions(t, f, taus)
            .into_iter()
            .map(|h| f.iter().zip(&h).map(|(f, h)| c * (f - h)).collect())
            .collect()
    };
    let problem = Separable::new(f.iter().map(|f| c * f).collect(), &columns, &u, ln_tau);
    let starts = problem.starts(settings.terms, &settings.multistart, (dt_min, span));
    let best = problem
        .best_of(&starts, settings.multistart.max_iters)
        .ok_or_else(|| AfmError::NotConverged {
            fit: "creep",
            detail: "no start gave a finite misfit".into(),
            hint: "check the creep segment and the tip radius",
        })?;
    let (taus, x, sse) = (best.taus, best.coefs, best.sse);
    if !(x[0] > 0.0) {
        return Err(AfmError::NotConverged {
            fit: "creep",
            detail: format!("instantaneous compliance J0 = {} 1/Pa", x[0]),
            hint: "the force does not indent the sample elastically; check contact and segments",
        });
    }
    let compliance = Compliance {
        j0: x[0],
        terms: taus
            .iter()
            .zip(&x[1..])
            .map(|(tau, j)| (*j, *tau))
            .collect(),
    };
    let model = creep_indentation(t, f, &compliance, settings.tip_radius);
    let ss: f64 = model.iter().zip(d).map(|(a, b)| (a - b).powi(2)).sum();
    let dmax = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let dmin = d.iter().copied().fold(f64::INFINITY, f64::min);
    let rmse = (ss / n as f64).sqrt();
    Ok(CreepFit {
        collapsed: x[1..].iter().filter(|v| **v == 0.0).count(),
        compliance,
        rmse_u: (sse / n as f64).sqrt(),
        rmse,
        range_normalised_rmse: rmse / (dmax - dmin),
        n_points: n,
    })
}

/// Sum of squared residuals of δ^{3/2} (m³) for `j` on `data` with a probe of radius
/// `r`: the objective [`fit_creep`] minimises, for comparing fits.
pub fn creep_objective(data: &Creep, j: &Compliance, r: f64) -> f64 {
    model_u(&data.time, &data.force, j, r)
        .iter()
        .zip(&data.indentation)
        .map(|(m, d)| (m - d.max(0.0).powf(1.5)).powi(2))
        .sum()
}
