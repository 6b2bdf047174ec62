//! Checking RMSE (thesis eq. 4.4) against the number of training runs N on
//! the analytic Hertz–Prony ramp-hold model over a 5-parameter cell domain
//! shaped like thesis Table 5.3 (G0, g1, g2, τ1, τ2; g1 + g2 < 1).
//!
//! `cargo run --release -p nlvid-surrogate --example rmse_vs_n [-- N1 N2 …]`

use nlvid_model::ForwardModel;
use nlvid_surrogate::check::summarise;
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{Correlation, KrigingModel, KrigingSettings, OutputScale, Regression};

mod common;
use common::{cell_model, cell_problem, kriging_inputs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let ns: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let ns = if ns.is_empty() {
        vec![50, 100, 200, 300]
    } else {
        ns
    };
    println!("model: {}", cell_model().identity());
    println!(
        "N, correlation, regression, outputs, pcs, theta_search_s, rmse_min_%, rmse_median_%, rmse_max_%"
    );
    for &n in &ns {
        let (domain, train, check, yt, yc) = cell_problem(n)?;
        // Kriging on log-scaled inputs for the log axes (as the design).
        let tr = |x: &Vec<f64>| kriging_inputs(&domain, x);
        let xt: Vec<Vec<f64>> = train.iter().map(tr).collect();
        let xm = Mat::from_fn(n, 5, |i, k| xt[i][k]);
        let ym = Mat::from_fn(n, 200, |i, j| yt[i][j]);
        // F ∝ G0 exactly for this model; input 0 is ln G0, so s = exp(x0).
        let g0 = Some(OutputScale::Exp {
            input: 0,
            slope: 1.0,
        });
        for (corr, reg, log, scale) in [
            (Correlation::Gauss, Regression::Poly1, false, None),
            (Correlation::Gauss, Regression::Poly1, true, None),
            (Correlation::Gauss, Regression::Poly1, false, g0),
            (Correlation::Expg, Regression::Poly1, false, g0),
        ] {
            if reg.n_terms(5) >= n {
                continue;
            }
            let mut s = KrigingSettings::new(reg, corr, 5);
            s.pca_energy = Some(1.0 - 1e-10);
            s.log_outputs = log;
            s.output_scale = scale;
            let t0 = std::time::Instant::now();
            let km = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s)?;
            let secs = t0.elapsed().as_secs_f64();
            let preds: Vec<Vec<f64>> = check
                .iter()
                .map(|x| km.predict(&tr(x)))
                .collect::<Result<_, _>>()?;
            let sm = summarise(&yc, &preds)?;
            println!(
                "{n}, {}, {}, {}, {}, {secs:.2}, {:.4}, {:.4}, {:.4}",
                corr.name(),
                reg.name(),
                match (log, scale.is_some()) {
                    (false, false) => "y",
                    (true, false) => "ln y",
                    (false, true) => "y/G0",
                    (true, true) => "ln(y/G0)",
                },
                km.report.kriged_outputs,
                100.0 * sm.min,
                100.0 * sm.median,
                100.0 * sm.max
            );
        }
    }
    Ok(())
}
