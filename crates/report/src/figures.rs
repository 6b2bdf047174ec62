//! The report's figures, drawn in the house style of `nlvid-figure` (SVG:
//! text stays text, so the page needs no font files and stays sharp when
//! zoomed or printed).

use nlvid_figure::{Chart, FigureError, GREY, Legend, Mark, Series, palette, panels_svg};

use crate::error::{ReportError, Result};

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

fn plot_err(figure: &str) -> impl Fn(FigureError) -> ReportError + '_ {
    move |e| ReportError::Plot {
        figure: figure.to_string(),
        message: e.message(),
    }
}

/// Mean ± sd bands of several groups (Figs. 5.3–5.8, 5.14–5.19 style); the
/// y axis includes 0.
pub(crate) fn band_chart(
    figure: &str,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    bands: &[Band],
) -> Result<String> {
    let mut chart = Chart::new(title, x_desc, y_desc).y_from_zero();
    for (i, b) in bands.iter().enumerate() {
        chart.push(
            Series::band(palette(i), &b.x, &b.mean, &b.sd)
                .labelled(format!("{} (mean ± sd)", b.name)),
        );
    }
    chart.svg().map_err(plot_err(figure))
}

/// p(t) on a log axis with the 0.05 level (Figs. 5.14–5.19, lower panels);
/// p values below the axis are drawn on its floor.
pub(crate) fn pvalue_chart(figure: &str, title: &str, lines: &[Line]) -> Result<String> {
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
    let mut chart = Chart::new(title, "t (s)", "p (Wilcoxon rank-sum)")
        .size(Chart::SIZE.0, 360)
        .log_y()
        .y_range(lo, 1.5)
        .legend(Legend::LowerRight)
        .with(Series::new(Mark::Thin, GREY, vec![(x0, 0.05), (x1, 0.05)]).labelled("p = 0.05"));
    for (i, l) in lines.iter().enumerate() {
        let p: Vec<f64> = l.y.iter().map(|p| p.max(lo)).collect();
        chart.push(Series::from_xy(Mark::Line, palette(i), &l.x, &p).labelled(&l.name));
    }
    chart.svg().map_err(plot_err(figure))
}

/// One panel per cell: measured force (grey) and fit (group colour).
pub(crate) struct FitPanel {
    pub title: String,
    pub group_index: usize,
    pub x: Vec<f64>,
    pub data: Vec<f64>,
    pub fit: Vec<f64>,
}

/// Small multiples of data vs fit, `cols` panels per row; each y axis
/// includes 0.
pub(crate) fn fits_chart(
    figure: &str,
    y_desc: &str,
    panels: &[FitPanel],
    cols: usize,
) -> Result<String> {
    let charts: Vec<Chart> = panels
        .iter()
        .map(|p| {
            let mut c = Chart::new(&p.title, "", y_desc)
                .y_from_zero()
                .legend(Legend::None)
                .with(Series::from_xy(Mark::Thin, GREY, &p.x, &p.data));
            if !p.fit.is_empty() {
                c.push(Series::from_xy(
                    Mark::Line,
                    palette(p.group_index),
                    &p.x,
                    &p.fit,
                ));
            }
            c
        })
        .collect();
    panels_svg(&charts, cols).map_err(plot_err(figure))
}

/// A credible band (lower, median, upper) of one curve.
pub(crate) struct RangeBand {
    pub name: String,
    pub colour_index: usize,
    pub x: Vec<f64>,
    pub lower: Vec<f64>,
    pub median: Vec<f64>,
    pub upper: Vec<f64>,
}

/// Credible bands of several curves on one chart; the y axis includes 0.
pub(crate) fn range_chart(
    figure: &str,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    bands: &[RangeBand],
) -> Result<String> {
    let mut chart = Chart::new(title, x_desc, y_desc).y_from_zero();
    for b in bands {
        chart.push(
            Series::range(palette(b.colour_index), &b.x, &b.median, &b.lower, &b.upper)
                .labelled(&b.name),
        );
    }
    chart.svg().map_err(plot_err(figure))
}

/// Small multiples of credible bands (one per cell), with an optional
/// point-estimate curve per panel drawn thin in grey.
pub(crate) fn range_panels(
    figure: &str,
    y_desc: &str,
    panels: &[(RangeBand, Vec<f64>)],
    cols: usize,
) -> Result<String> {
    let charts: Vec<Chart> = panels
        .iter()
        .map(|(b, point)| {
            let mut c = Chart::new(&b.name, "", y_desc)
                .y_from_zero()
                .legend(Legend::None)
                .with(Series::range(
                    palette(b.colour_index),
                    &b.x,
                    &b.median,
                    &b.lower,
                    &b.upper,
                ));
            if !point.is_empty() {
                c.push(Series::from_xy(Mark::Thin, GREY, &b.x, point));
            }
            c
        })
        .collect();
    panels_svg(&charts, cols).map_err(plot_err(figure))
}

/// p(t) over posterior draws (median line over the 5–95 % band) next to the
/// point-estimate p(t) and the 0.05 level, log axis.
pub(crate) fn p_draws_chart(
    figure: &str,
    title: &str,
    draws: &RangeBand,
    point: &Line,
) -> Result<String> {
    let pmin = draws
        .lower
        .iter()
        .chain(&point.y)
        .copied()
        .filter(|p| *p > 0.0)
        .fold(1.0f64, f64::min);
    let lo = (pmin / 3.0).min(1e-3);
    let (x0, x1) = (
        draws.x.first().copied().unwrap_or(0.0),
        draws.x.last().copied().unwrap_or(1.0),
    );
    let floor = |v: &[f64]| v.iter().map(|p| p.max(lo)).collect::<Vec<f64>>();
    let chart = Chart::new(title, "t (s)", "p (Wilcoxon rank-sum)")
        .size(Chart::SIZE.0, 360)
        .log_y()
        .y_range(lo, 1.5)
        .legend(Legend::LowerRight)
        .with(Series::new(Mark::Thin, GREY, vec![(x0, 0.05), (x1, 0.05)]).labelled("p = 0.05"))
        .with(
            Series::range(
                palette(draws.colour_index),
                &draws.x,
                &floor(&draws.median),
                &floor(&draws.lower),
                &floor(&draws.upper),
            )
            .labelled(&draws.name),
        )
        .with(
            Series::from_xy(Mark::Dashed, palette(1), &point.x, &floor(&point.y))
                .labelled(&point.name),
        );
    chart.svg().map_err(plot_err(figure))
}
