//! Validation of the x-dependent calibration of the Kriging variance
//! (docs/theory/surrogate.md, "Calibration of the Kriging variance"):
//! builds (or resumes) the study's checking runs into `STORE/check`, then
//! prints per bin of the Kriging variance v the mean standardised error
//! energy |e|²_Σ/(k·v) before (v, Σ_CV) and after (α v^β, Σ_CV) the
//! calibration, on the training sites (leave-one-out residuals, what the
//! calibration is fitted to) and on the held-out checking runs.
//!
//! ```text
//! cargo run --release -p nlvid-surrogate --example variance_calibration -- STUDY MODEL STORE
//! ```
//! e.g. `examples/demo/metamodel.toml examples/demo/metamodel/model.json work/demo-check` (a scratch
//! directory: the checking runs are not part of the committed demo).

use std::path::PathBuf;

use nlvid_surrogate::infill::checking_set;
use nlvid_surrogate::{
    BuildOptions, BuildStudy, CalibrationData, KrigingModel, VarianceCalibration, build_report,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let study = PathBuf::from(args.get(1).ok_or("STUDY")?);
    let model = PathBuf::from(args.get(2).ok_or("MODEL")?);
    let store = PathBuf::from(args.get(3).ok_or("STORE")?);
    let bs = BuildStudy::load(&study)?;
    let (_, check) = bs.settings.design.designs()?;
    let opts = BuildOptions::default();
    println!(
        "{}",
        build_report(
            "check",
            bs.model.as_ref(),
            &check,
            &store.join("check"),
            &opts
        )?
    );
    let (cx, cy) = checking_set(&store.join("check"), &bs.settings.filters)?;
    let km: KrigingModel = serde_json::from_slice(&std::fs::read(&model)?)?;
    let loo = km.loo_calibration_data()?;
    let held = km.calibration_data(&cx, &cy)?;
    let cal = VarianceCalibration::fit(&loo)?;
    println!(
        "model N = {}, k = {}; {} admissible checking runs",
        km.n_sites,
        loo.dof,
        cx.len()
    );
    println!(
        "fitted on the LOO residuals: alpha = {:.4e}, beta = {:.4} ± {:.4}",
        cal.alpha, cal.beta, cal.beta_se
    );
    let own = VarianceCalibration::fit(&held)?;
    println!(
        "(fitted on the checking runs alone, for comparison only: alpha = {:.4e}, beta = {:.4} ± {:.4})",
        own.alpha, own.beta, own.beta_se
    );
    for (name, data) in [
        ("LOO (training sites)", &loo),
        ("held-out checking runs", &held),
    ] {
        table(name, data, &cal);
    }
    per_direction(&km, &cx, &cy, &cal)?;
    Ok(())
}

/// The calibration direction by direction on the held-out checking runs:
/// per PCA score a, z_a = e_a²/(α v^β Σ_CV,aa) (e = Vᵀ D⁻¹ (y − ŷ), χ²_1
/// with mean 1 when that direction is calibrated), and for two linear
/// functionals of the curve w, the force at the last output time and the
/// mean force over the later half of the outputs (the curve's long-time
/// level, which sets G(t_end)): (wᵀ(y − ŷ))² / (α v^β wᵀ D V Σ_CV Vᵀ D w).
/// Means and medians (χ²_1: median 0.455) over all runs and over the runs
/// with v above and below the median v.
fn per_direction(
    km: &KrigingModel,
    cx: &[Vec<f64>],
    cy: &[Vec<f64>],
    cal: &VarianceCalibration,
) -> Result<(), Box<dyn std::error::Error>> {
    let Some(pca) = &km.pca else {
        println!("(no PCA: no per-direction table)");
        return Ok(());
    };
    let m = km.n_outputs;
    let q = pca.basis.len() / m;
    let sigma = km.cv_process_covariance()?;
    let last: Vec<f64> = (0..m).map(|j| f64::from(u8::from(j == m - 1))).collect();
    let half: Vec<f64> = (0..m).map(|j| if 2 * j >= m { 1.0 } else { 0.0 }).collect();
    // Per functional w: its score loadings (Vᵀ D w)_a and predicted
    // variance per unit calibrated v, wᵀ D V Σ Vᵀ D w.
    let functional = |w: &[f64]| {
        let l = km.score_loadings(w).expect("a PCA model");
        (0..q)
            .flat_map(|a| (0..q).map(move |b| (a, b)))
            .map(|(a, b)| l[a] * sigma[a * q + b] * l[b])
            .sum::<f64>()
    };
    let (var_last, var_half) = (functional(&last), functional(&half));
    let mut rows: Vec<(f64, Vec<f64>)> = Vec::new();
    for (x, y) in cx.iter().zip(cy) {
        let yh = km.predict(x)?;
        let v = km.mse_scale(x)?;
        let c = cal.apply(v);
        let d: Vec<f64> = (0..m).map(|j| (y[j] - yh[j]) / km.y_std[j]).collect();
        let mut z: Vec<f64> = (0..q)
            .map(|a| {
                let e: f64 = (0..m).map(|j| pca.basis[a * m + j] * d[j]).sum();
                e * e / (c * sigma[a * q + a])
            })
            .collect();
        let err = |w: &[f64]| -> f64 { (0..m).map(|j| w[j] * (y[j] - yh[j])).sum() };
        z.push(err(&last).powi(2) / (c * var_last));
        z.push(err(&half).powi(2) / (c * var_half));
        rows.push((v, z));
    }
    let mut vs: Vec<f64> = rows.iter().map(|r| r.0).collect();
    vs.sort_by(f64::total_cmp);
    let (v_med, v_q3) = (vs[vs.len() / 2], vs[3 * vs.len() / 4]);
    println!(
        "per direction, held-out checking runs: mean [median] of e²/(α v^β Σ_aa) (1 [0.455] when \
         calibrated); split at the median v = {v_med:.2e} and the upper quartile {v_q3:.2e}"
    );
    println!(
        "| direction | all ({}) | v < median | v ≥ median | v ≥ upper quartile |",
        rows.len()
    );
    println!("|---|---|---|---|---|");
    let stat = |sel: &dyn Fn(f64) -> bool, col: usize| {
        let mut z: Vec<f64> = rows.iter().filter(|r| sel(r.0)).map(|r| r.1[col]).collect();
        z.sort_by(f64::total_cmp);
        let n = z.len();
        let mean = z.iter().sum::<f64>() / n as f64;
        let med = if n % 2 == 1 {
            z[n / 2]
        } else {
            0.5 * (z[n / 2 - 1] + z[n / 2])
        };
        format!("{mean:.3} [{med:.3}]")
    };
    for col in 0..q + 2 {
        let name = match col {
            c if c < q => format!("PC {}", c + 1),
            c if c == q => "force at t_end".to_string(),
            _ => "mean force, later half".to_string(),
        };
        println!(
            "| {name} | {} | {} | {} | {} |",
            stat(&|_| true, col),
            stat(&|v| v < v_med, col),
            stat(&|v| v >= v_med, col),
            stat(&|v| v >= v_q3, col)
        );
    }
    Ok(())
}

/// Per decade of v: runs, the mean standardised energy E/(k·v) (before)
/// and E/(k·α v^β) (after), 1 when calibrated, and the mean Gaussian log
/// score −½[k ln c + E/c] per run (c the variance factor; higher is better).
fn table(name: &str, data: &CalibrationData, cal: &VarianceCalibration) {
    let before = data.standardised(&VarianceCalibration::IDENTITY);
    let after = data.standardised(cal);
    let k = data.dof as f64;
    let score = |c: f64, e: f64| -0.5 * (k * c.ln() + e / c);
    println!("{name}:");
    println!("| v | runs | mean E/(k v) before | after | median before | after |");
    println!("|---|---|---|---|---|---|");
    let lo = data
        .v
        .iter()
        .map(|v| v.log10().floor() as i32)
        .min()
        .unwrap_or(0);
    let hi = data
        .v
        .iter()
        .map(|v| v.log10().floor() as i32)
        .max()
        .unwrap_or(0);
    let median = |mut x: Vec<f64>| {
        x.sort_by(f64::total_cmp);
        let n = x.len();
        if n % 2 == 1 {
            x[n / 2]
        } else {
            0.5 * (x[n / 2 - 1] + x[n / 2])
        }
    };
    for d in lo..=hi {
        let idx: Vec<usize> = (0..data.v.len())
            .filter(|&i| data.v[i].log10().floor() as i32 == d)
            .collect();
        if idx.is_empty() {
            continue;
        }
        let b: Vec<f64> = idx.iter().map(|&i| before[i]).collect();
        let a: Vec<f64> = idx.iter().map(|&i| after[i]).collect();
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        println!(
            "| 1e{d}–1e{} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
            d + 1,
            idx.len(),
            mean(&b),
            mean(&a),
            median(b.clone()),
            median(a.clone())
        );
    }
    let n = data.v.len() as f64;
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let (sb, sa): (f64, f64) = data
        .v
        .iter()
        .zip(&data.energy)
        .map(|(&v, &e)| (score(v, e), score(cal.apply(v), e)))
        .fold((0.0, 0.0), |(p, q), (a, b)| (p + a, q + b));
    println!(
        "| all | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
        data.v.len(),
        mean(&before),
        mean(&after),
        median(before.clone()),
        median(after.clone())
    );
    println!(
        "mean log score per run (-1/2 [k ln c + E/c]): before {:.3}, after {:.3}",
        sb / n,
        sa / n
    );
}
