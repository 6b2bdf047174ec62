//! Kriging benchmarks on Hertz–Prony responses (5 inputs):
//! * `predict_one_curve/N1000_m5095_pca`: predictor for one curve of
//!   m = 5095 points from a model trained on N = 1000 sites (target ≤ 1 ms);
//! * `predict_one_curve/N1000_m5095_full`: same without output reduction;
//! * `fit/N200_m500_*`: repeated training at a size criterion can repeat.
//!
//! The full-size training time (N = 1000, m = 5095) is measured once by
//! `cargo run --release -p nlvid-surrogate --example train_timing`.
//! Set NLVID_BENCH_N / NLVID_BENCH_M to change the prediction model size.

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_forward::HertzProny;
use nlvid_model::{Domain, ForwardModel};
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OptimiserSettings, Regression, ThetaSearch,
};

fn data(n: usize, m: usize) -> (Mat<f64>, Mat<f64>) {
    let domain = Domain::cell_study();
    let design = sample(
        &domain,
        &SampleSettings {
            n,
            seed: 1,
            optimise_iterations: 0,
        },
    )
    .expect("design");
    let model = HertzProny::new(5e-6, 1e-6, 1.0, 10.0, m).expect("valid settings");
    let ys: Vec<Vec<f64>> = design.iter().map(|x| model.run(x).expect("run")).collect();
    let x = Mat::from_fn(n, 5, |i, k| {
        if domain.params()[k].is_log() {
            design[i][k].ln()
        } else {
            design[i][k]
        }
    });
    (x, Mat::from_fn(n, m, |i, j| ys[i][j]))
}

fn env(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn bench_predict(c: &mut Criterion) {
    let (n, m) = (env("NLVID_BENCH_N", 1000), env("NLVID_BENCH_M", 5095));
    let (x, y) = data(n, m);
    let mut g = c.benchmark_group("predict_one_curve");
    for (label, pca) in [("pca", Some(1.0 - 1e-8)), ("full", None)] {
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Expg, 5);
        // θ search is not what is measured here: a few cheap iterations.
        s.theta = ThetaSearch::Optimise {
            theta0: vec![1.0, 1.0, 1.0, 1.0, 1.0, 1.9],
            lower: vec![1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 0.1],
            upper: vec![1e2, 1e2, 1e2, 1e2, 1e2, 2.0],
            settings: OptimiserSettings {
                starts: 1,
                max_iter: 3,
                screen_sites: 0,
                ..Default::default()
            },
        };
        s.pca_energy = pca;
        let model = KrigingModel::fit(x.as_ref(), y.as_ref(), &s).expect("fit");
        let p: Vec<f64> = (0..5).map(|k| x[(7, k)] * 0.999).collect();
        g.bench_function(format!("N{n}_m{m}_{label}"), |b| {
            b.iter(|| model.predict(std::hint::black_box(&p)).expect("predict"))
        });
    }
    g.finish();
}

fn bench_fit(c: &mut Criterion) {
    let (x, y) = data(200, 500);
    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    for (label, pca) in [("pca", Some(1.0 - 1e-8)), ("full", None)] {
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Expg, 5);
        s.pca_energy = pca;
        g.bench_function(format!("N200_m500_{label}"), |b| {
            b.iter(|| KrigingModel::fit(x.as_ref(), y.as_ref(), &s).expect("fit"))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_predict, bench_fit);
criterion_main!(benches);
