//! SVG figures drawn with `plotters` (SVG backend: text stays text, so the
//! page needs no font files and stays sharp when zoomed or printed).

use plotters::prelude::*;

use crate::error::{ReportError, Result};

/// Group colours (colour-blind friendly: blue, vermilion, green, purple).
pub(crate) const PALETTE: [RGBColor; 4] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
];

/// A mean ± sd curve of one group.
pub(crate) struct Band {
    pub name: String,
    pub x: Vec<f64>,
    pub mean: Vec<f64>,
    pub sd: Vec<f64>,
}

/// A curve to draw as a line.
pub(crate) struct Line {
    pub name: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

fn plot_err(figure: &str) -> impl Fn(&dyn std::fmt::Display) -> ReportError + '_ {
    move |e| ReportError::Plot {
        figure: figure.to_string(),
        message: e.to_string(),
    }
}

fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let span = (hi - lo).abs().max(1e-300);
    (lo - 0.04 * span, hi + 0.04 * span)
}

/// Mean ± sd bands of several groups (Figs. 5.3–5.8, 5.14–5.19 style).
pub(crate) fn band_chart(
    figure: &str,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    bands: &[Band],
) -> Result<String> {
    let e = plot_err(figure);
    let xs = bands.iter().flat_map(|b| b.x.iter().copied());
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let ys = bands
        .iter()
        .flat_map(|b| b.mean.iter().zip(&b.sd).flat_map(|(m, s)| [m - s, m + s]));
    let (y0, y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let (y0, y1) = padded(y0.min(0.0), y1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|x| e(&x))?;
        for (i, b) in bands.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()];
            let mut poly: Vec<(f64, f64)> =
                b.x.iter()
                    .zip(b.mean.iter().zip(&b.sd))
                    .map(|(&x, (m, s))| (x, m + s))
                    .collect();
            poly.extend(
                b.x.iter()
                    .zip(b.mean.iter().zip(&b.sd))
                    .rev()
                    .map(|(&x, (m, s))| (x, m - s)),
            );
            chart
                .draw_series(std::iter::once(Polygon::new(poly, c.mix(0.18).filled())))
                .map_err(|x| e(&x))?;
            chart
                .draw_series(LineSeries::new(
                    b.x.iter().copied().zip(b.mean.iter().copied()),
                    c.stroke_width(2),
                ))
                .map_err(|x| e(&x))?
                .label(format!("{} (mean ± sd)", b.name))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
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

/// p(t) on a log axis with the 0.05 level (Figs. 5.14–5.19, lower panels).
pub(crate) fn pvalue_chart(figure: &str, title: &str, lines: &[Line]) -> Result<String> {
    let e = plot_err(figure);
    let (x0, x1) = lines
        .iter()
        .flat_map(|l| l.x.iter().copied())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let pmin = lines
        .iter()
        .flat_map(|l| l.y.iter().copied())
        .filter(|p| *p > 0.0)
        .fold(1.0f64, f64::min);
    let lo = (pmin / 3.0).min(1e-3);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 360)).into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, (lo..1.5).log_scale())
            .map_err(|x| e(&x))?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("p (Wilcoxon rank-sum)")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(|x| e(&x))?;
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(LineSeries::new(
                [(x0, 0.05), (x1, 0.05)],
                grey.stroke_width(1),
            ))
            .map_err(|x| e(&x))?
            .label("p = 0.05")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        for (i, l) in lines.iter().enumerate() {
            let c = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    l.x.iter().copied().zip(l.y.iter().map(|p| p.max(lo))),
                    c.stroke_width(2),
                ))
                .map_err(|x| e(&x))?
                .label(l.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(|x| e(&x))?;
        root.present().map_err(|x| e(&x))?;
    }
    Ok(svg)
}

/// One panel per cell: measured force (grey) and fit (group colour).
pub(crate) struct FitPanel {
    pub title: String,
    pub group_index: usize,
    pub x: Vec<f64>,
    pub data: Vec<f64>,
    pub fit: Vec<f64>,
}

/// Small multiples of data vs fit, `cols` panels per row.
pub(crate) fn fits_chart(
    figure: &str,
    y_desc: &str,
    panels: &[FitPanel],
    cols: usize,
) -> Result<String> {
    let e = plot_err(figure);
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols).max(1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (240 * cols as u32, 170 * rows as u32))
            .into_drawing_area();
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let areas = root.split_evenly((rows, cols));
        for (p, area) in panels.iter().zip(areas.iter()) {
            let (x0, x1) =
                p.x.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    });
            let y1 = p
                .data
                .iter()
                .chain(&p.fit)
                .fold(f64::NEG_INFINITY, |a, &v| a.max(v));
            let y0 = p.data.iter().chain(&p.fit).fold(0.0f64, |a, &v| a.min(v));
            let (y0, y1) = padded(y0, y1);
            let mut chart = ChartBuilder::on(area)
                .caption(&p.title, ("sans-serif", 12))
                .margin(6)
                .x_label_area_size(22)
                .y_label_area_size(38)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|x| e(&x))?;
            chart
                .configure_mesh()
                .x_labels(4)
                .y_labels(4)
                .label_style(("sans-serif", 10))
                .y_desc(y_desc)
                .axis_desc_style(("sans-serif", 10))
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|x| e(&x))?;
            let grey = RGBColor(150, 150, 150);
            chart
                .draw_series(LineSeries::new(
                    p.x.iter().copied().zip(p.data.iter().copied()),
                    grey.stroke_width(1),
                ))
                .map_err(|x| e(&x))?;
            if !p.fit.is_empty() {
                let c = PALETTE[p.group_index % PALETTE.len()];
                chart
                    .draw_series(LineSeries::new(
                        p.x.iter().copied().zip(p.fit.iter().copied()),
                        c.stroke_width(2),
                    ))
                    .map_err(|x| e(&x))?;
            }
        }
        root.present().map_err(|x| e(&x))?;
    }
    Ok(svg)
}
