//! Issue 6's recovery criterion on the finite-element AFM model: fit noisy
//! FE curves on a Kriging surrogate of FE runs, then re-run the FE model at
//! each optimum.
//!
//! The "data" are the first `CASES` admissible runs of the meta-model's
//! *checking* set (FE runs at known parameters that the surrogate never saw),
//! with 2 % Gaussian noise (σ = 0.02 · peak force, seeded). A case is
//! recovered when G0 is within 5 %, g1 + g2 within 0.03 and G(52 s) within
//! 5 % of the truth. The FE model is rebuilt from the same study file and
//! run at every optimum, so the surrogate misfit can be compared with the
//! real one. The fit uses the reduced (PCA) eq. 5.3 misfit
//! (`SurrogateMisfit`); the previous Gram-form fit is run as well and the
//! two optima are compared per case.
//!
//! ```sh
//! nlvid build examples/metamodel/afm-fe-setup1.toml --store S --export E
//! nlvid surrogate fit --x E/train/X.csv --y E/train/Y.csv --proportional-to G0 \
//!     --log-inputs G0,tau1,tau2 --out fe.model.json
//! cargo run --release -p nlvid-inverse --example fe_recovery -- \
//!     examples/metamodel/afm-fe-setup1.toml fe.model.json E
//! ```

use std::path::Path;

use anyhow::bail;
use nlvid_inverse::{
    BasisExperiment, BasisMisfit, Model, MultiStart, Objective, Precomputed, SurrogateCurve,
    SurrogateMisfit, gram, range_normalised_rmse,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

mod recovery;

use recovery::normal;

const CASES: usize = 10;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        bail!("usage: fe_recovery STUDY.toml MODEL.json EXPORT_DIR");
    }
    let (study_path, model_path, export) = (&args[1], &args[2], Path::new(&args[3]));

    let recovery::Setup {
        fe,
        domain,
        sur,
        xs,
        ys,
    } = recovery::setup(study_path, model_path, export, CASES)?;
    // The fit uses the reduced (PCA) misfit when the surrogate is
    // PCA-reduced; the previous Gram-form path is run too, to compare optima.
    let pre = Precomputed::new(&sur, None)?;
    let g = gram(&sur, None)?;

    let mut noise_rng = ChaCha8Rng::seed_from_u64(6);
    let (mut passed, mut agree, mut reached) = (0, 0, 0);
    let mut max_check: f64 = 0.0;
    for (x, y) in xs.iter().zip(&ys) {
        let e = range_normalised_rmse(&sur.response(x)?, y, None)?;
        max_check = max_check.max(e);
    }
    println!(
        "checking set: {} runs, max eq. 4.4 error {:.3} %",
        xs.len(),
        100.0 * max_check
    );
    for (case, (x, clean)) in xs.iter().zip(&ys).take(CASES).enumerate() {
        let x_true = x.clone();
        let peak = clean.iter().copied().fold(0.0, f64::max);
        let data: Vec<f64> = clean
            .iter()
            .map(|y| y + 0.02 * peak * normal(&mut noise_rng))
            .collect();
        let misfit = SurrogateMisfit::new(&[SurrogateCurve {
            label: "FE",
            surrogate: &sur,
            precomputed: &pre,
            data: &data,
            weights: None,
        }])?;
        let ms = MultiStart::new().with_starts(8)?.with_seed(case as u64);
        let t0 = std::time::Instant::now();
        let fit = ms.fit(&misfit)?;
        let fit_ms = 1e3 * t0.elapsed().as_secs_f64();
        let previous = BasisMisfit::new(vec![BasisExperiment::new(
            "FE",
            &sur,
            g.clone(),
            &data,
            None,
        )?])?;
        let t0 = std::time::Instant::now();
        let old = ms.fit(&previous)?;
        let old_ms = 1e3 * t0.elapsed().as_secs_f64();
        let max_rel = fit
            .best
            .x
            .iter()
            .zip(&old.best.x)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        println!(
            "case {case}: reduced fit {fit_ms:.1} ms ({} evaluations), previous Gram-form fit {old_ms:.1} ms ({} evaluations); optima differ by {max_rel:.2e} (max relative parameter), misfits {:.12} vs {:.12} (difference {:.1e}){}",
            fit.evaluations,
            old.evaluations,
            fit.best.misfit,
            old.best.misfit,
            (fit.best.misfit - old.best.misfit).abs(),
            if max_rel <= 1e-6 || (fit.best.misfit - old.best.misfit).abs() <= 1e-9 {
                " same"
            } else {
                " DIFFERENT"
            }
        );
        let xf = &fit.best.x;
        let at_truth = misfit.final_value(&x_true)?;
        let real_misfit = match fe.run(xf) {
            Ok(y) => Some(range_normalised_rmse(&y, &data, None)?),
            Err(e) => {
                println!("case {case}: FE re-run failed: {e}");
                None
            }
        };
        let g_true = nlvid_inverse::relaxation(&domain, &x_true)?;
        let g_fit = nlvid_inverse::relaxation(&domain, xf)?;
        let e_g0 = (xf[0] / x_true[0] - 1.0).abs();
        let e_sum = ((xf[1] + xf[2]) - (x_true[1] + x_true[2])).abs();
        let e_g52 = (g_fit.value(52.0) / g_true.value(52.0) - 1.0).abs();
        let ok = e_g0 <= 0.05 && e_sum <= 0.03 && e_g52 <= 0.05;
        let agrees = real_misfit.is_some_and(|r| (fit.best.misfit - r).abs() <= max_check);
        passed += usize::from(ok);
        agree += usize::from(agrees);
        reached += usize::from(fit.best.misfit <= at_truth * (1.0 + 1e-6));
        println!(
            "case {case}: true {x_true:.4?}\n        fit  {xf:.4?} ({fit_ms:.0} ms)\n        misfit surrogate {:.5} FE re-run {} (surrogate at truth {:.5}) | dG0 {:.2} % d(g1+g2) {:.4} dG52 {:.2} % {}{}",
            fit.best.misfit,
            real_misfit.map_or("failed".into(), |r| format!("{r:.5}")),
            at_truth,
            100.0 * e_g0,
            e_sum,
            100.0 * e_g52,
            if ok { "ok" } else { "FAIL" },
            if fit.on_bound() { " (on bound)" } else { "" }
        );
    }
    println!(
        "recovered {passed}/{CASES}; surrogate vs FE re-run misfit within the checking error {agree}/{CASES}; optimiser at or below the truth's surrogate misfit {reached}/{CASES}"
    );
    Ok(())
}
