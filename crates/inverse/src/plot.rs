//! Data vs fitted curve as an SVG figure (thesis Figs 4.9, 5.13): the
//! measured force (solid), the surrogate's curve at the optimum (dashed)
//! and, when there is one, the real model re-run at the optimum (dotted).
//! Drawn with `plotters` (SVG backend: text stays text, no font files).

use std::path::Path;

use plotters::prelude::*;

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

const BLUE: RGBColor = RGBColor(0, 114, 178);
const VERMILION: RGBColor = RGBColor(213, 94, 0);

impl FitFigure<'_> {
    /// The figure as an SVG document (force in nN against time in s).
    ///
    /// # Errors
    /// [`InverseError::LengthMismatch`] when a curve does not match the time
    /// grid, [`InverseError::Plot`] (path `figure`) when drawing fails.
    pub fn svg(&self) -> Result<String> {
        let m = self.times.len();
        for c in [Some(self.data), Some(self.fitted), self.rerun]
            .into_iter()
            .flatten()
        {
            crate::model::check_len(c.label, m, c.values.len())?;
        }
        let e = |x: &dyn std::fmt::Display| InverseError::Plot {
            path: "figure".into(),
            message: x.to_string(),
        };
        let (t0, t1) = min_max(self.times.iter().copied());
        let curves = [Some(self.data), Some(self.fitted), self.rerun];
        let (y0, y1) = min_max(
            curves
                .iter()
                .flatten()
                .flat_map(|c| c.values.iter().map(|v| v * 1e9)),
        );
        let pad = 0.05 * (y1 - y0).abs().max(1e-300);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (720, 440)).into_drawing_area();
            root.fill(&WHITE).map_err(|x| e(&x))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(self.title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(42)
                .y_label_area_size(64)
                .build_cartesian_2d(t0..t1.max(t0 + 1e-300), (y0 - pad)..(y1 + pad))
                .map_err(|x| e(&x))?;
            chart
                .configure_mesh()
                .x_desc("time [s]")
                .y_desc("force [nN]")
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|x| e(&x))?;
            let points = |v: &[f64]| -> Vec<(f64, f64)> {
                self.times
                    .iter()
                    .zip(v)
                    .map(|(&t, &f)| (t, f * 1e9))
                    .collect()
            };
            chart
                .draw_series(LineSeries::new(
                    points(self.data.values),
                    BLACK.stroke_width(1),
                ))
                .map_err(|x| e(&x))?
                .label(self.data.label)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            chart
                .draw_series(DashedLineSeries::new(
                    points(self.fitted.values),
                    8,
                    5,
                    BLUE.stroke_width(2),
                ))
                .map_err(|x| e(&x))?
                .label(self.fitted.label)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
            if let Some(r) = self.rerun {
                chart
                    .draw_series(DashedLineSeries::new(
                        points(r.values),
                        2,
                        4,
                        VERMILION.stroke_width(2),
                    ))
                    .map_err(|x| e(&x))?
                    .label(r.label)
                    .legend(|(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], VERMILION.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .draw()
                .map_err(|x| e(&x))?;
            root.present().map_err(|x| e(&x))?;
        }
        Ok(svg)
    }

    /// Writes [`FitFigure::svg`] to `path`.
    ///
    /// # Errors
    /// As [`FitFigure::svg`]; [`InverseError::Io`] when the file cannot be
    /// written.
    pub fn write(&self, path: &Path) -> Result<()> {
        let svg = self.svg().map_err(|err| match err {
            InverseError::Plot { message, .. } => InverseError::Plot {
                path: path.to_path_buf(),
                message,
            },
            other => other,
        })?;
        std::fs::write(path, svg).map_err(|err| InverseError::Io {
            path: path.to_path_buf(),
            message: err.to_string(),
        })
    }
}

fn min_max(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo <= hi { (lo, hi) } else { (0.0, 1.0) }
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
