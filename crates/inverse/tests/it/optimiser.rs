//! Multistart optimiser on analytic problems with known optima.

use nlvid_inverse::{Experiment, InverseError, Misfit, Model, MultiStart, Result, verify};
use nlvid_model::{BoundSide, Domain, Parameter, Scale};

/// y_j = x0 φ0(t_j) + x1 φ1(t_j): least squares with a closed-form answer.
struct Linear2 {
    domain: Domain,
    times: Vec<f64>,
    fail_above: Option<f64>,
}

impl Linear2 {
    fn new(upper: f64, constraint: Option<f64>) -> Self {
        let mut domain = Domain::new(vec![
            Parameter::new("a", "N", 0.0, upper, Scale::Linear),
            Parameter::new("b", "N", 0.0, upper, Scale::Linear),
        ])
        .expect("domain");
        if let Some(rhs) = constraint {
            domain = domain.with_sum_constraint(&["a", "b"], rhs).expect("c");
        }
        Self {
            domain,
            times: (0..50).map(|j| j as f64 * 0.1).collect(),
            fail_above: None,
        }
    }
    fn phi(t: f64) -> (f64, f64) {
        (1.0 - (-t).exp(), (0.7 * t).sin() + 0.2)
    }
}

impl Model for Linear2 {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        if let Some(limit) = self.fail_above
            && x[0] > limit
        {
            return Err(InverseError::Model {
                x: x.to_vec(),
                message: "synthetic failure".into(),
            });
        }
        Ok(self
            .times
            .iter()
            .map(|&t| {
                let (p0, p1) = Self::phi(t);
                x[0] * p0 + x[1] * p1
            })
            .collect())
    }
}

fn data_with_wiggle(m: &Linear2, x: &[f64]) -> Vec<f64> {
    m.response(x)
        .expect("y")
        .iter()
        .enumerate()
        .map(|(j, y)| y + 0.05 * ((j as f64) * 1.3).cos())
        .collect()
}

#[test]
fn constrained_least_squares_optimum_matches_closed_form() {
    // Unconstrained optimum near (0.9, 0.6) violates a + b <= 1; the
    // constrained optimum lies on a + b = 1 with
    // a* = <φ0 - φ1, d - φ1> / |φ0 - φ1|².
    let m = Linear2::new(2.0, Some(1.0));
    let d = data_with_wiggle(&m, &[0.9, 0.6]);
    let (mut num, mut den) = (0.0, 0.0);
    for (j, &t) in m.times.iter().enumerate() {
        let (p0, p1) = Linear2::phi(t);
        num += (p0 - p1) * (d[j] - p1);
        den += (p0 - p1) * (p0 - p1);
    }
    let a_star = num / den;
    let misfit = Misfit::new(vec![Experiment::new("lin", m, d, None).expect("e")]).expect("m");
    let fit = MultiStart::new()
        .with_starts(4)
        .expect("s")
        .with_seed(1)
        .fit(&misfit)
        .expect("fit");
    let x = &fit.best.x;
    assert!((x[0] - a_star).abs() < 1e-5, "{x:?} vs a* = {a_star}");
    assert!((x[0] + x[1] - 1.0).abs() < 1e-8);
    assert!(fit.to_string().contains("constraint a + b <= 1 is active"));
    assert_eq!(fit.best.active_constraints, vec!["a + b <= 1".to_string()]);
    assert!(!fit.on_bound());
    assert!(fit.alternatives.is_empty());
    assert_eq!(
        fit.best.starts, 4,
        "all starts reach the one convex optimum"
    );
}

#[test]
fn optimum_outside_the_domain_is_flagged_on_its_bound() {
    let m = Linear2::new(1.0, None);
    let d = m.response(&[1.4, 0.3]).expect("d");
    let misfit = Misfit::new(vec![Experiment::new("lin", m, d, None).expect("e")]).expect("m");
    let fit = MultiStart::new()
        .with_starts(3)
        .expect("s")
        .fit(&misfit)
        .expect("fit");
    assert!(fit.on_bound());
    let printed = fit.to_string();
    assert!(printed.contains("a is on its upper bound"), "{printed}");
    assert!(printed.contains("a = 1.000000e0 N"), "{printed}");
    assert_eq!(fit.best.on_bounds.len(), 1);
    assert_eq!(fit.best.on_bounds[0].name, "a");
    assert_eq!(fit.best.on_bounds[0].side, BoundSide::Upper);
    assert!((fit.best.x[0] - 1.0).abs() < 1e-9);
}

/// y = e^{-a t} + e^{-b t}: (a, b) and (b, a) fit equally well.
struct Symmetric {
    domain: Domain,
    times: Vec<f64>,
}

impl Model for Symmetric {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn response(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self
            .times
            .iter()
            .map(|&t| (-x[0] * t).exp() + (-x[1] * t).exp())
            .collect())
    }
}

#[test]
fn mirror_optima_with_equal_misfit_are_both_reported() {
    let m = Symmetric {
        domain: Domain::new(vec![
            Parameter::new("a", "1/s", 0.1, 10.0, Scale::Log),
            Parameter::new("b", "1/s", 0.1, 10.0, Scale::Log),
        ])
        .expect("domain"),
        times: (0..80).map(|j| j as f64 * 0.05).collect(),
    };
    let d = m.response(&[0.5, 4.0]).expect("d");
    let misfit = Misfit::new(vec![Experiment::new("sym", m, d, None).expect("e")]).expect("m");
    let fit = MultiStart::new()
        .with_starts(12)
        .expect("s")
        .with_seed(3)
        .fit(&misfit)
        .expect("fit");
    assert!(fit.best.misfit < 1e-6, "{}", fit.best.misfit);
    let mut pts = vec![fit.best.x.clone()];
    pts.extend(fit.alternatives.iter().map(|a| a.x.clone()));
    let has = |a: f64, b: f64| {
        pts.iter()
            .any(|x| (x[0] - a).abs() < 1e-3 * a && (x[1] - b).abs() < 1e-3 * b)
    };
    assert!(has(0.5, 4.0) && has(4.0, 0.5), "{pts:?}");
    assert!(
        fit.to_string()
            .contains("other distinct optima fit almost as well")
    );
}

#[test]
fn model_failures_are_reported_per_start_and_as_no_convergence_when_all_fail() {
    let mut m = Linear2::new(2.0, None);
    let d = data_with_wiggle(&m, &[0.9, 0.6]);
    m.fail_above = Some(-1.0); // fails everywhere
    let misfit =
        Misfit::new(vec![Experiment::new("lin", m, d.clone(), None).expect("e")]).expect("m");
    let e = MultiStart::new()
        .with_starts(2)
        .expect("s")
        .fit(&misfit)
        .expect_err("fails");
    assert!(
        matches!(e, InverseError::NoConvergence { starts: 2, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("synthetic failure"));

    let mut m = Linear2::new(2.0, None);
    m.fail_above = Some(1.5); // only starts wandering above a = 1.5 fail
    let misfit = Misfit::new(vec![Experiment::new("lin", m, d, None).expect("e")]).expect("m");
    let fit = MultiStart::new()
        .with_starts(6)
        .expect("s")
        .fit(&misfit)
        .expect("fit");
    assert!(fit.best.misfit.is_finite());
    assert_eq!(fit.starts, 6);
}

#[test]
fn verification_reports_both_misfits() {
    let m = Linear2::new(2.0, None);
    let d = data_with_wiggle(&m, &[0.9, 0.6]);
    let a = Misfit::new(vec![Experiment::new("lin", m, d.clone(), None).expect("e")]).expect("m");
    let m2 = Linear2::new(2.0, None);
    let b = Misfit::new(vec![Experiment::new("lin", m2, d, None).expect("e")]).expect("m");
    let v = verify(&a, &b, &[0.9, 0.6]).expect("v");
    assert_eq!(v.fitted, v.rerun);
    assert!(v.fitted[0] > 0.0);
    assert!(v.agrees_within(0.0));
    // a "real" model that differs: the misfits differ by a known amount
    let m3 = Linear2::new(2.0, None);
    let d3 = m3.response(&[0.9, 0.6]).expect("d");
    let exact = Misfit::new(vec![
        Experiment::new("lin", m3, d3.clone(), None).expect("e"),
    ])
    .expect("m");
    let m4 = Linear2::new(2.0, None);
    let shifted: Vec<f64> = d3.iter().map(|v| v + 0.01).collect();
    let off = Misfit::new(vec![Experiment::new("lin", m4, shifted, None).expect("e")]).expect("m");
    let v = verify(&exact, &off, &[0.9, 0.6]).expect("v");
    let range = d3.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - d3.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!((v.max_difference() - 0.01 / range).abs() < 1e-12);
    assert!(v.agrees_within(0.011 / range) && !v.agrees_within(0.009 / range));
}

#[test]
fn invalid_settings_are_rejected() {
    assert!(MultiStart::new().with_starts(0).is_err());
    assert!(MultiStart::new().with_max_evals(3).is_err());
    assert!(MultiStart::new().with_cluster_radius(0.0).is_err());
    assert!(MultiStart::new().with_misfit_tolerance(f64::NAN).is_err());
    assert!(MultiStart::new().with_bound_tolerance(0.5).is_err());
    assert!(MultiStart::new().with_ftol_rel(-1.0).is_err());
}
