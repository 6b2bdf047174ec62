//! Where are the worst checking cases? Trains the N-run surrogate of
//! `rmse_vs_n` (gauss/poly1, ln y, PCA) and prints the 10 worst checking
//! cases: parameters, eq. 4.4 error, distance to the nearest training site
//! (normalised unit cube, log axes) and the margin to the g1 + g2 face.
//!
//! `cargo run --release -p nlvid-surrogate --example diagnose_worst [-- N]`

use nlvid_surrogate::check::summarise;
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, Regression};

mod common;
use common::{cell_problem, kriging_inputs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(300);
    let (domain, train, check, yt, yc) = cell_problem(n)?;
    let unit = |x: &Vec<f64>| -> Vec<f64> { domain.to_unit(x) };
    let tr = |x: &Vec<f64>| kriging_inputs(&domain, x);
    let xm = Mat::from_fn(n, 5, |i, k| tr(&train[i])[k]);
    let ym = Mat::from_fn(n, 200, |i, j| yt[i][j]);
    let mut s = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, 5);
    s.pca_energy = Some(1.0 - 1e-10);
    s.log_outputs = true;
    let km = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s)?;
    println!("theta = {:?}, pcs = {}", km.theta, km.report.kriged_outputs);
    let preds: Vec<Vec<f64>> = check
        .iter()
        .map(|x| km.predict(&tr(x)))
        .collect::<Result<_, _>>()?;
    let sm = summarise(&yc, &preds)?;
    let ut: Vec<Vec<f64>> = train.iter().map(unit).collect();
    let mut order: Vec<usize> = (0..check.len()).collect();
    order.sort_by(|&a, &b| sm.rmse[b].total_cmp(&sm.rmse[a]));
    println!("rank, rmse_%, G0, g1, g2, tau1, tau2, 1-g1-g2, nearest_train_dist, unit coords");
    for (r, &i) in order.iter().take(12).enumerate() {
        let u = unit(&check[i]);
        let dn = ut
            .iter()
            .map(|t| {
                t.iter()
                    .zip(&u)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        let x = &check[i];
        println!(
            "{r}, {:.2}, {:.0}, {:.3}, {:.3}, {:.4}, {:.2}, {:.3}, {dn:.3}, {:?}",
            100.0 * sm.rmse[i],
            x[0],
            x[1],
            x[2],
            x[3],
            x[4],
            1.0 - x[1] - x[2],
            u.iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
        if r < 2 {
            let k = yc[i].len();
            let pick = [0, 5, 10, 19, 25, 50, 100, 199];
            let a: Vec<String> = pick
                .iter()
                .filter(|&&j| j < k)
                .map(|&j| format!("{:.3e}/{:.3e}", yc[i][j], preds[i][j]))
                .collect();
            println!("   ref/pred at t-index {pick:?}: {}", a.join(" "));
        }
    }
    Ok(())
}
