//! The default θ search on a design large enough to be screened on a
//! subset: the result must be a stationary point of the full likelihood
//! (checked by central differences of ψ computed by `likelihood_psi`, not
//! by the optimiser's analytic gradient) and about as good as the
//! unscreened multistart.

#![allow(clippy::unwrap_used)]

use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OptimiserSettings, Regression, ThetaSearch,
    likelihood_psi,
};

fn data() -> (Mat<f64>, Mat<f64>) {
    let n = 150;
    // Halton-like scattered sites in [0, 1]².
    let radical = |mut i: usize, b: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= b as f64;
            r += f * (i % b) as f64;
            i /= b;
        }
        r
    };
    let x = Mat::from_fn(n, 2, |i, k| radical(i + 1, [2, 3][k]));
    let y = Mat::from_fn(n, 2, |i, j| {
        let (a, b) = (x[(i, 0)], x[(i, 1)]);
        match j {
            0 => (9.0 * a).sin() * (7.0 * b).cos() + 0.5 * b * b,
            _ => (11.0 * b).cos() * (1.0 + a) + (13.0 * a * b).sin(),
        }
    });
    (x, y)
}

fn search(screen_sites: usize) -> ThetaSearch {
    ThetaSearch::Optimise {
        theta0: vec![1.0, 1.0],
        lower: vec![1e-3, 1e-3],
        upper: vec![1e2, 1e2],
        settings: OptimiserSettings {
            screen_sites,
            ..Default::default()
        },
    }
}

#[test]
fn screened_search_ends_at_a_stationary_point_of_the_full_likelihood() {
    let (x, y) = data();
    let mut set = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 2);
    set.auto_nugget = false;
    set.theta = search(40);
    let screened = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
    assert_eq!(screened.report.search, "optimise (screened)");
    set.theta = search(0);
    let full = KrigingModel::fit(x.as_ref(), y.as_ref(), &set).unwrap();
    assert_eq!(full.report.search, "optimise");
    let psi = |t: &[f64]| {
        likelihood_psi(
            x.as_ref(),
            y.as_ref(),
            Regression::Poly1,
            Correlation::Gauss,
            t,
        )
        .unwrap()
        .ln()
    };
    let t = screened.theta.clone();
    // R is ill conditioned at the optimum (cond ~1e11): ln ψ carries
    // rounding noise ~1e-5, so the difference step is 1e-2 (truncation
    // error ~1e-4 here) and the tolerance 1e-2.
    for k in 0..2 {
        let h = 1e-2;
        let (mut tp, mut tm) = (t.clone(), t.clone());
        tp[k] *= f64::exp(h);
        tm[k] *= f64::exp(-h);
        let g = (psi(&tp) - psi(&tm)) / (2.0 * h);
        let at_bound = t[k] <= 1e-3 * 1.000001 || t[k] >= 1e2 * 0.999999;
        assert!(at_bound || g.abs() < 1e-2, "∂lnψ/∂lnθ{k} = {g} at {t:?}");
    }
    // ψ as computed independently from the returned θ, and no worse than
    // the unscreened multistart by more than 0.1 %.
    assert!((psi(&t) - screened.report.psi.ln()).abs() < 1e-10);
    assert!(
        screened.report.psi <= full.report.psi * 1.001,
        "screened ψ {} vs full {}",
        screened.report.psi,
        full.report.psi
    );
}
