//! Issue 6 "Done when": synthetic recovery through a surrogate built with
//! the library API of `nlvid build` (`nlvid_surrogate::build` into a run
//! store, `load`, `KrigingModel::fit`), on the Table 5.3 domain, over the
//! analytic Lee–Radok Hertz ramp-hold model (the FE AFM model is not ready,
//! so it stands in as the "real" forward model). Ten seeded cases with 2 %
//! Gaussian noise; the fit runs on the surrogate (fast `BasisMisfit`), then
//! the real model is re-run at the optimum (`verify`).
//!
//! The default test is small (N = 120 runs, m = 61 points) and checks the
//! machinery plus what a small surrogate can honestly promise; the full
//! size (N = 300, m = 261) is `#[ignore]`:
//! `cargo test --release -p nlvid-inverse --test it surrogate_recovery:: -- --ignored --nocapture`

use std::path::PathBuf;

use nlvid_inverse::{
    BasisExperiment, BasisMisfit, Coordinates, ForwardFromModel, KrigingSurrogate, LeeRadokHertz,
    Model, MultiStart, gram, range_normalised_rmse,
};
use nlvid_model::Domain;
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Admissibility, BuildOptions, Correlation, KrigingModel, KrigingSettings, OutputScale,
    Regression, build, load,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::common::{draw, lee_radok_ramp_hold, normal};

struct Outcome {
    passed: usize,
    agree: usize,
    reached: usize,
    max_checking_error: f64,
    lines: Vec<String>,
}

/// Build (store), load, Kriging fit in the domain's unit coordinates.
/// `g0_scale`: krige F/G0 (the force of this model is exactly ∝ G0;
/// `OutputScale::Exp` on G0's unit coordinate, slope ln(hi/lo)).
fn build_surrogate(
    name: &str,
    domain: &Domain,
    real: &LeeRadokHertz,
    n_sites: usize,
    g0_scale: bool,
) -> (KrigingSurrogate, f64) {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("nlvid-fit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let design = sample(
        domain,
        &SampleSettings {
            n: n_sites,
            seed: 20261122,
            optimise_iterations: 30,
        },
    )
    .expect("design");
    let forward = ForwardFromModel {
        model: real.clone(),
        identity: format!("lee-radok-hertz ramp-hold m={}", real.times().len()),
    };
    let summary = build(&forward, &design, &dir, &BuildOptions::default()).expect("build");
    assert_eq!(summary.failed, 0);
    let mm = load(&dir, &Admissibility::default()).expect("load");
    let _ = std::fs::remove_dir_all(&dir);
    let n = mm.x.len();
    let xu: Vec<Vec<f64>> = mm.x.iter().map(|x| domain.to_unit(x)).collect();
    let xm = Mat::from_fn(n, 5, |i, k| xu[i][k]);
    let ym = Mat::from_fn(n, mm.y[0].len(), |i, j| mm.y[i][j]);
    let mut settings = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
    if g0_scale {
        let input = mm
            .meta
            .parameter_names
            .iter()
            .position(|p| p == "G0")
            .expect("G0 is a surrogate input");
        let g0 = &domain.params()[domain.index_of("G0").expect("G0")];
        settings.output_scale = Some(OutputScale::Exp {
            input,
            slope: (g0.upper / g0.lower).ln(),
        });
    }
    let k = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &settings).expect("kriging");
    domain
        .check_names(&mm.meta.parameter_names)
        .expect("the store's parameters are the domain's");
    let sur = KrigingSurrogate::new(k, domain.clone(), mm.meta.time.clone(), Coordinates::Unit)
        .expect("adapter");
    // Checking error (eq. 4.4) on 40 independent points.
    let check = sample(
        domain,
        &SampleSettings {
            n: 40,
            seed: 77,
            optimise_iterations: 0,
        },
    )
    .expect("checking design");
    let worst = check
        .iter()
        .map(|x| {
            let yr = real.response(x).expect("real");
            let ys = sur.response(x).expect("surrogate");
            range_normalised_rmse(&ys, &yr, None).expect("rmse")
        })
        .fold(0.0, f64::max);
    (sur, worst)
}

fn recovery(name: &str, n_sites: usize, n_ramp: usize, n_hold: usize, g0_scale: bool) -> Outcome {
    let domain = Domain::table_5_3(0.01).expect("domain");
    let real = lee_radok_ramp_hold(&domain, n_ramp, n_hold);
    let (sur, max_checking_error) = build_surrogate(name, &domain, &real, n_sites, g0_scale);
    let g = gram(&sur, None).expect("gram");
    let mut rng = ChaCha8Rng::seed_from_u64(20261122);
    let mut noise_rng = ChaCha8Rng::seed_from_u64(6);
    let mut out = Outcome {
        passed: 0,
        agree: 0,
        reached: 0,
        max_checking_error,
        lines: vec![format!(
            "N = {n_sites}, m = {}, max checking error (eq. 4.4, 40 points) = {max_checking_error:.4}",
            real.times().len()
        )],
    };
    for case in 0..10u64 {
        let x_true = draw(&mut rng);
        let clean = real.response(&x_true).expect("clean");
        let peak = clean.iter().copied().fold(0.0, f64::max);
        // 2 % Gaussian noise: sigma = 0.02 * peak force, additive.
        let data: Vec<f64> = clean
            .iter()
            .map(|y| y + 0.02 * peak * normal(&mut noise_rng))
            .collect();
        let misfit = BasisMisfit::new(vec![
            BasisExperiment::new("RH", &sur, g.clone(), &data, None).expect("experiment"),
        ])
        .expect("misfit");
        let fit = MultiStart::new()
            .with_starts(8)
            .expect("starts")
            .with_seed(case)
            .fit(&misfit)
            .expect("fit");
        let x = &fit.best.x;
        let at_truth = nlvid_inverse::Objective::value(&misfit, &x_true).expect("truth");
        let real_misfit =
            range_normalised_rmse(&real.response(x).expect("rerun"), &data, None).expect("e");
        let g_true = nlvid_inverse::relaxation(&domain, &x_true).expect("g");
        let g_fit = nlvid_inverse::relaxation(&domain, x).expect("g");
        let e_g0 = (x[0] / x_true[0] - 1.0).abs();
        let e_sum = ((x[1] + x[2]) - (x_true[1] + x_true[2])).abs();
        let e_g52 = (g_fit.value(52.0) / g_true.value(52.0) - 1.0).abs();
        let ok = e_g0 <= 0.05 && e_sum <= 0.03 && e_g52 <= 0.05;
        let agrees = (fit.best.misfit - real_misfit).abs() <= max_checking_error;
        out.passed += usize::from(ok);
        out.agree += usize::from(agrees);
        out.reached += usize::from(fit.best.misfit <= at_truth * (1.0 + 1e-6));
        out.lines.push(format!(
            "case {case}: true {x_true:.4?} fit {x:.4?} | misfit surrogate {:.5} real {:.5} (surrogate at truth {:.5}) | dG0 {:.2}% d(g1+g2) {:.4} dG52 {:.2}% {}{}",
            fit.best.misfit,
            real_misfit,
            at_truth,
            100.0 * e_g0,
            e_sum,
            100.0 * e_g52,
            if ok { "ok" } else { "FAIL" },
            if fit.on_bound() { " (on bound)" } else { "" }
        ));
    }
    out.lines.push(format!(
        "{name}: recovered {}/10; surrogate vs real misfit within the checking error {}/10; optimiser at or below the truth's surrogate misfit {}/10; max checking error {:.1} %",
        out.passed,
        out.agree,
        out.reached,
        100.0 * out.max_checking_error
    ));
    println!("{}", out.lines.join("\n"));
    out
}

#[test]
fn small_surrogate_built_by_nlvid_build_fits_noisy_ramp_hold_curves() {
    let o = recovery("small", 120, 20, 40, false);
    let report = o.lines.join("\n");
    // The optimiser must find the surrogate's minimum (at or below the
    // surrogate misfit of the true parameters) in every case, and the
    // re-run misfit must agree with the surrogate one within the checking
    // error; the recovery count of a 120-run surrogate is only reported
    // (measured: 2/10, max checking error 22.5 %; 1/10 and 17.5 % before the
    // parameter order was unified, which reorders the design's columns), the 9/10 claim is
    // checked at full size (ignored test below).
    assert_eq!(o.reached, 10, "{report}");
    assert_eq!(o.agree, 10, "{report}");
}

#[test]
#[ignore = "full size (N = 300, m = 261): run with --release -- --ignored"]
fn surrogate_of_300_runs_recovers_g0_sum_and_g52_in_9_of_10_cases() {
    // Surrogate option: krige F/G0 (exact structure of this model).
    let o = recovery("full", 300, 60, 200, true);
    let report = o.lines.join("\n");
    assert_eq!(o.agree, 10, "{report}");
    assert!(o.passed >= 9, "only {}/10 recovered:\n{report}", o.passed);
}
