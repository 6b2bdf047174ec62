//! SVG line plots of the thesis reproduction ([`crate::thesis::Figure`]) with
//! `plotters` (SVG backend: text stays text, no font files needed), in the
//! style of `nlvid-report`'s figures: axes with ticks and labels, a legend,
//! computed curves as lines, single points as dots and thesis reference
//! values as open black diamonds.

use plotters::prelude::*;

use crate::thesis::{Figure, SeriesKind};
use crate::{MembraneError, Result};

/// Colour-blind friendly palette (Okabe–Ito, as in `nlvid-report`).
const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(120, 120, 120),
];

fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() && hi > lo {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (0.0, 1.0)
    };
    let span = hi - lo;
    (lo - 0.04 * span, hi + 0.04 * span)
}

/// Draw `fig` as an SVG document (720 × 480 px).
///
/// # Errors
/// [`MembraneError::Input`] (name `figure`) when plotters fails to draw.
pub fn svg(fig: &Figure) -> Result<String> {
    let e = |x: &dyn std::fmt::Display| MembraneError::Input {
        name: "figure",
        value: f64::NAN,
        reason: format!("{}: {x}", fig.id),
    };
    let finite = |v: &&f64| v.is_finite();
    let bounds = |it: &mut dyn Iterator<Item = f64>| {
        it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
    };
    let (x0, x1) = bounds(
        &mut fig
            .series
            .iter()
            .flat_map(|s| s.x.iter().filter(finite).copied()),
    );
    let (y0, y1) = bounds(
        &mut fig
            .series
            .iter()
            .flat_map(|s| s.y.iter().filter(finite).copied()),
    );
    let (x0, x1) = padded(x0, x1);
    let (y0, y1) = padded(y0, y1);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (720, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&fig.title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(fig.x_label.as_str())
            .y_desc(fig.y_label.as_str())
            .light_line_style(BLACK.mix(0.05))
            .draw()
            .map_err(|x| e(&x))?;
        let mut colour = 0;
        for s in &fig.series {
            let pts: Vec<(f64, f64)> =
                s.x.iter()
                    .zip(&s.y)
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .map(|(x, y)| (*x, *y))
                    .collect();
            match s.kind {
                SeriesKind::Thesis => {
                    let style = BLACK.stroke_width(2);
                    chart
                        .draw_series(pts.iter().map(|&(x, y)| {
                            EmptyElement::at((x, y))
                                + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], style)
                        }))
                        .map_err(|x| e(&x))?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| {
                            EmptyElement::at((x + 10, y))
                                + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], style)
                        });
                }
                SeriesKind::Points => {
                    let c = PALETTE[colour % PALETTE.len()];
                    colour += 1;
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
                        .map_err(|x| e(&x))?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
                }
                SeriesKind::Line => {
                    let c = PALETTE[colour % PALETTE.len()];
                    colour += 1;
                    chart
                        .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                        .map_err(|x| e(&x))?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                        });
                }
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font(("sans-serif", 11))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    Ok(out)
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
            y_label: "F/(C1 h0 r0)".into(),
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
            "F/(C1 h0 r0)",
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
