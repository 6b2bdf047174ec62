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
//! samples): `h(t_{n+1}) = e^{−Δ/τ} h(t_n) + (ΔF/Δ) τ (1 − e^{−Δ/τ})`.
//!
//! The τₖ are searched globally: every combination of a log-spaced grid (the Gram
//! matrix of all grid columns is formed once, so a combination costs a few small
//! solves), then Nelder–Mead in log τ from the best combination. Terms whose Jₖ is 0
//! at the optimum are reported as collapsed.

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;

use crate::curve::{ForceCurve, SegmentKind};
use crate::error::{AfmError, Result};
use crate::hertz::prepare_approach;
use crate::prepare::{Baseline, ContactMethod, ContactPoint, tip_sample_separation};

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
    let ext_i = curve
        .segments
        .iter()
        .position(|s| s.kind == SegmentKind::Extend)
        .ok_or_else(|| AfmError::MissingSegment {
            kind: "extend".into(),
        })?;
    let pause = curve.segments[ext_i + 1..]
        .first()
        .filter(|s| s.kind == SegmentKind::Creep)
        .ok_or_else(|| AfmError::MissingSegment {
            kind: "creep (constant-force pause right after the extend)".into(),
        })?;
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
/// from 0 to F(t₀) at the first sample).
fn hereditary(time: &[f64], force: &[f64], tau: f64) -> Vec<f64> {
    let mut h = Vec::with_capacity(time.len());
    let mut acc = force.first().copied().unwrap_or(0.0);
    h.push(acc);
    for i in 1..time.len() {
        let dt = time[i] - time[i - 1];
        let df = force[i] - force[i - 1];
        let e = (-dt / tau).exp();
        acc = e * acc
            + if dt > 0.0 {
                df / dt * tau * (1.0 - e)
            } else {
                df
            };
        h.push(acc);
    }
    h
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
    /// Points of the log τ grid searched before Nelder–Mead.
    pub grid: usize,
}

impl CreepSettings {
    /// `terms` Prony terms for a probe of radius `tip_radius`, 40-point τ grid.
    pub fn new(tip_radius: f64, terms: usize) -> Self {
        CreepSettings {
            tip_radius,
            terms,
            grid: 40,
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

/// The fitting problem: u = δ^{3/2} against the basis F, F − hₖ.
struct Problem<'a> {
    time: &'a [f64],
    force: &'a [f64],
    u: Vec<f64>,
    c: f64,
    ln_tau: (f64, f64),
    /// Σ u², the objective's scale.
    uu: f64,
}

impl Problem<'_> {
    fn columns(&self, taus: &[f64]) -> Vec<Vec<f64>> {
        let mut cols = vec![self.force.iter().map(|f| self.c * f).collect::<Vec<_>>()];
        for &tau in taus {
            let h = hereditary(self.time, self.force, tau);
            cols.push(
                self.force
                    .iter()
                    .zip(&h)
                    .map(|(f, h)| self.c * (f - h))
                    .collect(),
            );
        }
        cols
    }

    /// (coefficients, SSE) of the non-negative fit for these τ.
    fn solve(&self, taus: &[f64]) -> (Vec<f64>, f64) {
        let cols = self.columns(taus);
        let m = cols.len();
        let mut gram = vec![vec![0.0; m]; m];
        let mut rhs = vec![0.0; m];
        for a in 0..m {
            for b in a..m {
                let g: f64 = cols[a].iter().zip(&cols[b]).map(|(x, y)| x * y).sum();
                gram[a][b] = g;
                gram[b][a] = g;
            }
            rhs[a] = cols[a].iter().zip(&self.u).map(|(x, y)| x * y).sum();
        }
        let (x, _) = nnls_gram(&gram, &rhs, self.uu);
        // The SSE summed directly: the Gram form uu − xᵀr cancels near a perfect fit.
        let sse = self
            .u
            .iter()
            .enumerate()
            .map(|(i, u)| {
                let m: f64 = cols.iter().zip(&x).map(|(c, xk)| xk * c[i]).sum();
                (u - m).powi(2)
            })
            .sum();
        (x, sse)
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        // Outside the τ range: the nearest admissible value's cost plus a steep wall.
        let (lo, hi) = self.ln_tau;
        let mut wall = 0.0;
        let taus: Vec<f64> = p
            .iter()
            .map(|&x| {
                let c = x.clamp(lo, hi);
                wall += (x - c).powi(2);
                c.exp()
            })
            .collect();
        let (_, sse) = self.solve(&taus);
        // Relative to Σu² so that Nelder–Mead's tolerance is scale-free.
        Ok(sse / self.uu * (1.0 + 1e3 * wall))
    }
}

/// Non-negative least squares from the Gram matrix `g = AᵀA`, `r = Aᵀy`, `yy = yᵀy`:
/// every active set is tried (≤ 4 unknowns, 16 sets); returns (x, SSE).
fn nnls_gram(g: &[Vec<f64>], r: &[f64], yy: f64) -> (Vec<f64>, f64) {
    let m = r.len();
    let mut best = (vec![0.0; m], yy);
    for mask in 1u32..(1 << m) {
        let idx: Vec<usize> = (0..m).filter(|i| mask & (1 << i) != 0).collect();
        let Some(x) = solve_spd(
            &idx.iter()
                .map(|&a| idx.iter().map(|&b| g[a][b]).collect())
                .collect::<Vec<Vec<f64>>>(),
            &idx.iter().map(|&a| r[a]).collect::<Vec<_>>(),
        ) else {
            continue;
        };
        if x.iter().any(|v| !(*v >= 0.0)) {
            continue;
        }
        // SSE = yy − 2 xᵀr + xᵀGx = yy − xᵀr at the subset's normal-equation solution.
        let sse = yy - x.iter().zip(&idx).map(|(xi, &a)| xi * r[a]).sum::<f64>();
        if sse < best.1 {
            let mut full = vec![0.0; m];
            for (xi, &a) in x.iter().zip(&idx) {
                full[a] = *xi;
            }
            best = (full, sse.max(0.0));
        }
    }
    best
}

/// Solve the small symmetric positive definite system `a x = b` (Cholesky on the
/// diagonally scaled matrix); None if singular.
fn solve_spd(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let d: Vec<f64> = (0..n).map(|i| a[i][i].sqrt()).collect();
    if d.iter().any(|v| !(*v > 0.0)) {
        return None;
    }
    let s = |i: usize, j: usize| a[i][j] / (d[i] * d[j]);
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let sum: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let v = s(i, i) - sum;
                if !(v > 1e-13) {
                    return None;
                }
                l[i][i] = v.sqrt();
            } else {
                l[i][j] = (s(i, j) - sum) / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let sum: f64 = (0..i).map(|k| l[i][k] * y[k]).sum();
        y[i] = (b[i] / d[i] - sum) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let sum: f64 = (i + 1..n).map(|k| l[k][i] * x[k]).sum();
        x[i] = (y[i] - sum) / l[i][i];
    }
    Some(x.iter().zip(&d).map(|(x, d)| x / d).collect())
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
    if !(1..=3).contains(&settings.terms) || settings.grid < 4 {
        return Err(AfmError::InvalidInput(format!(
            "creep fit takes 1 to 3 terms and a grid of ≥ 4 points (got {}, {})",
            settings.terms, settings.grid
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
    let uu: f64 = u.iter().map(|v| v * v).sum();
    if !(uu > 0.0) {
        return Err(AfmError::InvalidInput(
            "no positive indentation in the creep data".into(),
        ));
    }
    let p = Problem {
        time: t,
        force: f,
        u,
        c: 3.0 / (16.0 * settings.tip_radius.sqrt()),
        ln_tau,
        uu,
    };
    // Global search: all combinations τ₁ < τ₂ < … of the grid, from one Gram matrix.
    let g = settings.grid;
    let grid: Vec<f64> = (0..g)
        .map(|i| (ln_tau.0 + (ln_tau.1 - ln_tau.0) * i as f64 / (g - 1) as f64).exp())
        .collect();
    let cols = p.columns(&grid);
    let m = cols.len();
    let mut gram = vec![vec![0.0; m]; m];
    let mut rhs = vec![0.0; m];
    for a in 0..m {
        for b in a..m {
            let v: f64 = cols[a].iter().zip(&cols[b]).map(|(x, y)| x * y).sum();
            gram[a][b] = v;
            gram[b][a] = v;
        }
        rhs[a] = cols[a].iter().zip(&p.u).map(|(x, y)| x * y).sum();
    }
    let mut best: (Vec<usize>, f64) = (Vec::new(), f64::INFINITY);
    let mut combo: Vec<usize> = (0..settings.terms).collect();
    loop {
        let idx: Vec<usize> = std::iter::once(0)
            .chain(combo.iter().map(|c| c + 1))
            .collect();
        let sub: Vec<Vec<f64>> = idx
            .iter()
            .map(|&a| idx.iter().map(|&b| gram[a][b]).collect())
            .collect();
        let r: Vec<f64> = idx.iter().map(|&a| rhs[a]).collect();
        let (_, sse) = nnls_gram(&sub, &r, p.uu);
        if sse < best.1 {
            best = (combo.clone(), sse);
        }
        if !next_combination(&mut combo, g) {
            break;
        }
    }
    // Local refinement in log τ.
    let start: Vec<f64> = best.0.iter().map(|&i| grid[i].ln()).collect();
    let step = (ln_tau.1 - ln_tau.0) / (g - 1) as f64;
    let mut simplex = vec![start.clone()];
    for k in 0..settings.terms {
        let mut v = start.clone();
        v[k] += if v[k] + step <= ln_tau.1 { step } else { -step };
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-24)
        .map_err(|e| AfmError::InvalidInput(e.to_string()))?;
    let res = Executor::new(p, solver)
        .configure(|s| s.max_iters(2000))
        .run()
        .map_err(|e| AfmError::NotConverged {
            fit: "creep",
            detail: e.to_string(),
            hint: "check the creep segment and the tip radius",
        })?;
    let ln_best = res.state().get_best_param().cloned().unwrap_or(start);
    let p = res
        .problem
        .problem
        .as_ref()
        .ok_or_else(|| AfmError::NotConverged {
            fit: "creep",
            detail: "the optimiser returned no problem".into(),
            hint: "report this",
        })?;
    let mut taus: Vec<f64> = ln_best
        .iter()
        .map(|x| x.clamp(ln_tau.0, ln_tau.1).exp())
        .collect();
    taus.sort_by(f64::total_cmp);
    let (x, sse) = p.solve(&taus);
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

/// Advance `c` (strictly increasing indices below `n`) to the next combination in
/// lexicographic order; false after the last.
fn next_combination(c: &mut [usize], n: usize) -> bool {
    let k = c.len();
    for i in (0..k).rev() {
        if c[i] < n - k + i {
            c[i] += 1;
            for j in i + 1..k {
                c[j] = c[j - 1] + 1;
            }
            return true;
        }
    }
    false
}
