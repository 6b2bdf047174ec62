//! What the FE recovery examples (`fe_recovery`, `capsule_recovery`)
//! share: the forward model of the study, the Kriging surrogate on the
//! domain its `meta.json` stores, and the checking set of the export with
//! each row's inputs in the domain's order.

use std::path::Path;

use anyhow::{Context, bail};
use nlvid_inverse::{Coordinates, KrigingSurrogate, read_meta};
use nlvid_model::ForwardModel;
use nlvid_surrogate::KrigingModel;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The study's forward model, the surrogate and the checking set.
pub struct Setup {
    /// The forward model of the study's `[forward]`.
    pub fe: Box<dyn ForwardModel>,
    /// The domain of `train/meta.json`.
    pub domain: nlvid_model::Domain,
    /// The meta-model on that domain.
    pub sur: KrigingSurrogate,
    /// Checking inputs, in the domain's parameter order.
    pub xs: Vec<Vec<f64>>,
    /// Checking responses (rows of `check/Y.csv`).
    pub ys: Vec<Vec<f64>>,
}

/// Loads the forward model of `study_path`, the Kriging model file
/// `model_path` on the domain stored in `export/train/meta.json`, and at
/// least `cases` checking runs of `export/check`.
pub fn setup(
    study_path: &str,
    model_path: &str,
    export: &Path,
    cases: usize,
) -> anyhow::Result<Setup> {
    let mut study = nlvid_study::Study::load(study_path)?;
    let fe = nlvid_forward::from_study(&mut study)?;
    // The domain the meta-model was designed on, as `nlvid build --export`
    // stored it (the FE model's parameters, in its order).
    let meta = read_meta(&export.join("train/meta.json"))?;
    let domain = meta.domain.clone();
    domain.check_names(&fe.parameter_names())?;
    let kriging: KrigingModel = serde_json::from_slice(&std::fs::read(model_path)?)?;
    let sur = KrigingSurrogate::new(kriging, domain.clone(), meta.time_s, Coordinates::Physical)?;
    let (xhead, xs) = read_csv(&export.join("check/X.csv"))?;
    let (_, ys) = read_csv(&export.join("check/Y.csv"))?;
    if xs.len() < cases {
        bail!("only {} checking runs, need {cases}", xs.len());
    }
    // Export columns by name (the first one is the run index).
    let column = |name: &str| {
        xhead
            .iter()
            .position(|h| h == name || h.starts_with(&format!("{name} [")))
            .with_context(|| format!("column {name} not in {xhead:?}"))
    };
    let cols = domain
        .params()
        .iter()
        .map(|p| column(&p.name))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let xs = xs
        .iter()
        .map(|x| cols.iter().map(|&c| x[c]).collect())
        .collect();
    Ok(Setup {
        fe,
        domain,
        sur,
        xs,
        ys,
    })
}

fn read_csv(path: &Path) -> anyhow::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let mut rdr =
        csv::Reader::from_path(path).with_context(|| format!("cannot open {}", path.display()))?;
    let head = rdr.headers()?.iter().map(str::to_owned).collect();
    let mut rows = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        let row = rec
            .iter()
            .map(|v| v.trim().parse::<f64>())
            .collect::<Result<Vec<_>, _>>()
            .with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        rows.push(row);
    }
    Ok((head, rows))
}

/// Standard normal by Box–Muller (seeded, deterministic; u1 kept from 0 by
/// 1e-300 — the stream of the documented runs).
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
