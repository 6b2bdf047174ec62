//! SVG line plots of the thesis reproduction ([`crate::thesis::Figure`]) in
//! the house style of `nlvid-figure`: computed curves as lines, single points
//! as dots and thesis reference values as black diamonds.

use nlvid_figure::{BLACK, Chart, Legend, Mark, Series, palette};

use crate::thesis::{Figure, SeriesKind};
use crate::{MembraneError, Result};

/// Draw `fig` as an SVG document (720 × 440 px).
///
/// # Errors
/// [`MembraneError::Input`] (name `figure`) when plotters fails to draw.
pub fn svg(fig: &Figure) -> Result<String> {
    let mut chart = Chart::new(&fig.title, &fig.x_label, &fig.y_label).legend(Legend::UpperLeft);
    let mut colour = 0;
    for s in &fig.series {
        let (mark, c) = match s.kind {
            SeriesKind::Thesis => (Mark::Diamonds, BLACK),
            SeriesKind::Points => (Mark::Dots, palette(colour)),
            SeriesKind::Line => (Mark::Line, palette(colour)),
        };
        if s.kind != SeriesKind::Thesis {
            colour += 1;
        }
        chart.push(Series::from_xy(mark, c, &s.x, &s.y).labelled(&s.label));
    }
    chart.svg().map_err(|e| MembraneError::Input {
        name: "figure",
        value: f64::NAN,
        reason: format!("{}: {}", fig.id, e.message()),
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::thesis::Series;

    #[test]
    fn svg_has_axes_legend_and_every_series() {
        let f = Figure {
            id: "t".into(),
            title: "A & B".into(),
            x_label: "D/r0".into(),
            y_label: "F/(G10 h0 r0)".into(),
            series: vec![
                Series::line("model", vec![0.0, 0.5, 1.0], vec![0.0, 1.0, 4.0]),
                Series::points("edge", vec![0.5], vec![1.0]),
                Series::thesis("thesis value", vec![1.0], vec![4.2]),
            ],
        };
        let s = svg(&f).unwrap();
        assert!(s.starts_with("<svg"));
        for text in [
            "D/r0",
            "F/(G10 h0 r0)",
            "model",
            "edge",
            "thesis value",
            "A &amp; B",
        ] {
            assert!(s.contains(text), "missing {text}");
        }
        // a polyline for the curve, a circle for the point, a polygon for the thesis marker
        assert!(s.contains("<polyline"));
        assert!(s.contains("<circle"));
        assert!(s.contains("<polygon"));
    }
}
