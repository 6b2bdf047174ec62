//! One multistart fit on the cheap analytic Lee–Radok model, and the cost
//! of one model evaluation. Run:
//! `cargo bench -p nlvid-inverse --bench multistart_fit`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_inverse::{
    Domain, Experiment, LeeRadokHertz, Misfit, Model, MultiStart, ramp_hold_grid,
    ramp_hold_indentation,
};

fn model(n_ramp: usize, n_hold: usize) -> LeeRadokHertz {
    let domain = Domain::prony2_table_5_3(0.01).expect("domain");
    let t = ramp_hold_grid(0.2, n_ramp, 52.0, n_hold, 1e-3).expect("grid");
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    LeeRadokHertz::new(domain, t, &delta, 2.5e-6, 0.5).expect("model")
}

fn noisy_misfit(m: LeeRadokHertz, x: &[f64]) -> Misfit<LeeRadokHertz> {
    let clean = m.response(x).expect("y");
    let peak = clean.iter().cloned().fold(0.0, f64::max);
    // deterministic pseudo-noise, ~2 % of the peak
    let data = clean
        .iter()
        .enumerate()
        .map(|(j, y)| y + 0.02 * peak * ((j as f64 * 12.9898).sin() * 43758.5453).fract())
        .collect();
    Misfit::new(vec![Experiment::new("RH", m, data, None).expect("e")]).expect("misfit")
}

fn bench(c: &mut Criterion) {
    let x = [650.0, 0.45, 0.08, 0.35, 9.0];
    for (label, n_ramp, n_hold) in [("m5095", 199, 4895), ("m401", 100, 300)] {
        let m = model(n_ramp, n_hold);
        c.bench_function(&format!("lee_radok_response_{label}"), |b| {
            b.iter(|| m.response(black_box(&x)).expect("y"))
        });
        c.bench_function(&format!("lee_radok_response_and_jacobian_{label}"), |b| {
            b.iter(|| m.response_and_jacobian(black_box(&x)).expect("yj"))
        });
        let misfit = noisy_misfit(m, &x);
        let ms = MultiStart::new().with_starts(8).expect("starts");
        let fit = ms.fit(&misfit).expect("fit");
        eprintln!(
            "{label}: one 8-start fit uses {} misfit evaluations; best misfit {:.4}",
            fit.evaluations, fit.best.misfit
        );
        let mut group = c.benchmark_group("multistart_fit");
        group.sample_size(10);
        group.bench_function(format!("lee_radok_8_starts_{label}"), |b| {
            b.iter(|| ms.fit(black_box(&misfit)).expect("fit"))
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
