//! Calibration diagnostics of the per-cell posteriors (issue 17), on the
//! bundled demo meta-model: for `cells` synthetic cells (the coverage
//! example's two broad groups), the curve is written twice by the demo's
//! generator — with `noise` × peak force and without noise, same
//! parameters — and per cell this prints:
//! - σ̂/σ: the noise estimated from the noisy curve over the noise added;
//! - the surrogate's own error at the truth, ‖f(x) − ŷ(x)‖/(σ√m) (f the
//!   forward model, noise-free), and its part outside the Kriging
//!   covariance's span;
//! - χ²/m of the residual d − ŷ(x_true) under the likelihood's
//!   Σ = σ̂²I + v(x)K (≈ 1 ± √(2/m) when the likelihood is calibrated) and
//!   under σ̂²I alone;
//! - at the end, per PCA direction i: the surrogate error's score
//!   e_i = (Vᵀ D⁻¹ (f − ŷ))_i against its Kriging variance v(x)Σ_ii, the
//!   mean of e_i²/(vΣ_ii) over the cells with Σ by maximum likelihood and by
//!   leave-one-out (1 when calibrated in that direction), and the mean of
//!   vΣ_CV,ii over the measurement noise's variance in that direction,
//!   σ² Σ_j V_ji²/D_j² (where the surrogate term matters at all);
//! - with the Kriging variance calibrated (α v^β,
//!   `KrigingSurrogate::variance_calibration`): χ²/m uses it, and the
//!   Mahalanobis norm and per-direction means are printed for it too, and
//!   per group of cells by v·tr(K)/(mσ²) the median |a|²/(v k) before and
//!   after.
//!
//! ```text
//! - the linearised coverage of the 90 % intervals of G0, g1 + g2 and
//!   G(t_end) (below), with the likelihood's Σ (K = K_CV), with σ̂²I alone,
//!   and with K estimated near the truth
//!   (`KrigingModel::output_covariance_local`; its neighbourhood
//!   `NLVID_LOCAL_POWER`, default 1, and its pooling with K_CV
//!   `NLVID_LOCAL_PRIOR` pseudo-sites, default 0).
//!
//! *Linearised coverage.* At the truth x (unit coordinates u, where the
//! prior is flat) the posterior of a summary q(u) is taken as Gaussian with
//! C = (JᵀΣ⁻¹J)⁻¹ (J = ∂ŷ/∂u) and sd s_q = √(gᵀCg), g = ∂q/∂u; the data
//! d = f + n shift its mean by aᵀ(d − ŷ), a = Σ⁻¹JCg. The surrogate's
//! actual error e = f − ŷ contributes z_s = aᵀe/s_q (predicted variance
//! v aᵀKa/s_q² under the model), the noise a N(0, σ² aᵀa/s_q²) part; the
//! probability that |z_s + z_n| ≤ 1.645 is the cell's coverage with the
//! noise integrated out. Averaged over the cells it separates what the
//! likelihood (its error model) gives from what the prior's boundary and
//! the posterior's curvature add.
//!
//! ```text
//! cargo run --release -p nlvid-report --example posterior_diagnose [cells] [noise] [seed] [prior]
//! ```
//! (`prior`: the cells drawn from the posteriors' prior, `DemoSpec::from_prior`.)

use std::path::Path;

use nalgebra::{DMatrix, DVector};
use nlvid_inverse::Model;
use nlvid_inverse::posterior::noise_sd;
use nlvid_report::cell::{CellModel, fit_cell};
use nlvid_report::cohort::discover;
use nlvid_report::demo::write_demo_data;
use nlvid_report::settings::CohortSettings;
use nlvid_surrogate::OutputCovariance;

mod coverage_cohort;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let noise: f64 = args.get(2).map_or(Ok(0.02), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(17), |s| s.parse())?;
    let demo =
        std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo"))?;
    let root = std::env::temp_dir().join(format!("nlvid-diagnose-{}", std::process::id()));
    let from_prior = args.get(4).is_some_and(|a| a == "prior");
    let spec = |noise: f64| nlvid_report::demo::DemoSpec {
        from_prior,
        ..coverage_cohort::wide_groups(cells, seed, noise)
    };
    let noisy_study = coverage_cohort::write_study(&root.join("noisy"), &demo, "")?;
    let clean_study = coverage_cohort::write_study(&root.join("clean"), &demo, "")?;
    let files = write_demo_data(&spec(noise), &noisy_study, &demo.join("metamodel.toml"))?;
    let clean_files = write_demo_data(&spec(0.0), &clean_study, &demo.join("metamodel.toml"))?;
    let settings = CohortSettings::load(&noisy_study)?;
    let model = CellModel::load(&settings)?;
    let CellModel::Surrogate(fitter, _) = &model else {
        return Err("the demo study fits a meta-model".into());
    };
    let s = fitter.surrogate();
    let OutputCovariance::LowRank { m, k, factor } = s.kriging().output_covariance()? else {
        return Err("the demo meta-model is PCA-reduced".into());
    };
    let u = DMatrix::from_column_slice(m, k, &factor);
    let cv = s.kriging().cv_variance_ratio()?;
    let cal = s.variance_calibration(false)?;
    let student = s.variance_calibration(true)?;
    println!(
        "LOO calibration of the Kriging variance sigma2_CV/sigma2_ML = {cv:.3} (k = {k}, N = {}); \
         x-dependent: v_cal = {:.4e} v^{:.4} (± {:.4})",
        s.kriging().n_sites,
        cal.alpha,
        cal.beta,
        cal.beta_se
    );
    println!(
        "Student-t surrogate error (`[posterior] heavy_tails = true`): scale {:.4e} v^{:.4}, nu = {:.3}",
        student.alpha, student.beta, student.nu
    );
    let inputs = discover(&files.data)?;
    let clean_inputs = discover(&clean_files.data)?;
    println!(
        "cell  sigma_hat/sigma  |f-yhat|/(sigma sqrt m)  outside-span  chi2/m(Sigma)  chi2/m(sigma only)  v·tr(K)/(m sigma^2)  mahal/k  mahal/k(calibrated)"
    );
    let (mut ratios, mut chis, mut mahals) = (Vec::new(), Vec::new(), Vec::new());
    // (v·tr(K)/(m σ²), |a|²/(v k), |a|²/(v_cal k)) per cell.
    let mut by_v = Vec::new();
    // Leading PCA direction (the curve's level, G(52 s)) per cell:
    // (vΣ_00/noise_0, v_cal Σ_00/noise_0, e_0²/(vΣ_00), e_0²/(v_cal Σ_00)).
    let mut lead = Vec::new();
    let kr = s.kriging();
    let pca = kr.pca.as_ref().ok_or("PCA model")?;
    let sig_ml = pca.residual_cov.clone();
    let sig_cv = kr.cv_process_covariance()?;
    let basis = |i: usize, j: usize| pca.basis[i * m + j];
    // Per direction: Σ e_i²/(vΣ_ML,ii), Σ e_i²/(vΣ_CV,ii), Σ vΣ_CV,ii/noise_i.
    let mut per_dir = vec![[0.0f64; 4]; k];
    // Linearised coverage per summary: [with Σ, σ̂² only] sums of the
    // cells' coverage probabilities, Σ z_s², Σ predicted var(z_s).
    let mut linear = [[[0.0f64; 3]; 2]; 3];
    let mut linear_cells = 0usize;
    let mut linear_local = [[[0.0f64; 3]; 2]; 3];
    let mut n_effs = Vec::new();
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let (local_power, local_prior) = (env("NLVID_LOCAL_POWER", 1.0), env("NLVID_LOCAL_PRIOR", 0.0));
    let OutputCovariance::LowRank { factor: cvf, .. } = kr.output_covariance_cv()? else {
        return Err("PCA model".into());
    };
    let u_cv = DMatrix::from_column_slice(m, k, &cvf);
    let t_end = *s.times().last().ok_or("empty grid")?;
    for (inp, cin) in inputs.iter().zip(&clean_inputs).take(cells) {
        let r = fit_cell(&settings, &model, inp);
        let c = fit_cell(&settings, &model, cin);
        let truth = files
            .cells
            .iter()
            .find(|t| t.cell == r.cell && t.group == r.group)
            .ok_or("truth")?;
        let clean = &c.data;
        let peak = clean.iter().fold(0.0f64, |a, &b| a.max(b));
        let sigma = noise * peak;
        let est = noise_sd(s.times(), &r.data)?;
        let y = s.response(&truth.x)?;
        let v = s.mse_scale(&truth.x)?;
        let rs = DVector::from_iterator(m, clean.iter().zip(&y).map(|(f, y)| f - y));
        // Part of the surrogate error outside the span of U.
        let coef = (u.transpose() * &u)
            .cholesky()
            .ok_or("UtU")?
            .solve(&(u.transpose() * &rs));
        let outside = (&rs - &u * &coef).norm() / rs.norm();
        // Mahalanobis norm of the surrogate error under v(x)K on K's span,
        // per dimension (1 when the Kriging variance is calibrated).
        let mahal = coef.dot(&coef) / v / k as f64;
        let rd = DVector::from_iterator(m, r.data.iter().zip(&y).map(|(d, y)| d - y));
        let vc = cal.apply(v);
        let mut sig = &u * u.transpose() * vc;
        for j in 0..m {
            sig[(j, j)] += est * est;
        }
        let chi = rd.dot(&sig.cholesky().ok_or("spd")?.solve(&rd)) / m as f64;
        let chi0 = rd.dot(&rd) / (est * est) / m as f64;
        let trk = (0..m)
            .map(|j| (0..k).map(|i| u[(j, i)].powi(2)).sum::<f64>())
            .sum::<f64>();
        println!(
            "{:10} {:6.3} {:8.3} {:6.3} {:8.3} {:8.3} {:8.4} {:8.3} {:8.3}  x {:?}",
            r.cell,
            est / sigma,
            rs.norm() / (sigma * (m as f64).sqrt()),
            outside,
            chi,
            chi0,
            v * trk / (m as f64 * sigma * sigma),
            mahal,
            mahal * v / vc,
            truth.x
        );
        by_v.push((v * trk / (m as f64 * sigma * sigma), mahal, mahal * v / vc));
        for (i, acc) in per_dir.iter_mut().enumerate() {
            let e: f64 = (0..m).map(|j| basis(i, j) * rs[j] / kr.y_std[j]).sum();
            let noise_i: f64 = sigma
                * sigma
                * (0..m)
                    .map(|j| (basis(i, j) / kr.y_std[j]).powi(2))
                    .sum::<f64>();
            acc[0] += e * e / (v * sig_ml[i * k + i]);
            acc[1] += e * e / (v * sig_cv[i * k + i]);
            acc[2] += v * sig_cv[i * k + i] / noise_i;
            acc[3] += e * e / (vc * sig_cv[i * k + i]);
            if i == 0 {
                lead.push((
                    v * sig_cv[0] / noise_i,
                    vc * sig_cv[0] / noise_i,
                    e * e / (v * sig_cv[0]),
                    e * e / (vc * sig_cv[0]),
                ));
            }
        }
        let (local_k, n_eff) =
            kr.output_covariance_local(&truth.x, &cal, local_power, local_prior)?;
        let OutputCovariance::LowRank { factor: lf, .. } = local_k else {
            return Err("PCA model".into());
        };
        let u_local = DMatrix::from_column_slice(m, k, &lf);
        n_effs.push(n_eff);
        match (
            linearised(s, &truth.x, &rs, &u_cv, vc, est, t_end),
            linearised(s, &truth.x, &rs, &u_local, vc, est, t_end),
        ) {
            (Ok(cell), Ok(cell_local)) => {
                linear_cells += 1;
                for (lin, cell) in [(&mut linear, cell), (&mut linear_local, cell_local)] {
                    for (acc, c) in lin.iter_mut().zip(&cell) {
                        for (a, x) in acc.iter_mut().zip(c) {
                            for (ai, xi) in a.iter_mut().zip(x) {
                                *ai += xi;
                            }
                        }
                    }
                }
            }
            (Err(e), _) | (_, Err(e)) => println!("  {}: no linearisation ({e})", r.cell),
        }
        ratios.push(est / sigma);
        chis.push(chi);
        mahals.push(mahal);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mut sorted = mahals.clone();
    sorted.sort_by(f64::total_cmp);
    println!(
        "Kriging calibration |a|^2/(v k): mean {:.3}, median {:.3} (k = {k})",
        mean(&mahals),
        sorted[sorted.len() / 2]
    );
    println!(
        "mean sigma_hat/sigma {:.4}; mean chi2/m under Sigma {:.4} (expect 1 ± {:.3})",
        mean(&ratios),
        mean(&chis),
        (2.0 / m as f64 / chis.len() as f64).sqrt()
    );
    let nc = chis.len() as f64;
    println!(
        "per PCA direction i: mean e_i^2/(v Sigma_ii) with Sigma ML, CV (1 = calibrated); mean \
         v Sigma_CV,ii / noise variance in direction i"
    );
    for (i, acc) in per_dir.iter().enumerate() {
        println!(
            "  {i}: ML {:8.3}  CV {:8.3}  CV calibrated {:8.3}  surrogate/noise {:10.4}",
            acc[0] / nc,
            acc[1] / nc,
            acc[3] / nc,
            acc[2] / nc
        );
    }
    // The x-dependence: cells grouped by the surrogate's share of the
    // variance, v·tr(K)/(m σ²), median |a|²/(v k) before and after.
    by_v.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("v·tr(K)/(m sigma^2) range  cells  median mahal/k  calibrated");
    let med = |mut x: Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    // Where the surrogate term matters for the level: cells grouped by the
    // calibrated surrogate/noise variance ratio in the leading direction.
    println!(
        "leading direction: v_cal Sigma_00/noise_0 range  cells  median ratio before, after  \
         median e0^2/(v Sigma_00) before, after (1 = calibrated)"
    );
    for (lo, hi) in [(0.0, 0.1), (0.1, 1.0), (1.0, f64::INFINITY)] {
        let g: Vec<_> = lead.iter().filter(|c| c.1 >= lo && c.1 < hi).collect();
        if g.is_empty() {
            continue;
        }
        println!(
            "[{lo}, {hi})  {}  {:.3} {:.3}  {:.3} {:.3}",
            g.len(),
            med(g.iter().map(|c| c.0).collect()),
            med(g.iter().map(|c| c.1).collect()),
            med(g.iter().map(|c| c.2).collect()),
            med(g.iter().map(|c| c.3).collect())
        );
    }
    for (lo, hi) in [(0.0, 0.005), (0.005, 0.05), (0.05, f64::INFINITY)] {
        let g: Vec<_> = by_v.iter().filter(|c| c.0 >= lo && c.0 < hi).collect();
        if g.is_empty() {
            continue;
        }
        println!(
            "[{lo}, {hi})  {}  {:.3}  {:.3}",
            g.len(),
            med(g.iter().map(|c| c.1).collect()),
            med(g.iter().map(|c| c.2).collect())
        );
    }
    let nl = linear_cells.max(1) as f64;
    println!(
        "linearised coverage of the 90 % intervals over {linear_cells} cells (noise integrated \
         out): with Sigma = sigma^2 I + v K | with sigma^2 I only; mean z_s^2 (actual surrogate \
         shift) vs its predicted variance"
    );
    for (q, name) in ["G0", "g1 + g2", "G(t_end)"].iter().enumerate() {
        let [full, bare] = linear[q];
        let [local, _] = linear_local[q];
        println!(
            "  {name:9} {:5.1} % (z_s^2 {:.3} vs predicted {:.3}) | {:5.1} % (z_s^2 {:.3}) | local K {:5.1} % (predicted {:.3})",
            100.0 * full[0] / nl,
            full[1] / nl,
            full[2] / nl,
            100.0 * bare[0] / nl,
            bare[1] / nl,
            100.0 * local[0] / nl,
            local[2] / nl
        );
    }
    n_effs.sort_by(f64::total_cmp);
    println!(
        "local K (power {local_power}, prior sites {local_prior}): n_eff min {:.1}, median {:.1}, max {:.1}",
        n_effs[0],
        n_effs[n_effs.len() / 2],
        n_effs[n_effs.len() - 1]
    );
    std::fs::remove_dir_all(&root)?;
    Ok(())
}

/// The linearised coverage of one cell (module docs) for G0, g1 + g2 and
/// G(t_end): per summary, for Σ = σ̂²I + v_cal K and for σ̂²I alone,
/// [coverage probability, z_s², predicted var(z_s)].
fn linearised(
    s: &nlvid_inverse::KrigingSurrogate,
    x: &[f64],
    err: &DVector<f64>,
    u_factor: &DMatrix<f64>,
    v_cal: f64,
    noise: f64,
    t_end: f64,
) -> Result<[[[f64; 3]; 2]; 3], Box<dyn std::error::Error>> {
    const Z90: f64 = 1.644_853_626_951_472_2;
    let domain = s.domain();
    let n = x.len();
    let m = err.len();
    let u0 = domain.to_unit(x);
    let h = 1e-5;
    // dx/du (diagonal: each coordinate maps on its own) and ∂q/∂u.
    let summaries = |u: &[f64]| -> Result<[f64; 3], Box<dyn std::error::Error>> {
        let g = nlvid_inverse::relaxation(domain, &domain.from_unit(u))?;
        Ok([g.g0(), 1.0 - g.prony().long_term_weight(), g.value(t_end)])
    };
    let mut dxdu = vec![0.0; n];
    let mut grads = [DVector::zeros(n), DVector::zeros(n), DVector::zeros(n)];
    for i in 0..n {
        let (mut up, mut dn) = (u0.clone(), u0.clone());
        up[i] += h;
        dn[i] -= h;
        dxdu[i] = (domain.from_unit(&up)[i] - domain.from_unit(&dn)[i]) / (2.0 * h);
        let (qp, qm) = (summaries(&up)?, summaries(&dn)?);
        for q in 0..3 {
            grads[q][i] = (qp[q] - qm[q]) / (2.0 * h);
        }
    }
    let mut jac = s.jacobian(x)?;
    for (i, d) in dxdu.iter().enumerate() {
        jac.column_mut(i).scale_mut(*d);
    }
    let mut out = [[[0.0; 3]; 2]; 3];
    for (b, v) in [v_cal, 0.0].into_iter().enumerate() {
        let mut sig = u_factor * u_factor.transpose() * v;
        for j in 0..m {
            sig[(j, j)] += noise * noise;
        }
        let chol = sig.cholesky().ok_or("Sigma not positive definite")?;
        let sj = chol.solve(&jac);
        let cov = (jac.transpose() * &sj)
            .try_inverse()
            .ok_or("singular Fisher information")?;
        for (q, g) in grads.iter().enumerate() {
            let cg = &cov * g;
            let sd = g.dot(&cg).sqrt();
            let a = &sj * cg;
            let z_s = a.dot(err) / sd;
            let ua = u_factor.transpose() * &a;
            let var_s = v * ua.dot(&ua) / (sd * sd);
            let sd_n = noise * a.norm() / sd;
            let cover = 1.0
                - nlvid_stats::normal_sf((Z90 - z_s) / sd_n)
                - nlvid_stats::normal_sf((Z90 + z_s) / sd_n);
            out[q][b] = [cover, z_s * z_s, var_s];
        }
    }
    Ok(out)
}
