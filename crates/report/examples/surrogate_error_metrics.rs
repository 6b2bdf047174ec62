//! The demo meta-model's error at parameter sets drawn from the
//! posteriors' prior, in the two metrics that matter (issue 17,
//! docs/theory/inverse.md, "Session 17"). For `n` seeded sets it runs the
//! FE cell model of examples/demo/metamodel.toml twice — on the demo
//! writer's sample times (100 Hz to 2 s, then 10 Hz) and on the
//! meta-model's grid (every 0.1 s, as a training run) — and prints, in
//! units of the coverage cohort's noise (2 % of the peak force, σ√m):
//! - ‖writer − run‖ at the grid's times (the FE model's dependence on the
//!   output times);
//! - ‖ŷ − run‖, the surrogate's error, and the calibrated Kriging sd
//!   √(v·tr K/m);
//! - the error's fraction outside K's span, and its Mahalanobis norm per
//!   dimension under v·K in the likelihood's metric (its Euclidean
//!   projection on span K) and in the PCA coordinates the calibration uses
//!   (Vᵀ D⁻¹ e), with what a PCA truncation residual spread evenly over
//!   the discarded directions would add to the first;
//!
//! and, once, the variance inflation per direction of the statistic
//! Vᵀ D⁻¹ r against the whole curve (the information a likelihood blind
//! to the truncation residual would give up).
//!
//! ```text
//! cargo run --release -p nlvid-report --example surrogate_error_metrics [n] [seed]
//! ```

use std::path::Path;

use nlvid_forward::ForwardSettings;
use nlvid_forward::curves::afm_curve;
use nlvid_inverse::{Coordinates, Model, load_kriging_surrogate};
use nlvid_study::Study;
use nlvid_surrogate::OutputCovariance;
use rand::{RngExt, SeedableRng};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(Ok(20), |s| s.parse())?;
    let seed: u64 = args.get(2).map_or(Ok(5), |s| s.parse())?;
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let mut study = Study::load(demo.join("metamodel.toml"))?;
    let fwd = ForwardSettings::from_study(&mut study)?;
    let k = 0.12;
    let dir = demo.join("metamodel");
    let s = load_kriging_surrogate(
        &dir.join("model.json"),
        &dir.join("meta.json"),
        Coordinates::Physical,
    )?;
    let grid = s.times().to_vec();
    let t_end = *grid.last().ok_or("empty grid")?;
    // The demo's sample times (`DemoSpec::default`): every 0.01 s to 2 s,
    // then every 0.1 s.
    let fine = (t_end * 100.0).round() as usize;
    let writer: Vec<f64> = std::iter::once(0.0)
        .chain(
            (0..fine)
                .filter(|&i| i < 200 || (i + 1) % 10 == 0 || i + 1 == fine)
                .map(|i| t_end * (i + 1) as f64 / fine as f64),
        )
        .collect();
    let on_grid: Vec<usize> = grid
        .iter()
        .map(|&t| {
            writer
                .iter()
                .position(|&w| (w - t).abs() < 1e-9)
                .ok_or("a grid time is not a sample time")
        })
        .collect::<Result<_, _>>()?;
    let OutputCovariance::LowRank { m, k: rank, factor } = s.output_covariance_cv()? else {
        return Err("PCA meta-model expected".into());
    };
    let trace_k: f64 = factor.iter().map(|u| u * u).sum();
    let u_mat = nalgebra::DMatrix::from_column_slice(m, rank, &factor);
    let utu = (u_mat.transpose() * &u_mat)
        .cholesky()
        .ok_or("U has dependent columns")?;
    let cal = s.variance_calibration(false)?;
    let kr = s.kriging();
    let pca = kr.pca.as_ref().ok_or("PCA model")?;
    let sig_cv = nalgebra::DMatrix::from_column_slice(rank, rank, &kr.cv_process_covariance()?);
    // The PCA truncation residual, if isotropic in the discarded directions
    // of the standardised outputs: c (I − VVᵀ) with c from the kept energy;
    // its Euclidean projection on span(U) has coordinates a with
    // E[aᵀa] = tr G, G = (UᵀU)⁻¹ Uᵀ D c(I − VVᵀ) D U (UᵀU)⁻¹.
    let c_trunc = (1.0 - pca.energy) * m as f64 / (m - rank) as f64;
    let v_mat = nalgebra::DMatrix::from_fn(m, rank, |j, i| pca.basis[i * m + j]);
    let du = nalgebra::DMatrix::from_fn(m, rank, |j, i| kr.y_std[j] * u_mat[(j, i)]);
    let perp = &du - &v_mat * (v_mat.transpose() * &du);
    let dperp = nalgebra::DMatrix::from_fn(m, rank, |j, i| kr.y_std[j] * perp[(j, i)]);
    let inner = u_mat.transpose() * dperp * c_trunc;
    let utu_inv = (u_mat.transpose() * &u_mat).try_inverse().ok_or("UtU")?;
    let g = &utu_inv * inner * &utu_inv;
    let trace_g = g.trace();
    // Information on c kept by the PCA-coordinate statistic Vᵀ D⁻¹ r
    // against the whole curve (white noise): generalised eigenvalues of
    // VᵀD²V against (VᵀD⁻²V)⁻¹, the variance inflation per direction.
    let dv2 = nalgebra::DMatrix::from_fn(m, rank, |j, i| kr.y_std[j] * v_mat[(j, i)]);
    let dv_inv = nalgebra::DMatrix::from_fn(m, rank, |j, i| v_mat[(j, i)] / kr.y_std[j]);
    let full = dv2.transpose() * &dv2;
    let n_mat = dv_inv.transpose() * &dv_inv;
    let nh = n_mat.clone().symmetric_eigen();
    let n_half = &nh.eigenvectors
        * nalgebra::DMatrix::from_diagonal(&nh.eigenvalues.map(f64::sqrt))
        * nh.eigenvectors.transpose();
    let mut infl: Vec<f64> = (&n_half * full * &n_half)
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .copied()
        .collect();
    infl.sort_by(f64::total_cmp);
    println!("variance inflation of the PCA-coordinate statistic per direction: {infl:.3?}");
    let domain = s.domain().clone();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    println!(
        "m = {m}, k = {rank}; per set: ||writer - run||, ||yhat - run||, Kriging sd, all / (sigma sqrt m), sigma = 0.02 peak"
    );
    let (mut wr, mut sr) = (Vec::new(), Vec::new());
    while wr.len() < n {
        let u: Vec<f64> = (0..5).map(|_| 0.02 + 0.96 * rng.random::<f64>()).collect();
        let x = domain.from_unit(&u);
        if !domain.contains(&x, 0.0) {
            continue;
        }
        let run = afm_curve(&fwd, &x, &grid, k)?;
        let written = afm_curve(&fwd, &x, &writer, k)?;
        let f_run = run.values("force").ok_or("force")?;
        let f_w = written.values("force").ok_or("force")?;
        let y = s.response(&x)?;
        let peak = f_run.iter().fold(0.0f64, |a, &b| a.max(b));
        let sigma = 0.02 * peak;
        let scale = sigma * (m as f64).sqrt();
        let dw = (0..m)
            .map(|j| (f_w[on_grid[j]] - f_run[j]).powi(2))
            .sum::<f64>()
            .sqrt();
        let ds = (0..m)
            .map(|j| (y[j] - f_run[j]).powi(2))
            .sum::<f64>()
            .sqrt();
        let v = cal.apply(s.mse_scale(&x)?);
        let sd = (v * trace_k).sqrt();
        // The error's coordinates a in K = UUᵀ's span (e_in = U a) and its
        // Mahalanobis norm under v·K per dimension (1 when calibrated).
        let e = nalgebra::DVector::from_iterator(m, (0..m).map(|j| y[j] - f_run[j]));
        let a = utu.solve(&(u_mat.transpose() * &e));
        let outside = (&e - &u_mat * &a).norm() / e.norm();
        let mahal = a.dot(&a) / v / rank as f64;
        // The same in the PCA coordinates the calibration uses (standardised
        // outputs, e = Vᵀ D⁻¹ (ŷ − y), Σ_CV-whitened): the truncation
        // residual is orthogonal to V there, not in the likelihood's metric.
        let e_pca: Vec<f64> = (0..rank)
            .map(|i| {
                (0..m)
                    .map(|j| pca.basis[i * m + j] * e[j] / kr.y_std[j])
                    .sum()
            })
            .collect();
        let ep = nalgebra::DVector::from_vec(e_pca);
        let mahal_pca =
            ep.dot(&sig_cv.clone().lu().solve(&ep).ok_or("Sigma_CV")?) / v / rank as f64;
        println!(
            "u {:?}: {:.4} {:.4} {:.4}  outside-span {:.3}  in-span mahal/k {:.3} (PCA metric {:.3}; isotropic truncation leak would give {:.3})",
            u.iter()
                .map(|v| (v * 1000.0).round() / 1000.0)
                .collect::<Vec<_>>(),
            dw / scale,
            ds / scale,
            sd / scale,
            outside,
            mahal,
            mahal_pca,
            trace_g / v / rank as f64
        );
        wr.push(dw / scale);
        sr.push(ds / scale);
    }
    let med = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "median ||writer - run|| {:.4}, median ||yhat - run|| {:.4} (sigma sqrt m)",
        med(wr),
        med(sr)
    );
    Ok(())
}
