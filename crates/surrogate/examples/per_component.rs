//! Measurement behind docs/theory/surrogate.md, choice 15: one Kriging per
//! principal component with its own θ (SMT/egobox style, done here by the
//! caller: PCA of the training outputs, then an independent single-output
//! `KrigingModel` per component score) against the library's shared-θ
//! model, on the rmse_vs_n problem (Hertz–Prony, 5-parameter cell domain,
//! 200 checking cases). Flags: `g0` krige F/G0 (divided by the caller),
//! `log` krige ln, `pc` one GP per component, `wide` θ ∈ [1e-6, 1e3] and 6
//! starts, `expg` correlation (default gauss).
//!
//! `cargo run --release -p nlvid-surrogate --example per_component -- 300 g0 pc`
use nlvid_surrogate::check::summarise;
use nlvid_surrogate::faer::{Mat, Side};
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OptimiserSettings, Regression, ThetaSearch,
};

mod common;
use common::{cell_problem, kriging_inputs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args[0].parse()?;
    let scale_g0 = args.iter().any(|a| a == "g0");
    let log = args.iter().any(|a| a == "log");
    let percomp = args.iter().any(|a| a == "pc");
    let wide = args.iter().any(|a| a == "wide");
    let expg = args.iter().any(|a| a == "expg");
    let (domain, train, check, yt, yc) = cell_problem(n)?;
    let tr = |x: &Vec<f64>| kriging_inputs(&domain, x);
    let m = 200;
    let xm = Mat::from_fn(n, 5, |i, k| tr(&train[i])[k]);
    let ym = Mat::from_fn(n, m, |i, j| {
        let mut v = yt[i][j];
        if scale_g0 {
            v /= train[i][0];
        }
        if log {
            v = v.ln();
        }
        v
    });
    let corr = if expg {
        Correlation::Expg
    } else {
        Correlation::Gauss
    };
    let mut s = KrigingSettings::new(Regression::Poly1, corr, 5);
    if wide
        && let ThetaSearch::Optimise {
            lower,
            upper,
            settings,
            ..
        } = &mut s.theta
    {
        for k in 0..5 {
            lower[k] = 1e-6;
            upper[k] = 1e3;
        }
        *settings = OptimiserSettings {
            starts: 6,
            ..Default::default()
        };
    }
    let t0 = std::time::Instant::now();
    let post = |v: f64, x: &Vec<f64>| {
        let mut v = v;
        if log {
            v = v.exp();
        }
        if scale_g0 {
            v *= x[0];
        }
        v
    };
    let preds: Vec<Vec<f64>> = if !percomp {
        s.pca_energy = Some(1.0 - 1e-10);
        let km = KrigingModel::fit(xm.as_ref(), ym.as_ref(), &s)?;
        println!("theta {:?} pcs {}", km.theta, km.report.kriged_outputs);
        check
            .iter()
            .map(|x| {
                km.predict(&tr(x))
                    .map(|p| p.iter().map(|&v| post(v, x)).collect())
            })
            .collect::<Result<_, _>>()?
    } else {
        // PCA by hand, then one GP per component.
        let mean: Vec<f64> = (0..m)
            .map(|j| (0..n).map(|i| ym[(i, j)]).sum::<f64>() / n as f64)
            .collect();
        let yc0 = Mat::from_fn(n, m, |i, j| ym[(i, j)] - mean[j]);
        let gram = &yc0 * yc0.transpose();
        let evd = gram
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| format!("{e:?}"))?;
        let lam: Vec<f64> = (0..n).rev().map(|i| evd.S()[i].max(0.0)).collect();
        let tot: f64 = lam.iter().sum();
        let mut k = 0;
        let mut acc = 0.0;
        while k < n && acc < (1.0 - 1e-10) * tot {
            acc += lam[k];
            k += 1;
        }
        let u = Mat::from_fn(n, k, |i, j| evd.U()[(i, n - 1 - j)]);
        let z = Mat::from_fn(n, k, |i, j| u[(i, j)] * lam[j].sqrt());
        let uk = Mat::from_fn(n, k, |i, j| u[(i, j)] / lam[j].sqrt());
        let v = yc0.transpose() * &uk; // m × k
        let mut models = Vec::new();
        for c in 0..k {
            let zc = Mat::from_fn(n, 1, |i, _| z[(i, c)]);
            let km = KrigingModel::fit(xm.as_ref(), zc.as_ref(), &s)?;
            if c < 6 {
                println!(
                    "pc {c} theta {:?}",
                    km.theta
                        .iter()
                        .map(|t| format!("{t:.3e}"))
                        .collect::<Vec<_>>()
                );
            }
            models.push(km);
        }
        println!("pcs {k}");
        check
            .iter()
            .map(|x| {
                let xi = tr(x);
                let zs: Vec<f64> = models
                    .iter()
                    .map(|km| km.predict(&xi).map(|p| p[0]))
                    .collect::<Result<_, _>>()?;
                Ok::<_, nlvid_surrogate::SurrogateError>(
                    (0..m)
                        .map(|j| {
                            let val = mean[j] + (0..k).map(|c| v[(j, c)] * zs[c]).sum::<f64>();
                            post(val, x)
                        })
                        .collect(),
                )
            })
            .collect::<Result<_, _>>()?
    };
    let sm = summarise(&yc, &preds)?;
    println!(
        "N {n} {args:?}: {:.1}s min {:.3}% median {:.3}% max {:.3}%",
        t0.elapsed().as_secs_f64(),
        100.0 * sm.min,
        100.0 * sm.median,
        100.0 * sm.max
    );
    Ok(())
}
