//! The reduced form ŷ(x) = A c(x) of `KrigingModel::output_map` /
//! `output_coordinates`: A c must equal the predictor (with and without
//! PCA, output scaling and log inputs), ∂c/∂x must match central
//! differences of c, and ln-output models must be refused.

#![allow(clippy::unwrap_used)]

use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OutputScale, Regression, ThetaSearch,
};

/// 40 scattered sites in [0.5, 3] × [−1, 1] × [0.2, 2], 30 outputs
/// y_j = x0 · u(t_j; x1, x2) (curves on a "time" grid, low rank plus detail).
fn data() -> (Mat<f64>, Mat<f64>) {
    let (n, m) = (40, 30);
    let x = Mat::from_fn(n, 3, |i, k| {
        let v = ((i * (7 + 4 * k) + 3 * k + 1) % n) as f64 / n as f64;
        match k {
            0 => 0.5 + 2.5 * v,
            1 => 2.0 * v - 1.0,
            _ => 0.2 + 1.8 * ((v + 0.37 * i as f64) % 1.0),
        }
    });
    let y = Mat::from_fn(n, m, |i, j| {
        let t = j as f64 / (m - 1) as f64;
        let (a, b, c) = (x[(i, 0)], x[(i, 1)], x[(i, 2)]);
        a * (1.0 + 0.5 * b * t + (-t / c).exp() + 0.1 * (3.0 * t * b).sin())
    });
    (x, y)
}

fn fit(pca: Option<f64>, scaled: bool, log_inputs: bool) -> KrigingModel {
    fit_with(Correlation::Gauss, pca, scaled, log_inputs)
}

fn fit_with(
    correlation: Correlation,
    pca: Option<f64>,
    scaled: bool,
    log_inputs: bool,
) -> KrigingModel {
    let (x, y) = data();
    let mut s = KrigingSettings::new(Regression::Poly1, correlation, 3);
    s.theta = ThetaSearch::Fixed(vec![0.3, 1.1, 0.7]);
    s.pca_energy = pca;
    if scaled {
        s.output_scale = Some(OutputScale::Linear { input: 0 });
    }
    if log_inputs {
        s.log_inputs = vec![true, false, true];
    }
    KrigingModel::fit(x.as_ref(), y.as_ref(), &s).unwrap()
}

const POINTS: [[f64; 3]; 3] = [[1.2, 0.3, 0.4], [2.7, -0.8, 1.9], [0.6, 0.05, 1.0]];

#[test]
fn output_map_times_coordinates_is_the_predictor() {
    // Gauss has its own fast path in output_coordinates; cubic takes the
    // generic correlation code.
    for (corr, pca, scaled, log_inputs) in [
        (Correlation::Gauss, None, false, false),
        (Correlation::Gauss, None, true, true),
        (Correlation::Gauss, Some(0.9999), false, false),
        (Correlation::Gauss, Some(0.9999), true, false),
        (Correlation::Gauss, Some(0.9999), false, true),
        (Correlation::Gauss, Some(0.9999), true, true),
        (Correlation::Cubic, Some(0.9999), true, true),
        (Correlation::Exp, None, true, false),
    ] {
        {
            {
                let model = fit_with(corr, pca, scaled, log_inputs);
                let m = model.n_outputs;
                let r = model.n_output_coordinates();
                if pca.is_some() {
                    assert!(r < m, "the PCA should reduce 30 outputs, kept {}", r - 1);
                } else {
                    assert_eq!(r, m + 1);
                }
                let a = model.output_map().unwrap();
                assert_eq!(a.len(), m * r);
                for p in POINTS {
                    let y = model.predict(&p).unwrap();
                    let (c, dc) = model.output_coordinates(&p).unwrap();
                    assert_eq!((c.len(), dc.len()), (r, r * 3));
                    // The value-only path (one correlation column) gives the same c.
                    let values = model.output_coordinate_values(&p).unwrap();
                    let cscale = c.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
                    for (k, (v, w)) in values.iter().zip(&c).enumerate() {
                        assert!(
                            (v - w).abs() <= 1e-13 * cscale,
                            "pca {pca:?} scaled {scaled} log {log_inputs} at {p:?}, coordinate {k}: value-only {v}, with derivatives {w}"
                        );
                    }
                    assert_eq!(values.len(), r);
                    let scale = y.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
                    for j in 0..m {
                        let ac: f64 = (0..r).map(|k| a[k * m + j] * c[k]).sum();
                        assert!(
                            (ac - y[j]).abs() <= 1e-12 * scale,
                            "pca {pca:?} scaled {scaled} log {log_inputs} at {p:?}, output {j}: A c = {ac}, predictor {}",
                            y[j]
                        );
                    }
                    // Jacobian through A equals the predictor's own analytic one.
                    let pp = model.predict_full(&p).unwrap();
                    let dscale = pp.dy.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
                    for j in 0..m {
                        for k in 0..3 {
                            let adc: f64 = (0..r).map(|l| a[l * m + j] * dc[l * 3 + k]).sum();
                            assert!((adc - pp.dy[j * 3 + k]).abs() <= 1e-10 * dscale);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn coordinate_jacobian_matches_central_differences() {
    let model = fit(Some(0.9999), true, true);
    let r = model.n_output_coordinates();
    for p in POINTS {
        let (_, dc) = model.output_coordinates(&p).unwrap();
        for k in 0..3 {
            let h = 1e-6 * p[k].abs().max(1.0);
            let (mut xp, mut xm) = (p, p);
            xp[k] += h;
            xm[k] -= h;
            let (cp, _) = model.output_coordinates(&xp).unwrap();
            let (cm, _) = model.output_coordinates(&xm).unwrap();
            for l in 0..r {
                let fd = (cp[l] - cm[l]) / (2.0 * h);
                let an = dc[l * 3 + k];
                assert!(
                    (fd - an).abs() <= 1e-6 * (1.0 + an.abs()),
                    "c_{l} d/dx_{k} at {p:?}: analytic {an}, central {fd}"
                );
            }
        }
    }
}

#[test]
fn log_output_models_have_no_output_map() {
    let (x, y) = data();
    let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 3);
    s.theta = ThetaSearch::Fixed(vec![0.3, 1.1, 0.7]);
    s.log_outputs = true;
    let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &s).unwrap();
    let e = model.output_map().unwrap_err().to_string();
    assert!(e.contains("log-outputs"), "{e}");
    assert!(model.output_coordinates(&POINTS[0]).is_err());
}
