//! Issue 5 "Done when": max checking RMSE (thesis eq. 4.4) ≤ 2 % with
//! N ≤ 300 on the 5-parameter cell domain (G0, g1, g2, τ1, τ2; g1 + g2 < 1),
//! here on the analytic Hertz–Prony ramp-hold model (exactly F ∝ G0, used
//! through `OutputScale`). The reference curves are the model's own runs
//! at 200 separate checking points, not the surrogate.
//!
//! `cargo test --release -p nlvid-surrogate --test it cell_domain_accuracy:: -- --ignored --nocapture`

#![allow(clippy::unwrap_used)]

use nlvid_surrogate::check::summarise;
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, OutputScale, Regression};

// The problem of the rmse_vs_n example, written once for both.
#[path = "../../examples/common/mod.rs"]
mod common;
use common::{cell_problem, kriging_inputs};

fn max_checking_error(n: usize, scale: bool) -> f64 {
    let (domain, train, check, yt, yc) = cell_problem(n).unwrap();
    let tr = |x: &Vec<f64>| kriging_inputs(&domain, x);
    let xm = Mat::from_fn(n, 5, |i, k| tr(&train[i])[k]);
    let ym = Mat::from_fn(n, 200, |i, j| yt[i][j]);
    let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
    s.pca_energy = Some(1.0 - 1e-10);
    if scale {
        s.output_scale = Some(OutputScale::Exp {
            input: 0,
            slope: 1.0,
        });
    }
    let km = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s).unwrap();
    let preds: Vec<Vec<f64>> = check.iter().map(|x| km.predict(&tr(x)).unwrap()).collect();
    let sm = summarise(&yc, &preds).unwrap();
    println!(
        "N = {n}, F/G0 {scale}: min {:.4} % median {:.4} % max {:.4} %",
        100.0 * sm.min,
        100.0 * sm.median,
        100.0 * sm.max
    );
    sm.max
}

#[test]
#[ignore = "N = 200 and 300 fits (≈ 10 s release): run with --release -- --ignored"]
fn max_checking_error_below_2_percent_with_300_runs_on_the_cell_domain() {
    // Measured: N = 200: 1.07 %, N = 300: 0.38 % (y without the structure:
    // 92.7 %, 37.0 %).
    assert!(max_checking_error(300, true) <= 0.02);
    assert!(max_checking_error(200, true) <= 0.02);
    // The structure is what does it: without it the max is far above 2 %.
    assert!(max_checking_error(300, false) > 0.05);
}
