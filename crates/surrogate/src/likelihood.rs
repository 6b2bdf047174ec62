//! The concentrated likelihood objective of DACE (Lophaven et al. 2002,
//! eqs. 2.24–2.28, 3.1): for given θ,
//!
//! `R = C Cᵀ`, `F̃ = C⁻¹F = QG`, `Ỹ = C⁻¹Y`, `β = G⁻¹QᵀỸ`, `ρ = Ỹ − F̃β`,
//! `σ²_j = |ρ_j|²/n`, `ψ(θ) = |R|^{1/n} Σ_j σ²_j`.
//!
//! Cost per evaluation: building R (n² d / 2 kernel calls), its Cholesky
//! factorisation (n³/3 flops) and the triangular solve with q right-hand
//! sides (n² q flops). The gradient of ln ψ additionally needs R⁻¹
//! (≈ 2n³/3 flops) and ΓΓᵀ (n² q).

use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Accum, Mat, MatRef, Par, Side};

use crate::correlation::Correlation;
use crate::error::{Result, SurrogateError};
use crate::regression::Regression;

/// Inputs of the θ problem: normalised sites and outputs, models, nugget.
pub(crate) struct Problem<'a> {
    /// Normalised design sites, n × d.
    pub s: MatRef<'a, f64>,
    /// Normalised outputs, n × q.
    pub y: MatRef<'a, f64>,
    /// Regression matrix, n × p.
    pub f: Mat<f64>,
    pub corr: Correlation,
    /// Added to the unit diagonal of R (DACE's (10+n)·eps plus any nugget).
    pub diag_add: f64,
    pairs: Vec<(usize, usize)>,
    /// Pair differences, row-major npairs × d.
    diffs: Vec<f64>,
    pub par: Par,
}

/// Everything DACE's `objfunc` returns for one θ.
pub(crate) struct Factors {
    /// Lower Cholesky factor of R.
    pub c: Mat<f64>,
    /// C⁻¹F, n × p.
    pub ft: Mat<f64>,
    /// Upper-triangular factor of F̃ = QG, p × p.
    pub g: Mat<f64>,
    /// β, p × q.
    pub beta: Mat<f64>,
    /// ρ = Ỹ − F̃β, n × q.
    pub rho: Mat<f64>,
    /// σ²_j in normalised units.
    pub sigma2: Vec<f64>,
    /// ψ(θ).
    pub psi: f64,
}

/// Outcome of one objective evaluation.
pub(crate) enum Eval {
    Ok(Box<Factors>),
    /// R not positive definite or F̃ too ill conditioned: ψ = ∞ (as DACE).
    Infeasible,
}

impl<'a> Problem<'a> {
    pub fn new(
        s: MatRef<'a, f64>,
        y: MatRef<'a, f64>,
        regression: Regression,
        corr: Correlation,
        nugget: f64,
    ) -> Self {
        let (n, d) = (s.nrows(), s.ncols());
        let p = regression.n_terms(d);
        let mut f = Mat::<f64>::zeros(n, p);
        let mut xi = vec![0.0; d];
        let mut fi = vec![0.0; p];
        for i in 0..n {
            for k in 0..d {
                xi[k] = s[(i, k)];
            }
            regression.eval(&xi, &mut fi);
            for j in 0..p {
                f[(i, j)] = fi[j];
            }
        }
        let mut pairs = Vec::with_capacity(n * (n.saturating_sub(1)) / 2);
        let mut diffs = Vec::with_capacity(pairs.capacity() * d);
        for j in 0..n {
            for i in j + 1..n {
                pairs.push((i, j));
                for k in 0..d {
                    diffs.push(s[(i, k)] - s[(j, k)]);
                }
            }
        }
        let diag_add = (10.0 + n as f64) * f64::EPSILON + nugget;
        Problem {
            s,
            y,
            f,
            corr,
            diag_add,
            pairs,
            diffs,
            par: Par::rayon(0),
        }
    }

    fn dim(&self) -> usize {
        self.s.ncols()
    }

    /// Correlation matrix R(θ) (full, symmetric) with the diagonal addition.
    pub fn corr_matrix(&self, theta: &[f64]) -> Mat<f64> {
        let n = self.s.nrows();
        let d = self.dim();
        let mut r = Mat::<f64>::zeros(n, n);
        for (idx, &(i, j)) in self.pairs.iter().enumerate() {
            let v = self.corr.value(theta, &self.diffs[idx * d..(idx + 1) * d]);
            r[(i, j)] = v;
            r[(j, i)] = v;
        }
        for i in 0..n {
            r[(i, i)] = 1.0 + self.diag_add;
        }
        r
    }

    /// DACE's `objfunc`: ψ(θ) and the factors at θ.
    pub fn eval(&self, theta: &[f64]) -> Result<Eval> {
        let n = self.s.nrows();
        let r = self.corr_matrix(theta);
        let Ok(llt) = r.llt(Side::Lower) else {
            return Ok(Eval::Infeasible);
        };
        let c = llt.L().to_owned();
        drop(r);
        let mut ft = self.f.clone();
        solve_lower_triangular_in_place(c.as_ref(), ft.as_mut(), self.par);
        let g = r_factor(ft.as_ref());
        if rcond_upper(g.as_ref()) < 1e-10 {
            let gf = r_factor(self.f.as_ref());
            let rc = rcond_upper(gf.as_ref());
            if rc < 1e-15 {
                return Err(SurrogateError::IllConditionedRegression { rcond: rc });
            }
            return Ok(Eval::Infeasible);
        }
        let mut yt = self.y.to_owned();
        solve_lower_triangular_in_place(c.as_ref(), yt.as_mut(), self.par);
        // β = G⁻¹ QᵀỸ with QᵀỸ = G⁻ᵀ F̃ᵀỸ (Q never formed).
        let mut beta = ft.transpose() * &yt;
        solve_lower_triangular_in_place(g.transpose(), beta.as_mut(), Par::Seq);
        solve_upper_triangular_in_place(g.as_ref(), beta.as_mut(), Par::Seq);
        let mut rho = yt;
        faer::linalg::matmul::matmul(
            rho.as_mut(),
            Accum::Add,
            ft.as_ref(),
            beta.as_ref(),
            -1.0,
            self.par,
        );
        let q = rho.ncols();
        let sigma2: Vec<f64> = (0..q)
            .map(|j| rho.col(j).iter().map(|v| v * v).sum::<f64>() / n as f64)
            .collect();
        let log_det_n: f64 = (0..n).map(|i| c[(i, i)].ln()).sum::<f64>() * 2.0 / n as f64;
        let psi = sigma2.iter().sum::<f64>() * log_det_n.exp();
        if !psi.is_finite() {
            return Ok(Eval::Infeasible);
        }
        Ok(Eval::Ok(Box::new(Factors {
            c,
            ft,
            g,
            beta,
            rho,
            sigma2,
            psi,
        })))
    }

    /// Gradient of ln ψ with respect to ln θ at the factors of `eval(theta)`.
    ///
    /// With W = R⁻¹/n − ΓΓᵀ/(n Σσ²), Γ = C⁻ᵀρ (β stationary, so its
    /// variation drops out): ∂lnψ/∂θ_k = Σ_il W_il ∂R_il/∂θ_k.
    pub fn grad_log_psi(&self, theta: &[f64], fac: &Factors) -> Vec<f64> {
        let n = self.s.nrows();
        let d = self.dim();
        let nt = theta.len();
        let mut cinv = Mat::<f64>::identity(n, n);
        solve_lower_triangular_in_place(fac.c.as_ref(), cinv.as_mut(), self.par);
        let mut w = Mat::<f64>::zeros(n, n);
        faer::linalg::matmul::matmul(
            w.as_mut(),
            Accum::Replace,
            cinv.transpose(),
            cinv.as_ref(),
            1.0 / n as f64,
            self.par,
        );
        let mut gamma = fac.rho.clone();
        solve_upper_triangular_in_place(fac.c.transpose(), gamma.as_mut(), self.par);
        let s_tot: f64 = fac.sigma2.iter().sum::<f64>() * n as f64;
        faer::linalg::matmul::matmul(
            w.as_mut(),
            Accum::Add,
            gamma.as_ref(),
            gamma.transpose(),
            -1.0 / s_tot,
            self.par,
        );
        let mut grad = vec![0.0; nt];
        let mut gk = vec![0.0; nt];
        for (idx, &(i, j)) in self.pairs.iter().enumerate() {
            self.corr
                .value_and_grad_theta(theta, &self.diffs[idx * d..(idx + 1) * d], &mut gk);
            let wij = w[(i, j)] + w[(j, i)];
            for k in 0..nt {
                grad[k] += wij * gk[k];
            }
        }
        for k in 0..nt {
            grad[k] *= theta[k];
        }
        grad
    }
}

/// R factor of a thin QR (p × p upper triangular).
pub(crate) fn r_factor(a: MatRef<'_, f64>) -> Mat<f64> {
    let p = a.ncols();
    let qr = a.qr();
    let r = qr.thin_R();
    Mat::from_fn(p, p, |i, j| if i <= j { r[(i, j)] } else { 0.0 })
}

/// Reciprocal 1-norm condition number of an upper-triangular matrix
/// (exact, by inversion; p is small).
pub(crate) fn rcond_upper(g: MatRef<'_, f64>) -> f64 {
    let p = g.nrows();
    if (0..p).any(|i| g[(i, i)] == 0.0 || !g[(i, i)].is_finite()) {
        return 0.0;
    }
    let mut inv = Mat::<f64>::identity(p, p);
    solve_upper_triangular_in_place(g, inv.as_mut(), Par::Seq);
    let norm1 = |m: MatRef<'_, f64>| {
        (0..p)
            .map(|j| (0..p).map(|i| m[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let r = 1.0 / (norm1(g) * norm1(inv.as_ref()));
    if r.is_finite() { r } else { 0.0 }
}
