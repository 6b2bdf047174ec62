//! `nlvid surrogate fit | predict | check`: Kriging on any table.

use crate::say;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use nlvid_surrogate::faer::Mat;
use nlvid_surrogate::{
    Correlation, KrigingModel, KrigingSettings, OptimiserSettings, OutputScale, Regression,
    ThetaSearch, check,
};

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
    #[arg(long, default_value = "poly1")]
    pub regression: String,
    /// Correlation: gauss, exp, expg, lin, spherical, cubic, spline.
    #[arg(long, default_value = "gauss")]
    pub correlation: String,
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
    /// Set from the global `--json` flag.
    #[arg(skip)]
    pub json: bool,
}

/// Arguments of `surrogate predict`.
#[derive(Debug, Args)]
pub struct PredictArgs {
    /// Model file from `surrogate fit`.
    pub model: PathBuf,
    /// Points: CSV with a header.
    #[arg(long)]
    pub x: PathBuf,
    /// Output CSV (default: stdout).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Also write the MSE of every output (columns `mse_<j>`).
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
    /// Set from the global `--json` flag.
    #[arg(skip)]
    pub json: bool,
}

/// `model.json` → `model.check.json`: where `nlvid surrogate check` saves
/// its summary and `nlvid fit` looks for the model's checking error.
pub fn checking_summary_path(model: &Path) -> PathBuf {
    model.with_extension("check.json")
}

/// A numeric table read from CSV.
pub struct Table {
    /// Column names.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// As a faer matrix.
    pub fn mat(&self) -> Mat<f64> {
        Mat::from_fn(self.rows.len(), self.header.len(), |i, j| self.rows[i][j])
    }
}

/// A column by its full header (`G0 [Pa]`) or by its name without the unit
/// suffix that `nlvid build --export` writes (`G0`).
fn column_index(header: &[String], name: &str) -> Option<usize> {
    header.iter().position(|h| h == name).or_else(|| {
        header
            .iter()
            .position(|h| h.split_once(" [").is_some_and(|(bare, _)| bare == name))
    })
}

/// Read a numeric CSV with a header; a column named `index` is dropped.
/// Errors name the file, row (1-based line) and column.
pub fn read_table(path: &Path) -> anyhow::Result<Table> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    let head: Vec<String> = rdr
        .headers()
        .with_context(|| format!("{}: no header", path.display()))?
        .iter()
        .map(String::from)
        .collect();
    let keep: Vec<usize> = (0..head.len()).filter(|&j| head[j] != "index").collect();
    let mut rows = Vec::new();
    for (r, rec) in rdr.records().enumerate() {
        let line = r + 2;
        let rec = rec.with_context(|| format!("{}:{line}: bad CSV record", path.display()))?;
        if rec.len() != head.len() {
            bail!(
                "{}:{line}: {} fields, header has {}",
                path.display(),
                rec.len(),
                head.len()
            );
        }
        let mut row = Vec::with_capacity(keep.len());
        for &j in &keep {
            let v: f64 = rec[j].parse().with_context(|| {
                format!(
                    "{}:{line}: column `{}`: `{}` is not a number",
                    path.display(),
                    head[j],
                    &rec[j]
                )
            })?;
            row.push(v);
        }
        rows.push(row);
    }
    if rows.is_empty() {
        bail!("{}: no data rows", path.display());
    }
    Ok(Table {
        header: keep.iter().map(|&j| head[j].clone()).collect(),
        rows,
    })
}

/// Write rows as CSV with a header.
pub fn write_table(out: Option<&Path>, header: &[String], rows: &[Vec<f64>]) -> anyhow::Result<()> {
    let w: Box<dyn std::io::Write> = match out {
        Some(p) => Box::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        ),
        None => Box::new(std::io::stdout()),
    };
    let mut w = csv::Writer::from_writer(w);
    w.write_record(header)?;
    for r in rows {
        w.write_record(r.iter().map(|v| format!("{v:e}")))?;
    }
    w.flush()?;
    Ok(())
}

fn load_model(path: &Path) -> anyhow::Result<KrigingModel> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text)
        .with_context(|| format!("{}: not a Kriging model file", path.display()))
}

impl SurrogateCmd {
    /// Run.
    pub fn run(self, json: bool) -> anyhow::Result<ExitCode> {
        match self {
            SurrogateCmd::Fit(mut a) => {
                a.json = json;
                fit(*a)
            }
            SurrogateCmd::Predict(a) => predict(a),
            SurrogateCmd::Check(mut a) => {
                a.json = json;
                check_cmd(a)
            }
        }
    }
}

fn fit(a: FitArgs) -> anyhow::Result<ExitCode> {
    let x = read_table(&a.x)?;
    let y = read_table(&a.y)?;
    if x.rows.len() != y.rows.len() {
        bail!(
            "{} has {} rows but {} has {}",
            a.x.display(),
            x.rows.len(),
            a.y.display(),
            y.rows.len()
        );
    }
    let reg = Regression::parse(&a.regression).with_context(|| {
        format!(
            "--regression {}: expected poly0, poly1 or poly2",
            a.regression
        )
    })?;
    let corr = Correlation::parse(&a.correlation).with_context(|| {
        format!(
            "--correlation {}: expected gauss, exp, expg, lin, spherical, cubic or spline",
            a.correlation
        )
    })?;
    let d = x.header.len();
    let mut s = KrigingSettings::new(reg, corr, d);
    s.nugget = a.nugget;
    s.pca_energy = a.pca;
    s.log_outputs = a.log_outputs;
    if let Some(cols) = &a.log_inputs {
        let mut flags = vec![false; d];
        for col in cols {
            let k = column_index(&x.header, col).with_context(|| {
                format!(
                    "--log-inputs {col}: no such column in {} (columns: {:?})",
                    a.x.display(),
                    x.header
                )
            })?;
            flags[k] = true;
        }
        s.log_inputs = flags;
    }
    if let Some(col) = &a.proportional_to {
        let input = column_index(&x.header, col).with_context(|| {
            format!(
                "--proportional-to {col}: no such column in {} (columns: {:?})",
                a.x.display(),
                x.header
            )
        })?;
        s.output_scale = Some(match a.log_coded {
            Some(slope) => OutputScale::Exp { input, slope },
            None => OutputScale::Linear { input },
        });
    }
    if let Some(t) = a.theta {
        s.theta = ThetaSearch::Fixed(t);
    } else if let ThetaSearch::Optimise {
        theta0,
        lower,
        upper,
        ..
    } = ThetaSearch::default_for(corr, d)
    {
        let theta0 = a.theta0.unwrap_or(theta0);
        let lower = a.lower.unwrap_or(lower);
        let upper = a.upper.unwrap_or(upper);
        s.theta = if a.boxmin {
            ThetaSearch::Boxmin {
                theta0,
                lower,
                upper,
            }
        } else {
            ThetaSearch::Optimise {
                theta0,
                lower,
                upper,
                settings: OptimiserSettings {
                    starts: a.starts,
                    screen_sites: a.screen_sites,
                    ..Default::default()
                },
            }
        };
    }
    let t0 = std::time::Instant::now();
    let model = KrigingModel::fit(x.mat().as_ref(), y.mat().as_ref(), &s)?;
    let secs = t0.elapsed().as_secs_f64();
    let bytes = serde_json::to_vec(&model)?;
    std::fs::write(&a.out, bytes).with_context(|| format!("cannot write {}", a.out.display()))?;
    let r = &model.report;
    if a.json {
        say!(
            "{}",
            serde_json::json!({"report": r, "seconds": secs, "model": a.out})
        )?;
    } else {
        say!(
            "fitted {} sites × {} inputs → {} outputs ({} kriged, energy {:.8}) in {secs:.2} s\n\
             θ = {:?}\nψ = {:.6e} after {} evaluations ({}), nugget {:e}\nmodel written to {}",
            model.n_sites,
            model.dim,
            model.n_outputs,
            r.kriged_outputs,
            r.energy,
            r.theta,
            r.psi,
            r.evaluations,
            r.search,
            r.nugget,
            a.out.display()
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

fn predict(a: PredictArgs) -> anyhow::Result<ExitCode> {
    let model = load_model(&a.model)?;
    let x = read_table(&a.x)?;
    if x.header.len() != model.dim {
        bail!(
            "{}: {} input columns, the model has {}",
            a.x.display(),
            x.header.len(),
            model.dim
        );
    }
    let mut header: Vec<String> = (0..model.n_outputs).map(|j| format!("y_{j}")).collect();
    if a.mse {
        header.extend((0..model.n_outputs).map(|j| format!("mse_{j}")));
    }
    let mut rows = Vec::with_capacity(x.rows.len());
    for (i, xi) in x.rows.iter().enumerate() {
        let row = if a.mse {
            let p = model
                .predict_full(xi)
                .with_context(|| format!("{}:{}", a.x.display(), i + 2))?;
            let mut r = p.y;
            r.extend(p.mse);
            r
        } else {
            model
                .predict(xi)
                .with_context(|| format!("{}:{}", a.x.display(), i + 2))?
        };
        rows.push(row);
    }
    write_table(a.out.as_deref(), &header, &rows)?;
    Ok(ExitCode::SUCCESS)
}

fn check_cmd(a: CheckArgs) -> anyhow::Result<ExitCode> {
    let model = load_model(&a.model)?;
    let x = read_table(&a.x)?;
    let y = read_table(&a.y)?;
    if x.rows.len() != y.rows.len() {
        bail!(
            "{} has {} rows but {} has {}",
            a.x.display(),
            x.rows.len(),
            a.y.display(),
            y.rows.len()
        );
    }
    let pred = model.predict_many(x.mat().as_ref())?;
    let preds: Vec<Vec<f64>> = (0..pred.nrows())
        .map(|i| (0..pred.ncols()).map(|j| pred[(i, j)]).collect())
        .collect();
    let s = check::summarise(&y.rows, &preds)?;
    if let Some(dir) = &a.plots {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let t: Vec<f64> = y
            .header
            .iter()
            .enumerate()
            .map(|(j, h)| parse_time(h).unwrap_or(j as f64))
            .collect();
        let best = s
            .rmse
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, _)| i)
            .unwrap_or(0);
        for (label, i) in [
            ("worst", s.worst),
            ("median", s.median_case),
            ("best", best),
        ] {
            let title = format!(
                "checking case {i} ({label}): RMSE = {:.3} %",
                100.0 * s.rmse[i]
            );
            check::plot_svg(
                &dir.join(format!("{label}_case{i}.svg")),
                &title,
                &t,
                &y.rows[i],
                &preds[i],
            )?;
        }
    }
    let summary = serde_json::to_string(&s)?;
    let saved = a
        .summary
        .clone()
        .unwrap_or_else(|| checking_summary_path(&a.model));
    crate::output::write_atomic(&saved, format!("{summary}\n").as_bytes()).with_context(|| {
        format!(
            "cannot save the checking summary to {} (choose another place with --summary)",
            saved.display()
        )
    })?;
    eprintln!("checking summary saved to {}", saved.display());
    if a.json {
        say!("{summary}")?;
    } else {
        say!(
            "{} checking cases: range-normalised RMSE (eq. 4.4) min {:.4} %, median {:.4} %, max {:.4} % (case {})",
            s.rmse.len(),
            100.0 * s.min,
            100.0 * s.median,
            100.0 * s.max,
            s.worst
        )?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Time from a `F(t=1.0e0 s) [N]` header as written by `nlvid build --export`.
fn parse_time(h: &str) -> Option<f64> {
    let a = h.find("t=")? + 2;
    let rest = &h[a..];
    let b = rest.find(' ')?;
    rest[..b].parse().ok()
}

#[cfg(test)]
mod tests {
    use super::column_index;

    #[test]
    fn columns_are_found_with_or_without_their_unit_suffix() {
        let header: Vec<String> = ["index", "G0 [Pa]", "g1 [1]", "tau1 [s]"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(column_index(&header, "G0 [Pa]"), Some(1));
        assert_eq!(column_index(&header, "G0"), Some(1));
        assert_eq!(column_index(&header, "tau1"), Some(3));
        assert_eq!(column_index(&header, "tau"), None);
        assert_eq!(column_index(&header, "Pa"), None);
    }
}
