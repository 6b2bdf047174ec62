//! Issue 6 target: one fit on the surrogate ≤ 100 ms on one core. A real
//! Kriging surrogate (N = 300 Lee–Radok ramp-hold runs on the Table 5.3
//! domain, m = 261 time points, θ by maximum likelihood) wrapped by
//! `KrigingSurrogate`; one fit = per-data-set setup (h, k) + an 8-start
//! SLSQP run on the O(N²) misfit. The inverse crate runs single-threaded.
//! Run: `cargo bench -p nlvid-inverse --bench surrogate_fit`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_inverse::{
    BasisExperiment, BasisMisfit, Coordinates, KrigingSurrogate, LeeRadokHertz, Model, MultiStart,
    gram, ramp_hold_grid, ramp_hold_indentation,
};
use nlvid_model::Domain;
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression};

fn setup() -> (KrigingSurrogate, Vec<f64>) {
    let domain = Domain::table_5_3(0.01).expect("domain");
    let t = ramp_hold_grid(0.2, 60, 52.0, 200, 1e-3).expect("grid");
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    let real = LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5).expect("model");
    let design = sample(
        &domain,
        &SampleSettings {
            n: 300,
            seed: 20261122,
            optimise_iterations: 30,
        },
    )
    .expect("design");
    let xu: Vec<Vec<f64>> = design.iter().map(|x| domain.to_unit(x)).collect();
    let ys: Vec<Vec<f64>> = design
        .iter()
        .map(|x| real.response(x).expect("run"))
        .collect();
    let xm = Mat::from_fn(xu.len(), 5, |i, k| xu[i][k]);
    let ym = Mat::from_fn(ys.len(), ys[0].len(), |i, j| ys[i][j]);
    let settings = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
    let k = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &settings).expect("kriging");
    let sur = KrigingSurrogate::new(k, domain, real.times().to_vec(), Coordinates::Unit)
        .expect("adapter");
    let clean = real.response(&[650.0, 0.45, 0.35, 0.08, 9.0]).expect("y");
    let peak = clean.iter().copied().fold(0.0, f64::max);
    let data = clean
        .iter()
        .enumerate()
        .map(|(j, y)| y + 0.02 * peak * (((j as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5))
        .collect();
    (sur, data)
}

fn bench(c: &mut Criterion) {
    let (sur, data) = setup();
    let g = gram(&sur, None).expect("gram");
    let ms = MultiStart::new().with_starts(8).expect("starts");
    let fit_once = || {
        let misfit = BasisMisfit::new(vec![
            BasisExperiment::new("RH", &sur, g.clone(), &data, None).expect("e"),
        ])
        .expect("m");
        ms.fit(&misfit).expect("fit")
    };
    let f = fit_once();
    eprintln!(
        "surrogate N = 300, m = 261: 8-start fit, {} evaluations, misfit {:.4}",
        f.evaluations, f.best.misfit
    );
    let mut group = c.benchmark_group("surrogate_fit");
    group.sample_size(10);
    group.bench_function("kriging_N300_m261_8_starts", |b| {
        b.iter(|| black_box(fit_once()))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
