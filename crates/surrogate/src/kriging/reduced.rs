//! The predictor in its reduced (output-space) form, for fitters whose cost
//! must not grow with n·m (thesis §5.4.1: one fit per cell on a surrogate
//! with N ≈ 970 runs and m ≈ 5000 output times).
//!
//! Every linear-output model (no `log_outputs`) predicts
//! `ŷ(x) = s(x)·(μ + σ ⊙ V z(x)) = A c(x)` with
//! `A = [μ, diag(σ)·V]` (m × (q + 1), fixed) and `c(x) = s(x)·[1; z(x)]`
//! (q + 1 values), where `z = βᵀf(x) + γᵀr(x)` are the q kriged outputs
//! (PC scores with a PCA, V = I without), μ, σ the output means and
//! deviations and s(x) the [`OutputScale`](super::OutputScale) (1 without).
//! c(x) and ∂c/∂x cost O(n·q·d); A is shared by every evaluation.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use rayon::prelude::*;

use super::KrigingModel;
use crate::correlation::{Correlation, exp_neg};
use crate::error::{Result, SurrogateError};

impl KrigingModel {
    /// Number of reduced coordinates q + 1 of [`KrigingModel::output_coordinates`].
    pub fn n_output_coordinates(&self) -> usize {
        self.n_kriged() + 1
    }

    /// The fixed output map A = [μ, diag(σ)·V] (m × (q + 1), column-major)
    /// with ŷ(x) = A c(x) (DACE report eq. 2.16 with the output
    /// normalisation, PCA rotation V and output scaling written out).
    /// Without a PCA, V = I (q = m: then A has m + 1 columns and no
    /// reduction is gained).
    ///
    /// # Errors
    /// [`SurrogateError::InvalidSettings`] for a model with `log_outputs`
    /// (its predictor exp(·) is not linear in c).
    pub fn output_map(&self) -> Result<Vec<f64>> {
        self.check_linear_outputs()?;
        let (m, q) = (self.n_outputs, self.n_kriged());
        let mut a = vec![0.0; m * (q + 1)];
        a[..m].copy_from_slice(&self.y_mean);
        match &self.pca {
            Some(pca) => {
                for k in 0..q {
                    let v = &pca.basis[k * m..(k + 1) * m];
                    let col = &mut a[(k + 1) * m..(k + 2) * m];
                    for j in 0..m {
                        col[j] = self.y_std[j] * v[j];
                    }
                }
            }
            None => {
                for j in 0..m {
                    a[(j + 1) * m + j] = self.y_std[j];
                }
            }
        }
        Ok(a)
    }

    /// Reduced coordinates c(x) = s(x)·[1; z(x)] of the prediction
    /// (ŷ = A c, see [`KrigingModel::output_map`]) and ∂c/∂x with respect
    /// to the caller's x (log inputs and normalisation included),
    /// row-major (q + 1) × d. Cost O(n·q·d) — independent of m.
    ///
    /// # Errors
    /// `x` of the wrong length or not finite, a log input ≤ 0, s(x) ≤ 0,
    /// or a model with `log_outputs`.
    pub fn output_coordinates(&self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>)> {
        self.coordinates_at(x, true)
    }

    /// c(x) of [`KrigingModel::output_coordinates`] without the derivative:
    /// one correlation column instead of d + 1, for value-only evaluations
    /// (line-search trials, reported misfits).
    ///
    /// # Errors
    /// As [`KrigingModel::output_coordinates`].
    pub fn output_coordinate_values(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self.coordinates_at(x, false)?.0)
    }

    /// c(x) and, if `derivatives`, ∂c/∂x (else an empty vector).
    fn coordinates_at(&self, x: &[f64], derivatives: bool) -> Result<(Vec<f64>, Vec<f64>)> {
        self.check_linear_outputs()?;
        let xi = self.internal_x(x)?;
        let (n, d, p, q) = (self.n_sites, self.dim, self.p(), self.n_kriged());
        let xn: Vec<f64> = (0..d)
            .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
            .collect();
        let mut f = vec![0.0; p];
        self.regression.eval(&xn, &mut f);
        let mut df = vec![0.0; if derivatives { d * p } else { 0 }];
        if derivatives {
            self.regression.jacobian(&xn, &mut df);
        }
        // M = [r, ∂r/∂xn_1, …, ∂r/∂xn_dd], column-major n × (dd + 1); dd = 0
        // for values only.
        let dd = if derivatives { d } else { 0 };
        let mut rm = vec![0.0; n * (dd + 1)];
        let mut dx = vec![0.0; d];
        let mut g = vec![0.0; d];
        for i in 0..n {
            for k in 0..d {
                dx[k] = xn[k] - self.sites[k * n + i];
            }
            let ri = if self.correlation == Correlation::Gauss || dd == 0 {
                let ri = self.correlation_value(&dx);
                for k in 0..dd {
                    g[k] = -2.0 * self.theta[k] * dx[k] * ri;
                }
                ri
            } else {
                self.correlation.value_and_grad_d(&self.theta, &dx, &mut g)
            };
            rm[i] = ri;
            for k in 0..dd {
                rm[(k + 1) * n + i] = g[k];
            }
        }
        // P = Mᵀγ ((dd + 1) × q): row 0 is γᵀr, row k + 1 is γᵀ∂r/∂xn_k.
        let mut pm = Mat::<f64>::zeros(dd + 1, q);
        matmul(
            pm.as_mut(),
            Accum::Replace,
            MatRef::from_column_major_slice(&rm, n, dd + 1).transpose(),
            MatRef::from_column_major_slice(&self.gamma, n, q),
            1.0,
            Par::Seq,
        );
        // ∂xn_k/∂x_k.
        let scale: Vec<f64> = (0..dd)
            .map(|k| self.dinternal(x, k) / self.x_std[k])
            .collect();
        let mut c = vec![0.0; q + 1];
        let mut dc = vec![0.0; (q + 1) * dd];
        c[0] = 1.0;
        for j in 0..q {
            let b = &self.beta[j * p..(j + 1) * p];
            c[j + 1] = dot(b, &f) + pm[(0, j)];
            for k in 0..dd {
                let dz = dot(&df[k * p..(k + 1) * p], b) + pm[(k + 1, j)];
                dc[(j + 1) * d + k] = dz * scale[k];
            }
        }
        if let Some(sc) = self.output_scale {
            let s = sc.check(x, "the prediction point")?;
            let (_, ds) = sc.eval(x);
            let kk = sc.input();
            for j in 0..=q {
                if derivatives {
                    for k in 0..d {
                        dc[j * d + k] *= s;
                    }
                    dc[j * d + kk] += ds * c[j];
                }
                c[j] *= s;
            }
        }
        Ok((c, dc))
    }

    /// c(x) of [`KrigingModel::output_coordinate_values`] and v(x) of
    /// [`KrigingModel::mse_scale`] at many points at once (issue 17: the
    /// posterior sampler proposes a batch of walkers per step). Each
    /// point's correlation column r(x) is computed once and shared by the
    /// predictor (z = βᵀf + γᵀr) and the variance (rt = C⁻¹r), and the
    /// B columns are solved together: one multi-right-hand-side triangular
    /// solve C⁻¹[r(x_1) … r(x_B)] streams the n × n factor once for the
    /// batch instead of once per point (the O(n²) part of every likelihood
    /// evaluation; same flops, cache-bound instead of memory-bound).
    ///
    /// With `threads` > 1 the batch is cut into up to `threads` contiguous
    /// parts of at least 2 points each, solved on the rayon pool (for one
    /// posterior run alone; a cohort already runs one cell per core and
    /// passes 1). Each point's values are bitwise the same for every
    /// `threads`: faer's multi-column products and triangular solve give a
    /// column the same arithmetic in any batch of ≥ 2 columns (a single
    /// column takes a matrix–vector path with another summation order, so
    /// no part has one point; pinned by the test
    /// `batch_values_do_not_depend_on_the_thread_count`).
    ///
    /// # Errors
    /// As [`KrigingModel::output_coordinates`] and
    /// [`KrigingModel::mse_scale`] for any point of the batch.
    pub fn coordinates_and_mse_scales(
        &self,
        xs: &[Vec<f64>],
        threads: usize,
    ) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
        let mut coords = Vec::with_capacity(xs.len());
        let mut scales = Vec::with_capacity(xs.len());
        for (c, v) in in_parts(xs, threads, |part| {
            self.batch_coordinates_and_mse_scales(part)
        })? {
            coords.extend(c);
            scales.extend(v);
        }
        Ok((coords, scales))
    }

    /// c(x) of [`KrigingModel::output_coordinate_values`] at many points at
    /// once: the correlation columns and one product Z = βᵀF + γᵀR for the
    /// batch, O(n·(d + q)) per point, without the variance's O(n²) solve
    /// (the screening stage of the posterior sampler's delayed acceptance,
    /// issue 17). The values are those of
    /// [`KrigingModel::coordinates_and_mse_scales`] bit for bit, for any
    /// `threads` (split as there). A point alone is computed as two copies
    /// of it, as there: faer's product of one column sums in another
    /// order, and the screen must be one function of the point whatever
    /// batch it comes in.
    ///
    /// # Errors
    /// As [`KrigingModel::output_coordinates`] for any point of the batch.
    pub fn output_coordinate_batch(
        &self,
        xs: &[Vec<f64>],
        threads: usize,
    ) -> Result<Vec<Vec<f64>>> {
        Ok(in_parts(xs, threads, |part| self.batch_coordinates(part))?
            .into_iter()
            .flatten()
            .collect())
    }

    /// [`KrigingModel::output_coordinate_batch`] of one part, on the
    /// calling thread.
    fn batch_coordinates(&self, xs: &[Vec<f64>]) -> Result<Vec<Vec<f64>>> {
        self.check_linear_outputs()?;
        if let [x] = xs {
            let mut c = self.batch_coordinates(&[x.clone(), x.clone()])?;
            c.truncate(1);
            return Ok(c);
        }
        let (_, _, zm) = self.batch_columns(xs)?;
        Ok(self.scaled_coordinates(xs, &zm)?.0)
    }

    /// [`KrigingModel::coordinates_and_mse_scales`] of one part, on the
    /// calling thread. A part of one point is solved as two copies of it:
    /// faer's single-column solve sums in another order, and a point's
    /// values must not depend on the batch it came in (the sampler's
    /// batches shrink to one point under delayed acceptance).
    fn batch_coordinates_and_mse_scales(
        &self,
        xs: &[Vec<f64>],
    ) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
        self.check_linear_outputs()?;
        self.check_linear_for_variance()?;
        if let [x] = xs {
            let (mut c, mut v) = self.batch_coordinates_and_mse_scales(&[x.clone(), x.clone()])?;
            c.truncate(1);
            v.truncate(1);
            return Ok((c, v));
        }
        let (rm, fm, zm) = self.batch_columns(xs)?;
        let phi = self.mse_factors_of(rm, &fm)?;
        let (coords, scales) = self.scaled_coordinates(xs, &zm)?;
        Ok((
            coords,
            scales.iter().zip(phi).map(|(s, p)| s * s * p).collect(),
        ))
    }

    /// The batch's correlation columns R (n × B), regressors F (p × B)
    /// and kriged outputs Z = βᵀF + γᵀR (q × B).
    fn batch_columns(&self, xs: &[Vec<f64>]) -> Result<(Mat<f64>, Mat<f64>, Mat<f64>)> {
        let (n, d, p, q) = (self.n_sites, self.dim, self.p(), self.n_kriged());
        let b = xs.len();
        let mut rm = Mat::<f64>::zeros(n, b);
        let mut fm = Mat::<f64>::zeros(p, b);
        let mut f = vec![0.0; p];
        let mut dx = vec![0.0; d];
        for (j, x) in xs.iter().enumerate() {
            let xi = self.internal_x(x)?;
            let xn: Vec<f64> = (0..d)
                .map(|k| (xi[k] - self.x_mean[k]) / self.x_std[k])
                .collect();
            self.regression.eval(&xn, &mut f);
            for k in 0..p {
                fm[(k, j)] = f[k];
            }
            self.correlation_column(
                &xn,
                rm.col_mut(j)
                    .try_as_col_major_mut()
                    .expect("contiguous")
                    .as_slice_mut(),
                &mut dx,
            );
        }
        let mut zm = Mat::<f64>::zeros(q, b);
        matmul(
            zm.as_mut(),
            Accum::Replace,
            MatRef::from_column_major_slice(&self.gamma, n, q).transpose(),
            rm.as_ref(),
            1.0,
            Par::Seq,
        );
        matmul(
            zm.as_mut(),
            Accum::Add,
            MatRef::from_column_major_slice(&self.beta, p, q).transpose(),
            fm.as_ref(),
            1.0,
            Par::Seq,
        );
        Ok((rm, fm, zm))
    }

    /// c(x) = s(x)·[1; z(x)] of each point from the batch's Z, and each
    /// point's output scale s(x) (1 without).
    fn scaled_coordinates(
        &self,
        xs: &[Vec<f64>],
        zm: &Mat<f64>,
    ) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
        let q = self.n_kriged();
        let mut coords = Vec::with_capacity(xs.len());
        let mut scales = Vec::with_capacity(xs.len());
        for (j, x) in xs.iter().enumerate() {
            let s = match self.output_scale {
                Some(sc) => sc.check(x, "the prediction point")?,
                None => 1.0,
            };
            let mut c = Vec::with_capacity(q + 1);
            c.push(s);
            c.extend((0..q).map(|k| s * zm[(k, j)]));
            coords.push(c);
            scales.push(s);
        }
        Ok((coords, scales))
    }

    /// The correlation column r_i = R(xn − s_i) of a normalised point
    /// against every site (DACE report eq. 2.15), into `out` (n values;
    /// `dx` is d values of scratch). For `gauss` the exponent
    /// Σ_k θ_k (xn_k − s_ik)² is accumulated dimension by dimension over
    /// all sites (contiguous in the column-major sites, so vectorised at
    /// the CPU's widest width: [`GaussColumn`]) in
    /// the order of [`KrigingModel::correlation_value`]: the same value bit
    /// for bit, at a fraction of its instructions. The first dimension's
    /// term is stored, not added to a zeroed column (0 + a = a exactly for
    /// a ≥ 0: the same sums without a pass that clears `out`).
    pub(super) fn correlation_column(&self, xn: &[f64], out: &mut [f64], dx: &mut [f64]) {
        let n = self.n_sites;
        if self.correlation == Correlation::Gauss {
            pulp::Arch::new().dispatch(GaussColumn {
                theta: &self.theta,
                sites: &self.sites[..n * xn.len()],
                xn,
                out,
            });
        } else {
            for (i, r) in out.iter_mut().enumerate() {
                for (k, v) in dx.iter_mut().enumerate() {
                    *v = xn[k] - self.sites[k * n + i];
                }
                *r = self.correlation_value(dx);
            }
        }
    }

    /// r(d) of the model's correlation at a normalised difference d; for
    /// `gauss` exp(−Σ θ_k d_k²) with one exp instead of one per dimension
    /// (the exp of [`KrigingModel::correlation_column`]).
    pub(super) fn correlation_value(&self, dx: &[f64]) -> f64 {
        if self.correlation == Correlation::Gauss {
            exp_neg(
                (0..dx.len())
                    .map(|k| self.theta[k] * dx[k] * dx[k])
                    .sum::<f64>(),
            )
        } else {
            self.correlation.value(&self.theta, dx)
        }
    }

    fn check_linear_outputs(&self) -> Result<()> {
        if self.log_outputs {
            Err(SurrogateError::InvalidSettings(
                "the model predicts exp(kriged ln y): it has no linear output map (refit \
                 without --log-outputs to use the reduced form)"
                    .into(),
            ))
        } else {
            Ok(())
        }
    }
}

/// `f` of `xs` cut into up to `threads` contiguous parts of at least 2
/// points each (balanced: ⌊B/parts⌋ or one more), run on the rayon pool,
/// the results in the parts' order; one part on the calling thread.
fn in_parts<T: Send>(
    xs: &[Vec<f64>],
    threads: usize,
    f: impl Fn(&[Vec<f64>]) -> Result<T> + Sync,
) -> Result<Vec<T>> {
    let parts = threads.min(xs.len() / 2);
    if parts <= 1 {
        return Ok(vec![f(xs)?]);
    }
    let (base, extra) = (xs.len() / parts, xs.len() % parts);
    (0..parts)
        .into_par_iter()
        .map(|j| {
            let start = j * base + j.min(extra);
            f(&xs[start..start + base + usize::from(j < extra)])
        })
        .collect()
}

/// The Gaussian correlation column of [`KrigingModel::correlation_column`]
/// as a `pulp::WithSimd` operation: its body is inlined into pulp's
/// `#[target_feature]` entry points, so the sums over sites and
/// [`exp_neg`] are vectorised at the CPU's widest width (AVX2: 4 lanes;
/// the baseline build has 2). Rust never fuses `a * b + c`, so every
/// width gives the same bits.
struct GaussColumn<'a> {
    theta: &'a [f64],
    /// Column-major sites, one block of n per input dimension.
    sites: &'a [f64],
    xn: &'a [f64],
    out: &'a mut [f64],
}

impl pulp::WithSimd for GaussColumn<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self {
            theta,
            sites,
            xn,
            out,
        } = self;
        let n = out.len();
        for (k, &xk) in xn.iter().enumerate() {
            let (theta, site) = (theta[k], &sites[k * n..(k + 1) * n]);
            if k == 0 {
                for (acc, s) in out.iter_mut().zip(site) {
                    let t = xk - s;
                    *acc = theta * t * t;
                }
                continue;
            }
            for (acc, s) in out.iter_mut().zip(site) {
                let t = xk - s;
                *acc += theta * t * t;
            }
        }
        if xn.is_empty() {
            out.fill(0.0);
        }
        for r in out.iter_mut() {
            *r = exp_neg(*r);
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
