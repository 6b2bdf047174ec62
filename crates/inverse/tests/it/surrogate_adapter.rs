//! The Kriging → inverse adapter: the basis form (used by the fast misfit)
//! and the Model form must reproduce the surrogate's own predictor and its
//! gradient, and the gradient must match central differences of the
//! predictor; the fast misfit must equal eq. 5.3 on the predicted curve.

use nlvid_inverse::{
    AsModel, BasisExperiment, BasisMisfit, Coordinates, Experiment, KrigingSurrogate,
    LeeRadokHertz, Misfit, Model, Objective, gram, ramp_hold_grid, ramp_hold_indentation,
};
use nlvid_model::Domain;
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression, ThetaSearch};

fn real_model(domain: &Domain) -> LeeRadokHertz {
    let t = ramp_hold_grid(0.2, 8, 52.0, 24, 1e-2).expect("grid");
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5).expect("model")
}

/// Surrogate over `domain` (inputs G0, g1, g2, tau1, tau2, the domain's
/// order), in the given coordinates.
fn surrogate(coords: Coordinates, pca: Option<f64>) -> (KrigingSurrogate, LeeRadokHertz) {
    let (k, domain, real) = fitted(coords, pca, false);
    let sur = KrigingSurrogate::new(k, domain, real.times().to_vec(), coords).expect("adapter");
    (sur, real)
}

/// The Kriging model of [`surrogate`], optionally kriging ln y.
fn fitted(
    coords: Coordinates,
    pca: Option<f64>,
    log_outputs: bool,
) -> (KrigingModel, Domain, LeeRadokHertz) {
    let domain = Domain::table_5_3(0.01).expect("domain");
    let real = real_model(&domain);
    let design = sample(
        &domain,
        &SampleSettings {
            n: 40,
            seed: 3,
            optimise_iterations: 0,
        },
    )
    .expect("design");
    let input = |x: &[f64]| -> Vec<f64> {
        match coords {
            Coordinates::Physical => x.to_vec(),
            Coordinates::Unit => domain.to_unit(x),
        }
    };
    let xs: Vec<Vec<f64>> = design.iter().map(|x| input(x)).collect();
    let ys: Vec<Vec<f64>> = design
        .iter()
        .map(|x| real.response(x).expect("run"))
        .collect();
    let xm = Mat::from_fn(xs.len(), 5, |i, k| xs[i][k]);
    // ln y needs y > 0: the curves start at F = 0, so a ln y model krige
    // F + 1 nN (still a predictor that is not linear in its basis).
    let offset = if log_outputs { 1e-9 } else { 0.0 };
    let ym = Mat::from_fn(ys.len(), ys[0].len(), |i, j| ys[i][j] + offset);
    let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
    s.theta = ThetaSearch::Fixed(vec![0.5; 5]);
    s.pca_energy = pca;
    s.log_outputs = log_outputs;
    let k = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s).expect("kriging");
    (k, domain, real)
}

/// A predictor of ln y is not linear in its basis: the adapter refuses it
/// (the basis-form check allows rounding, not a nonlinearity); the same
/// fit in y is accepted.
#[test]
fn a_log_output_surrogate_is_refused_by_the_basis_form_check() {
    for pca in [None, Some(0.99999)] {
        let (k, domain, real) = fitted(Coordinates::Physical, pca, true);
        let Err(err) =
            KrigingSurrogate::new(k, domain, real.times().to_vec(), Coordinates::Physical)
        else {
            panic!("a ln y surrogate is refused");
        };
        let err = err.to_string();
        assert!(err.contains("not of the form"), "{err}");
        let (k, domain, real) = fitted(Coordinates::Physical, pca, false);
        assert!(
            KrigingSurrogate::new(k, domain, real.times().to_vec(), Coordinates::Physical).is_ok()
        );
    }
}

const POINTS: [[f64; 5]; 3] = [
    [900.0, 0.5, 0.3, 0.05, 12.0],
    [150.0, 0.2, 0.6, 1.2, 3.0],
    [3000.0, 0.05, 0.05, 0.02, 35.0],
];

#[test]
fn basis_form_equals_the_surrogates_own_predictor_and_gradient() {
    for coords in [Coordinates::Physical, Coordinates::Unit] {
        for pca in [None, Some(0.9999)] {
            let (sur, _) = surrogate(coords, pca);
            for x in POINTS {
                // Reference: the surrogate's own predict_full (Model impl).
                let (y_ref, j_ref) = sur.response_and_jacobian(&x).expect("predict");
                let (y, j) = AsModel(&sur).response_and_jacobian(&x).expect("basis");
                let scale = y_ref.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                for (a, b) in y.iter().zip(&y_ref) {
                    assert!(
                        (a - b).abs() <= 1e-10 * scale,
                        "{coords:?} {pca:?}: {a} vs {b}"
                    );
                }
                for k in 0..5 {
                    let col = j_ref.column(k).amax().max(1e-300);
                    for r in 0..y.len() {
                        assert!(
                            (j[(r, k)] - j_ref[(r, k)]).abs() <= 1e-9 * col,
                            "{coords:?} {pca:?} dy[{r}]/dx{k}: {} vs {}",
                            j[(r, k)],
                            j_ref[(r, k)]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn surrogate_gradient_matches_central_differences_of_the_predictor() {
    for coords in [Coordinates::Physical, Coordinates::Unit] {
        let (sur, _) = surrogate(coords, None);
        for x in POINTS {
            let (_, jac) = sur.response_and_jacobian(&x).expect("jac");
            for k in 0..5 {
                let h = 1e-6 * x[k];
                let (mut xp, mut xm) = (x, x);
                xp[k] += h;
                xm[k] -= h;
                let yp = sur.response(&xp).expect("p");
                let ym = sur.response(&xm).expect("m");
                let col = jac.column(k).amax();
                for r in 0..yp.len() {
                    let fd = (yp[r] - ym[r]) / (2.0 * h);
                    assert!(
                        (fd - jac[(r, k)]).abs() <= 1e-5 * col + 1e-12,
                        "{coords:?} x = {x:?} dy[{r}]/dx{k}: FD {fd} vs {}",
                        jac[(r, k)]
                    );
                }
            }
        }
    }
}

#[test]
fn fast_misfit_equals_eq_5_3_on_the_predicted_curve() {
    let (sur, real) = surrogate(Coordinates::Unit, None);
    let data = real.response(&[1100.0, 0.4, 0.35, 0.1, 9.0]).expect("data");
    let g = gram(&sur, None).expect("gram");
    let fast = BasisMisfit::new(vec![
        BasisExperiment::new("RH", &sur, g, &data, None).expect("e"),
    ])
    .expect("m");
    let slow = Misfit::new(vec![
        Experiment::new("RH", &sur, data.clone(), None).expect("e"),
    ])
    .expect("m");
    for x in POINTS {
        let (a, ga) = fast.value_and_gradient(&x).expect("fast");
        let (b, gb) = slow.value_and_gradient(&x).expect("slow");
        assert!((a - b).abs() <= 1e-9 * b, "misfit {a} vs {b}");
        for k in 0..5 {
            assert!(
                (ga[k] - gb[k]).abs() <= 1e-6 * gb[k].abs().max(1e-12 / x[k]),
                "gradient {k}: {} vs {}",
                ga[k],
                gb[k]
            );
        }
    }
}

#[test]
fn mismatched_parameter_count_or_grid_are_rejected() {
    let (sur, real) = surrogate(Coordinates::Physical, None);
    let k = sur.kriging().clone();
    let four = Domain::new(Domain::table_5_3(0.01).expect("domain").params()[..4].to_vec())
        .expect("domain");
    let err = KrigingSurrogate::new(
        k.clone(),
        four,
        real.times().to_vec(),
        Coordinates::Physical,
    )
    .expect_err("4 parameters for 5 inputs");
    assert!(
        err.to_string().contains("5 inputs") && err.to_string().contains("tau1"),
        "{err}"
    );
    let domain = Domain::table_5_3(0.01).expect("domain");
    let err =
        KrigingSurrogate::new(k, domain, vec![0.0, 1.0], Coordinates::Physical).expect_err("grid");
    assert!(err.to_string().contains("time grid"), "{err}");
}
