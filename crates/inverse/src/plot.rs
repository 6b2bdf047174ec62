//! Data vs fitted curve as an SVG figure (thesis Figs 4.9, 5.13): the
//! measured force (solid), the surrogate's curve at the optimum (dashed)
//! and, when there is one, the real model re-run at the optimum (dotted).
//! Drawn in the house style of `nlvid-figure`.

use std::path::Path;

use nlvid_figure::{BLACK, Chart, FigureError, Mark, Series, palette};

use crate::error::{InverseError, Result};

/// One curve of a [`FitFigure`].
#[derive(Debug, Clone, Copy)]
pub struct FigureCurve<'a> {
    /// Legend text.
    pub label: &'a str,
    /// Values (N) on the figure's time grid.
    pub values: &'a [f64],
}

/// Data vs fit of one experiment.
#[derive(Debug, Clone, Copy)]
pub struct FitFigure<'a> {
    /// Caption.
    pub title: &'a str,
    /// Time grid (s).
    pub times: &'a [f64],
    /// Measured force on the grid (solid black).
    pub data: FigureCurve<'a>,
    /// Surrogate at the optimum (dashed blue).
    pub fitted: FigureCurve<'a>,
    /// Real model re-run at the optimum (dotted vermilion), if any.
    pub rerun: Option<FigureCurve<'a>>,
}

impl FitFigure<'_> {
    /// The figure as an SVG document (force in nN against time in s).
    ///
    /// # Errors
    /// [`InverseError::LengthMismatch`] when a curve does not match the time
    /// grid, [`InverseError::Plot`] (path `figure`) when drawing fails.
    pub fn svg(&self) -> Result<String> {
        self.chart()?
            .svg()
            .map_err(|e| plot_err(Path::new("figure"), &e))
    }

    /// Writes [`FitFigure::svg`] to `path`.
    ///
    /// # Errors
    /// As [`FitFigure::svg`]; [`InverseError::Io`] when the file cannot be
    /// written.
    pub fn write(&self, path: &Path) -> Result<()> {
        self.chart()?.write(path).map_err(|e| match e {
            FigureError::Io { path, message } => InverseError::Io { path, message },
            e => plot_err(path, &e),
        })
    }

    fn chart(&self) -> Result<Chart> {
        let m = self.times.len();
        for c in [Some(self.data), Some(self.fitted), self.rerun]
            .into_iter()
            .flatten()
        {
            crate::model::check_len(c.label, m, c.values.len())?;
        }
        let nano: fn(&FigureCurve<'_>) -> Vec<f64> = |c| c.values.iter().map(|v| v * 1e9).collect();
        let curve = |mark, colour, c: &FigureCurve<'_>| {
            Series::from_xy(mark, colour, self.times, &nano(c)).labelled(c.label)
        };
        let mut chart = Chart::new(self.title, "time [s]", "force [nN]")
            .with(curve(Mark::Thin, BLACK, &self.data))
            .with(curve(Mark::Dashed, palette(0), &self.fitted));
        if let Some(r) = &self.rerun {
            chart.push(curve(Mark::Dotted, palette(1), r));
        }
        Ok(chart)
    }
}

fn plot_err(path: &Path, e: &FigureError) -> InverseError {
    InverseError::Plot {
        path: path.to_path_buf(),
        message: e.message(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure_is_an_svg_with_three_labelled_curves() {
        let t: Vec<f64> = (0..50).map(|i| 0.2 * i as f64).collect();
        let d: Vec<f64> = t.iter().map(|t| 1e-9 * (1.0 + (-t).exp())).collect();
        let f: Vec<f64> = d.iter().map(|v| v * 1.01).collect();
        let r: Vec<f64> = d.iter().map(|v| v * 0.99).collect();
        let fig = FitFigure {
            title: "cell & <1>",
            times: &t,
            data: FigureCurve {
                label: "data",
                values: &d,
            },
            fitted: FigureCurve {
                label: "surrogate fit",
                values: &f,
            },
            rerun: Some(FigureCurve {
                label: "real model",
                values: &r,
            }),
        };
        let svg = fig.svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for s in [
            "data",
            "surrogate fit",
            "real model",
            "time [s]",
            "force [nN]",
        ] {
            assert!(svg.contains(s), "{s} missing");
        }
        // The title is escaped (valid XML).
        assert!(svg.contains("cell &amp; &lt;1&gt;"), "title not escaped");
        // Solid data: one polyline; dashes: many short segments.
        assert!(svg.matches("<polyline").count() >= 1);
        assert!(svg.matches("<line").count() + svg.matches("<polyline").count() > 20);
    }

    #[test]
    fn a_curve_off_the_grid_is_an_error() {
        let t = [0.0, 1.0];
        let fig = FitFigure {
            title: "x",
            times: &t,
            data: FigureCurve {
                label: "data",
                values: &[1.0, 2.0],
            },
            fitted: FigureCurve {
                label: "fit",
                values: &[1.0],
            },
            rerun: None,
        };
        assert!(fig.svg().unwrap_err().to_string().contains("fit"));
    }
}
