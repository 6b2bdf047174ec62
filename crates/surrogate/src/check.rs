//! Checking a surrogate on a separate checking set (thesis §4.4.1 step 4):
//! the per-case range-normalised RMSE of eq. 4.4 (= eq. 5.2),
//! `RMSE(i) = sqrt(mean_k (y_ref,k − y_krg,k)²) / range(y_ref)`,
//! its min / median / max, and SVG plots of chosen cases (Figs. 4.8, 5.12).

use std::fmt::Write as _;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SurrogateError, io_err};

/// Eq. 4.4: RMSE of `pred` against `reference`, divided by the range of
/// `reference`.
///
/// # Errors
/// Different lengths, empty input, or a reference with zero range.
pub fn range_normalised_rmse(reference: &[f64], pred: &[f64]) -> Result<f64> {
    if reference.len() != pred.len() || reference.is_empty() {
        return Err(SurrogateError::InvalidInput(format!(
            "curves of length {} and {} cannot be compared",
            reference.len(),
            pred.len()
        )));
    }
    let max = reference.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = reference.iter().copied().fold(f64::INFINITY, f64::min);
    let range = max - min;
    if range <= 0.0 || !range.is_finite() {
        return Err(SurrogateError::InvalidInput(
            "reference curve has zero range".into(),
        ));
    }
    let mse = reference
        .iter()
        .zip(pred)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / reference.len() as f64;
    Ok(mse.sqrt() / range)
}

/// Summary of the checking errors.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CheckSummary {
    /// Per-case RMSE (eq. 4.4), in checking-set order.
    pub rmse: Vec<f64>,
    /// Smallest.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// Largest.
    pub max: f64,
    /// Index of the worst case.
    pub worst: usize,
    /// Index of the case closest to the median.
    pub median_case: usize,
}

/// Eq. 4.4 for every case and its statistics.
pub fn summarise(references: &[Vec<f64>], predictions: &[Vec<f64>]) -> Result<CheckSummary> {
    if references.is_empty() || references.len() != predictions.len() {
        return Err(SurrogateError::InvalidInput(format!(
            "{} reference and {} predicted curves",
            references.len(),
            predictions.len()
        )));
    }
    let rmse: Vec<f64> = references
        .iter()
        .zip(predictions)
        .map(|(r, p)| range_normalised_rmse(r, p))
        .collect::<Result<_>>()?;
    let mut order: Vec<usize> = (0..rmse.len()).collect();
    order.sort_by(|&a, &b| rmse[a].total_cmp(&rmse[b]));
    let n = order.len();
    let median = if n % 2 == 1 {
        rmse[order[n / 2]]
    } else {
        0.5 * (rmse[order[n / 2 - 1]] + rmse[order[n / 2]])
    };
    Ok(CheckSummary {
        min: rmse[order[0]],
        median,
        max: rmse[order[n - 1]],
        worst: order[n - 1],
        median_case: order[n / 2],
        rmse,
    })
}

impl std::fmt::Display for CheckSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} checking cases: range-normalised RMSE (eq. 4.4) min {:.4} %, median {:.4} %, \
             max {:.4} % (case {})",
            self.rmse.len(),
            100.0 * self.min,
            100.0 * self.median,
            100.0 * self.max,
            self.worst
        )
    }
}

/// Time from a `F(t=1.0e0 s) [N]` header as written by `nlvid build --export`.
fn header_time(h: &str) -> Option<f64> {
    let a = h.find("t=")? + 2;
    let rest = &h[a..];
    let b = rest.find(' ')?;
    rest[..b].parse().ok()
}

/// Writes `worst_case<i>.svg`, `median_case<i>.svg` and `best_case<i>.svg`
/// into `dir`: the checking cases of `summary` with the largest, median and
/// smallest RMSE, reference against prediction, on the times of the
/// outputs' headers (`F(t=… s) [N]`; the column index where a header has
/// none).
///
/// # Errors
/// The directory or a file cannot be written.
pub fn plot_cases(
    dir: &Path,
    header: &[String],
    references: &[Vec<f64>],
    predictions: &[Vec<f64>],
    summary: &CheckSummary,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(crate::error::io_err(dir))?;
    let t: Vec<f64> = header
        .iter()
        .enumerate()
        .map(|(j, h)| header_time(h).unwrap_or(j as f64))
        .collect();
    let best = summary
        .rmse
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or(0, |(i, _)| i);
    for (label, i) in [
        ("worst", summary.worst),
        ("median", summary.median_case),
        ("best", best),
    ] {
        let title = format!(
            "checking case {i} ({label}): RMSE = {:.3} %",
            100.0 * summary.rmse[i]
        );
        let path = dir.join(format!("{label}_case{i}.svg"));
        plot_svg(&path, &title, &t, &references[i], &predictions[i])?;
    }
    Ok(())
}

/// Checks `model` on the checking runs `x` → `y` (eq. 4.4 per case), saves
/// the summary as JSON to `summary` (default [`summary_path`] of
/// `model_path`) and, with `plots`, the worst, median and best cases there
/// ([`plot_cases`]). Returns the summary and where it was saved.
///
/// # Errors
/// Tables of different lengths, a prediction failure, unwritable files
/// (naming the path and how to choose another).
pub fn check_and_save(
    model: &crate::KrigingModel,
    model_path: &Path,
    x: &crate::Table,
    y: &crate::Table,
    plots: Option<&Path>,
    summary: Option<&Path>,
) -> Result<(CheckSummary, std::path::PathBuf)> {
    if x.rows.len() != y.rows.len() {
        return Err(SurrogateError::InvalidInput(format!(
            "{} checking inputs but {} checking outputs",
            x.rows.len(),
            y.rows.len()
        )));
    }
    let pred = model.predict_many(x.mat().as_ref())?;
    let preds: Vec<Vec<f64>> = (0..pred.nrows())
        .map(|i| (0..pred.ncols()).map(|j| pred[(i, j)]).collect())
        .collect();
    let s = summarise(&y.rows, &preds)?;
    if let Some(dir) = plots {
        plot_cases(dir, &y.header, &y.rows, &preds, &s)?;
    }
    let saved = summary.map_or_else(|| summary_path(model_path), Path::to_path_buf);
    let text = serde_json::to_string(&s)
        .map_err(|e| SurrogateError::InvalidInput(format!("serialising the summary: {e}")))?;
    nlvid_study::write_atomic(&saved, format!("{text}\n").as_bytes()).map_err(|e| {
        SurrogateError::InvalidInput(format!(
            "cannot save the checking summary to {}: {e} (choose another place with --summary)",
            saved.display()
        ))
    })?;
    Ok((s, saved))
}

/// `model.json` → `model.check.json`: where `nlvid surrogate check` saves
/// its summary and fits look for the model's checking error.
pub fn summary_path(model: &Path) -> std::path::PathBuf {
    model.with_extension("check.json")
}

/// Write an SVG plot of reference (solid) and surrogate (dashed) curves.
pub fn plot_svg(
    path: &Path,
    title: &str,
    t: &[f64],
    reference: &[f64],
    pred: &[f64],
) -> Result<()> {
    let (w, h, ml, mr, mt, mb) = (640.0, 400.0, 70.0, 20.0, 40.0, 50.0);
    let tmin = t.iter().copied().fold(f64::INFINITY, f64::min);
    let tmax = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let all = reference.iter().chain(pred);
    let ymin = all.clone().copied().fold(f64::INFINITY, f64::min);
    let ymax = all.copied().fold(f64::NEG_INFINITY, f64::max);
    let (ymin, ymax) = if ymax > ymin {
        (ymin, ymax)
    } else {
        (ymin - 1.0, ymax + 1.0)
    };
    let tx = |v: f64| ml + (v - tmin) / (tmax - tmin).max(1e-300) * (w - ml - mr);
    let ty = |v: f64| h - mb - (v - ymin) / (ymax - ymin) * (h - mt - mb);
    let line = |ys: &[f64]| {
        let mut s = String::new();
        for (i, (a, b)) in t.iter().zip(ys).enumerate() {
            let _ = write!(
                s,
                "{}{:.2},{:.2}",
                if i == 0 { "M" } else { " L" },
                tx(*a),
                ty(*b)
            );
        }
        s
    };
    let mut svg = String::new();
    let _ = write!(
        svg,
        r##"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">
<rect width="100%" height="100%" fill="white"/>
<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>
<rect x="{ml}" y="{mt}" width="{}" height="{}" fill="none" stroke="black"/>
<text x="{}" y="{}" text-anchor="middle">time [s]  ({tmin:.3e} … {tmax:.3e})</text>
<text x="14" y="{}" transform="rotate(-90 14 {})" text-anchor="middle">force [N]  ({ymin:.3e} … {ymax:.3e})</text>
<path d="{}" fill="none" stroke="black" stroke-width="1.5"/>
<path d="{}" fill="none" stroke="red" stroke-width="1.5" stroke-dasharray="6,4"/>
<text x="{}" y="{}" fill="black">— real run</text>
<text x="{}" y="{}" fill="red">- - surrogate</text>
</svg>
"##,
        w / 2.0,
        xml_escape(title),
        w - ml - mr,
        h - mt - mb,
        (w + ml - mr) / 2.0,
        h - 15.0,
        h / 2.0,
        h / 2.0,
        line(reference),
        line(pred),
        w - mr - 120.0,
        mt + 20.0,
        w - mr - 120.0,
        mt + 36.0,
    );
    nlvid_study::write_atomic(path, svg.as_bytes()).map_err(io_err(path))
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmse_is_normalised_by_the_reference_range() {
        // Constant offset 0.1 on a curve of range 2: RMSE = 0.05.
        let r = [0.0, 1.0, 2.0, 1.0];
        let p = [0.1, 1.1, 2.1, 1.1];
        assert!((range_normalised_rmse(&r, &p).unwrap() - 0.05).abs() < 1e-15);
    }

    #[test]
    fn summary_finds_worst_and_median() {
        let refs = vec![vec![0.0, 1.0]; 3];
        let preds = vec![vec![0.0, 1.0], vec![0.3, 1.3], vec![0.1, 1.1]];
        let s = summarise(&refs, &preds).unwrap();
        assert_eq!(s.worst, 1);
        assert!((s.median - 0.1).abs() < 1e-12 && s.min == 0.0 && (s.max - 0.3).abs() < 1e-12);
    }

    #[test]
    fn flat_reference_is_an_error() {
        assert!(range_normalised_rmse(&[1.0, 1.0], &[1.0, 1.0]).is_err());
    }
}
