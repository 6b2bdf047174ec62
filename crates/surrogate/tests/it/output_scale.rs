//! Outputs exactly proportional to a function of one input
//! ([`OutputScale`]): the model must equal s(x) times a plain model fitted
//! by the caller on y / s, its gradients must match central differences,
//! its basis form μ + Bᵀφ must equal the predictor, and model files
//! without the field must still load.

#![allow(clippy::unwrap_used)]

use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OutputScale, Regression, ThetaSearch,
};

/// 40 scattered sites in [0.5, 3] × [−1, 1] × [0, 2] and 3 outputs
/// y_j = s(x0) · u_j(x1, x2).
fn data(scale: OutputScale) -> (Mat<f64>, Mat<f64>) {
    let n = 40;
    let x = Mat::from_fn(n, 3, |i, k| {
        let v = ((i * (7 + 4 * k) + 3 * k + 1) % n) as f64 / n as f64;
        match k {
            0 => 0.5 + 2.5 * v,
            1 => 2.0 * v - 1.0,
            _ => 2.0 * ((v + 0.37 * i as f64) % 1.0),
        }
    });
    let y = Mat::from_fn(n, 3, |i, j| {
        let xi = [x[(i, 0)], x[(i, 1)], x[(i, 2)]];
        let (s, _) = scale.eval(&xi);
        let u = match j {
            0 => 2.0 + (1.3 * xi[1]).sin() + 0.2 * xi[2],
            1 => 1.0 + xi[1] * xi[1] * 0.5 + (0.7 * xi[2]).cos(),
            _ => 3.0 + 0.4 * xi[1] * xi[2],
        };
        s * u
    });
    (x, y)
}

fn settings(theta: Vec<f64>) -> KrigingSettings {
    let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 3);
    s.theta = ThetaSearch::Fixed(theta);
    s
}

const SCALES: [OutputScale; 2] = [
    OutputScale::Linear { input: 0 },
    OutputScale::Exp {
        input: 0,
        slope: 0.8,
    },
];

#[test]
fn scaled_model_equals_s_times_a_plain_model_of_y_over_s() {
    for scale in SCALES {
        let (x, y) = data(scale);
        let n = x.nrows();
        let mut set = settings(vec![0.3, 1.1, 0.7]);
        set.output_scale = Some(scale);
        let scaled = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
        // Independent route: the caller divides, a plain model krige y / s.
        let u = Mat::from_fn(n, 3, |i, j| {
            let (s, _) = scale.eval(&[x[(i, 0)], x[(i, 1)], x[(i, 2)]]);
            y[(i, j)] / s
        });
        let plain =
            KrigingModel::fit(x.as_ref(), u.as_ref(), &settings(vec![0.3, 1.1, 0.7])).unwrap();
        for p in [[1.2, 0.3, 0.4], [2.7, -0.8, 1.9], [0.6, 0.0, 1.0]] {
            let (s, _) = scale.eval(&p);
            let a = scaled.predict_full(&p).unwrap();
            let b = plain.predict_full(&p).unwrap();
            for j in 0..3 {
                let yb = s * b.y[j];
                assert!((a.y[j] - yb).abs() < 1e-12 * yb.abs(), "{scale:?} y");
                let mb = s * s * b.mse[j];
                assert!(
                    (a.mse[j] - mb).abs() < 1e-10 * mb.abs() + 1e-300,
                    "{scale:?} mse"
                );
            }
            assert_eq!(scaled.predict(&p).unwrap(), a.y);
        }
    }
}

/// dy and dmse of `predict_full` at `p` against central differences
/// (h = 1e-5) of y and mse, for every output and input.
fn assert_gradients_match_central_differences(model: &KrigingModel, p: [f64; 3], what: &str) {
    let a = model.predict_full(&p).unwrap();
    for k in 0..3 {
        let h = 1e-5;
        let (mut xp, mut xm) = (p, p);
        xp[k] += h;
        xm[k] -= h;
        let (pp, pm) = (
            model.predict_full(&xp).unwrap(),
            model.predict_full(&xm).unwrap(),
        );
        for j in 0..3 {
            let fd = (pp.y[j] - pm.y[j]) / (2.0 * h);
            let an = a.dy[j * 3 + k];
            assert!(
                (fd - an).abs() < 1e-6 * (1.0 + fd.abs()),
                "{what} dy{j}/dx{k}: fd {fd} vs {an}"
            );
            let fd = (pp.mse[j] - pm.mse[j]) / (2.0 * h);
            let an = a.dmse[j * 3 + k];
            assert!(
                (fd - an).abs() < 1e-5 * (fd.abs() + a.mse[j].abs()) + 1e-14,
                "{what} dmse{j}/dx{k}: fd {fd} vs {an}"
            );
        }
    }
}

#[test]
fn scaled_gradients_match_central_differences() {
    for scale in SCALES {
        for log in [false, true] {
            let (x, y) = data(scale);
            let mut set = settings(vec![0.3, 1.1, 0.7]);
            set.output_scale = Some(scale);
            set.log_outputs = log;
            let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
            for p in [[1.2, 0.3, 0.4], [2.7, -0.8, 1.9]] {
                assert_gradients_match_central_differences(
                    &model,
                    p,
                    &format!("{scale:?} log {log}"),
                );
            }
        }
    }
}

#[test]
fn basis_form_equals_the_predictor_with_an_output_scale() {
    for scale in SCALES {
        let (x, y) = data(scale);
        let mut set = settings(vec![0.3, 1.1, 0.7]);
        set.output_scale = Some(scale);
        set.pca_energy = Some(1.0 - 1e-12);
        let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
        let nb = model.n_basis();
        let (b, mu) = model.basis_coefficients();
        for p in [[1.2, 0.3, 0.4], [2.7, -0.8, 1.9]] {
            let (phi, dphi) = model.basis(&p).unwrap();
            assert_eq!(phi.len(), nb);
            let pred = model.predict_full(&p).unwrap();
            for j in 0..3 {
                let v = mu[j] + (0..nb).map(|a| b[j * nb + a] * phi[a]).sum::<f64>();
                assert!(
                    (v - pred.y[j]).abs() < 1e-10 * pred.y[j].abs(),
                    "{v} vs {}",
                    pred.y[j]
                );
                for k in 0..3 {
                    let dv: f64 = (0..nb).map(|a| b[j * nb + a] * dphi[a * 3 + k]).sum();
                    let an = pred.dy[j * 3 + k];
                    assert!((dv - an).abs() < 1e-9 * (1.0 + an.abs()), "{dv} vs {an}");
                }
            }
        }
    }
}

#[test]
fn structure_makes_the_surrogate_far_more_accurate_and_old_files_load() {
    // y = x0 · u(x1, x2) with x0 spanning a factor 6: kriging u is much
    // closer than kriging y on the same sites (both with the same θ search).
    let scale = OutputScale::Linear { input: 0 };
    let (x, y) = data(scale);
    let mut a = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 3);
    let plain = KrigingModel::fit(x.as_ref(), y.as_ref(), &a).unwrap();
    a.output_scale = Some(scale);
    let scaled = KrigingModel::fit(x.as_ref(), y.as_ref(), &a).unwrap();
    let mut err = [0.0f64; 2];
    for i in 0..50 {
        let p = [
            0.6 + 2.3 * ((i * 7) % 50) as f64 / 50.0,
            -0.9 + 1.8 * ((i * 13) % 50) as f64 / 50.0,
            1.9 * ((i * 29) % 50) as f64 / 50.0,
        ];
        let truth = p[0] * (2.0 + (1.3 * p[1]).sin() + 0.2 * p[2]);
        err[0] = err[0].max((plain.predict(&p).unwrap()[0] - truth).abs());
        err[1] = err[1].max((scaled.predict(&p).unwrap()[0] - truth).abs());
    }
    assert!(
        err[1] < 0.2 * err[0],
        "scaled {} vs plain {}",
        err[1],
        err[0]
    );
    // A model file written before the field existed.
    let mut v: serde_json::Value = serde_json::to_value(&plain).unwrap();
    v.as_object_mut().unwrap().remove("output_scale");
    v.as_object_mut().unwrap().remove("log_inputs");
    let back: KrigingModel = serde_json::from_value(v).unwrap();
    assert!(back.output_scale.is_none() && back.log_inputs.is_empty());
    assert_eq!(
        back.predict(&[1.0, 0.2, 0.3]).unwrap(),
        plain.predict(&[1.0, 0.2, 0.3]).unwrap()
    );
}

#[test]
fn log_inputs_equal_a_plain_model_on_ln_x_with_matching_gradients() {
    // Inputs 0 and 2 kriged in ln x (both > 0 in `data`); output scale on
    // input 0 in the caller's coordinates.
    let scale = OutputScale::Linear { input: 0 };
    let (x, y) = data(scale);
    let n = x.nrows();
    let mut set = settings(vec![0.3, 1.1, 0.7]);
    set.log_inputs = vec![true, false, true];
    set.output_scale = Some(scale);
    // Shift input 2 away from 0 so that ln is defined.
    let x = Mat::from_fn(
        n,
        3,
        |i, k| if k == 2 { x[(i, k)] + 0.5 } else { x[(i, k)] },
    );
    let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
    // Independent route: the caller takes ln and divides by x0.
    let xl = Mat::from_fn(n, 3, |i, k| if k == 1 { x[(i, k)] } else { x[(i, k)].ln() });
    let u = Mat::from_fn(n, 3, |i, j| y[(i, j)] / x[(i, 0)]);
    let plain = KrigingModel::fit(xl.as_ref(), u.as_ref(), &settings(vec![0.3, 1.1, 0.7])).unwrap();
    for p in [[1.2, 0.3, 0.9], [2.7, -0.8, 2.2]] {
        let a = model.predict_full(&p).unwrap();
        let b = plain.predict(&[p[0].ln(), p[1], p[2].ln()]).unwrap();
        for j in 0..3 {
            assert!(
                (a.y[j] - p[0] * b[j]).abs() < 1e-12 * a.y[j].abs(),
                "{} vs {}",
                a.y[j],
                p[0] * b[j]
            );
        }
        assert_gradients_match_central_differences(&model, p, "log inputs");
        let (phi, dphi) = model.basis(&p).unwrap();
        let (bm, mu) = model.basis_coefficients();
        let nb = model.n_basis();
        for k in 0..3 {
            for j in 0..3 {
                let dv: f64 = (0..nb).map(|c| bm[j * nb + c] * dphi[c * 3 + k]).sum();
                assert!((dv - a.dy[j * 3 + k]).abs() < 1e-9 * (1.0 + dv.abs()));
            }
        }
        for j in 0..3 {
            let v = mu[j] + (0..nb).map(|c| bm[j * nb + c] * phi[c]).sum::<f64>();
            assert!((v - a.y[j]).abs() < 1e-10 * a.y[j].abs());
        }
    }
    // Stored in the model file; x ≤ 0 on a log input is a located error.
    let back: KrigingModel = serde_json::from_str(&serde_json::to_string(&model).unwrap()).unwrap();
    assert_eq!(back.log_inputs, vec![true, false, true]);
    let e = model.predict(&[1.0, 0.0, -1.0]).unwrap_err().to_string();
    assert!(e.contains("coordinate 2"), "{e}");
}
