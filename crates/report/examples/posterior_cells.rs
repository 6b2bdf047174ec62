//! Convergence of the per-cell posteriors (issue 17) cell by cell: the
//! coverage example's synthetic cohort is written and fitted, and for the
//! named cells (all when none is named) the posterior is sampled with the
//! given settings; per parameter this prints the split R̂ across
//! ensembles, the ESS and each ensemble's median and 5/95 % quantiles in
//! the domain's unit coordinates u (which ensemble is off, and where),
//! and per posterior the wall and CPU seconds of `sample_posterior` alone
//! (the curve writing and the fit excluded; `threads=2` splits each batch
//! of proposals over two threads, the same draws).
//!
//! ```text
//! cargo run --release -p nlvid-report --example posterior_cells \
//!     [cells] [noise] [seed] [max_steps] [refresh=F] [refit=BOOL] [ridge=F] [ridge_time=kept|redrawn|viscous] \
//!     [threads=N] [rungs=N] [ratio=F] [temper_after=N] [temper_ridge=F] [temper_burn=N] \
//!     [temper_min=N] [temper_rhat=F|none] [hot_starts=B] [check=N] \
//!     [delayed=BOOL,...] [seed=N] [prior=BOOL] [heavy_tails=BOOL] \
//!     [direction_scales=BOOL] [variance_at_fit=BOOL] [cell ...]
//! ```
//! (`prior=true`: the cells drawn from the posteriors' prior,
//! `DemoSpec::from_prior`, as `posterior_coverage … prior`.)
//! (`rungs`, `ratio`, `temper_after`, `temper_ridge`, `temper_burn`,
//! `temper_min` (`temper_min_steps`) and `delayed` (delayed
//! acceptance) take comma-separated lists, e.g. `delayed=true,false`: every
//! combination in turn, on the same curves and fits; `seed` is the
//! sampler's, the study's fit seed by default.)

use std::path::Path;

use nlvid_inverse::Model;
use nlvid_inverse::posterior::{PosteriorSettings, RidgeTime, quantile, sample_posterior};
use nlvid_report::cell::{CellModel, fit_cell};
use nlvid_report::cohort::discover;
use nlvid_report::demo::write_demo_data;
use nlvid_report::settings::CohortSettings;

mod coverage_cohort;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let cells: usize = args.get(1).map_or(Ok(100), |s| s.parse())?;
    let noise: f64 = args.get(2).map_or(Ok(0.02), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(17), |s| s.parse())?;
    let max_steps: usize = args.get(4).map_or(Ok(2000), |s| s.parse())?;
    let names: Vec<String> = args
        .iter()
        .skip(5)
        .filter(|a| !a.contains('='))
        .cloned()
        .collect();
    let opt = |key: &str| {
        args.iter()
            .skip(5)
            .find_map(|a| a.strip_prefix(&format!("{key}=")).map(str::to_string))
    };
    let refresh: Option<f64> = opt("refresh").map(|v| v.parse()).transpose()?;
    let refit: Option<bool> = opt("refit").map(|v| v.parse()).transpose()?;
    let ridge: Option<f64> = opt("ridge").map(|v| v.parse()).transpose()?;
    let ridge_time: RidgeTime = opt("ridge_time").map_or(Ok(RidgeTime::Kept), |v| v.parse())?;
    let threads: usize = opt("threads").map_or(Ok(1), |v| v.parse())?;
    let heavy_tails: Option<bool> = opt("heavy_tails").map(|v| v.parse()).transpose()?;
    let variance_at_fit: Option<bool> = opt("variance_at_fit").map(|v| v.parse()).transpose()?;
    let direction_scales: Option<bool> = opt("direction_scales").map(|v| v.parse()).transpose()?;
    // The tempering options take comma-separated lists: every
    // combination is sampled in turn on the same curves (one curve
    // writing for several settings).
    let list = |key: &str| -> Result<Vec<Option<f64>>, std::num::ParseFloatError> {
        opt(key).map_or(Ok(vec![None]), |v| {
            v.split(',').map(|s| s.parse().map(Some)).collect()
        })
    };
    let (rungs_l, ratio_l) = (list("rungs")?, list("ratio")?);
    let (after_l, tridge_l) = (list("temper_after")?, list("temper_ridge")?);
    let (tburn_l, tmin_l) = (list("temper_burn")?, list("temper_min")?);
    let check: Option<usize> = opt("check").map(|v| v.parse()).transpose()?;
    // `none`: tempered only after `temper_after` (the sampler before
    // session 21).
    let temper_rhat: Option<Option<f64>> = opt("temper_rhat")
        .map(|v| (v != "none").then(|| v.parse()).transpose())
        .transpose()?;
    let hot_starts: Option<bool> = opt("hot_starts").map(|v| v.parse()).transpose()?;
    let sampler_seed: Option<u64> = opt("seed").map(|v| v.parse()).transpose()?;
    let delayed: Vec<Option<bool>> = opt("delayed").map_or(Ok(vec![None]), |v| {
        v.split(',')
            .map(|s| s.parse().map(Some))
            .collect::<Result<_, _>>()
    })?;
    let mut tempering = Vec::new();
    for &r in &rungs_l {
        for &q in &ratio_l {
            for &a in &after_l {
                for &t in &tridge_l {
                    for &da in &delayed {
                        for &b in &tburn_l {
                            for &m in &tmin_l {
                                // Counts are written as whole numbers.
                                tempering.push((
                                    (r.map(|v| v as usize), q, a.map(|v| v as usize), t, da),
                                    (b.map(|v| v as usize), m.map(|v| v as usize)),
                                ));
                            }
                        }
                    }
                }
            }
        }
    }
    let demo =
        std::fs::canonicalize(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo"))?;
    let root = std::env::temp_dir().join(format!("nlvid-cells-{}", std::process::id()));
    let study = coverage_cohort::write_study(&root, &demo, "")?;
    let spec = nlvid_report::demo::DemoSpec {
        from_prior: opt("prior").map_or(Ok(false), |v| v.parse())?,
        ..coverage_cohort::wide_groups(cells, seed, noise)
    };
    let files = write_demo_data(&spec, &study, &demo.join("metamodel.toml"))?;
    let settings = CohortSettings::load(&study)?;
    let model = CellModel::load(&settings)?;
    let CellModel::Surrogate(fitter, _) = &model else {
        return Err("the demo study fits a meta-model".into());
    };
    let s = fitter.surrogate();
    let domain = Model::domain(s).clone();
    for inp in discover(&files.data)? {
        if !names.is_empty() && !names.iter().any(|n| inp.file.contains(&format!("{n}."))) {
            continue;
        }
        let r = fit_cell(&settings, &model, &inp);
        let Some(truth) = files
            .cells
            .iter()
            .find(|t| t.cell == r.cell && t.group == r.group)
        else {
            continue;
        };
        let x_hat: Vec<f64> = r.parameters.iter().map(|p| p.value).collect();
        let ps = PosteriorSettings {
            max_steps,
            seed: sampler_seed.unwrap_or(settings.seed),
            keep: usize::MAX / 2,
            ..PosteriorSettings::new(settings.hold_end)
        };
        // Without refresh=/refit=: the sampler before issue 17's second
        // round (neither), refits only, and both.
        let configs: Vec<(f64, bool)> = match (refresh, refit) {
            (None, None) => vec![(0.0, false), (0.0, true), (ps.refresh_fraction, true)],
            _ => vec![(
                refresh.unwrap_or(ps.refresh_fraction),
                refit.unwrap_or(ps.refit_proposal),
            )],
        };
        for (
            (refresh_fraction, refit_proposal),
            ((rungs, ratio, temper_after, temper_ridge, da), (temper_burn, temper_min)),
        ) in configs
            .iter()
            .flat_map(|&c| tempering.iter().map(move |&t| (c, t)))
        {
            let ps = PosteriorSettings {
                refresh_fraction,
                refit_proposal,
                ridge_fraction: ridge.unwrap_or(ps.ridge_fraction),
                ridge_time,
                threads,
                rungs: rungs.unwrap_or(ps.rungs),
                rung_ratio: ratio.unwrap_or(ps.rung_ratio),
                temper_after: temper_after.unwrap_or(ps.temper_after),
                temper_ridge: temper_ridge.unwrap_or(ps.temper_ridge),
                temper_burn: temper_burn.unwrap_or(ps.temper_burn),
                temper_min_steps: temper_min.unwrap_or(ps.temper_min_steps),
                temper_rhat: temper_rhat.unwrap_or(ps.temper_rhat),
                hot_starts: hot_starts.unwrap_or(ps.hot_starts),
                check_every: check.unwrap_or(ps.check_every),
                delayed_acceptance: da.unwrap_or(ps.delayed_acceptance),
                heavy_tails: heavy_tails.unwrap_or(ps.heavy_tails),
                direction_scales: direction_scales.unwrap_or(ps.direction_scales),
                variance_at_fit: variance_at_fit.unwrap_or(ps.variance_at_fit),
                ..ps.clone()
            };
            println!(
                "refresh {refresh_fraction}, refit {refit_proposal}, ridge {}, ridge_time \
                 {ridge_time:?}, rungs {} ratio {} after {} (or R-hat > {:?}) ridge {} burn {} min {}, R-hat checked \
                 every {}, delayed acceptance {}:",
                ps.ridge_fraction,
                ps.rungs,
                ps.rung_ratio,
                ps.temper_after,
                ps.temper_rhat,
                ps.temper_ridge,
                ps.temper_burn,
                ps.temper_min_steps,
                ps.check_every,
                ps.delayed_acceptance
            );
            let (t0, cpu0) = (std::time::Instant::now(), cpu_time::ProcessTime::now());
            let p = sample_posterior(s, &r.data, (&x_hat, &r.other_optima), &ps)?;
            let (wall, cpu) = (t0.elapsed(), cpu0.elapsed());
            let n_per = p.draws.len() / ps.ensembles;
            println!(
                "{} R-hat {:.4} ESS {:.0} acc {:.2} kept {} per walker, rungs {} (swaps {:.2}), \
                 {} proposals ({} evaluated), {:.2} s wall, {:.2} s CPU ({threads} thread(s)); \
                 truth u {:?}; fit u {:?}",
                r.cell,
                p.rhat_max,
                p.ess_min,
                p.acceptance,
                p.kept_steps,
                p.rungs,
                p.swap_acceptance,
                p.proposals,
                p.evaluations,
                wall.as_secs_f64(),
                cpu.as_secs_f64(),
                round(&domain.to_unit(&truth.x)),
                round(&domain.to_unit(&x_hat)),
            );
            for (i, (name, iv)) in p.parameters.iter().enumerate() {
                let mut per = Vec::new();
                for e in 0..ps.ensembles {
                    let mut v: Vec<f64> = p.draws[e * n_per..(e + 1) * n_per]
                        .iter()
                        .map(|x| domain.to_unit(x)[i])
                        .collect();
                    v.sort_by(f64::total_cmp);
                    per.push(format!(
                        "{:.3}[{:.3},{:.3}]",
                        quantile(&v, 0.5),
                        quantile(&v, 0.05),
                        quantile(&v, 0.95)
                    ));
                }
                println!(
                    "   {name:5} R-hat {:.4} ESS {:6.0}  per ensemble (u) {}",
                    iv.rhat,
                    iv.ess,
                    per.join(" ")
                );
            }
            for (name, iv) in [("G0", p.g0), ("gsum", p.g_sum), ("Gend", p.g_end)] {
                println!("   {name:5} R-hat {:.4} ESS {:6.0}", iv.rhat, iv.ess);
            }
        }
    }
    std::fs::remove_dir_all(&root)?;
    Ok(())
}

fn round(u: &[f64]) -> Vec<f64> {
    u.iter().map(|v| (v * 1000.0).round() / 1000.0).collect()
}
