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
    pub regression: Regression,
    /// Added to the unit diagonal of R (DACE's (10+n)·eps plus any nugget).
    pub diag_add: f64,
    /// Treat θ as infeasible when the lower bound (max C_ii / min C_ii)² of
    /// cond(R) exceeds this (∞: DACE behaviour, any positive definite R).
    pub max_cond: f64,
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

/// C, F̃, G of [`Problem::factor`].
pub(crate) type RFactors = (Mat<f64>, Mat<f64>, Mat<f64>);

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
            regression,
            diag_add,
            max_cond: f64::INFINITY,
            pairs,
            diffs,
            par: Par::rayon(0),
        }
    }

    fn dim(&self) -> usize {
        self.s.ncols()
    }

    /// Correlation matrix R(θ) (full, symmetric) with the diagonal addition.
    /// The n(n−1)/2 kernel values are computed in parallel.
    pub fn corr_matrix(&self, theta: &[f64]) -> Mat<f64> {
        use rayon::prelude::*;
        let n = self.s.nrows();
        let d = self.dim();
        let vals: Vec<f64> = self
            .diffs
            .par_chunks(d)
            .map(|dx| self.corr.value(theta, dx))
            .collect();
        let mut r = Mat::<f64>::zeros(n, n);
        for (&(i, j), &v) in self.pairs.iter().zip(&vals) {
            r[(i, j)] = v;
            r[(j, i)] = v;
        }
        for i in 0..n {
            r[(i, i)] = 1.0 + self.diag_add;
        }
        r
    }

    /// The factors of R(θ) and F that do not depend on the outputs:
    /// `R = C Cᵀ`, `F̃ = C⁻¹F = QG` (C, F̃, G); `None` when R is not
    /// positive definite, too ill conditioned (`max_cond`) or F̃ is.
    /// [`Problem::eval`] and the Kriging variance of a loaded model (which
    /// does not store them) share it.
    pub fn factor(&self, theta: &[f64]) -> Result<Option<RFactors>> {
        let n = self.s.nrows();
        let r = self.corr_matrix(theta);
        let Ok(llt) = r.llt(Side::Lower) else {
            return Ok(None);
        };
        let c = llt.L().to_owned();
        drop(r);
        if self.max_cond.is_finite() {
            let d = (0..n).map(|i| c[(i, i)]);
            let (lo, hi) = d.fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
            if (hi / lo).powi(2) > self.max_cond {
                return Ok(None);
            }
        }
        let mut ft = self.f.clone();
        solve_lower_triangular_in_place(c.as_ref(), ft.as_mut(), self.par);
        let g = r_factor(ft.as_ref());
        if rcond_upper(g.as_ref()) < 1e-10 {
            let gf = r_factor(self.f.as_ref());
            let rc = rcond_upper(gf.as_ref());
            if rc < 1e-15 {
                return Err(SurrogateError::IllConditionedRegression { rcond: rc });
            }
            return Ok(None);
        }
        Ok(Some((c, ft, g)))
    }

    /// DACE's `objfunc`: ψ(θ) and the factors at θ.
    pub fn eval(&self, theta: &[f64]) -> Result<Eval> {
        let n = self.s.nrows();
        let Some((c, ft, g)) = self.factor(theta)? else {
            return Ok(Eval::Infeasible);
        };
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
    /// variation drops out): ∂lnψ/∂θ_k = Σ_il W_il ∂R_il/∂θ_k. Only the
    /// strict lower triangle of W is needed (the diagonal of R does not
    /// depend on θ): R⁻¹ from C by a triangular inverse and a triangular
    /// product (≈ n³/3 + n³/3 flops), ΓΓᵀ by a triangular product (n² q),
    /// then a parallel loop over the n(n−1)/2 pairs (kernel derivatives).
    pub fn grad_log_psi(&self, theta: &[f64], fac: &Factors) -> Vec<f64> {
        use faer::linalg::matmul::triangular::{BlockStructure, matmul as tri_matmul};
        use rayon::prelude::*;
        let n = self.s.nrows();
        let d = self.dim();
        let nt = theta.len();
        // w ← lower(R⁻¹).
        let mut w = Mat::<f64>::zeros(n, n);
        let mut mem = faer::dyn_stack::MemBuffer::new(
            faer::linalg::cholesky::llt::inverse::inverse_scratch::<f64>(n, self.par),
        );
        let stack = faer::dyn_stack::MemStack::new(&mut mem);
        faer::linalg::cholesky::llt::inverse::inverse(w.as_mut(), fac.c.as_ref(), self.par, stack);
        let mut gamma = fac.rho.clone();
        solve_upper_triangular_in_place(fac.c.transpose(), gamma.as_mut(), self.par);
        let s_tot: f64 = fac.sigma2.iter().sum::<f64>() * n as f64;
        // w ← lower(R⁻¹ − (n/S) ΓΓᵀ) = n·W.
        tri_matmul(
            w.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Add,
            gamma.as_ref(),
            BlockStructure::Rectangular,
            gamma.transpose(),
            BlockStructure::Rectangular,
            -(n as f64) / s_tot,
            self.par,
        );
        let w = &w;
        let chunk = 4096;
        let grad = self
            .pairs
            .par_chunks(chunk)
            .enumerate()
            .map(|(c, pairs)| {
                let mut acc = vec![0.0; nt];
                let mut gk = vec![0.0; nt];
                for (l, &(i, j)) in pairs.iter().enumerate() {
                    let idx = c * chunk + l;
                    self.corr.value_and_grad_theta(
                        theta,
                        &self.diffs[idx * d..(idx + 1) * d],
                        &mut gk,
                    );
                    let wij = w[(i, j)];
                    for k in 0..nt {
                        acc[k] += wij * gk[k];
                    }
                }
                acc
            })
            .reduce(
                || vec![0.0; nt],
                |mut a, b| {
                    a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                    a
                },
            );
        // Both triangles of the symmetric W, its 1/n, and the chain rule
        // ∂/∂ln θ_k = θ_k ∂/∂θ_k.
        (0..nt)
            .map(|k| 2.0 * grad[k] * theta[k] / n as f64)
            .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn problem_data() -> (Mat<f64>, Mat<f64>) {
        // Deterministic scattered sites in [−1.5, 1.5]² and 3 smooth outputs.
        let n = 30;
        let s = Mat::from_fn(n, 2, |i, k| {
            let v = ((i * (7 + 5 * k) + 3 * k) % n) as f64 / n as f64;
            3.0 * (v + 0.013 * i as f64 % 0.03) - 1.5
        });
        let y = Mat::from_fn(n, 3, |i, j| {
            let (a, b) = (s[(i, 0)], s[(i, 1)]);
            match j {
                0 => (2.0 * a).sin() + b * b,
                1 => a * b - 0.3 * b,
                _ => (a + b).cos(),
            }
        });
        (s, y)
    }

    #[test]
    fn log_likelihood_gradient_matches_central_differences() {
        let (s, y) = problem_data();
        for (corr, theta) in [
            (Correlation::Gauss, vec![0.7, 1.9]),
            (Correlation::Expg, vec![0.9, 1.4, 1.7]),
            (Correlation::Exp, vec![0.5, 0.8]),
        ] {
            let prob = Problem::new(s.as_ref(), y.as_ref(), Regression::Poly1, corr, 1e-10);
            let Eval::Ok(fac) = prob.eval(&theta).unwrap() else {
                panic!("infeasible")
            };
            let g = prob.grad_log_psi(&theta, &fac);
            for k in 0..theta.len() {
                let h: f64 = 1e-5;
                let (mut tp, mut tm) = (theta.clone(), theta.clone());
                tp[k] *= h.exp();
                tm[k] *= (-h).exp();
                let f = |t: &[f64]| match prob.eval(t).unwrap() {
                    Eval::Ok(f) => f.psi.ln(),
                    Eval::Infeasible => f64::NAN,
                };
                let fd = (f(&tp) - f(&tm)) / (2.0 * h);
                assert!(
                    (fd - g[k]).abs() < 1e-6 * (1.0 + fd.abs()),
                    "{corr:?} θ{k}: fd {fd} vs {}",
                    g[k]
                );
            }
        }
    }

    #[test]
    fn psi_is_invariant_under_an_orthogonal_rotation_of_the_outputs() {
        let (s, y) = problem_data();
        // Rotation by a Householder reflection H = I − 2vvᵀ/vᵀv.
        let v = [0.3, -1.1, 0.7];
        let vv: f64 = v.iter().map(|a| a * a).sum();
        let h = Mat::from_fn(
            3,
            3,
            |i, j| if i == j { 1.0 } else { 0.0 } - 2.0 * v[i] * v[j] / vv,
        );
        let yr = &y * &h;
        let theta = [1.1, 0.6];
        let p1 = Problem::new(
            s.as_ref(),
            y.as_ref(),
            Regression::Poly1,
            Correlation::Gauss,
            0.0,
        );
        let p2 = Problem::new(
            s.as_ref(),
            yr.as_ref(),
            Regression::Poly1,
            Correlation::Gauss,
            0.0,
        );
        let (Eval::Ok(a), Eval::Ok(b)) = (p1.eval(&theta).unwrap(), p2.eval(&theta).unwrap())
        else {
            panic!("infeasible")
        };
        assert!(
            (a.psi / b.psi - 1.0).abs() < 1e-12,
            "{} vs {}",
            a.psi,
            b.psi
        );
    }
}
