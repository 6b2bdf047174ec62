//! Per-direction calibration of the Kriging variance on a model's own
//! leave-one-out residuals (docs/theory/inverse.md, "Session 18"): the
//! one-scale fit α v^β ([`VarianceCalibration::fit`]) against a scale per
//! eigen-direction of Σ_CV with one β ([`VarianceCalibration::fit_directions`],
//! what the likelihood can use) and against a separate (α_k, β_k) per
//! direction (each direction fitted alone, dof 1; a diagnostic). Prints the
//! scales, the mean ln-likelihood per LOO site of each, and per direction
//! its share of the variance of two curve functionals (the force at the
//! last output time and the mean force over the later half, the level that
//! sets G(t_end)).
//!
//! ```text
//! cargo run --release -p nlvid-surrogate --example direction_calibration -- MODEL
//! ```
//! e.g. `examples/demo/metamodel/model.json`.

use std::path::PathBuf;

use faer::{Mat, Side};
use nlvid_surrogate::{CalibrationData, KrigingModel, VarianceCalibration};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let model = PathBuf::from(args.get(1).ok_or("MODEL")?);
    let km: KrigingModel = serde_json::from_slice(&std::fs::read(&model)?)?;
    let data = km.loo_calibration_data()?;
    let (n, k) = (data.v.len(), data.dof);
    let scalar = VarianceCalibration::fit(&data)?;
    let dirs = VarianceCalibration::fit_directions(&data)?;
    let ll_scalar = scalar.mean_log_likelihood(&data);
    let ll_dirs = dirs.mean_log_likelihood(&data);
    println!("model N = {n}, k = {k}");
    println!(
        "one scale:              alpha = {:.4e}, beta = {:.4} ± {:.4}; mean ln L per site {:.4}",
        scalar.alpha, scalar.beta, scalar.beta_se, ll_scalar
    );
    println!(
        "per direction, one beta: beta = {:.4} ± {:.4}; mean ln L per site {:.4} (gain {:+.4}, \
         {:+.1} over the sites, {} more parameters)",
        dirs.beta,
        dirs.beta_se,
        ll_dirs,
        ll_dirs - ll_scalar,
        (ll_dirs - ll_scalar) * n as f64,
        k - 1
    );
    // Each direction alone: (α_k, β_k), dof 1.
    let column = |c: usize| -> Vec<f64> { (0..n).map(|i| data.directions[i * k + c]).collect() };
    let mut ll_separate = 0.0;
    let mut separate = Vec::new();
    for c in 0..k {
        let d = CalibrationData {
            v: data.v.clone(),
            energy: column(c),
            dof: 1,
            directions: Vec::new(),
        };
        let f = VarianceCalibration::fit(&d)?;
        ll_separate += f.mean_log_likelihood(&d);
        separate.push(f);
    }
    println!(
        "per direction, own beta: mean ln L per site {:.4} (gain {:+.4}, {:+.1} over the sites, \
         {} more parameters)",
        ll_separate,
        ll_separate - ll_scalar,
        (ll_separate - ll_scalar) * n as f64,
        2 * k - 2
    );
    // Functionals: score loadings l = Vᵀ D w; share of direction j in
    // lᵀΣl: λ_j (q_jᵀ l)² / lᵀΣl.
    let sigma = km.cv_process_covariance()?;
    let q = km.n_kriged();
    let evd = Mat::from_fn(q, q, |i, j| sigma[j * q + i])
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| format!("{e:?}"))?;
    let m = km.n_outputs;
    let shares = |w: &[f64]| -> Vec<f64> {
        let Some(l) = km.score_loadings(w) else {
            return vec![f64::NAN; k];
        };
        let parts: Vec<f64> = (0..k)
            .map(|c| {
                let e = q - 1 - c; // descending
                let ql: f64 = (0..q).map(|r| evd.U()[(r, e)] * l[r]).sum();
                evd.S()[e] * ql * ql
            })
            .collect();
        let total: f64 = parts.iter().sum();
        parts.iter().map(|p| p / total).collect()
    };
    let last: Vec<f64> = (0..m).map(|j| f64::from(u8::from(j == m - 1))).collect();
    let half: Vec<f64> = (0..m).map(|j| if 2 * j >= m { 1.0 } else { 0.0 }).collect();
    let (s_last, s_half) = (shares(&last), shares(&half));
    // Standardised z²/(α v^β) per direction under the one-scale fit, split
    // at the median v.
    let mut vs = data.v.clone();
    vs.sort_by(f64::total_cmp);
    let (v_med, v_q3) = (vs[n / 2], vs[3 * n / 4]);
    let mean_ratio = |c: usize, sel: &dyn Fn(f64) -> bool| {
        let (mut s, mut cnt) = (0.0, 0usize);
        for i in 0..n {
            if sel(data.v[i]) {
                s += data.directions[i * k + c] / scalar.apply(data.v[i]);
                cnt += 1;
            }
        }
        s / cnt as f64
    };
    println!(
        "| direction | λ_k | α_k (one β) | α_k/α | α_k at β = 1 | own α_k, β_k ± se | \
         mean z²/(α v^β): all, v < {v_med:.1e}, v ≥ median, v ≥ {v_q3:.1e} | share of var: \
         F(t_end), later-half level |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for c in 0..k {
        let at_one: f64 = (0..n)
            .map(|i| data.directions[i * k + c] / data.v[i])
            .sum::<f64>()
            / n as f64;
        let f = &separate[c];
        println!(
            "| {} | {:.3e} | {:.4e} | {:.3} | {:.4} | {:.3e}, {:.4} ± {:.4} | {:.3}, {:.3}, {:.3}, \
             {:.3} | {:.3}, {:.3} |",
            c + 1,
            evd.S()[q - 1 - c],
            dirs.alpha * dirs.directions[c],
            dirs.directions[c],
            at_one,
            f.alpha,
            f.beta,
            f.beta_se,
            mean_ratio(c, &|_| true),
            mean_ratio(c, &|v| v < v_med),
            mean_ratio(c, &|v| v >= v_med),
            mean_ratio(c, &|v| v >= v_q3),
            s_last[c],
            s_half[c]
        );
    }
    Ok(())
}
