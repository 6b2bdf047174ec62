//! Identifiability analysis against independent references.

use nlvid_inverse::{Experiment, Misfit, Model, Result, SensitivityScaling, Z95, identifiability};
use nlvid_model::{Domain, Parameter, Scale};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// y = a e^{-t/b} + c: identifiable; or y = a·b·f(t): only the product is.
struct Toy {
    domain: Domain,
    times: Vec<f64>,
    product_only: bool,
}

impl Toy {
    fn new(product_only: bool) -> Self {
        Self {
            domain: Domain::new(vec![
                Parameter::new("a", "N", 0.1, 10.0, Scale::Log),
                Parameter::new("b", "s", 0.1, 10.0, Scale::Log),
                Parameter::new("c", "N", 0.0, 5.0, Scale::Linear),
            ])
            .expect("domain"),
            times: (0..200).map(|j| j as f64 * 0.05).collect(),
            product_only,
        }
    }
}

impl Model for Toy {
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
            .map(|&t| {
                if self.product_only {
                    x[0] * x[1] * (-t).exp() + x[2] * t
                } else {
                    x[0] * (-t / x[1]).exp() + x[2]
                }
            })
            .collect())
    }
}

fn noisy(m: &Toy, x: &[f64], sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    m.response(x)
        .expect("y")
        .iter()
        .map(|y| {
            let u1: f64 = 1.0 - rng.random::<f64>();
            let u2: f64 = rng.random();
            y + sigma * (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        })
        .collect()
}

#[test]
fn product_only_model_shows_a_tiny_singular_value_and_unbounded_intervals() {
    let m = Toy::new(true);
    let x = [2.0, 3.0, 0.5];
    let d = noisy(&m, &x, 0.05, 1);
    let misfit = Misfit::new(vec![Experiment::new("toy", m, d, None).expect("e")]).expect("m");
    let id = identifiability(&misfit, &x, SensitivityScaling::Value).expect("id");
    let sv = &id.singular_values;
    assert!(sv[2] < 1e-10 * sv[0], "{sv:?}");
    assert!(id.condition_number > 1e10);
    // the null direction is d ln a = -d ln b (scaled by value): (1, -1, 0)/√2
    let null = &id.directions[2];
    assert!(
        (null[0] + null[1]).abs() < 1e-6 && null[2].abs() < 1e-6,
        "{null:?}"
    );
    let w = id.relative_half_widths();
    assert!(
        w[0] > 1e3 && w[1] > 1e3,
        "a, b intervals must be huge: {w:?}"
    );
    assert!(w[2] < 0.2, "c stays identifiable: {w:?}");
}

#[test]
fn intervals_match_the_gauss_newton_formula_computed_independently() {
    // Independent reference: form JᵀJ by hand from the closed-form
    // derivatives of y = a e^{-t/b} + c, invert the 3x3 matrix by cofactors.
    let m = Toy::new(false);
    let x = [2.0, 1.5, 0.7];
    let d = noisy(&m, &x, 0.02, 2);
    let range = d.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - d.iter().cloned().fold(f64::INFINITY, f64::min);
    let times = m.times.clone();
    let misfit =
        Misfit::new(vec![Experiment::new("toy", m, d.clone(), None).expect("e")]).expect("m");
    let id = identifiability(&misfit, &x, SensitivityScaling::Range).expect("id");

    let mut jtj = [[0.0f64; 3]; 3];
    let mut ssr = 0.0;
    for (j, &t) in times.iter().enumerate() {
        let e = (-t / x[1]).exp();
        let g = [e / range, x[0] * e * t / (x[1] * x[1]) / range, 1.0 / range];
        for p in 0..3 {
            for q in 0..3 {
                jtj[p][q] += g[p] * g[q];
            }
        }
        ssr += ((x[0] * e + x[2] - d[j]) / range).powi(2);
    }
    let s2 = ssr / (times.len() - 3) as f64;
    let a = jtj;
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    let inv_diag = [
        (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / det,
        (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / det,
        (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / det,
    ];
    assert!((id.residual_variance - s2).abs() < 1e-12 * s2);
    for k in 0..3 {
        let se = (s2 * inv_diag[k]).sqrt();
        assert!(
            (id.std_errors[k] - se).abs() < 1e-6 * se,
            "k = {k}: {} vs {se}",
            id.std_errors[k]
        );
        assert!((id.intervals[k].1 - (x[k] + Z95 * se)).abs() < 1e-6 * se);
    }
    assert!(id.condition_number.is_finite());
}

#[test]
fn ninety_five_percent_intervals_cover_the_truth_about_95_percent_of_the_time() {
    // 200 noise realisations, each fitted by the multistart optimiser; the
    // binomial sd of the coverage at p = 0.95 is 1.5 %, accept 0.90 ... 0.99.
    use nlvid_inverse::MultiStart;
    let x_true = [2.0, 1.5, 0.7];
    let ms = MultiStart::new().with_starts(2).expect("s");
    let mut covered = [0usize; 3];
    let n = 200;
    for seed in 0..n {
        let m = Toy::new(false);
        let d = noisy(&m, &x_true, 0.05, 100 + seed);
        let misfit = Misfit::new(vec![Experiment::new("toy", m, d, None).expect("e")]).expect("m");
        let fit = ms.fit(&misfit).expect("fit");
        let id = identifiability(&misfit, &fit.best.x, SensitivityScaling::Value).expect("id");
        for k in 0..3 {
            let (lo, hi) = id.intervals[k];
            covered[k] += usize::from(lo <= x_true[k] && x_true[k] <= hi);
        }
    }
    for (k, c) in covered.iter().enumerate() {
        let p = *c as f64 / n as f64;
        println!("parameter {k}: coverage {p}");
        assert!((0.90..=0.99).contains(&p), "parameter {k}: coverage {p}");
    }
}
