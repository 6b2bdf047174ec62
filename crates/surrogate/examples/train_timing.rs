//! One-shot timing of the full-size training problem of the issue:
//! N = 1000 sites, d = 5, m = 5095 outputs (Hertz–Prony responses), with
//! and without principal-component reduction, plus the cost of predicting
//! one curve.
//!
//! `cargo run --release -p nlvid-surrogate --example train_timing [-- N M]`

use std::time::Instant;

use nlvid_forward::HertzProny;
use nlvid_model::{Domain, ForwardModel};
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression, ThetaSearch};
use rayon::prelude::*;

mod common;
use common::kriging_inputs;

/// CPU time (user + system) of this process so far [s], from
/// /proc/self/stat (Linux; 0 elsewhere): wall time on a shared machine
/// depends on the other users' load, CPU time much less.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let Some(rest) = stat.rsplit(')').next() else {
        return 0.0;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 and 15 of stat (utime, stime) are 11 and 12 after the ')'.
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let n = args.first().copied().unwrap_or(1000);
    let m = args.get(1).copied().unwrap_or(5095);
    let domain = Domain::cell_study();
    let t0 = Instant::now();
    let design = sample(
        &domain,
        &SampleSettings {
            n,
            seed: 1,
            optimise_iterations: 5,
        },
    )?;
    let model = HertzProny::new(5e-6, 1e-6, 1.0, 10.0, m).expect("valid settings");
    let ys: Vec<Vec<f64>> = design
        .par_iter()
        .map(|x| model.run(x))
        .collect::<Result<_, _>>()?;
    println!(
        "design + {n} analytic runs (m = {m}): {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    let xs: Vec<Vec<f64>> = design.iter().map(|x| kriging_inputs(&domain, x)).collect();
    let xm = Mat::from_fn(n, 5, |i, k| xs[i][k]);
    let ym = Mat::from_fn(n, m, |i, j| ys[i][j]);
    let fixed = ThetaSearch::Fixed(vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.9]);
    // The default search: 4-start BFGS screened on 300 sites, then one
    // refinement (≤ 60 iterations) on all sites.
    let default = KrigingSettings::new(Regression::Poly1, Correlation::Expg, 5).theta;
    for (pca, search) in [
        (Some(1.0 - 1e-8), fixed.clone()),
        (None, fixed),
        (Some(1.0 - 1e-8), default.clone()),
        (None, default),
    ] {
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Expg, 5);
        s.theta = search;
        s.pca_energy = pca;
        let t0 = Instant::now();
        let c0 = cpu_seconds();
        let km = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s)?;
        let fit = t0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - c0;
        let reps = 200;
        let t1 = Instant::now();
        let mut acc = 0.0;
        for i in 0..reps {
            acc += km.predict(&xs[i % n])?[m / 2];
        }
        let per = t1.elapsed().as_secs_f64() / reps as f64;
        println!(
            "pca {:?} {}: fit {fit:.2} s wall, {cpu:.2} s CPU ({} evaluations, {} of them on the screening subset, {} kriged outputs, ψ = {:.4e}, θ = {:?}); predict one curve {:.3} ms [{acc:.3e}]",
            pca,
            km.report.search,
            km.report.evaluations,
            km.report.screen_evaluations,
            km.report.kriged_outputs,
            km.report.psi,
            km.theta,
            per * 1e3
        );
    }
    Ok(())
}
