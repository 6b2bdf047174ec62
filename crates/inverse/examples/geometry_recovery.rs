//! Issue 17, per-cell geometry: cells of varied shape fitted with their own
//! height H and base diameter D, and with the mean shape (the thesis's way,
//! §5.4.2), on a meta-model with H and D as inputs
//! (`[forward] geometry = "inputs"`).
//!
//! The meta-model is fitted here from the training runs of the build's store
//! (gauss/poly1, log axes kriged in ln x, F ∝ G0, PCA 1 − 1e-6: the settings
//! of the adaptive infill), so a build that was stopped early can be used as
//! it is; `--max-train N` uses the first N stored training runs only.
//! The "cells" are the build's admissible *checking* runs — FE curves at
//! known parameters that the surrogate never saw — whose H and D lie
//! within ±20 % of the mean shape (setup 1: 12.22 µm, 28.88 µm), the first
//! `CASES` of them, with 2 % Gaussian noise (σ = 0.02 · peak force,
//! seeded). Each is fitted twice (8 SLSQP starts): H, D held at the cell's
//! values, and at the mean shape; the table gives |G0 − G0_true|/G0_true
//! for both. Target (issue 17): own shape within 5 % in ≥ 9/10 cells.
//!
//! ```sh
//! RAYON_NUM_THREADS=1 nice -n 10 nlvid build examples/metamodel/afm-fe-geometry.toml
//! cargo run --release -p nlvid-inverse --example geometry_recovery -- \
//!     examples/metamodel/afm-fe-geometry.toml examples/metamodel/afm-fe-geometry.store
//! ```

use std::path::Path;

use anyhow::{Context, bail};
use nlvid_inverse::{Coordinates, FixedInputs, KrigingSurrogate, MultiStart, SurrogateFitter};
use nlvid_model::names::{DIAMETER, G0, HEIGHT};
use nlvid_surrogate::{
    BuildStudy, Correlation, KrigingModel, KrigingSettings, OutputScale, Regression, faer::Mat,
    load,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const CASES: usize = 10;
/// Setup-1 mean shape (Table 5.2, App. B.2), m.
const MEAN_H: f64 = 12.22e-6;
const MEAN_D: f64 = 28.88e-6;
/// Cells drawn within this relative distance of the mean shape.
const SPREAD: f64 = 0.2;

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let max_train = match args.iter().position(|a| a == "--max-train") {
        Some(i) => Some(args.get(i + 1).context("--max-train N")?.parse::<usize>()?),
        None => None,
    };
    if args.len() < 3 {
        bail!("usage: geometry_recovery STUDY.toml STORE_DIR [--max-train N]");
    }
    let (study_path, store) = (Path::new(&args[1]), Path::new(&args[2]));
    let study = BuildStudy::load(study_path)?;
    let domain = study.settings.design.domain.clone();
    let filters = &study.settings.filters;
    let (ih, id, i0) = (
        domain
            .index_of(HEIGHT)
            .context("the meta-model has no input H")?,
        domain
            .index_of(DIAMETER)
            .context("the meta-model has no input D")?,
        domain.index_of(G0).context("no G0")?,
    );

    let mut train = load(&store.join("train"), filters)?;
    if let Some(n) = max_train {
        let keep: Vec<bool> = train.index.iter().map(|&i| i < n).collect();
        let pick = |v: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            v.into_iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(r, _)| r)
                .collect()
        };
        train.x = pick(std::mem::take(&mut train.x));
        train.y = pick(std::mem::take(&mut train.y));
    }
    let check = load(&store.join("check"), filters)?;
    let mut ks = KrigingSettings::new(Regression::Poly1, Correlation::Gauss, domain.len());
    ks.log_inputs = domain.params().iter().map(|p| p.is_log()).collect();
    ks.output_scale = Some(OutputScale::Linear { input: i0 });
    ks.pca_energy = Some(0.999_999);
    let (n, d, m) = (train.x.len(), domain.len(), train.y[0].len());
    let t0 = std::time::Instant::now();
    let kriging = KrigingModel::fit(
        Mat::from_fn(n, d, |i, k| train.x[i][k]).as_ref(),
        Mat::from_fn(n, m, |i, j| train.y[i][j]).as_ref(),
        &ks,
    )?;
    let fit_s = t0.elapsed().as_secs_f64();
    let sur = KrigingSurrogate::new(
        kriging,
        domain.clone(),
        train.meta.time.clone(),
        Coordinates::Physical,
    )?;
    use nlvid_inverse::Model as _;
    let mut errs = Vec::new();
    for (x, y) in check.x.iter().zip(&check.y) {
        errs.push(nlvid_inverse::range_normalised_rmse(
            &sur.response(x)?,
            y,
            None,
        )?);
    }
    errs.sort_by(f64::total_cmp);
    println!(
        "meta-model: {n} admissible training runs of {} stored ({} design points), fitted in \
         {fit_s:.1} s; checking set {} admissible runs: eq. 4.4 error max {:.2} %, median {:.2} %",
        train.counts.design - train.counts.missing,
        train.counts.design,
        errs.len(),
        100.0 * errs.last().copied().unwrap_or(f64::NAN),
        100.0 * errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN)
    );

    let cells: Vec<(&Vec<f64>, &Vec<f64>)> = check
        .x
        .iter()
        .zip(&check.y)
        .filter(|(x, _)| {
            (x[ih] / MEAN_H - 1.0).abs() <= SPREAD && (x[id] / MEAN_D - 1.0).abs() <= SPREAD
        })
        .take(CASES)
        .collect();
    if cells.len() < CASES {
        bail!(
            "only {} admissible checking runs with H, D within ±20 % of the mean",
            cells.len()
        );
    }
    let fitter = SurrogateFitter::new(sur, None)?;
    let mean = FixedInputs::new(&domain, &[(HEIGHT, MEAN_H), (DIAMETER, MEAN_D)])?;
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    println!(
        "| cell | H µm (ΔH) | D µm (ΔD) | G0 true Pa | g1 | g2 | τ1 s | τ2 s | G0 own shape | \
         error own | G0 mean shape | error mean | mean/own − 1 | misfit own / mean |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let (mut own_ok, mut mean_within, mut worst_mean, mut sum_mean) = (0, 0, 0.0f64, 0.0);
    let mut own_errs = Vec::new();
    let mut shifts = Vec::new();
    for (case, (x, clean)) in cells.iter().enumerate() {
        let peak = clean.iter().copied().fold(0.0, f64::max);
        let data: Vec<f64> = clean
            .iter()
            .map(|y| y + 0.02 * peak * normal(&mut rng))
            .collect();
        let ms = MultiStart::new().with_starts(8)?.with_seed(case as u64);
        let own = FixedInputs::new(&domain, &[(HEIGHT, x[ih]), (DIAMETER, x[id])])?;
        let a = fitter.fit_fixed(&[("cell", data.as_slice())], &ms, &own)?;
        let b = fitter.fit_fixed(&[("cell", data.as_slice())], &ms, &mean)?;
        let g0 = x[i0];
        let ea = (a.fit.best.x[i0] - g0).abs() / g0;
        let eb = (b.fit.best.x[i0] - g0).abs() / g0;
        own_errs.push(ea);
        // the shape's own effect, whatever the identifiability of G0
        let shift = b.fit.best.x[i0] / a.fit.best.x[i0] - 1.0;
        shifts.push(shift.abs());
        if ea <= 0.05 {
            own_ok += 1;
        }
        worst_mean = worst_mean.max(eb);
        if eb <= 0.05 {
            mean_within += 1;
        }
        sum_mean += eb;
        println!(
            "| {case} | {:.2} ({:+.0} %) | {:.2} ({:+.0} %) | {:.1} | {:.3} | {:.3} | {:.3} | \
             {:.2} | {:.1} | {:.2} % | {:.1} | {:.2} % | {:+.2} % | {:.4} / {:.4} |",
            x[ih] * 1e6,
            100.0 * (x[ih] / MEAN_H - 1.0),
            x[id] * 1e6,
            100.0 * (x[id] / MEAN_D - 1.0),
            g0,
            x[1],
            x[2],
            x[3],
            x[4],
            a.fit.best.x[i0],
            100.0 * ea,
            b.fit.best.x[i0],
            100.0 * eb,
            100.0 * shift,
            a.fit.best.misfit,
            b.fit.best.misfit
        );
    }
    own_errs.sort_by(f64::total_cmp);
    shifts.sort_by(f64::total_cmp);
    println!(
        "own shape: G0 within 5 % in {own_ok}/{CASES} (median error {:.2} %); mean shape: \
         within 5 % in {mean_within}/{CASES}, mean error {:.2} %, worst {:.2} %; \
         |G0 mean shape / G0 own shape − 1|: median {:.2} %, max {:.2} %",
        100.0 * own_errs[CASES / 2],
        100.0 * sum_mean / CASES as f64,
        100.0 * worst_mean,
        100.0 * shifts[CASES / 2],
        100.0 * shifts[CASES - 1]
    );
    Ok(())
}
