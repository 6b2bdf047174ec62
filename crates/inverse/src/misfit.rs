//! The fitting error of eq. 5.3 — RMSE divided by the *range of the
//! measured curve* — with optional per-point (per-segment) weights, summed
//! over several experiments fitted with one parameter set (§4.4.2).
//!
//! For one experiment with data d_j, model y_j(x) and weights w_j ≥ 0:
//! e(x) = √(Σ w_j (y_j − d_j)² / Σ w_j) / range(d),
//! which is eq. 5.3 when all w_j = 1. The objective is Σ_e e_e(x).
//! Its gradient is ∂e/∂x_k = Σ w_j r_j J_jk / (W · R · √S) with
//! S = Σ w_j r_j² / W, computed from the model Jacobian J.

use nalgebra::{DMatrix, DVector};
use nlvid_model::Domain;

use crate::error::{InverseError, Result};
use crate::measured::MeasuredCurve;
use crate::model::{Model, check_finite, check_jacobian, check_len};

/// Range-normalised RMSE (eq. 5.3) of `model` against `reference`
/// (the measured curve, whose range normalises), with optional weights.
///
/// # Errors
/// [`InverseError::LengthMismatch`], [`InverseError::ZeroRange`], or
/// [`InverseError::InvalidSetting`] for negative or all-zero weights.
pub fn range_normalised_rmse(
    model: &[f64],
    reference: &[f64],
    weights: Option<&[f64]>,
) -> Result<f64> {
    check_len("model curve vs reference", reference.len(), model.len())?;
    let range = curve_range(reference, "reference")?;
    let (sum_w, sum_wr2): (f64, f64) = match weights {
        None => (
            reference.len() as f64,
            model
                .iter()
                .zip(reference)
                .map(|(y, d)| (y - d) * (y - d))
                .sum(),
        ),
        Some(w) => {
            check_weights(w, reference.len())?;
            (
                w.iter().sum::<f64>(),
                model
                    .iter()
                    .zip(reference)
                    .zip(w)
                    .map(|((y, d), w)| w * (y - d) * (y - d))
                    .sum(),
            )
        }
    };
    Ok((sum_wr2 / sum_w).sqrt() / range)
}

pub(crate) fn curve_range(reference: &[f64], what: &str) -> Result<f64> {
    let (lo, hi) = reference
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let range = hi - lo;
    if range > 0.0 && range.is_finite() {
        Ok(range)
    } else {
        Err(InverseError::ZeroRange {
            what: what.to_string(),
        })
    }
}

pub(crate) fn check_weights(w: &[f64], m: usize) -> Result<()> {
    check_len("weights", m, w.len())?;
    if let Some(j) = w.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(InverseError::InvalidSetting(format!(
            "weight {j} is {} (weights must be finite and >= 0)",
            w[j]
        )));
    }
    if w.iter().sum::<f64>() <= 0.0 {
        return Err(InverseError::InvalidSetting(
            "all weights are zero".to_string(),
        ));
    }
    Ok(())
}

/// One weighted time segment [start, end) (s) for [`segment_weights`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Start time (s), inclusive.
    pub start: f64,
    /// End time (s), exclusive (the last segment may use `f64::INFINITY`).
    pub end: f64,
    /// Weight of the points inside.
    pub weight: f64,
}

/// Per-point weights from time segments (e.g. ramp-reverse cycles vs hold);
/// points in no segment get `default`; where segments overlap the last wins.
pub fn segment_weights(times: &[f64], segments: &[Segment], default: f64) -> Vec<f64> {
    times
        .iter()
        .map(|&t| {
            segments
                .iter()
                .rev()
                .find(|s| t >= s.start && t < s.end)
                .map_or(default, |s| s.weight)
        })
        .collect()
}

/// A measured curve on a model's time grid, with the model that predicts it.
#[derive(Debug, Clone)]
pub struct Experiment<M> {
    /// Label for reports ("RH d = 1.5 mm").
    pub label: String,
    /// Forward model (surrogate or real) on the same grid as `data`.
    pub model: M,
    /// Measured curve resampled onto `model.times()`.
    pub data: Vec<f64>,
    /// Optional per-point weights (see [`segment_weights`]).
    pub weights: Option<Vec<f64>>,
    range: f64,
}

impl<M: Model> Experiment<M> {
    /// Pairs data with a model, checking lengths, finiteness and range.
    ///
    /// # Errors
    /// [`InverseError::LengthMismatch`], [`InverseError::ZeroRange`],
    /// [`InverseError::InvalidSetting`] (NaN in data, bad weights).
    pub fn new(label: &str, model: M, data: Vec<f64>, weights: Option<Vec<f64>>) -> Result<Self> {
        check_len(
            &format!("data of experiment '{label}'"),
            model.times().len(),
            data.len(),
        )?;
        if let Some(j) = data.iter().position(|v| !v.is_finite()) {
            return Err(InverseError::InvalidSetting(format!(
                "data of experiment '{label}' is not finite at index {j}"
            )));
        }
        if let Some(w) = &weights {
            check_weights(w, data.len())?;
        }
        let range = curve_range(&data, &format!("data of experiment '{label}'"))?;
        Ok(Self {
            label: label.to_string(),
            model,
            data,
            weights,
            range,
        })
    }

    /// Pairs a measured curve with a model: `values` (one per sample of
    /// `curve`, e.g. `curve.force`) are resampled onto `model.times()`,
    /// which count from the curve's first sample.
    ///
    /// # Errors
    /// As [`MeasuredCurve::resample`] and [`Experiment::new`].
    pub fn from_measured(
        label: &str,
        model: M,
        curve: &MeasuredCurve,
        values: &[f64],
        weights: Option<Vec<f64>>,
    ) -> Result<Self> {
        let data = curve.resample(values, model.times())?;
        Self::new(label, model, data, weights)
    }

    /// Range of the data (max − min), the eq. 5.3 normaliser.
    pub fn data_range(&self) -> f64 {
        self.range
    }

    fn weight(&self, j: usize) -> f64 {
        self.weights.as_ref().map_or(1.0, |w| w[j])
    }

    fn sum_weights(&self) -> f64 {
        self.weights
            .as_ref()
            .map_or(self.data.len() as f64, |w| w.iter().sum())
    }

    /// e(x) of eq. 5.3 for this experiment.
    ///
    /// # Errors
    /// Model errors; non-finite model output.
    pub fn misfit(&self, x: &[f64]) -> Result<f64> {
        let y = self.model.response(x)?;
        self.misfit_of_curve(&y, x)
    }

    fn misfit_of_curve(&self, y: &[f64], x: &[f64]) -> Result<f64> {
        check_len(
            &format!("model curve of '{}'", self.label),
            self.data.len(),
            y.len(),
        )?;
        check_finite(y, self.model.times(), x)?;
        let s: f64 = (0..y.len())
            .map(|j| self.weight(j) * (y[j] - self.data[j]).powi(2))
            .sum::<f64>()
            / self.sum_weights();
        Ok(s.sqrt() / self.range)
    }

    /// e(x) and ∂e/∂x from the model Jacobian.
    ///
    /// # Errors
    /// Model errors; non-finite model output.
    pub fn misfit_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        let (y, jac) = self.model.response_and_jacobian(x)?;
        let e = self.misfit_of_curve(&y, x)?;
        check_jacobian(&jac, y.len(), x.len())?;
        Ok((e, self.gradient_from(&y, &jac, e)))
    }

    fn gradient_from(&self, y: &[f64], jac: &DMatrix<f64>, e: f64) -> Vec<f64> {
        let n = jac.ncols();
        let sqrt_s = e * self.range;
        if sqrt_s == 0.0 {
            return vec![0.0; n];
        }
        let denom = self.sum_weights() * self.range * sqrt_s;
        (0..n)
            .map(|k| {
                (0..y.len())
                    .map(|j| self.weight(j) * (y[j] - self.data[j]) * jac[(j, k)])
                    .sum::<f64>()
                    / denom
            })
            .collect()
    }
}

/// What [`crate::MultiStart`] minimises: a scalar misfit over a [`Domain`]
/// with its gradient (argmin's cost + gradient traits in one).
pub trait Objective {
    /// The parameter domain.
    fn domain(&self) -> &Domain;

    /// Objective value at physical parameters x.
    ///
    /// # Errors
    /// Model errors.
    fn value(&self, x: &[f64]) -> Result<f64>;

    /// Value and gradient (physical units).
    ///
    /// # Errors
    /// Model errors.
    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)>;

    /// Eq. 5.3 misfit of each experiment (for reports).
    ///
    /// # Errors
    /// Model errors.
    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>>;

    /// The value reported for the end point of a local run (the fit's
    /// misfit): [`Objective::value`] unless an objective searches with a
    /// faster form and reports the directly computed one
    /// ([`crate::ReducedMisfit`]).
    ///
    /// # Errors
    /// Model errors.
    fn final_value(&self, x: &[f64]) -> Result<f64> {
        self.value(x)
    }
}

impl<M: Model> Objective for Misfit<M> {
    fn domain(&self) -> &Domain {
        Misfit::domain(self)
    }
    fn value(&self, x: &[f64]) -> Result<f64> {
        Misfit::value(self, x)
    }
    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        Misfit::value_and_gradient(self, x)
    }
    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        Misfit::per_experiment(self, x)
    }
}

/// Checks that experiments fitted together share one parameter set (the
/// same names in the same order); `experiments` yields (label, domain).
///
/// # Errors
/// [`InverseError::InvalidSetting`] for no experiments or differing domains.
/// Eq. 5.3 from the weighted residual sum of squares `swr2` = Σ w r²
/// formed in some coordinates z of the curve: e = √(swr2/Σw) / range; with
/// `gradient` = (J = ∂z/∂x with `rows` rows, v = ½ ∂(Σ w r²)/∂z, formed
/// only when needed), ∂e/∂x = Jᵀv / (Σw · √(swr2/Σw) · range). `time0`
/// (the grid's first time) and `x` name a non-finite sum.
///
/// # Errors
/// [`InverseError::NonFinite`] for a non-finite `swr2`; a Jacobian of the
/// wrong shape.
pub(crate) fn rmse_of_sum(
    swr2: f64,
    (sum_w, range): (f64, f64),
    x: &[f64],
    time0: f64,
    gradient: Option<(&DMatrix<f64>, usize, impl FnOnce() -> DVector<f64>)>,
) -> Result<(f64, Vec<f64>)> {
    if !swr2.is_finite() {
        return Err(InverseError::NonFinite {
            index: 0,
            time: time0,
            x: x.to_vec(),
        });
    }
    let sqrt_s = (swr2 / sum_w).sqrt();
    let e = sqrt_s / range;
    let Some((jac, rows, v)) = gradient else {
        return Ok((e, Vec::new()));
    };
    check_jacobian(jac, rows, x.len())?;
    if sqrt_s == 0.0 {
        return Ok((e, vec![0.0; x.len()]));
    }
    let grad = jac.tr_mul(&v()) / (sum_w * sqrt_s * range);
    Ok((e, grad.iter().copied().collect()))
}

/// One experiment's term of a [`SummedMisfit`] (eq. 5.3 of one curve):
/// [`crate::BasisExperiment`] (Gram form), [`crate::ReducedExperiment`]
/// (PCA-reduced form).
pub trait MisfitTerm {
    /// Label for reports.
    fn label(&self) -> &str;
    /// The parameter domain.
    fn domain(&self) -> &Domain;
    /// Value and, with `with_gradient`, gradient in the search's form.
    ///
    /// # Errors
    /// Model errors.
    fn eval(&self, x: &[f64], with_gradient: bool) -> Result<(f64, Vec<f64>)>;
    /// The value reported for the experiment: [`MisfitTerm::eval`]'s
    /// unless the search form is an approximation of a direct one.
    ///
    /// # Errors
    /// Model errors.
    fn reported(&self, x: &[f64]) -> Result<f64> {
        Ok(self.eval(x, false)?.0)
    }
}

/// Sum of eq. 5.3 misfits over experiments fitted with one parameter set
/// (§5.4.2): the search uses each term's [`MisfitTerm::eval`], the
/// reports ([`Objective::per_experiment`], [`Objective::final_value`]) its
/// [`MisfitTerm::reported`] value.
#[derive(Debug, Clone)]
pub struct SummedMisfit<E> {
    experiments: Vec<E>,
}

impl<E: MisfitTerm> SummedMisfit<E> {
    /// Combines experiments (at least one, same parameter names).
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`].
    pub fn new(experiments: Vec<E>) -> Result<Self> {
        check_shared_parameters(experiments.iter().map(|e| (e.label(), e.domain())))?;
        Ok(Self { experiments })
    }

    /// The experiments.
    pub fn experiments(&self) -> &[E] {
        &self.experiments
    }
}

impl<E: MisfitTerm> Objective for SummedMisfit<E> {
    fn domain(&self) -> &Domain {
        self.experiments[0].domain()
    }

    fn value(&self, x: &[f64]) -> Result<f64> {
        let mut total = 0.0;
        for e in &self.experiments {
            total += e.eval(x, false)?.0;
        }
        Ok(total)
    }

    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        sum_with_gradient(&self.experiments, x.len(), |e| e.eval(x, true))
    }

    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.experiments.iter().map(|e| e.reported(x)).collect()
    }

    fn final_value(&self, x: &[f64]) -> Result<f64> {
        Ok(self.per_experiment(x)?.iter().sum())
    }
}

/// Σ_e of each experiment's value and gradient (`eval`), the gradient of
/// length `n`: a misfit over several experiments (eq. 5.3 summed, §5.4.2).
pub(crate) fn sum_with_gradient<E>(
    experiments: &[E],
    n: usize,
    eval: impl Fn(&E) -> Result<(f64, Vec<f64>)>,
) -> Result<(f64, Vec<f64>)> {
    let mut total = 0.0;
    let mut grad = vec![0.0; n];
    for e in experiments {
        let (v, g) = eval(e)?;
        total += v;
        for (a, b) in grad.iter_mut().zip(g) {
            *a += b;
        }
    }
    Ok((total, grad))
}

pub(crate) fn check_shared_parameters<'a>(
    mut experiments: impl Iterator<Item = (&'a str, &'a Domain)>,
) -> Result<()> {
    let names = |d: &Domain| {
        d.params()
            .iter()
            .map(|p| p.name.clone())
            .collect::<Vec<_>>()
    };
    let Some((_, first)) = experiments.next() else {
        return Err(InverseError::InvalidSetting(
            "a fit needs at least one experiment".into(),
        ));
    };
    let reference = names(first);
    for (label, domain) in experiments {
        let other = names(domain);
        if other != reference {
            return Err(InverseError::InvalidSetting(format!(
                "experiment '{label}' has parameters {other:?}, the first has {reference:?}: \
                 experiments fitted together must share one parameter set"
            )));
        }
    }
    Ok(())
}

/// Sum of eq. 5.3 misfits of several experiments sharing one parameter set.
#[derive(Debug, Clone)]
pub struct Misfit<M> {
    experiments: Vec<Experiment<M>>,
}

impl<M: Model> Misfit<M> {
    /// Combines experiments; their domains must have the same parameter names.
    ///
    /// # Errors
    /// [`InverseError::InvalidSetting`] for no experiments or differing domains.
    pub fn new(experiments: Vec<Experiment<M>>) -> Result<Self> {
        check_shared_parameters(
            experiments
                .iter()
                .map(|e| (e.label.as_str(), e.model.domain())),
        )?;
        Ok(Self { experiments })
    }

    /// The experiments.
    pub fn experiments(&self) -> &[Experiment<M>] {
        &self.experiments
    }

    /// The shared domain (that of the first experiment).
    pub fn domain(&self) -> &Domain {
        self.experiments[0].model.domain()
    }

    /// Σ_e e_e(x).
    ///
    /// # Errors
    /// As [`Experiment::misfit`].
    pub fn value(&self, x: &[f64]) -> Result<f64> {
        Ok(self.per_experiment(x)?.iter().sum())
    }

    /// e_e(x) for each experiment.
    ///
    /// # Errors
    /// As [`Experiment::misfit`].
    pub fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.experiments.iter().map(|e| e.misfit(x)).collect()
    }

    /// Σ_e e_e(x) and its gradient.
    ///
    /// # Errors
    /// As [`Experiment::misfit_and_gradient`].
    pub fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        sum_with_gradient(&self.experiments, x.len(), |e| e.misfit_and_gradient(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hertz::{LeeRadokHertz, ramp_hold_grid, ramp_hold_indentation};
    use nlvid_model::Domain;

    #[test]
    fn rmse_is_range_normalised_as_in_eq_5_3() {
        // residuals (1, -1, 1, -1): RMSE = 1; range of reference = 10.
        let reference = [0.0, 10.0, 5.0, 2.0];
        let model = [1.0, 9.0, 6.0, 1.0];
        let e = range_normalised_rmse(&model, &reference, None).expect("e");
        assert!((e - 0.1).abs() < 1e-15);
        // weights (1, 0, 0, 0) keep only the first residual, still /range.
        let e = range_normalised_rmse(&model, &reference, Some(&[1.0, 0.0, 0.0, 0.0])).expect("e");
        assert!((e - 0.1).abs() < 1e-15);
        let e = range_normalised_rmse(
            &[0.0, 10.0, 5.0, 5.0],
            &reference,
            Some(&[0.0, 0.0, 1.0, 3.0]),
        )
        .expect("e");
        assert!((e - (27.0f64 / 4.0).sqrt() / 10.0).abs() < 1e-15);
    }

    #[test]
    fn flat_reference_and_bad_weights_are_errors() {
        assert!(matches!(
            range_normalised_rmse(&[1.0, 2.0], &[3.0, 3.0], None),
            Err(InverseError::ZeroRange { .. })
        ));
        assert!(range_normalised_rmse(&[1.0, 2.0], &[0.0, 3.0], Some(&[0.0, 0.0])).is_err());
        assert!(range_normalised_rmse(&[1.0, 2.0], &[0.0, 3.0], Some(&[-1.0, 1.0])).is_err());
        assert!(range_normalised_rmse(&[1.0], &[0.0, 3.0], None).is_err());
    }

    #[test]
    fn segment_weights_pick_the_segment_containing_each_time() {
        let w = segment_weights(
            &[0.0, 0.5, 1.0, 2.0, 9.0],
            &[
                Segment {
                    start: 0.0,
                    end: 1.0,
                    weight: 3.0,
                },
                Segment {
                    start: 1.5,
                    end: f64::INFINITY,
                    weight: 0.5,
                },
            ],
            1.0,
        );
        assert_eq!(w, vec![3.0, 3.0, 1.0, 0.5, 0.5]);
    }

    fn experiment(depth: f64, x_true: &[f64], label: &str) -> Experiment<LeeRadokHertz> {
        let d = Domain::table_5_3(0.01).expect("domain");
        let t = ramp_hold_grid(0.2, 40, 52.0, 120, 1e-3).expect("grid");
        let delta = ramp_hold_indentation(&t, 10e-6, depth);
        let m = LeeRadokHertz::new(d, t.clone(), &delta, 2.5e-6, 0.5).expect("model");
        let mut data = m.response(x_true).expect("data");
        // deterministic perturbation so the misfit is not zero at x_true
        for (j, v) in data.iter_mut().enumerate() {
            *v *= 1.0 + 0.03 * ((j as f64) * 0.7).sin();
        }
        let w = segment_weights(
            &t,
            &[Segment {
                start: 0.0,
                end: 0.25,
                weight: 2.0,
            }],
            1.0,
        );
        Experiment::new(label, m, data, Some(w)).expect("experiment")
    }

    #[test]
    fn gradient_of_summed_misfit_matches_central_differences() {
        let x_true = [900.0, 0.5, 0.3, 0.05, 12.0];
        let misfit = Misfit::new(vec![
            experiment(2e-6, &x_true, "RH 2 um"),
            experiment(1e-6, &x_true, "RH 1 um"),
        ])
        .expect("misfit");
        let x = [700.0, 0.4, 0.35, 0.1, 8.0];
        let (v, g) = misfit.value_and_gradient(&x).expect("grad");
        assert!((v - misfit.value(&x).expect("value")).abs() < 1e-15);
        for k in 0..5 {
            let h = 1e-6 * x[k];
            let mut xp = x;
            let mut xm = x;
            xp[k] += h;
            xm[k] -= h;
            let fd = (misfit.value(&xp).expect("v") - misfit.value(&xm).expect("v")) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-6 * fd.abs().max(1e-12),
                "k = {k}: {fd} vs {}",
                g[k]
            );
        }
    }

    /// A model under another domain (G0 renamed C1): same curve, other
    /// parameter set.
    #[derive(Debug)]
    struct Renamed(LeeRadokHertz, Domain);

    impl Model for Renamed {
        fn domain(&self) -> &Domain {
            &self.1
        }
        fn times(&self) -> &[f64] {
            self.0.times()
        }
        fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
            self.0.response(x)
        }
    }

    #[test]
    fn experiments_with_different_parameter_sets_cannot_be_combined() {
        let x_true = [900.0, 0.5, 0.3, 0.05, 12.0];
        let a = experiment(2e-6, &x_true, "a");
        let b = experiment(1e-6, &x_true, "b");
        let renamed = Domain::new(
            b.model
                .domain()
                .params()
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let mut p = p.clone();
                    if i == 0 {
                        p.name = "C1".into();
                    }
                    p
                })
                .collect(),
        )
        .expect("domain");
        let table = a.model.domain().clone();
        let a = Experiment::new("a", Renamed(a.model, table), a.data, None).expect("experiment");
        let b = Experiment::new("b", Renamed(b.model, renamed), b.data, None).expect("experiment");
        let e = Misfit::new(vec![a, b]).expect_err("differ");
        assert!(e.to_string().contains("'b'"), "{e}");
    }

    #[test]
    fn experiments_with_other_parameters_are_refused_by_name() {
        use nlvid_model::{Parameter, Scale};
        let a = Domain::table_5_3(0.01).unwrap();
        let b = Domain::new(vec![Parameter::new("E", "Pa", 1.0, 2.0, Scale::Linear)]).unwrap();
        assert!(check_shared_parameters([("rh1", &a), ("rh2", &a)].into_iter()).is_ok());
        let msg = check_shared_parameters([("rh1", &a), ("rr", &b)].into_iter())
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("experiment 'rr' has parameters [\"E\"]"),
            "{msg}"
        );
        assert!(msg.contains("must share one parameter set"), "{msg}");
        let none = check_shared_parameters(std::iter::empty()).unwrap_err();
        assert!(
            none.to_string().contains("at least one experiment"),
            "{none}"
        );
    }
}
