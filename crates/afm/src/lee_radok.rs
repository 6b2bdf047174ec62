//! Linear-viscoelastic Prony fit of a ramp-hold indentation through the Lee–Radok
//! hereditary integral.
//!
//! For a rigid sphere of radius R on an incompressible (ν = ½) linear-viscoelastic
//! half-space whose contact grows monotonically (Lee & Radok 1960),
//!
//! ```text
//! F(t) = (16/3) √R ∫₀ᵗ G(t − s) d(δ^{3/2})/ds ds,
//! G(t) = G0 (g∞ + Σₖ gₖ exp(−t/τₖ))                  (eq. 5.1)
//! ```
//!
//! (the elastic limit G = E/3 gives back eq. 1.1 with ν = ½). It is the small-strain limit
//! of the thesis's NLV models (§2.2, eqs. 4.2–4.3 / 5.1).
//!
//! The integral is the one Lee–Radok kernel of the pipeline, `nlvid_forward::LeeRadok`,
//! on the measured indentation (exact for u = δ^{3/2} piecewise linear between samples),
//! O(n) per evaluation. The moduli G∞ = G0 g∞ and Gₖ = G0 gₖ enter linearly, so the fit
//! is a variable projection: Nelder–Mead (argmin) over log τₖ, non-negative least squares
//! for (G∞, Gₖ) at each trial. Non-negative moduli make G(t) monotonically non-increasing
//! by construction; the result is an `nlvid_model::Relaxation`.

use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use nlvid_forward::LeeRadok;
use nlvid_model::{Prony, Relaxation};

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::prepare::{
    Baseline, ContactMethod, ContactPoint, contact_point, contact_point_from_baseline,
    tip_sample_separation,
};

/// The kernel on a measured curve (ν = ½), with the crate's error type.
fn kernel(time: &[f64], delta: &[f64], tip_radius: f64) -> Result<LeeRadok> {
    LeeRadok::sampled(tip_radius, 0.5, time.to_vec(), delta)
        .map_err(|e| AfmError::InvalidInput(e.to_string()))
}

/// Columns [P u, P h_1, ..., P h_m] with P = (16/3)√R: the force per unit modulus of the
/// long-term part and of each term.
fn basis(kernel: &LeeRadok, taus: &[f64]) -> Vec<Vec<f64>> {
    std::iter::once(kernel.elastic())
        .chain(taus.iter().map(|&tau| kernel.hereditary(tau)))
        .collect()
}

/// Settings of a Lee–Radok Prony fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeeRadokSettings {
    /// Probe radius R, m (not stored in JPK files: the study must give it).
    pub tip_radius: f64,
    /// Number of Prony terms, 1 to 3.
    pub n_terms: usize,
    /// Maximum Nelder–Mead iterations.
    pub max_iters: u64,
}

impl LeeRadokSettings {
    /// Two-term fit for a probe of radius `tip_radius`.
    pub fn new(tip_radius: f64) -> Self {
        LeeRadokSettings {
            tip_radius,
            n_terms: 2,
            max_iters: 2000,
        }
    }
}

/// Result of a Lee–Radok Prony fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LeeRadokFit {
    /// Fitted shear relaxation modulus G(t) (eq. 5.1), terms sorted by τ.
    pub relaxation: Relaxation,
    /// Root-mean-square residual, N.
    pub rmse: f64,
    /// RMSE divided by the range of the measured force (eq. 5.2 convention).
    pub range_normalised_rmse: f64,
    /// Nelder–Mead iterations used.
    pub iterations: u64,
    /// Model force at the fitted samples, N.
    pub force_fit: Vec<f64>,
}

struct VarPro<'a> {
    kernel: &'a LeeRadok,
    force: &'a [f64],
    log_tau_bounds: (f64, f64),
    scale: f64,
}

impl VarPro<'_> {
    /// Moduli and SSE for the given log τ's; None if out of bounds.
    fn solve(&self, log_tau: &[f64]) -> Option<(Vec<f64>, Vec<f64>, f64)> {
        if log_tau
            .iter()
            .any(|l| !(*l >= self.log_tau_bounds.0 && *l <= self.log_tau_bounds.1))
        {
            return None;
        }
        let mut taus: Vec<f64> = log_tau.iter().map(|l| l.exp()).collect();
        taus.sort_by(f64::total_cmp);
        let cols = basis(self.kernel, &taus);
        let (g, sse) = nnls(&cols, self.force)?;
        Some((taus, g, sse))
    }
}

impl CostFunction for VarPro<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        Ok(match self.solve(p) {
            Some((_, _, sse)) => sse * self.scale,
            None => f64::MAX / 4.0,
        })
    }
}

/// Non-negative least squares min ‖Σ g_j c_j − y‖², g ≥ 0, by enumerating active sets
/// (m ≤ 4 columns: at most 15 small solves). Returns (g, sse).
fn nnls(cols: &[Vec<f64>], y: &[f64]) -> Option<(Vec<f64>, f64)> {
    let m = cols.len();
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let yy: f64 = y.iter().map(|v| v * v).sum();
    // Gram matrix and right-hand side of the normalised columns
    let mut gram = vec![vec![0.0; m]; m];
    let mut rhs = vec![0.0; m];
    for a in 0..m {
        if norms[a] == 0.0 {
            continue;
        }
        rhs[a] = cols[a].iter().zip(y).map(|(c, v)| c * v).sum::<f64>() / norms[a];
        for b in a..m {
            if norms[b] == 0.0 {
                continue;
            }
            let v = cols[a]
                .iter()
                .zip(&cols[b])
                .map(|(p, q)| p * q)
                .sum::<f64>()
                / (norms[a] * norms[b]);
            gram[a][b] = v;
            gram[b][a] = v;
        }
    }
    let mut best: Option<(Vec<f64>, f64)> = None;
    for mask in 1u32..(1 << m) {
        let idx: Vec<usize> = (0..m)
            .filter(|j| mask & (1 << j) != 0 && norms[*j] > 0.0)
            .collect();
        if idx.len() != mask.count_ones() as usize {
            continue;
        }
        let a: Vec<Vec<f64>> = idx
            .iter()
            .map(|&i| idx.iter().map(|&j| gram[i][j]).collect())
            .collect();
        let b: Vec<f64> = idx.iter().map(|&i| rhs[i]).collect();
        let Some(x) = solve_spd(a, b.clone()) else {
            continue;
        };
        if x.iter().any(|v| *v < 0.0) {
            continue;
        }
        // sse = yy − 2 xᵀb + xᵀ A x = yy − xᵀb at the LS optimum
        let sse = (yy - x.iter().zip(&b).map(|(p, q)| p * q).sum::<f64>()).max(0.0);
        if best.as_ref().is_none_or(|bst| sse < bst.1) {
            let mut g = vec![0.0; m];
            for (k, &i) in idx.iter().enumerate() {
                g[i] = x[k] / norms[i];
            }
            best = Some((g, sse));
        }
    }
    best
}

/// Gaussian elimination with partial pivoting for a small system; None if singular.
fn solve_spd(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-13 {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        for row in col + 1..n {
            let f = a[row][col] / a[col][col];
            let pivot_row = a[col].clone();
            for (v, p) in a[row].iter_mut().zip(&pivot_row).skip(col) {
                *v -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| a[i][k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    Some(x)
}

/// Fit a Prony series to a ramp-hold curve: time (s, from contact), indentation δ (m),
/// force (N, baseline-corrected).
///
/// Relaxation times are kept within [Δt_min, 10·T] (sampling step to ten times the record
/// length); start values are log-spaced over [10·Δt_min, T/3].
///
/// # Errors
/// [`AfmError::InvalidInput`] for bad settings or data; [`AfmError::NotConverged`] when
/// Nelder–Mead reaches `max_iters` or no non-negative solution exists.
pub fn fit_lee_radok(
    time: &[f64],
    delta: &[f64],
    force: &[f64],
    settings: &LeeRadokSettings,
) -> Result<LeeRadokFit> {
    let kernel = kernel(time, delta, settings.tip_radius)?;
    if force.len() != time.len() || force.iter().any(|f| !f.is_finite()) {
        return Err(AfmError::InvalidInput(
            "force must be finite and as long as time".into(),
        ));
    }
    if !(1..=3).contains(&settings.n_terms) {
        return Err(AfmError::InvalidInput(format!(
            "Prony terms must be 1 to 3, got {}",
            settings.n_terms
        )));
    }
    let n = time.len();
    if n < 4 * (settings.n_terms + 1) {
        return Err(AfmError::InvalidInput(format!(
            "{n} samples are too few for {} Prony terms",
            settings.n_terms
        )));
    }
    let span = time[n - 1] - time[0];
    let dt_min = time
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let fmax = force.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let fmin = force.iter().copied().fold(f64::INFINITY, f64::min);
    let range = fmax - fmin;
    if range <= 0.0 {
        return Err(AfmError::InvalidInput("force does not vary".into()));
    }
    // Unscaled problem for the final solve; the search minimises the
    // range-normalised RMSE² (the same problem, scaled).
    let unscaled = VarPro {
        kernel: &kernel,
        force,
        log_tau_bounds: (dt_min.ln(), (10.0 * span).ln()),
        scale: 1.0,
    };
    let problem = VarPro {
        scale: 1.0 / (n as f64 * range * range),
        ..unscaled
    };
    let m = settings.n_terms;
    let (lo, hi) = ((10.0 * dt_min).ln(), (span / 3.0).ln());
    let start: Vec<f64> = (0..m)
        .map(|k| lo + (hi - lo) * (k as f64 + 0.5) / m as f64)
        .collect();
    let mut simplex = vec![start.clone()];
    for k in 0..m {
        let mut v = start.clone();
        v[k] += 0.7;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-14)
        .map_err(|e| AfmError::InvalidInput(e.to_string()))?;
    let res = Executor::new(problem, solver)
        .configure(|s| s.max_iters(settings.max_iters))
        .run()
        .map_err(|e| AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: e.to_string(),
            hint: "check the ramp-hold data and the tip radius",
        })?;
    let state = res.state();
    let iterations = state.get_iter();
    if !matches!(
        state.get_termination_status(),
        TerminationStatus::Terminated(TerminationReason::SolverConverged)
    ) {
        return Err(AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: format!(
                "Nelder–Mead on log τ stopped after {iterations} iterations ({:?}), range-normalised RMSE² {:.3e}",
                state.get_termination_status(),
                state.get_best_cost()
            ),
            hint: "raise max_iters or use fewer Prony terms",
        });
    }
    let best = state.get_best_param().cloned().unwrap_or(start);
    let (taus, g, sse) = unscaled
        .solve(&best)
        .ok_or_else(|| AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: "no non-negative Prony moduli fit the data".into(),
            hint: "check the contact point and baseline (force must rise with indentation)",
        })?;
    let g0: f64 = g.iter().sum();
    if !g0.is_finite() || g0 <= 0.0 {
        return Err(AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: format!("instantaneous modulus G(0) = {g0} Pa"),
            hint: "check the contact point and baseline",
        });
    }
    let weights: Vec<(f64, f64)> = g[1..].iter().map(|gk| gk / g0).zip(taus).collect();
    let relaxation = Prony::new("G", &weights)
        .and_then(|p| Relaxation::new("G0", g0, p))
        .map_err(|e| AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: format!(
                "the best moduli have no long-term part (G∞ = {:e} Pa): {e}",
                g[0]
            ),
            hint: "the force has not levelled off by the end of the hold: record a longer hold \
                   or fit fewer Prony terms",
        })?;
    let force_fit = kernel.force(&relaxation);
    let rmse = (sse / n as f64).sqrt();
    Ok(LeeRadokFit {
        relaxation,
        rmse,
        range_normalised_rmse: rmse / range,
        iterations,
        force_fit,
    })
}

/// A ramp-hold record ready for [`fit_lee_radok`]: from the contact on the extend
/// segment through the end of the first hold segment.
#[derive(Debug, Clone, PartialEq)]
pub struct RampHold {
    /// Time since contact, s.
    pub time: Vec<f64>,
    /// Indentation δ = s_c − s, m.
    pub indentation: Vec<f64>,
    /// Force minus the pre-contact baseline, N.
    pub force: Vec<f64>,
    /// Contact point on the extend segment.
    pub contact: ContactPoint,
    /// Absolute time of the contact, s.
    pub contact_time: f64,
    /// Baseline subtracted (offset only, fitted on the extend samples before contact).
    pub baseline: Baseline,
}

/// Cut a ramp-hold curve (extend then constant-height hold) at the contact point found on
/// the extend segment, subtract the pre-contact force offset, and compute δ(t).
///
/// With [`ContactMethod::Deviation`] and a constant-height pause recorded right before the
/// extend, the baseline (offset and noise) is taken from that pause, and the contact is
/// the last extend sample within `n_sigma` of it (its `baseline_fraction` is unused);
/// otherwise the method runs on the extend segment alone.
///
/// # Errors
/// Missing extend or hold segment or channels; no contact.
pub fn prepare_ramp_hold(curve: &ForceCurve, method: ContactMethod) -> Result<RampHold> {
    let k = curve.calibration.spring_constant;
    let ext_i = curve
        .segments
        .iter()
        .position(|s| s.kind == SegmentKind::Extend)
        .ok_or_else(|| AfmError::MissingSegment {
            kind: "extend".into(),
        })?;
    let ext = &curve.segments[ext_i];
    let hold = curve.segments[ext_i + 1..]
        .first()
        .filter(|s| s.kind == SegmentKind::Hold)
        .ok_or_else(|| AfmError::MissingSegment {
            kind: "hold (constant-height pause right after the extend)".into(),
        })?;
    let fe = ext.force()?;
    let se = tip_sample_separation(ext.height()?, fe, k)?;
    // A pause recorded just before the approach (the probe still free) is the better
    // baseline: the force may rise from the very first extend sample.
    let pre = ext_i
        .checked_sub(1)
        .map(|i| &curve.segments[i])
        .filter(|s| matches!(s.kind, SegmentKind::Hold) && s.len() >= 16);
    let (contact, baseline) = match (method, pre) {
        (ContactMethod::Deviation { n_sigma, .. }, Some(pre)) => {
            let fp = pre.force()?;
            let sp = tip_sample_separation(pre.height()?, fp, k)?;
            let base = Baseline::fit(&sp, fp, 0..fp.len(), false)?;
            (contact_point_from_baseline(&se, fe, &base, n_sigma)?, base)
        }
        _ => {
            let contact = contact_point(&se, fe, method)?;
            let base = Baseline::fit(&se, fe, 0..contact.index.max(2), false)?;
            (contact, base)
        }
    };
    let sh = tip_sample_separation(hold.height()?, hold.force()?, k)?;
    let t_c = ext.time[contact.index];
    let mut time = Vec::new();
    let mut indentation = Vec::new();
    let mut force = Vec::new();
    let fh = hold.force()?;
    let samples = ext.time[contact.index..]
        .iter()
        .zip(&se[contact.index..])
        .zip(&fe[contact.index..])
        .chain(hold.time.iter().zip(&sh).zip(fh));
    for ((t, s), f) in samples {
        time.push(t - t_c);
        indentation.push(contact.separation - s);
        force.push(f - baseline.offset);
    }
    Ok(RampHold {
        time,
        indentation,
        force,
        contact,
        contact_time: t_c,
        baseline,
    })
}
