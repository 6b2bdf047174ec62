//! `nlvid surrogate fit | predict | check`: Kriging on any table.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, Subcommand};
use nlvid_surrogate::{
    Correlation, FitOptions, NamedModel, OptimiserSettings, Regression, check, read_table,
};

use crate::output::{emit, print_json, print_text, write_atomic};

/// Kriging surrogates (DACE-equivalent).
#[derive(Debug, Subcommand)]
pub enum SurrogateCmd {
    /// Fit a Kriging model to a table of inputs X and outputs Y.
    Fit(Box<FitArgs>),
    /// Predict outputs at the rows of X with a fitted model.
    Predict(PredictArgs),
    /// Range-normalised RMSE (thesis eq. 4.4) of a model on a checking set.
    Check(CheckArgs),
}

/// Arguments of `surrogate fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Inputs: CSV with a header, one row per site (a column named `index` is ignored).
    #[arg(long)]
    pub x: PathBuf,
    /// Outputs: CSV with a header, same rows as X.
    #[arg(long)]
    pub y: PathBuf,
    /// Regression: poly0, poly1, poly2.
    #[arg(long, default_value = "poly1", value_parser = |s: &str| Regression::parse(s)
          .ok_or_else(|| format!("`{s}`: expected poly0, poly1 or poly2")))]
    pub regression: Regression,
    /// Correlation: gauss, exp, expg, lin, spherical, cubic, spline.
    #[arg(long, default_value = "gauss", value_parser = |s: &str| Correlation::parse(s)
          .ok_or_else(|| format!("`{s}`: expected gauss, exp, expg, lin, spherical, cubic or spline")))]
    pub correlation: Correlation,
    /// Fixed θ (comma separated, one per input; expg: + power). Skips the search.
    #[arg(long, value_delimiter = ',')]
    pub theta: Option<Vec<f64>>,
    /// Start of the θ search (comma separated).
    #[arg(long, value_delimiter = ',')]
    pub theta0: Option<Vec<f64>>,
    /// Lower bounds of θ.
    #[arg(long, value_delimiter = ',')]
    pub lower: Option<Vec<f64>>,
    /// Upper bounds of θ.
    #[arg(long, value_delimiter = ',')]
    pub upper: Option<Vec<f64>>,
    /// Use DACE's boxmin instead of the default optimiser (to compare with published fits).
    #[arg(long)]
    pub boxmin: bool,
    /// Starts of the default optimiser.
    #[arg(long, default_value_t = 4)]
    pub starts: usize,
    /// Reduce outputs to principal components keeping this variance fraction (e.g. 0.99999).
    #[arg(long)]
    pub pca: Option<f64>,
    /// Nugget added to the diagonal of R (on top of DACE's (10+n)·eps).
    #[arg(long, default_value_t = 0.0)]
    pub nugget: f64,
    /// Krige ln y (every output must be > 0).
    #[arg(long)]
    pub log_outputs: bool,
    /// Every output is exactly proportional to this input column (e.g. the
    /// force to G0): krige y / x_col, predict x_col · ŷ. Recorded in the model.
    #[arg(long, value_name = "COLUMN")]
    pub proportional_to: Option<String>,
    /// With --proportional-to: the column holds a log-coded factor, y ∝ exp(SLOPE · x_col)
    /// (1 for ln G0, ln(hi/lo) for a unit coordinate on a log axis).
    #[arg(long, value_name = "SLOPE", requires = "proportional_to")]
    pub log_coded: Option<f64>,
    /// Krige these input columns in ln x (comma separated names; values must
    /// be > 0). Recorded in the model: predict takes the original values.
    #[arg(long, value_delimiter = ',', value_name = "COLUMNS")]
    pub log_inputs: Option<Vec<String>>,
    /// With more than 2× this many sites, screen the optimiser's starts on a
    /// random subset of this size (0: never).
    #[arg(long, default_value_t = 300)]
    pub screen_sites: usize,
    /// Model file to write (JSON).
    #[arg(long, short)]
    pub out: PathBuf,
}

/// Arguments of `surrogate predict`.
#[derive(Debug, Args)]
pub struct PredictArgs {
    /// Model file from `surrogate fit`.
    pub model: PathBuf,
    /// Points: CSV with a header.
    #[arg(long)]
    pub x: PathBuf,
    /// Output CSV (default: stdout; with --json, one JSON document with the output names).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Also write the MSE of every output (columns `mse_<output name>`).
    #[arg(long)]
    pub mse: bool,
}

/// Arguments of `surrogate check`.
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Model file from `surrogate fit`.
    pub model: PathBuf,
    /// Checking inputs (CSV).
    #[arg(long)]
    pub x: PathBuf,
    /// Checking outputs from real runs (CSV).
    #[arg(long)]
    pub y: PathBuf,
    /// Directory for SVG plots of the worst, median and best cases.
    #[arg(long)]
    pub plots: Option<PathBuf>,
    /// Where to save the summary (JSON, as `--json` prints it); default
    /// `<model stem>.check.json` next to the model, where `nlvid fit` looks.
    #[arg(long, value_name = "FILE")]
    pub summary: Option<PathBuf>,
}

impl SurrogateCmd {
    /// Run.
    pub fn run(self, json: bool) -> anyhow::Result<ExitCode> {
        match self {
            SurrogateCmd::Fit(a) => fit(*a, json),
            SurrogateCmd::Predict(a) => predict(a, json),
            SurrogateCmd::Check(a) => check_cmd(a, json),
        }
    }
}

fn fit(a: FitArgs, json: bool) -> anyhow::Result<ExitCode> {
    nlvid_study::check_output_file(&a.out)?;
    let (x, y) = (read_table(&a.x)?, read_table(&a.y)?);
    let options = FitOptions {
        regression: a.regression,
        correlation: a.correlation,
        theta: a.theta,
        theta0: a.theta0,
        lower: a.lower,
        upper: a.upper,
        boxmin: a.boxmin,
        optimiser: OptimiserSettings {
            starts: a.starts,
            screen_sites: a.screen_sites,
            ..Default::default()
        },
        pca: a.pca,
        nugget: a.nugget,
        log_outputs: a.log_outputs,
        proportional_to: a.proportional_to.map(|c| (c, a.log_coded)),
        log_inputs: a.log_inputs.unwrap_or_default(),
    };
    let t0 = std::time::Instant::now();
    let named = NamedModel::fit(&x, &y, options)
        .with_context(|| format!("{} → {}", a.x.display(), a.y.display()))?;
    let secs = t0.elapsed().as_secs_f64();
    named.save(&a.out)?;
    let mut v = named.report_json();
    (v["seconds"], v["model"]) = (serde_json::json!(secs), serde_json::json!(a.out));
    let out = a.out.display();
    let text = format!(
        "{}in {secs:.2} s; model written to {out}\n",
        named.report_text()
    );
    emit(json, &v, &text)?;
    Ok(ExitCode::SUCCESS)
}

fn predict(a: PredictArgs, json: bool) -> anyhow::Result<ExitCode> {
    let named = NamedModel::load(&a.model)?;
    let x = read_table(&a.x)?;
    let p = named
        .predict_table(&x, a.mse)
        .with_context(|| format!("{}", a.x.display()))?;
    if json {
        let mut v = p.to_json(&x);
        v["model"] = serde_json::json!(a.model);
        return print_json(&v).map(|()| ExitCode::SUCCESS);
    }
    match &a.out {
        Some(path) => write_atomic(path, p.to_csv()?.as_bytes())?,
        None => print_text(&p.to_csv()?)?,
    }
    Ok(ExitCode::SUCCESS)
}

fn check_cmd(a: CheckArgs, json: bool) -> anyhow::Result<ExitCode> {
    let model = NamedModel::load(&a.model)?.model;
    let (x, y) = (read_table(&a.x)?, read_table(&a.y)?);
    let (s, saved) = check::check_and_save(
        &model,
        &a.model,
        &x,
        &y,
        a.plots.as_deref(),
        a.summary.as_deref(),
    )?;
    let summary = serde_json::to_string(&s)?;
    eprintln!("checking summary saved to {}", saved.display());
    if json {
        say!("{summary}")?;
    } else {
        say!("{s}")?;
    }
    Ok(ExitCode::SUCCESS)
}
