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
//! is a variable projection (`varpro.rs`): non-negative least squares for (G∞, Gₖ) at
//! given τₖ, and a global search over log τₖ — every combination of a 40-point log grid,
//! then Nelder–Mead from the best grid combinations, from log-spaced τ and from seeded
//! random starts; the lowest SSE wins. Non-negative moduli make G(t) monotonically
//! non-increasing by construction; terms whose modulus is 0 at the optimum are dropped
//! and counted as collapsed; the result is an `nlvid_model::Relaxation`.

use nlvid_forward::LeeRadok;
use nlvid_model::{Prony, Relaxation};

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::prepare::{
    Baseline, ContactMethod, ContactPoint, contact_point, contact_point_from_baseline,
    tip_sample_separation,
};
use crate::varpro::{Multistart, Optimum, Separable};

/// The kernel on a measured curve (ν = ½), with the crate's error type.
fn kernel(time: &[f64], delta: &[f64], tip_radius: f64) -> Result<LeeRadok> {
    LeeRadok::sampled(tip_radius, 0.5, time.to_vec(), delta)
        .map_err(|e| AfmError::InvalidInput(e.to_string()))
}

/// Settings of a Lee–Radok Prony fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeeRadokSettings {
    /// Probe radius R, m (not stored in JPK files: the study must give it).
    pub tip_radius: f64,
    /// Number of Prony terms, 1 to 3.
    pub n_terms: usize,
    /// Maximum Nelder–Mead iterations per start.
    pub max_iters: u64,
    /// The global τ search (grid, starts, seed).
    pub multistart: Multistart,
}

impl LeeRadokSettings {
    /// Two-term fit for a probe of radius `tip_radius`, default global search.
    pub fn new(tip_radius: f64) -> Self {
        LeeRadokSettings {
            tip_radius,
            n_terms: 2,
            max_iters: 2000,
            multistart: Multistart::default(),
        }
    }
}

/// Result of a Lee–Radok Prony fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LeeRadokFit {
    /// Fitted shear relaxation modulus G(t) (eq. 5.1), terms sorted by τ; collapsed
    /// terms (modulus 0) are dropped.
    pub relaxation: Relaxation,
    /// Root-mean-square residual, N.
    pub rmse: f64,
    /// RMSE divided by the range of the measured force (eq. 5.2 convention).
    pub range_normalised_rmse: f64,
    /// Nelder–Mead iterations of the winning start.
    pub iterations: u64,
    /// Nelder–Mead starts run (1 for [`fit_lee_radok_from`]).
    pub starts: usize,
    /// Nelder–Mead met its tolerance at the winning start.
    pub converged: bool,
    /// Terms asked for whose modulus came out 0 (dropped: the data support fewer).
    pub collapsed: usize,
    /// Model force at the fitted samples, N.
    pub force_fit: Vec<f64>,
}

/// Checked inputs: the kernel, the τ bounds [Δt_min, 10·T], Δt_min, T and the force range.
struct Checked {
    kernel: LeeRadok,
    ln_tau: (f64, f64),
    dt_min: f64,
    span: f64,
    range: f64,
}

fn check(
    time: &[f64],
    delta: &[f64],
    force: &[f64],
    settings: &LeeRadokSettings,
) -> Result<Checked> {
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
    if !(range > 0.0) {
        return Err(AfmError::InvalidInput("force does not vary".into()));
    }
    Ok(Checked {
        kernel,
        ln_tau: (dt_min.ln(), (10.0 * span).ln()),
        dt_min,
        span,
        range,
    })
}

/// Fit a Prony series to a ramp-hold curve: time (s, from contact), indentation δ (m),
/// force (N, baseline-corrected), searching the relaxation times globally (module
/// documentation; deterministic for given settings).
///
/// Relaxation times are kept within [Δt_min, 10·T] (sampling step to ten times the record
/// length).
///
/// # Errors
/// [`AfmError::InvalidInput`] for bad settings or data; [`AfmError::NotConverged`] when
/// no non-negative solution with a long-term modulus exists.
pub fn fit_lee_radok(
    time: &[f64],
    delta: &[f64],
    force: &[f64],
    settings: &LeeRadokSettings,
) -> Result<LeeRadokFit> {
    let c = check(time, delta, force, settings)?;
    let best = c.solve(force, |problem| {
        let starts = problem.starts(settings.n_terms, &settings.multistart, (c.dt_min, c.span));
        problem.best_of(&starts, settings.max_iters)
    });
    let best = best.ok_or_else(|| AfmError::NotConverged {
        fit: "Lee–Radok",
        detail: "no start gave a finite misfit".into(),
        hint: "check the ramp-hold data and the tip radius",
    })?;
    finish(&c, force, best)
}

/// One local Lee–Radok fit: Nelder–Mead in log τ from `start_taus` (s, one per term;
/// `settings.n_terms` is ignored), the moduli by non-negative least squares. What the
/// global search of [`fit_lee_radok`] runs from each of its starts.
///
/// # Errors
/// As [`fit_lee_radok`]; a start outside the τ bounds or of more than 3 terms is
/// [`AfmError::InvalidInput`].
pub fn fit_lee_radok_from(
    time: &[f64],
    delta: &[f64],
    force: &[f64],
    settings: &LeeRadokSettings,
    start_taus: &[f64],
) -> Result<LeeRadokFit> {
    let mut s = *settings;
    s.n_terms = start_taus.len();
    let c = check(time, delta, force, &s)?;
    let ln: Vec<f64> = start_taus.iter().map(|t| t.ln()).collect();
    if ln.iter().any(|l| !(*l >= c.ln_tau.0 && *l <= c.ln_tau.1)) {
        return Err(AfmError::InvalidInput(format!(
            "start τ {start_taus:?} s outside [{:e}, {:e}] s",
            c.ln_tau.0.exp(),
            c.ln_tau.1.exp()
        )));
    }
    let best = c.solve(force, |problem| problem.local(&ln, settings.max_iters));
    finish(&c, force, best)
}

impl Checked {
    /// Runs `search` on the separable Lee–Radok problem of `force`: the
    /// elastic column and one hereditary column per relaxation time.
    fn solve<T>(&self, force: &[f64], search: impl FnOnce(&Separable<'_>) -> T) -> T {
        let columns = |taus: &[f64]| self.kernel.hereditary_many(taus);
        search(&Separable::new(
            self.kernel.elastic(),
            &columns,
            force,
            self.ln_tau,
        ))
    }
}

/// The relaxation modulus of an optimum, collapsed terms dropped, and its misfit.
fn finish(c: &Checked, force: &[f64], best: Optimum) -> Result<LeeRadokFit> {
    let g = &best.coefs;
    let g0: f64 = g.iter().sum();
    if !g0.is_finite() || g0 <= 0.0 {
        return Err(AfmError::NotConverged {
            fit: "Lee–Radok",
            detail: format!("instantaneous modulus G(0) = {g0} Pa"),
            hint: "check the contact point and baseline (force must rise with indentation)",
        });
    }
    let weights: Vec<(f64, f64)> = g[1..]
        .iter()
        .zip(&best.taus)
        .filter(|(gk, _)| **gk > 0.0)
        .map(|(gk, tau)| (gk / g0, *tau))
        .collect();
    let collapsed = best.taus.len() - weights.len();
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
    let force_fit = c.kernel.force(&relaxation);
    let n = force.len();
    let sse: f64 = force_fit
        .iter()
        .zip(force)
        .map(|(m, f)| (m - f).powi(2))
        .sum();
    let rmse = (sse / n as f64).sqrt();
    Ok(LeeRadokFit {
        relaxation,
        rmse,
        range_normalised_rmse: rmse / c.range,
        iterations: best.iterations,
        starts: best.starts,
        converged: best.converged,
        collapsed,
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
    let (ext_i, hold) = curve.extend_then(
        SegmentKind::Hold,
        "hold (constant-height pause right after the extend)",
    )?;
    let ext = &curve.segments[ext_i];
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
