//! SVG line plots of curves (data vs fit, channels vs time) in the house
//! style of `nlvid-figure`.

use std::path::Path;

use nlvid_figure::{Chart, Mark, palette};

use crate::error::{AfmError, Result};

/// One curve of a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates (same length as `x`).
    pub y: &'a [f64],
}

/// Write an SVG line plot of `series` to `path` (720×440 px), axes labelled `x_label`
/// and `y_label`. Non-finite points are skipped.
///
/// # Errors
/// [`AfmError::InvalidInput`] if no finite point exists or lengths differ;
/// [`AfmError::Plot`] if the figure cannot be drawn or the file cannot be written.
pub fn write_svg(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
) -> Result<()> {
    if series.iter().any(|s| s.x.len() != s.y.len()) {
        return Err(AfmError::InvalidInput(
            "plot series with x and y of different lengths".into(),
        ));
    }
    let finite = series
        .iter()
        .flat_map(|s| s.x.iter().zip(s.y))
        .any(|(x, y)| x.is_finite() && y.is_finite());
    if !finite {
        return Err(AfmError::InvalidInput("nothing finite to plot".into()));
    }
    let mut chart = Chart::new(title, x_label, y_label);
    for (i, s) in series.iter().enumerate() {
        chart.push(
            nlvid_figure::Series::from_xy(Mark::Line, palette(i), s.x, s.y).labelled(s.label),
        );
    }
    chart.write(path).map_err(|e| AfmError::Plot {
        path: path.to_path_buf(),
        detail: e.message(),
    })
}
