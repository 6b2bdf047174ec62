//! Issue 6 target "one fit on the surrogate ≤ 100 ms on one core" at the
//! thesis size (m = 5095 output times), with the reduced (PCA) misfit
//! (`SurrogateMisfit` → `ReducedMisfit`) against the previous path (Gram
//! form with its direct O(N·m) fallback, `BasisMisfit`).
//!
//! - `fe_N234_m5095/*`: the real FE meta-model /work/fe/fe.gauss.json (or
//!   `$NLVID_FE_MODEL`, with `$NLVID_FE_EXPORT`, default /work/fe/export,
//!   for meta.json and the first checking curve + 2 % noise); skipped with
//!   a message when the file is absent.
//! - `synthetic_N{234,900}_m5095/*`: always available — Lee–Radok ramp-hold
//!   runs (m = 5095) on an N-point design of Table 5.3, Kriging with the FE
//!   meta-model's settings (poly1, Gauss, outputs ∝ G0, ln G0, ln τ1,
//!   ln τ2, PCA 0.999999; θ fixed to the FE model's, no likelihood search,
//!   to keep the setup short).
//!
//! One "fit" = per-data-set setup + an 8-start SLSQP run (the per-surrogate
//! precomputation — QR of √W A, or the Gram matrix — is done once outside).
//! Single-threaded. Run: `cargo bench -p nlvid-inverse --bench fe_fit`
//! (filter e.g. `-- synthetic_N900`).

use std::cell::Cell;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_inverse::{
    BasisExperiment, BasisMisfit, BasisModel, Coordinates, FitResult, KrigingSurrogate,
    LeeRadokHertz, Model, MultiStart, Objective, Precomputed, ReducedModel, Result, SurrogateCurve,
    SurrogateMisfit, gram, ramp_hold_grid, ramp_hold_indentation, read_meta,
};
use nlvid_model::Domain;
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OutputScale, Regression, ThetaSearch,
};

/// Counts value-only and value+gradient calls of an objective.
struct Counting<'a, O> {
    inner: &'a O,
    values: Cell<usize>,
    gradients: Cell<usize>,
}

impl<O: Objective> Objective for Counting<'_, O> {
    fn domain(&self) -> &Domain {
        self.inner.domain()
    }
    fn value(&self, x: &[f64]) -> Result<f64> {
        self.values.set(self.values.get() + 1);
        self.inner.value(x)
    }
    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        self.gradients.set(self.gradients.get() + 1);
        self.inner.value_and_gradient(x)
    }
    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.inner.per_experiment(x)
    }
    fn final_value(&self, x: &[f64]) -> Result<f64> {
        self.inner.final_value(x)
    }
}

fn describe<O: Objective>(label: &str, o: &O, ms: &MultiStart) -> FitResult {
    let c = Counting {
        inner: o,
        values: Cell::new(0),
        gradients: Cell::new(0),
    };
    let t0 = Instant::now();
    let fit = ms.fit(&c).expect("fit");
    eprintln!(
        "{label}: {:.1} ms, {} value-only + {} value+gradient evaluations over 8 starts, misfit {:.6}, x {:.5?}",
        1e3 * t0.elapsed().as_secs_f64(),
        c.values.get(),
        c.gradients.get(),
        fit.best.misfit,
        fit.best.x
    );
    fit
}

fn bench_surrogate(c: &mut Criterion, name: &str, sur: &KrigingSurrogate, data: &[f64]) {
    let ms = MultiStart::new().with_starts(8).expect("starts");
    let t0 = Instant::now();
    let pre = Precomputed::new(sur, None).expect("precompute");
    eprintln!(
        "{name}: {} PCA components, reduced form precomputed (QR of √W A) in {:.1} ms",
        sur.kriging().n_kriged(),
        1e3 * t0.elapsed().as_secs_f64()
    );
    let reduced = || {
        SurrogateMisfit::new(&[SurrogateCurve {
            label: "RH",
            surrogate: sur,
            precomputed: &pre,
            data,
            weights: None,
        }])
        .expect("misfit")
    };
    let x = reduced_fit_point(sur);
    let fast = reduced();
    let a = describe(&format!("{name} reduced"), &fast, &ms);
    let mut group = c.benchmark_group(name);
    group.sample_size(20);
    group.bench_function("kriging_coordinates_c_and_dc", |b| {
        b.iter(|| ReducedModel::coordinates(sur, black_box(&x)).expect("c"))
    });
    group.bench_function("reduced_value_and_gradient", |b| {
        b.iter(|| fast.value_and_gradient(black_box(&x)).expect("vg"))
    });
    group.bench_function("reduced_8_starts", |b| {
        b.iter(|| ms.fit(black_box(&reduced())).expect("fit"))
    });
    // The previous path (N ≤ 300 only: the Gram matrix costs O(N²·m)).
    if sur.kriging().n_sites <= 300 {
        let t0 = Instant::now();
        let g = gram(sur, None).expect("gram");
        eprintln!(
            "{name}: Gram matrix in {:.0} ms",
            1e3 * t0.elapsed().as_secs_f64()
        );
        let basis = || {
            BasisMisfit::new(vec![
                BasisExperiment::new("RH", sur, g.clone(), data, None).expect("e"),
            ])
            .expect("m")
        };
        let old = basis();
        let b = describe(
            &format!("{name} previous (Gram + direct fallback)"),
            &old,
            &ms,
        );
        let rel = a
            .best
            .x
            .iter()
            .zip(&b.best.x)
            .map(|(p, q)| ((p - q) / q).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{name}: reduced vs previous optimum: max relative parameter difference {rel:.2e}, misfit difference {:.2e}",
            (a.best.misfit - b.best.misfit).abs()
        );
        // Where the previous path's time goes: φ(x), ∂φ/∂x (Kriging
        // correlations), ŷ = μ + Bᵀφ (reconstruction, O(N·m)), B(w ⊙ r)
        // for the gradient (O(N·m)).
        let (phi, _) = BasisModel::basis(sur, &x).expect("phi");
        let bm = BasisModel::coefficients(sur);
        group.bench_function("previous_kriging_basis_phi_and_dphi", |b| {
            b.iter(|| BasisModel::basis(sur, black_box(&x)).expect("phi"))
        });
        group.bench_function("previous_reconstruction_bt_phi", |b| {
            b.iter(|| bm.tr_mul(black_box(&phi)))
        });
        let r = bm.tr_mul(&phi);
        group.bench_function("previous_gradient_b_times_r", |b| {
            b.iter(|| bm * black_box(&r))
        });
        group.bench_function("previous_value_and_gradient", |b| {
            b.iter(|| old.value_and_gradient(black_box(&x)).expect("vg"))
        });
        group.sample_size(10);
        group.bench_function("previous_8_starts", |b| {
            b.iter(|| ms.fit(black_box(&basis())).expect("fit"))
        });
    }
    group.finish();
}

/// A point inside the domain for per-evaluation timings.
fn reduced_fit_point(sur: &KrigingSurrogate) -> Vec<f64> {
    let d = Model::domain(sur);
    d.from_unit(&vec![0.4; d.len()])
}

/// 2 % Gaussian-like deterministic noise of the peak.
fn noisy(clean: &[f64]) -> Vec<f64> {
    let peak = clean.iter().copied().fold(0.0, f64::max);
    clean
        .iter()
        .enumerate()
        .map(|(j, y)| {
            let u = ((j as f64 * 12.9898).sin() * 43758.5453).fract();
            y + 0.02 * peak * 2.0 * (u - 0.5) * 3f64.sqrt()
        })
        .collect()
}

fn real_file(c: &mut Criterion) {
    let model = std::env::var_os("NLVID_FE_MODEL")
        .map_or_else(|| PathBuf::from("/work/fe/fe.gauss.json"), PathBuf::from);
    let export = std::env::var_os("NLVID_FE_EXPORT")
        .map_or_else(|| PathBuf::from("/work/fe/export"), PathBuf::from);
    if !model.exists() {
        eprintln!(
            "fe_fit: {} not found (set NLVID_FE_MODEL): real-file bench skipped",
            model.display()
        );
        return;
    }
    let meta = read_meta(&export.join("train/meta.json")).expect("meta.json");
    let kriging: KrigingModel =
        serde_json::from_slice(&std::fs::read(&model).expect("read model")).expect("model JSON");
    let sur = KrigingSurrogate::new(kriging, meta.domain, meta.time_s, Coordinates::Physical)
        .expect("surrogate");
    let y = std::fs::read_to_string(export.join("check/Y.csv")).expect("check/Y.csv");
    let clean: Vec<f64> = y
        .lines()
        .nth(1)
        .expect("a checking curve")
        .split(',')
        .map(|v| v.trim().parse().expect("number"))
        .collect();
    let name = format!("fe_N{}_m{}", sur.kriging().n_sites, sur.kriging().n_outputs);
    bench_surrogate(c, &name, &sur, &noisy(&clean));
}

fn synthetic(c: &mut Criterion) {
    let domain = Domain::table_5_3(0.01).expect("domain");
    let t = ramp_hold_grid(0.2, 199, 52.0, 4895, 1e-3).expect("grid");
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    let real = LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5).expect("model");
    for n in [234, 900] {
        let t0 = Instant::now();
        let design = sample(
            &domain,
            &SampleSettings {
                n,
                seed: 7,
                optimise_iterations: 0,
            },
        )
        .expect("design");
        let ys: Vec<Vec<f64>> = design
            .iter()
            .map(|x| real.response(x).expect("run"))
            .collect();
        let xm = Mat::from_fn(n, 5, |i, k| design[i][k]);
        let ym = Mat::from_fn(n, ys[0].len(), |i, j| ys[i][j]);
        let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
        // Domain order G0, g1, g2, tau1, tau2; θ of the FE meta-model.
        s.theta = ThetaSearch::Fixed(vec![0.072, 0.039, 0.046, 0.108, 0.093]);
        s.pca_energy = Some(0.999999);
        s.output_scale = Some(OutputScale::Linear { input: 0 });
        s.log_inputs = vec![true, false, false, true, true];
        let k = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s).expect("kriging");
        let sur = KrigingSurrogate::new(
            k,
            domain.clone(),
            Model::times(&real).to_vec(),
            Coordinates::Physical,
        )
        .expect("surrogate");
        eprintln!(
            "synthetic N = {n}, m = {}: built in {:.1} s",
            Model::times(&real).len(),
            t0.elapsed().as_secs_f64()
        );
        let clean = real.response(&[650.0, 0.45, 0.35, 0.08, 9.0]).expect("y");
        let name = format!("synthetic_N{n}_m{}", Model::times(&real).len());
        bench_surrogate(c, &name, &sur, &noisy(&clean));
    }
}

criterion_group!(benches, real_file, synthetic);
criterion_main!(benches);
