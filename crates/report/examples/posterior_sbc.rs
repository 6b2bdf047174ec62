//! Simulation-based check of the posterior sampler (issue 17,
//! docs/theory/inverse.md "Session 19"): cells whose curves are the
//! bundled demo meta-model's own prediction ŷ(x) plus white noise, so that
//! the likelihood without the surrogate's error (`PosteriorSettings::
//! surrogate_error = false`, Σ = σ̂²I) is the exact one. With truths drawn
//! from the prior (uniform on the Table 5.3 domain in the unit coordinates
//! the sampler uses, g1 + g2 ≤ 0.99) a correct sampler gives 90 % intervals
//! that cover the truth in 90 % of cells up to the binomial noise; with
//! truths drawn from the coverage cohort's two groups it shows what the
//! Bayesian intervals of the same likelihood give on cells not drawn from
//! the prior — the part of a coverage figure no error model can change.
//!
//! Each cell is fitted as a cohort cell is (multistart on the surrogate,
//! `starts` points) and its posterior sampled with the default settings but
//! `max_steps` 2000 (as `posterior_coverage`), cells in parallel.
//!
//! ```text
//! cargo run --release -p nlvid-report --example posterior_sbc \
//!     [cells] [noise] [seed] [prior|groups] [key=value ...]
//! ```
//! (defaults 100, 0.02, 17, prior; keys `starts` (`DEFAULT_STARTS`), `surrogate_error`
//! (false) and the sampler's `steps`, `burn`, `max_steps` (2000),
//! `ridge_fraction`, `refresh_fraction`, `refit_proposal`, `rungs`, `ridge_time`, `ridge_starts`, `mode_starts`; `only=I,J,…` runs those cells only;
//! `noise_only=true` prints the noise estimate's σ̂/σ and stops;
//! `is_check=true` checks each missed G0 interval by importance sampling,
//! `importance_tails`). Prints the coverage of G0,
//! g1 + g2 and G(52 s) with binomial standard errors, R̂ and the misses.

use std::path::Path;

use nlvid_inverse::posterior::{CurveLikelihood, noise_sd};
use nlvid_inverse::{
    Coordinates, FixedInputs, Model, MultiStart, PosteriorSettings, SurrogateFitter,
    load_kriging_surrogate, relaxation, sample_posterior,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

mod coverage_cohort;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = args.get(1).map_or(Ok(100), |s| s.parse())?;
    let noise: f64 = args.get(2).map_or(Ok(0.02), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(17), |s| s.parse())?;
    let groups = match args.get(4).map(String::as_str) {
        None | Some("prior") => false,
        Some("groups") => true,
        Some(other) => return Err(format!("expected prior or groups, got {other}").into()),
    };
    let (mut starts, mut settings) = (nlvid_inverse::DEFAULT_STARTS, PosteriorSettings::new(0.0));
    settings.max_steps = 2000;
    settings.threads = 1;
    settings.surrogate_error = false;
    let mut only: Vec<usize> = Vec::new();
    for kv in args.iter().skip(5) {
        let (k, v) = kv
            .split_once('=')
            .ok_or_else(|| format!("expected key=value, got {kv}"))?;
        match k {
            "starts" => starts = v.parse()?,
            "surrogate_error" => settings.surrogate_error = v.parse()?,
            "steps" => settings.steps = v.parse()?,
            "burn" => settings.burn = v.parse()?,
            "max_steps" => settings.max_steps = v.parse()?,
            "ridge_fraction" => settings.ridge_fraction = v.parse()?,
            "refresh_fraction" => settings.refresh_fraction = v.parse()?,
            "refit_proposal" => settings.refit_proposal = v.parse()?,
            "rungs" => settings.rungs = v.parse()?,
            "ridge_time" => settings.ridge_time = v.parse()?,
            "ridge_starts" => settings.ridge_starts = v.parse()?,
            "mode_starts" => settings.mode_starts = v.parse()?,
            "temper_rhat" => settings.temper_rhat = Some(v.parse()?),
            "temper_burn" => settings.temper_burn = v.parse()?,
            "hot_starts" => settings.hot_starts = v.parse()?,
            "only" => {
                only = v
                    .split(',')
                    .map(str::parse)
                    .collect::<Result<Vec<usize>, _>>()?
            }
            "noise_only" | "is_check" => {}
            _ => return Err(format!("unknown key {k}").into()),
        }
    }
    let surrogate_error = settings.surrogate_error;
    let noise_only = args.iter().any(|a| a == "noise_only=true");
    let is_check = args.iter().any(|a| a == "is_check=true");
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo/metamodel");
    let surrogate = load_kriging_surrogate(
        &dir.join("model.json"),
        &dir.join("meta.json"),
        Coordinates::Physical,
    )?;
    let fitter = SurrogateFitter::new(surrogate, None)?;
    let s = fitter.surrogate();
    let domain = s.domain().clone();
    let t_end = *s.times().last().ok_or("empty grid")?;

    // Truths and noisy curves, one seeded stream in cell order.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let spec = coverage_cohort::wide_groups(cells, seed, noise);
    let mut truths = Vec::with_capacity(cells);
    while truths.len() < cells {
        let x = if groups {
            spec.groups[truths.len() % 2]
                .draw(&domain, &mut rng)?
                .to_vec()
        } else {
            let u: Vec<f64> = (0..domain.len()).map(|_| rng.random::<f64>()).collect();
            let x = domain.from_unit(&u);
            if !domain.feasible(&x, 0.0) {
                continue;
            }
            x
        };
        let y = s.response(&x)?;
        let sd = noise * y.iter().fold(0.0f64, |a, &b| a.max(b));
        let data: Vec<f64> = y
            .iter()
            .map(|v| v + sd * nlvid_forward::curves::standard_normal(&mut rng))
            .collect();
        truths.push((x, data, sd));
    }
    // The noise estimate on these curves (the likelihood's σ̂).
    let ratios: Vec<f64> = truths
        .iter()
        .map(|(_, d, sd)| noise_sd(s.times(), d).map(|e| e / sd))
        .collect::<Result<_, _>>()?;
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    let sd_ratio =
        (ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / ratios.len() as f64).sqrt();
    println!("noise estimate sigma_hat/sigma: mean {mean:.4}, sd {sd_ratio:.4}");
    if noise_only {
        return Ok(());
    }

    let t0 = std::time::Instant::now();
    let settings = PosteriorSettings {
        t_end,
        band_times: PosteriorSettings::new(t_end).band_times,
        ..settings
    };
    let results: Vec<_> = truths
        .par_iter()
        .enumerate()
        .filter(|(i, _)| only.is_empty() || only.contains(i))
        .map(|(i, (x, data, _))| -> Result<_, String> {
            let ms = MultiStart::new()
                .with_starts(starts)
                .map(|m| m.with_seed(1))
                .map_err(|e| e.to_string())?;
            let fit = fitter
                .fit_fixed(
                    &[("cell", data.as_slice())],
                    &ms,
                    &FixedInputs::none(&domain),
                )
                .map_err(|e| format!("cell {i}: fit: {e}"))?;
            let p = sample_posterior(
                s,
                data,
                (&fit.fit.best.x, &fit.fit.other_optima()),
                &settings,
            )
            .map_err(|e| format!("cell {i}: posterior: {e}"))?;
            // ln L at the truth over ln L at the fit (> 0: the fit missed
            // a better region).
            let sigma_hat = noise_sd(s.times(), data).map_err(|e| e.to_string())?;
            let lik = CurveLikelihood::new(s, data, sigma_hat, false, false)
                .map_err(|e| e.to_string())?
                .with_surrogate_error(surrogate_error);
            let gain = lik.value(x).map_err(|e| e.to_string())?
                - lik.value(&fit.fit.best.x).map_err(|e| e.to_string())?;
            Ok((i, x.clone(), p, gain))
        })
        .collect();
    let seconds = t0.elapsed().as_secs_f64();

    let (mut n, mut cover, mut rhat_max, mut above) = (0usize, [0usize; 3], 0.0f64, 0usize);
    let mut misses = Vec::new();
    for r in results {
        let (i, x, p, gain) = match r {
            Ok(v) => v,
            Err(e) => {
                println!("  {e}");
                continue;
            }
        };
        let g = relaxation(&domain, &x)?;
        let want = [g.g0(), 1.0 - g.prony().long_term_weight(), g.value(p.t_end)];
        let got = [&p.g0, &p.g_sum, &p.g_end];
        n += 1;
        for k in 0..3 {
            if got[k].covers(want[k]) {
                cover[k] += 1;
            } else {
                let side = if want[k] < got[k].lower {
                    "below"
                } else {
                    "above"
                };
                if is_check && k == 0 {
                    let tails = importance_tails(s, &truths[i].1, &x, &p, surrogate_error)?;
                    misses.push(format!(
                        "cell {i} G0 importance check: P(G0 < lower) {:.3}, P(G0 > upper) {:.3} \
                         (the sampler: 0.05 each), importance ESS {:.0}; {}",
                        tails.0,
                        tails.1,
                        tails.2,
                        fast_term(&domain, &x, &p.draws)
                    ));
                }
                misses.push(format!(
                    "cell {i} {}: truth {side} [{:.4e}, {:.4e}] ({:.4e}); ln L(truth) - ln L(fit) \
                     {gain:.2}; R-hat {:.4}, rungs {}, kept {}; x {:?}",
                    ["G0", "g_sum", "G_end"][k],
                    got[k].lower,
                    got[k].upper,
                    want[k],
                    p.rhat_max,
                    p.rungs,
                    p.kept_steps,
                    x.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>()
                ));
            }
        }
        rhat_max = rhat_max.max(p.rhat_max);
        above += usize::from(!(p.rhat_max <= 1.01));
    }
    println!(
        "{n} cells drawn from the {} on the surrogate's own curves + {noise} x peak noise, seed \
         {seed}; likelihood {}",
        if groups { "two groups" } else { "prior" },
        if surrogate_error {
            "with the surrogate's error (not exact here)"
        } else {
            "noise only (exact here)"
        }
    );
    for (k, name) in ["G0", "g1 + g2", "G(t_end)"].iter().enumerate() {
        let frac = cover[k] as f64 / n.max(1) as f64;
        let se = (0.9 * 0.1 / n.max(1) as f64).sqrt();
        println!(
            "coverage of the 90 % interval of {name}: {} / {n} = {:.1} % ({:+.1} se from 90 %)",
            cover[k],
            100.0 * frac,
            (frac - 0.9) / se
        );
    }
    println!(
        "largest split R-hat {rhat_max:.4} ({above} cells above 1.01); {seconds:.1} s wall on {} \
         threads",
        rayon::current_num_threads()
    );
    for m in &misses {
        println!("  miss {m}");
    }
    Ok(())
}

/// The fast term where the draws are and at the truth: the medians of
/// each parameter over the kept draws and of the fast viscosity
/// η1 = G0·g1·τ1 (the quantity the viscous ridge map keeps), against the
/// truth's (Table 5.3 order G0, g1, g2, τ1, τ2).
fn fast_term(domain: &nlvid_model::Domain, truth: &[f64], draws: &[Vec<f64>]) -> String {
    let idx = |n: &str| domain.index_of(n).unwrap_or(usize::MAX);
    let [g0, g1, t1] = [
        nlvid_model::names::G0,
        &nlvid_model::names::weight(1),
        &nlvid_model::names::time(1),
    ]
    .map(idx);
    if [g0, g1, t1].iter().any(|&i| i >= truth.len()) || draws.is_empty() {
        return String::new();
    }
    let median = |f: &dyn Fn(&[f64]) -> f64| {
        let mut v: Vec<f64> = draws.iter().map(|d| f(d)).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let eta = |x: &[f64]| x[g0] * x[g1] * x[t1];
    let medians: Vec<String> = (0..truth.len())
        .map(|i| format!("{:.4}", median(&|x| x[i])))
        .collect();
    format!(
        "draws' medians {medians:?}, eta1 {:.4e} (truth {:.4e})",
        median(&eta),
        eta(truth)
    )
}

/// An independent check of one posterior's G0 interval by importance
/// sampling: 20 000 draws in u from a defensive mixture — a Student t
/// (ν = 4) around the sampler's draws and one around the truth, both with
/// 4 × the draws' covariance, and the uniform prior (weight 0.1) — weighted
/// by L/q. Returns the posterior probabilities of G0 below and above the
/// sampler's interval and the weights' effective sample size.
fn importance_tails(
    s: &nlvid_inverse::KrigingSurrogate,
    data: &[f64],
    truth: &[f64],
    p: &nlvid_inverse::Posterior,
    surrogate_error: bool,
) -> Result<(f64, f64, f64), Box<dyn std::error::Error>> {
    use nalgebra::{DMatrix, DVector};
    const NU: f64 = 4.0;
    const N: usize = 20_000;
    let domain = s.domain();
    let d = domain.len();
    let sigma = noise_sd(s.times(), data)?;
    let lik =
        CurveLikelihood::new(s, data, sigma, false, false)?.with_surrogate_error(surrogate_error);
    let us: Vec<DVector<f64>> = p
        .draws
        .iter()
        .map(|x| DVector::from_vec(domain.to_unit(x)))
        .collect();
    let mean = us.iter().fold(DVector::zeros(d), |a, u| a + u) / us.len() as f64;
    let mut cov = us.iter().fold(DMatrix::zeros(d, d), |a, u| {
        let c = u - &mean;
        a + &c * c.transpose()
    }) / us.len() as f64
        * 4.0;
    for i in 0..d {
        cov[(i, i)] += 1e-8;
    }
    let chol = cov.clone().cholesky().ok_or("draws' covariance")?;
    let l = chol.l();
    let ln_det = 2.0 * l.diagonal().iter().map(|v| v.ln()).sum::<f64>();
    // ln Γ((ν + d)/2) − ln Γ(ν/2) for ν = 4, d = 5: ln Γ(4.5) − ln Γ(2).
    assert_eq!(d, 5, "the constant below is for five parameters");
    let ln_norm =
        2.453_736_570_842_442 - 0.5 * d as f64 * (NU * std::f64::consts::PI).ln() - 0.5 * ln_det;
    let centres = [mean.clone(), DVector::from_vec(domain.to_unit(truth))];
    let ln_t = |u: &DVector<f64>, c: &DVector<f64>| {
        let z = chol.solve(&(u - c));
        let q = (u - c).dot(&z);
        ln_norm - 0.5 * (NU + d as f64) * (1.0 + q / NU).ln()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let normal = |rng: &mut ChaCha8Rng| nlvid_forward::curves::standard_normal(rng);
    let (mut us, mut ln_q) = (Vec::with_capacity(N), Vec::with_capacity(N));
    for k in 0..N {
        let u = if k % 10 == 0 {
            DVector::from_fn(d, |_, _| rng.random::<f64>())
        } else {
            let z = DVector::from_fn(d, |_, _| normal(&mut rng));
            let w: f64 = (0..4).map(|_| normal(&mut rng).powi(2)).sum::<f64>() / NU;
            &centres[k % 2] + &l * z / w.sqrt()
        };
        let q = 0.1 * f64::from(u.iter().all(|v| (0.0..=1.0).contains(v)))
            + 0.45 * ln_t(&u, &centres[0]).exp()
            + 0.45 * ln_t(&u, &centres[1]).exp();
        ln_q.push(q.ln());
        us.push(u);
    }
    let inside: Vec<usize> = (0..N)
        .filter(|&k| {
            let u = us[k].as_slice();
            u.iter().all(|v| (0.0..=1.0).contains(v)) && domain.feasible(&domain.from_unit(u), 0.0)
        })
        .collect();
    let xs: Vec<Vec<f64>> = inside
        .iter()
        .map(|&k| domain.from_unit(us[k].as_slice()))
        .collect();
    let ln_l = lik.values(&xs)?;
    let ln_w: Vec<f64> = inside
        .iter()
        .zip(&ln_l)
        .map(|(&k, l)| l - ln_q[k])
        .collect();
    let top = ln_w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let w: Vec<f64> = ln_w.iter().map(|v| (v - top).exp()).collect();
    let total: f64 = w.iter().sum();
    let (mut below, mut above) = (0.0, 0.0);
    for (x, wi) in xs.iter().zip(&w) {
        let g0 = relaxation(domain, x)?.g0();
        if g0 < p.g0.lower {
            below += wi;
        } else if g0 > p.g0.upper {
            above += wi;
        }
    }
    let ess = total * total / w.iter().map(|v| v * v).sum::<f64>();
    Ok((below / total, above / total, ess))
}
