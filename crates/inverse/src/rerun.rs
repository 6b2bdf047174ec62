//! Re-check of a fitted parameter set with a *real* forward model (thesis
//! §4.4.1 step 5, §5.4.1: "the FE model was re-run with the optimum
//! parameters"): any [`nlvid_surrogate::ForwardModel`] — the analytic
//! Lee–Radok model, the membrane solver, the FE AFM model — is run once at
//! the optimum and scored against the data with eq. 5.3.
//!
//! The forward model and the fit share the one parameter order of
//! `nlvid_model` (the model's parameters are the domain's, in order: a
//! meta-model is built on the domain of its forward model); the model has
//! its own time grid. [`rerun`] interpolates the response linearly onto the
//! data grid (exact when the grids are equal, as they are when the
//! surrogate was built from the same model).

use nlvid_model::{Domain, ForwardModel};
use serde::Serialize;

use crate::error::{InverseError, Result};
use crate::misfit::range_normalised_rmse;

/// The real model's response at the optimum and its eq. 5.3 misfit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rerun {
    /// Response of the real model on the data grid (SI, N).
    pub response: Vec<f64>,
    /// Eq. 5.3 misfit of `response` against the data.
    pub misfit: f64,
}

/// Runs `model` at the physical parameters `x` (in `domain`'s order),
/// interpolates its response onto `grid` and returns it with its eq. 5.3
/// misfit against `data` (weights as in the fit).
///
/// # Errors
/// [`InverseError::InvalidSetting`] when the model's parameters are not the
/// domain's (same names, same order) or `grid` reaches outside the model's
/// time grid; [`InverseError::Model`] when the run fails (its message kept);
/// [`InverseError::LengthMismatch`] / [`InverseError::NonFinite`] for an
/// unusable response; as [`range_normalised_rmse`].
pub fn rerun(
    model: &dyn ForwardModel,
    domain: &Domain,
    x: &[f64],
    grid: &[f64],
    data: &[f64],
    weights: Option<&[f64]>,
) -> Result<Rerun> {
    domain.check_len(x)?;
    domain
        .check_names(&model.parameter_names())
        .map_err(|e| InverseError::InvalidSetting(format!("the real model: {e}")))?;
    let y = model.run(x).map_err(|e| InverseError::Model {
        x: x.to_vec(),
        message: format!("real model re-run: {e}"),
    })?;
    let times = model.time_grid();
    crate::model::check_len("real model response", times.len(), y.len())?;
    crate::model::check_finite(&y, times, x)?;
    let response = interpolate_onto(times, &y, grid)?;
    let misfit = range_normalised_rmse(&response, data, weights)?;
    Ok(Rerun { response, misfit })
}

/// Linear interpolation of (ts, ys) at every t of `grid`; `grid` must lie
/// inside [ts₀, ts_last] up to 1e-9 of the span.
fn interpolate_onto(ts: &[f64], ys: &[f64], grid: &[f64]) -> Result<Vec<f64>> {
    let (Some(&first), Some(&last)) = (ts.first(), ts.last()) else {
        return Err(InverseError::InvalidSetting(
            "the real model has an empty time grid".into(),
        ));
    };
    let slack = 1e-9 * (last - first).abs().max(f64::MIN_POSITIVE);
    if let Some(&t) = grid
        .iter()
        .find(|&&t| t < first - slack || t > last + slack)
    {
        return Err(InverseError::InvalidSetting(format!(
            "the data grid needs t = {t} s but the real model covers {first} ... {last} s: \
             give the real model the surrogate's protocol"
        )));
    }
    if ts.len() == 1 {
        return Ok(vec![ys[0]; grid.len()]);
    }
    Ok(grid
        .iter()
        .map(|&t| {
            let t = t.clamp(first, last);
            let i = ts.partition_point(|&s| s <= t).clamp(1, ts.len() - 1);
            let w = (t - ts[i - 1]) / (ts[i] - ts[i - 1]);
            ys[i - 1] * (1.0 - w) + ys[i] * w
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_model::{FailureKind, Parameter, RunFailure, Scale};

    /// y(t) = a + b t on its own grid, parameters (a, b).
    struct Line {
        times: Vec<f64>,
    }

    impl ForwardModel for Line {
        fn parameter_names(&self) -> Vec<String> {
            vec!["a".into(), "b".into()]
        }
        fn parameter_units(&self) -> Vec<String> {
            vec!["1".into(), "1".into()]
        }
        fn time_grid(&self) -> &[f64] {
            &self.times
        }
        fn identity(&self) -> String {
            "line".into()
        }
        fn run(&self, p: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
            if p[1] < 0.0 {
                return Err(RunFailure {
                    kind: FailureKind::NotConverged,
                    time: Some(0.5),
                    message: "negative slope".into(),
                });
            }
            Ok(self.times.iter().map(|t| p[0] + p[1] * t).collect())
        }
    }

    fn domain() -> Domain {
        Domain::new(vec![
            Parameter::new("a", "1", -10.0, 10.0, Scale::Linear),
            Parameter::new("b", "1", -10.0, 10.0, Scale::Linear),
        ])
        .unwrap()
    }

    #[test]
    fn the_response_is_interpolated_onto_the_data_grid() {
        // Coarse model grid, finer data grid: a line is interpolated exactly.
        let model = Line {
            times: vec![0.0, 1.0, 2.5, 4.0],
        };
        let grid: Vec<f64> = (0..=16).map(|i| 0.25 * i as f64).collect();
        let (a, b) = (1.5, 0.75);
        let data: Vec<f64> = grid
            .iter()
            .enumerate()
            .map(|(j, t)| a + b * t + if j % 2 == 0 { 0.1 } else { -0.1 })
            .collect();
        let r = rerun(&model, &domain(), &[a, b], &grid, &data, None).unwrap();
        for (t, y) in grid.iter().zip(&r.response) {
            assert!((y - (a + b * t)).abs() < 1e-12, "t = {t}: {y}");
        }
        // Residuals ±0.1 everywhere: RMSE 0.1 over the data range.
        let lo = data.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = data.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!((r.misfit - 0.1 / (hi - lo)).abs() < 1e-12, "{}", r.misfit);
    }

    #[test]
    fn a_grid_beyond_the_model_or_a_foreign_parameter_or_a_failed_run_is_a_clear_error() {
        let model = Line {
            times: vec![0.0, 1.0],
        };
        let e = rerun(
            &model,
            &domain(),
            &[0.0, 1.0],
            &[0.0, 2.0],
            &[0.0, 1.0],
            None,
        )
        .unwrap_err();
        assert!(e.to_string().contains("needs t = 2 s"), "{e}");

        // Another parameter, or the same ones in another order: refused,
        // never permuted.
        for names in [["a", "c"], ["b", "a"]] {
            let other = Domain::new(
                names
                    .iter()
                    .map(|n| Parameter::new(n, "1", -10.0, 10.0, Scale::Linear))
                    .collect(),
            )
            .unwrap();
            let e = rerun(&model, &other, &[0.0, 1.0], &[0.0, 1.0], &[0.0, 1.0], None)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("the real model: parameter domain: parameters [a, b] do not match"),
                "{e}"
            );
        }

        let e = rerun(
            &model,
            &domain(),
            &[0.0, -1.0],
            &[0.0, 1.0],
            &[0.0, 1.0],
            None,
        )
        .unwrap_err();
        assert!(
            e.to_string().contains("negative slope") && e.to_string().contains("t = 5e-1 s"),
            "{e}"
        );
    }
}
