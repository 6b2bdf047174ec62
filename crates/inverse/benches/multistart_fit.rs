//! One multistart fit on the cheap analytic Lee–Radok model, and the cost
//! of one model evaluation. Run:
//! `cargo bench -p nlvid-inverse --bench multistart_fit`

use std::hint::black_box;

use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector};
use nlvid_inverse::{
    AsModel, BasisExperiment, BasisMisfit, BasisModel, Experiment, LeeRadokHertz, Misfit, Model,
    MultiStart, Objective, Result, gram, ramp_hold_grid, ramp_hold_indentation,
};
use nlvid_model::Domain;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Surrogate-sized stand-in for a DACE predictor: φ = [1, exp(-θ|u - s_i|²)]
/// over N sites, random coefficients B ((N + 1) × m).
struct Kernel {
    domain: Domain,
    times: Vec<f64>,
    sites: Vec<Vec<f64>>,
    b: DMatrix<f64>,
    mu: Vec<f64>,
}

impl Kernel {
    fn new(n_sites: usize, m: usize) -> Self {
        let domain = Domain::table_5_3(0.01).expect("domain");
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let sites = (0..n_sites)
            .map(|_| (0..5).map(|_| rng.random::<f64>()).collect())
            .collect();
        let b = DMatrix::from_fn(n_sites + 1, m, |_, _| rng.random::<f64>() - 0.5);
        Self {
            domain,
            times: (0..m).map(|j| j as f64 * 0.01).collect(),
            sites,
            b,
            mu: (0..m).map(|j| (j as f64 * 0.003).sin()).collect(),
        }
    }
}

impl BasisModel for Kernel {
    fn domain(&self) -> &Domain {
        &self.domain
    }
    fn times(&self) -> &[f64] {
        &self.times
    }
    fn basis(&self, x: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let u = self.domain.to_unit(x);
        let du_dx: Vec<f64> = self
            .domain
            .params()
            .iter()
            .zip(&u)
            .map(|(p, &ui)| 1.0 / p.dx_du(ui))
            .collect();
        let n = self.sites.len() + 1;
        let mut phi = DVector::zeros(n);
        let mut dphi = DMatrix::zeros(n, 5);
        phi[0] = 1.0;
        for (i, s) in self.sites.iter().enumerate() {
            let d2: f64 = u.iter().zip(s).map(|(a, b)| (a - b) * (a - b)).sum();
            let r = (-4.0 * d2).exp();
            phi[i + 1] = r;
            for k in 0..5 {
                dphi[(i + 1, k)] = -8.0 * (u[k] - s[k]) * r * du_dx[k];
            }
        }
        Ok((phi, dphi))
    }
    fn coefficients(&self) -> &DMatrix<f64> {
        &self.b
    }
    fn offset(&self) -> &[f64] {
        &self.mu
    }
}

fn bench_surrogate_sized(c: &mut Criterion) {
    // DACE sizes of §5.4.1: N = 970 training sites, m = 5095 time points.
    let k = Kernel::new(970, 5095);
    let x = [650.0, 0.45, 0.35, 0.08, 9.0];
    let clean = AsModel(&k).response(&x).expect("y");
    let range = clean.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - clean.iter().cloned().fold(f64::INFINITY, f64::min);
    let data: Vec<f64> = clean
        .iter()
        .enumerate()
        .map(|(j, y)| y + 0.02 * range * ((j as f64 * 12.9898).sin() * 43758.5453).fract())
        .collect();
    let start = Instant::now();
    let g = gram(&k, None).expect("gram");
    eprintln!(
        "kernel N = 970, m = 5095: Gram matrix B Bᵀ in {:.2} s (once per surrogate and weights)",
        start.elapsed().as_secs_f64()
    );
    let start = Instant::now();
    let fast = BasisMisfit::new(vec![
        BasisExperiment::new("RH", &k, g, &data, None).expect("e"),
    ])
    .expect("m");
    eprintln!(
        "per data set (h, k): {:.1} ms",
        1e3 * start.elapsed().as_secs_f64()
    );
    let direct = Misfit::new(vec![
        Experiment::new("RH", AsModel(&k), data, None).expect("e"),
    ])
    .expect("m");
    c.bench_function("kernel_N970_m5095_direct_value_and_gradient", |b| {
        b.iter(|| direct.value_and_gradient(black_box(&x)).expect("vg"))
    });
    c.bench_function("kernel_N970_m5095_gram_value_and_gradient", |b| {
        b.iter(|| Objective::value_and_gradient(&fast, black_box(&x)).expect("vg"))
    });
    for starts in [4, 8] {
        let ms = MultiStart::new().with_starts(starts).expect("starts");
        let fit = ms.fit(&fast).expect("fit");
        eprintln!(
            "kernel gram fit, {starts} starts: {} evaluations, misfit {:.4}",
            fit.evaluations, fit.best.misfit
        );
        let mut group = c.benchmark_group("multistart_fit");
        group.sample_size(10);
        group.bench_function(format!("kernel_N970_m5095_gram_{starts}_starts"), |b| {
            b.iter(|| ms.fit(black_box(&fast)).expect("fit"))
        });
        group.finish();
    }
}

fn model(n_ramp: usize, n_hold: usize) -> LeeRadokHertz {
    let domain = Domain::table_5_3(0.01).expect("domain");
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
    let x = [650.0, 0.45, 0.35, 0.08, 9.0];
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

criterion_group!(benches, bench, bench_surrogate_sized);
criterion_main!(benches);
