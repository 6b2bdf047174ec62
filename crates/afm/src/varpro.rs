//! Variable projection with a global search over the relaxation (or retardation) times,
//! shared by the Lee–Radok relaxation fit ([`crate::fit_lee_radok`], eq. 5.1) and the
//! creep-compliance fit ([`crate::fit_creep`]).
//!
//! Both models are linear in their moduli (compliances) for given times τₖ:
//! `y ≈ c₀ a + Σₖ cₖ bₖ(τₖ)` with a τ-free column `a` and one column `b(τ)` per term,
//! coefficients c ≥ 0 (G(t) non-increasing, J(t) non-decreasing). For given τ the
//! coefficients are a non-negative least-squares solve (every active set of ≤ 4
//! columns); the τ are searched in log τ within bounds:
//!
//! 1. every combination τ₁ < … < τ_m of a log-spaced grid, from one Gram matrix of all
//!    grid columns (a combination costs a few ≤ 4 × 4 solves);
//! 2. Nelder–Mead in log τ from the best few grid combinations, from τ log-spaced over
//!    the record, and from `random_starts` seeded log-uniform random points;
//! 3. the lowest SSE of all wins (ties: the first start).
//!
//! The objective is the SSE divided by Σy² (scale-free), summed directly (the Gram form
//! `yy − xᵀr` cancels near a perfect fit); outside the bounds the cost of the nearest
//! admissible point times a steep wall.

use argmin::core::{CostFunction, Executor, State, TerminationReason, TerminationStatus};
use argmin::solver::neldermead::NelderMead;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// How the τ are searched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Multistart {
    /// Points of the log τ grid of stage 1 (≥ 4).
    pub grid: usize,
    /// Best distinct grid combinations refined by Nelder–Mead.
    pub grid_starts: usize,
    /// Seeded random starts (log-uniform within the bounds).
    pub random_starts: usize,
    /// Seed of the random starts.
    pub seed: u64,
    /// Nelder–Mead iterations per start.
    pub max_iters: u64,
}

impl Default for Multistart {
    fn default() -> Self {
        Multistart {
            grid: 40,
            grid_starts: 3,
            random_starts: 8,
            seed: 14,
            max_iters: 2000,
        }
    }
}

/// The separable least-squares problem.
pub(crate) struct Separable<'a> {
    /// The τ-free column.
    fixed: Vec<f64>,
    /// The columns of terms with times τ (one per τ, in order).
    columns: &'a (dyn Fn(&[f64]) -> Vec<Vec<f64>> + Sync),
    /// Data.
    y: &'a [f64],
    /// yᵀy, once (every evaluation needs it).
    yy: f64,
    /// Bounds of ln τ.
    ln_tau: (f64, f64),
}

/// One local (or the global) optimum.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Optimum {
    /// τₖ sorted ascending, s.
    pub taus: Vec<f64>,
    /// Coefficients: τ-free column first, then one per τ (same order).
    pub coefs: Vec<f64>,
    /// Sum of squared residuals (units of y²).
    pub sse: f64,
    /// Nelder–Mead iterations of this start.
    pub iterations: u64,
    /// Nelder–Mead met its tolerance.
    pub converged: bool,
    /// Starts run to find it (1 for a local fit).
    pub starts: usize,
}

impl<'a> Separable<'a> {
    /// The problem of fitting `y` by the τ-free column `fixed` and one column per
    /// τ from `columns`, with ln τ within `ln_tau`.
    pub fn new(
        fixed: Vec<f64>,
        columns: &'a (dyn Fn(&[f64]) -> Vec<Vec<f64>> + Sync),
        y: &'a [f64],
        ln_tau: (f64, f64),
    ) -> Self {
        let yy = y.iter().map(|v| v * v).sum();
        Separable {
            fixed,
            columns,
            y,
            yy,
            ln_tau,
        }
    }

    /// Coefficients and SSE (summed directly) of the non-negative fit for `taus`.
    pub fn solve(&self, taus: &[f64]) -> (Vec<f64>, f64) {
        let hereditary = (self.columns)(taus);
        let cols: Vec<&[f64]> = std::iter::once(self.fixed.as_slice())
            .chain(hereditary.iter().map(Vec::as_slice))
            .collect();
        let (gram, rhs) = gram(&cols, self.y);
        let (x, _) = nnls_gram(&gram, &rhs, self.yy);
        let sse = sum_of_squared_residuals(&cols, &x, self.y);
        (x, sse)
    }

    /// Clamp ln τ into the bounds: (sorted τ, squared distance outside).
    fn taus(&self, ln_tau: &[f64]) -> (Vec<f64>, f64) {
        let (lo, hi) = self.ln_tau;
        let mut wall = 0.0;
        let mut taus: Vec<f64> = ln_tau
            .iter()
            .map(|&x| {
                let c = if x.is_nan() { lo } else { x.clamp(lo, hi) };
                wall += if x.is_nan() { 1e6 } else { (x - c).powi(2) };
                c.exp()
            })
            .collect();
        taus.sort_by(f64::total_cmp);
        (taus, wall)
    }

    /// Nelder–Mead in ln τ from `start` (ln τ, one per term).
    pub fn local(&self, start: &[f64], max_iters: u64) -> Optimum {
        let step = 0.1 * (self.ln_tau.1 - self.ln_tau.0).max(1e-3);
        let mut simplex = vec![start.to_vec()];
        for k in 0..start.len() {
            let mut v = start.to_vec();
            v[k] += if v[k] + step <= self.ln_tau.1 {
                step
            } else {
                -step
            };
            simplex.push(v);
        }
        let scale = 1.0 / self.yy.max(f64::MIN_POSITIVE);
        let cost = Cost {
            problem: self,
            scale,
        };
        let run = NelderMead::new(simplex)
            .with_sd_tolerance(1e-24)
            .and_then(|solver| {
                Executor::new(cost, solver)
                    .configure(|s| s.max_iters(max_iters))
                    .run()
            });
        let (best, iterations, converged) = match run {
            Ok(res) => {
                let st = res.state();
                (
                    st.get_best_param()
                        .cloned()
                        .unwrap_or_else(|| start.to_vec()),
                    st.get_iter(),
                    matches!(
                        st.get_termination_status(),
                        TerminationStatus::Terminated(TerminationReason::SolverConverged)
                    ),
                )
            }
            Err(_) => (start.to_vec(), 0, false),
        };
        let (taus, _) = self.taus(&best);
        let (coefs, sse) = self.solve(&taus);
        Optimum {
            taus,
            coefs,
            sse,
            iterations,
            converged,
            starts: 1,
        }
    }

    /// The starts of the global search for `terms` terms (ln τ each), see the module
    /// documentation; `span` = (shortest sampling step, record length), s.
    pub fn starts(&self, terms: usize, opts: &Multistart, span: (f64, f64)) -> Vec<Vec<f64>> {
        let (lo, hi) = self.ln_tau;
        let mut starts = Vec::new();
        // 1. grid combinations from one Gram matrix
        let g = opts.grid.max(4);
        let grid: Vec<f64> = (0..g)
            .map(|i| (lo + (hi - lo) * i as f64 / (g - 1) as f64).exp())
            .collect();
        if terms <= g {
            let hereditary: Vec<Vec<f64>> =
                grid.par_chunks(4).flat_map_iter(self.columns).collect();
            let cols: Vec<&[f64]> = std::iter::once(self.fixed.as_slice())
                .chain(hereditary.iter().map(Vec::as_slice))
                .collect();
            let (gram, rhs) = gram(&cols, self.y);
            let yy = self.yy;
            let mut scored: Vec<(f64, Vec<usize>)> = Vec::new();
            let mut combo: Vec<usize> = (0..terms).collect();
            loop {
                let idx: Vec<usize> = std::iter::once(0)
                    .chain(combo.iter().map(|c| c + 1))
                    .collect();
                let sub: Vec<Vec<f64>> = idx
                    .iter()
                    .map(|&a| idx.iter().map(|&b| gram[a][b]).collect())
                    .collect();
                let r: Vec<f64> = idx.iter().map(|&a| rhs[a]).collect();
                let (_, sse) = nnls_gram(&sub, &r, yy);
                scored.push((sse, combo.clone()));
                if !next_combination(&mut combo, g) {
                    break;
                }
            }
            scored.sort_by(|a, b| a.0.total_cmp(&b.0));
            // distinct: no two picked combinations within one grid step of each other
            let mut picked: Vec<Vec<usize>> = Vec::new();
            for (_, c) in scored {
                if picked.len() >= opts.grid_starts {
                    break;
                }
                let near = picked
                    .iter()
                    .any(|p| p.iter().zip(&c).all(|(a, b)| a.abs_diff(*b) <= 1));
                if !near {
                    picked.push(c);
                }
            }
            starts.extend(
                picked
                    .into_iter()
                    .map(|c| c.iter().map(|&i| grid[i].ln()).collect()),
            );
        }
        // 2. log-spaced over [10 Δt, T/3]
        let (a, b) = (
            (10.0 * span.0).ln().clamp(lo, hi),
            (span.1 / 3.0).ln().clamp(lo, hi),
        );
        starts.push(
            (0..terms)
                .map(|k| a + (b - a) * (k as f64 + 0.5) / terms as f64)
                .collect(),
        );
        // 3. seeded random starts
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        for _ in 0..opts.random_starts {
            starts.push(
                (0..terms)
                    .map(|_| lo + (hi - lo) * rng.random::<f64>())
                    .collect(),
            );
        }
        starts
    }

    /// Nelder–Mead from every start; the lowest SSE (first on ties).
    pub fn best_of(&self, starts: &[Vec<f64>], max_iters: u64) -> Option<Optimum> {
        let results: Vec<Optimum> = starts
            .par_iter()
            .map(|s| self.local(s, max_iters))
            .collect();
        let n = results.len();
        let mut best = results
            .into_iter()
            .filter(|o| o.sse.is_finite())
            .reduce(|a, b| if b.sse < a.sse { b } else { a })?;
        best.starts = n;
        Some(best)
    }
}

struct Cost<'a, 'b> {
    problem: &'a Separable<'b>,
    scale: f64,
}

impl CostFunction for Cost<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        let (taus, wall) = self.problem.taus(p);
        let (_, sse) = self.problem.solve(&taus);
        Ok(sse * self.scale * (1.0 + 1e3 * wall))
    }
}

/// Gram matrix `AᵀA` and `Aᵀy` of the columns of A.
///
/// Every entry is the sum over the samples in order, so it rounds exactly as
/// one dot product at a time. For the few columns of a Nelder–Mead step
/// (≤ 4: the τ-free one and up to three terms) all entries are summed in one
/// pass with their accumulators in registers: their additions overlap instead
/// of waiting on one chain and each sample is read once. This is most of the
/// cost of a fit (a Lee–Radok fit of a real curve evaluates it ≈ 10⁵ times).
fn gram(cols: &[&[f64]], y: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    match cols {
        [a] => gram_one_pass([*a], y),
        [a, b] => gram_one_pass([*a, *b], y),
        [a, b, c] => gram_one_pass([*a, *b, *c], y),
        [a, b, c, d] => gram_one_pass([*a, *b, *c, *d], y),
        _ => {
            let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
            let m = cols.len();
            let mut g = vec![vec![0.0; m]; m];
            for a in 0..m {
                for b in a..m {
                    g[a][b] = dot(cols[a], cols[b]);
                    g[b][a] = g[a][b];
                }
            }
            (g, cols.iter().map(|c| dot(c, y)).collect())
        }
    }
}

/// [`gram`] of `M` columns in one pass (`-0.0` is the empty sum of `Iterator::sum`).
fn gram_one_pass<const M: usize>(cols: [&[f64]; M], y: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let n = cols.iter().map(|c| c.len()).fold(y.len(), usize::min);
    let cols = cols.map(|c| &c[..n]);
    let y = &y[..n];
    let mut g = [[-0.0; M]; M];
    let mut r = [-0.0; M];
    for i in 0..n {
        let v: [f64; M] = std::array::from_fn(|a| cols[a][i]);
        for a in 0..M {
            for b in a..M {
                g[a][b] += v[a] * v[b];
            }
            r[a] += v[a] * y[i];
        }
    }
    let full = (0..M)
        .map(|a| (0..M).map(|b| g[a.min(b)][a.max(b)]).collect())
        .collect();
    (full, r.to_vec())
}

/// Σᵢ (yᵢ − Σₖ xₖ Aᵢₖ)², summed directly (the Gram form `yy − xᵀr` cancels near a
/// perfect fit), in sample order; one pass with the columns in registers for ≤ 4
/// columns, as [`gram`].
fn sum_of_squared_residuals(cols: &[&[f64]], x: &[f64], y: &[f64]) -> f64 {
    match cols {
        [a] => ssr_one_pass([*a], x, y),
        [a, b] => ssr_one_pass([*a, *b], x, y),
        [a, b, c] => ssr_one_pass([*a, *b, *c], x, y),
        [a, b, c, d] => ssr_one_pass([*a, *b, *c, *d], x, y),
        _ => y
            .iter()
            .enumerate()
            .map(|(i, y)| {
                let m: f64 = cols.iter().zip(x).map(|(c, xk)| xk * c[i]).sum();
                (y - m).powi(2)
            })
            .sum(),
    }
}

/// [`sum_of_squared_residuals`] of `M` columns.
fn ssr_one_pass<const M: usize>(cols: [&[f64]; M], x: &[f64], y: &[f64]) -> f64 {
    let n = cols.iter().map(|c| c.len()).fold(y.len(), usize::min);
    let cols = cols.map(|c| &c[..n]);
    let x: [f64; M] = std::array::from_fn(|k| x[k]);
    let mut sum = -0.0;
    for (i, y) in y[..n].iter().enumerate() {
        let mut m = -0.0;
        for k in 0..M {
            m += x[k] * cols[k][i];
        }
        sum += (y - m).powi(2);
    }
    sum
}

/// Non-negative least squares from the Gram matrix `g = AᵀA`, `r = Aᵀy`, `yy = yᵀy`:
/// every active set is tried (≤ 4 unknowns, 15 sets); returns (x, SSE).
pub(crate) fn nnls_gram(g: &[Vec<f64>], r: &[f64], yy: f64) -> (Vec<f64>, f64) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_matches_the_unconstrained_solution_when_it_is_non_negative() {
        // y = 2 a + 3 b exactly
        let a = [1.0, 2.0, 3.0, 4.0];
        let b = [1.0, 0.0, 1.0, 0.0];
        let y: Vec<f64> = a.iter().zip(&b).map(|(p, q)| 2.0 * p + 3.0 * q).collect();
        let (g, r) = gram(&[&a, &b], &y);
        let (x, sse) = nnls_gram(&g, &r, y.iter().map(|v| v * v).sum());
        assert!(
            (x[0] - 2.0).abs() < 1e-12 && (x[1] - 3.0).abs() < 1e-12,
            "{x:?}"
        );
        assert!(sse.abs() < 1e-9);
        // y = a − b = [0, 2, 2, 4]: the non-negative optimum drops b; x₀ = aᵀy/aᵀa = 26/30
        let y: Vec<f64> = a.iter().zip(&b).map(|(p, q)| p - q).collect();
        let (g, r) = gram(&[&a, &b], &y);
        let (x, _) = nnls_gram(&g, &r, y.iter().map(|v| v * v).sum());
        assert_eq!(x[1], 0.0);
        assert!((x[0] - 26.0 / 30.0).abs() < 1e-12, "{x:?}");
    }

    #[test]
    fn one_pass_gram_is_every_dot_product_to_the_bit() {
        // Seeded, irregular columns: the one-pass form must round exactly as
        // the dot products taken one at a time.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 1001;
        let cols: Vec<Vec<f64>> = (0..4)
            .map(|_| (0..n).map(|_| rng.random::<f64>() * 1e-9 - 3e-10).collect())
            .collect();
        let y: Vec<f64> = (0..n).map(|_| rng.random::<f64>()).collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let (g, r) = gram(&refs, &y);
        let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
        for a in 0..4 {
            assert_eq!(r[a].to_bits(), dot(&cols[a], &y).to_bits());
            for b in 0..4 {
                assert_eq!(g[a][b].to_bits(), dot(&cols[a], &cols[b]).to_bits());
            }
        }
    }

    #[test]
    fn combinations_are_enumerated_once_each() {
        let mut c = vec![0, 1, 2];
        let mut n = 1;
        while next_combination(&mut c, 6) {
            n += 1;
        }
        assert_eq!(n, 20); // C(6, 3)
        assert_eq!(c, vec![3, 4, 5]);
    }
}
