//! Fixed inputs (issue 17, per-cell geometry): a model with a geometry
//! input beside the five Prony parameters, the geometry held at a known
//! value, fits exactly as the model with that value baked in; the wrapped
//! gradient and Jacobian agree with finite differences in the free
//! parameters.

#![allow(clippy::unwrap_used)]

use nalgebra::DMatrix;
use nlvid_inverse::{
    Experiment, Fixed, FixedInputs, LeeRadokHertz, Misfit, Model, MultiStart, Objective, Result,
    SensitivityScaling, fd_jacobian, identifiability, ramp_hold_grid, ramp_hold_indentation,
};
use nlvid_model::{Domain, Parameter, Scale};

/// The Lee–Radok ramp-hold model (F ∝ √R, eq. 1.1 with G(t) of eq. 5.1)
/// with the probe radius R as a 6th input: a geometry input whose effect
/// is known in closed form.
struct WithRadius {
    domain: Domain,
    prony: Domain,
    times: Vec<f64>,
    delta: Vec<f64>,
}

impl WithRadius {
    fn baked(&self, radius: f64) -> LeeRadokHertz {
        LeeRadokHertz::new(
            self.prony.clone(),
            self.times.clone(),
            &self.delta,
            radius,
            0.5,
        )
        .unwrap()
    }
}

impl Model for WithRadius {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.baked(x[5]).response(&x[..5])
    }
    /// The baked model's analytic Prony columns, and ∂F/∂R = F/(2R).
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>> {
        let m = self.baked(x[5]);
        let (y, j5) = m.response_and_jacobian(&x[..5])?;
        let mut j = DMatrix::zeros(y.len(), 6);
        j.columns_mut(0, 5).copy_from(&j5);
        for (r, v) in y.iter().enumerate() {
            j[(r, 5)] = v / (2.0 * x[5]);
        }
        Ok(j)
    }
}

fn setup() -> WithRadius {
    let prony = Domain::table_5_3(0.01).unwrap();
    let mut params = prony.params().to_vec();
    params.push(Parameter::new("R", "m", 1.5e-6, 3.5e-6, Scale::Linear));
    let domain = Domain::new(params)
        .unwrap()
        .with_sum_constraint(&["g1", "g2"], 0.99)
        .unwrap();
    let times = ramp_hold_grid(0.2, 30, 20.0, 60, 1e-3).unwrap();
    let delta = ramp_hold_indentation(&times, 10e-6, 2e-6);
    WithRadius {
        domain,
        prony,
        times,
        delta,
    }
}

const X_TRUE: [f64; 5] = [900.0, 0.45, 0.3, 0.08, 9.0];
const RADIUS: f64 = 2.2e-6;

#[test]
fn a_fit_with_the_radius_fixed_equals_the_fit_of_the_model_with_it_baked_in() {
    let model = setup();
    let data = model.baked(RADIUS).response(&X_TRUE).unwrap();
    let ms = MultiStart::new().with_starts(4).unwrap().with_seed(3);

    let baked = Misfit::new(vec![
        Experiment::new("baked", model.baked(RADIUS), data.clone(), None).unwrap(),
    ])
    .unwrap();
    let want = ms.fit(&baked).unwrap();

    let fixed = FixedInputs::new(model.domain(), &[("R", RADIUS)]).unwrap();
    assert_eq!(fixed.free_domain(), &Domain::table_5_3(0.01).unwrap());
    let full = Misfit::new(vec![
        Experiment::new("R input", setup(), data, None).unwrap(),
    ])
    .unwrap();
    let got = ms
        .fit(&Fixed::objective(full, fixed.clone()).unwrap())
        .unwrap();

    assert_eq!(got.domain, want.domain);
    // The same starts and the same path: equal up to rounding (the misfit
    // sums over a 6-column Jacobian in another order: 1e-14 relative seen).
    for (a, b) in got.best.x.iter().zip(&want.best.x) {
        assert!(
            (a - b).abs() <= 1e-10 * b.abs(),
            "{:?} vs {:?}",
            got.best.x,
            want.best.x
        );
    }
    // eq. 5.3 is range-normalised: an absolute 1e-12 is far below any fit
    assert!(
        (got.best.misfit - want.best.misfit).abs() <= 1e-12,
        "{} vs {}",
        got.best.misfit,
        want.best.misfit
    );
    assert_eq!(got.evaluations, want.evaluations);
    // and the truth is found (noise-free data)
    assert!(
        (got.best.x[0] / X_TRUE[0] - 1.0).abs() < 1e-3,
        "{:?}",
        got.best.x
    );

    // fixed at another radius, the fit must move G0 by √(R_true/R) (F ∝ G0 √R)
    let other = FixedInputs::new(model.domain(), &[("R", 2.0e-6)]).unwrap();
    let full = Misfit::new(vec![
        Experiment::new(
            "R input",
            setup(),
            model.baked(RADIUS).response(&X_TRUE).unwrap(),
            None,
        )
        .unwrap(),
    ])
    .unwrap();
    let moved = ms.fit(&Fixed::objective(full, other).unwrap()).unwrap();
    let expected = X_TRUE[0] * (RADIUS / 2.0e-6_f64).sqrt();
    assert!(
        (moved.best.x[0] / expected - 1.0).abs() < 1e-3,
        "G0 {} vs {expected}",
        moved.best.x[0]
    );
}

#[test]
fn fixed_gradient_and_jacobian_agree_with_finite_differences_in_the_free_parameters() {
    let model = setup();
    let data = model.baked(RADIUS).response(&X_TRUE).unwrap();
    let fixed = FixedInputs::new(model.domain(), &[("R", RADIUS), ("g2", 0.3)]).unwrap();
    // g1 + g2 <= 0.99 with g2 = 0.3 fixed: g1 <= 0.69 on the free set
    let free = fixed.free_domain();
    assert_eq!(free.names(), ["G0", "g1", "tau1", "tau2"]);
    let c = &free.constraints()[0];
    assert_eq!(c.coefficients, [0.0, 1.0, 0.0, 0.0]);
    assert!((c.rhs - 0.69).abs() < 1e-15);

    let x = [700.0, 0.35, 0.12, 7.0];
    let full = Misfit::new(vec![
        Experiment::new("R input", setup(), data, None).unwrap(),
    ])
    .unwrap();
    let obj = Fixed::objective(full, fixed.clone()).unwrap();
    let (v, g) = obj.value_and_gradient(&x).unwrap();
    assert_eq!(g.len(), 4);
    for (k, p) in free.params().iter().enumerate() {
        let h = 1e-6 * (p.upper - p.lower);
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        xp[k] += h;
        xm[k] -= h;
        let fd = (obj.value(&xp).unwrap() - obj.value(&xm).unwrap()) / (2.0 * h);
        assert!(
            (g[k] - fd).abs() <= 1e-5 * g[k].abs().max(v / (p.upper - p.lower)),
            "{}: gradient {} vs finite difference {fd}",
            p.name,
            g[k]
        );
    }

    let fm = Fixed::model(setup(), fixed.clone()).unwrap();
    let j = fm.jacobian(&x).unwrap();
    let jfd = fd_jacobian(&fm, &x).unwrap();
    assert_eq!((j.nrows(), j.ncols()), (model.times().len(), 4));
    let scale = j.amax();
    assert!((&j - &jfd).amax() <= 1e-5 * scale, "{}", (&j - &jfd).amax());
    // the response is the full model's at the expanded point
    assert_eq!(
        fm.response(&x).unwrap(),
        model.response(&fixed.expand(&x)).unwrap()
    );
    // Gauss–Newton intervals see the four free parameters only
    let data = model
        .baked(RADIUS)
        .response(&[700.0, 0.35, 0.3, 0.12, 7.0])
        .unwrap();
    let misfit = Misfit::new(vec![Experiment::new("fixed", fm, data, None).unwrap()]).unwrap();
    let id = identifiability(&misfit, &x, SensitivityScaling::Value).unwrap();
    assert_eq!(id.intervals.len(), 4);
}

#[test]
fn fixed_values_outside_the_range_or_unknown_names_are_refused_by_name() {
    let model = setup();
    let e = FixedInputs::new(model.domain(), &[("R", 5e-6)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("R = 5e-6") && e.contains("outside"), "{e}");
    let e = FixedInputs::new(model.domain(), &[("H", 1e-5)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("`H`") && e.contains("not an input"), "{e}");
    let e = FixedInputs::new(model.domain(), &[("R", 2e-6), ("R", 2e-6)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("twice"), "{e}");
    let none = FixedInputs::none(model.domain());
    assert_eq!(none.free_domain(), model.domain());
    assert_eq!(none.expand(&[1.0, 2.0]), [1.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
}
