//! A chart as data, drawn in the house style.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::prelude::*;

use crate::Colour;
use crate::error::{FigureError, Result, draw_err};
use crate::range::{extent, log_padded, padded};

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    /// Solid line, 2 px (computed curves, fits).
    Line,
    /// Solid line, 1 px (measured data, reference levels).
    Thin,
    /// Dashed line, 2 px (a surrogate's curve).
    Dashed,
    /// Dotted line, 2 px (a model re-run).
    Dotted,
    /// Filled dots (single computed points).
    Dots,
    /// Diamonds (values read from the thesis).
    Diamonds,
    /// A mean line (2 px) over a translucent band mean ± `sd`; `sd[i]`
    /// belongs to point `i`.
    Band(Vec<f64>),
    /// A line (2 px) over a translucent band between `(lower, upper)[i]`
    /// at point `i` (an asymmetric band: credible or confidence limits).
    Range(Vec<(f64, f64)>),
}

/// Where the legend box sits (or none).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legend {
    /// Top left corner.
    UpperLeft,
    /// Top right corner (the default).
    UpperRight,
    /// Bottom right corner.
    LowerRight,
    /// No legend.
    None,
}

/// Scale of the y axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear (the default).
    Linear,
    /// Logarithmic; points with y ≤ 0 are not drawn.
    Log,
}

/// One curve or point set of a [`Chart`].
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    label: Option<String>,
    mark: Mark,
    colour: Colour,
    points: Vec<(f64, f64)>,
}

impl Series {
    /// A series of `(x, y)` points; non-finite points are not drawn.
    pub fn new(mark: Mark, colour: Colour, points: Vec<(f64, f64)>) -> Self {
        Series {
            label: None,
            mark,
            colour,
            points,
        }
    }

    /// A series of the pairs `(x[i], y[i])` (up to the shorter length).
    pub fn from_xy(mark: Mark, colour: Colour, x: &[f64], y: &[f64]) -> Self {
        Self::new(
            mark,
            colour,
            x.iter().copied().zip(y.iter().copied()).collect(),
        )
    }

    /// A mean ± sd band ([`Mark::Band`]).
    pub fn band(colour: Colour, x: &[f64], mean: &[f64], sd: &[f64]) -> Self {
        Self::from_xy(Mark::Band(sd.to_vec()), colour, x, mean)
    }

    /// A line `mid` over the band `lower`…`upper` ([`Mark::Range`]).
    pub fn range(colour: Colour, x: &[f64], mid: &[f64], lower: &[f64], upper: &[f64]) -> Self {
        let limits = lower.iter().copied().zip(upper.iter().copied()).collect();
        Self::from_xy(Mark::Range(limits), colour, x, mid)
    }

    /// The same series with a legend entry.
    #[must_use]
    pub fn labelled(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    /// Drawable points `(x, y, low, high)` (the band's limits; y itself
    /// for marks without a band): finite, and y > 0 on a log axis.
    fn drawable(&self, scale: Scale) -> Vec<(f64, f64, f64, f64)> {
        let limits = |i: usize, y: f64| match &self.mark {
            Mark::Band(sd) => sd.get(i).map_or((f64::NAN, f64::NAN), |s| (y - s, y + s)),
            Mark::Range(r) => r.get(i).copied().unwrap_or((f64::NAN, f64::NAN)),
            _ => (y, y),
        };
        self.points
            .iter()
            .enumerate()
            .map(|(i, &(x, y))| {
                let (lo, hi) = limits(i, y);
                (x, y, lo, hi)
            })
            .filter(|(x, y, lo, hi)| {
                x.is_finite() && y.is_finite() && lo.is_finite() && hi.is_finite()
            })
            .filter(|(_, y, _, _)| scale == Scale::Linear || *y > 0.0)
            .collect()
    }

    fn is_marker(&self) -> bool {
        matches!(self.mark, Mark::Dots | Mark::Diamonds)
    }
}

/// A figure: title, axis labels (with units), series, and layout choices.
/// Build with [`Chart::new`] and the `with`/setter methods, draw with
/// [`Chart::svg`] or [`Chart::write`].
#[derive(Debug, Clone, PartialEq)]
pub struct Chart {
    title: String,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
    size: (u32, u32),
    legend: Legend,
    y_scale: Scale,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
    y_from_zero: bool,
}

/// Text sizes and spacing of one layout.
struct Style {
    caption: u32,
    margin: u32,
    x_area: u32,
    y_area: u32,
    /// Tick label and axis title size; `None` = plotters' default.
    text: Option<u32>,
    /// Number of ticks per axis; `None` = plotters' default.
    ticks: Option<usize>,
    legend_text: u32,
}

const FULL: Style = Style {
    caption: 18,
    margin: 12,
    x_area: 42,
    y_area: 64,
    text: None,
    ticks: None,
    legend_text: 12,
};

const PANEL: Style = Style {
    caption: 12,
    margin: 6,
    x_area: 22,
    y_area: 38,
    text: Some(10),
    ticks: Some(4),
    legend_text: 10,
};

/// Size of one panel of [`panels_svg`] (px).
pub const PANEL_SIZE: (u32, u32) = (240, 170);

/// Fraction of the data span added on each side of the y axis (and of the x
/// axis when a series has markers, so none is cut at the frame).
const PAD: f64 = 0.04;

impl Chart {
    /// Default figure size (px).
    pub const SIZE: (u32, u32) = (720, 440);

    /// An empty chart; an empty axis label draws no axis title.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Chart {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            size: Self::SIZE,
            legend: Legend::UpperRight,
            y_scale: Scale::Linear,
            x_range: None,
            y_range: None,
            y_from_zero: false,
        }
    }

    /// Adds a series (drawn in the order added, legend in the same order).
    #[must_use]
    pub fn with(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }

    /// Adds a series.
    pub fn push(&mut self, series: Series) {
        self.series.push(series);
    }

    /// Figure size in px (default [`Chart::SIZE`]; ignored in [`panels_svg`]).
    #[must_use]
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.size = (width, height);
        self
    }

    /// Legend position (default [`Legend::UpperRight`]).
    #[must_use]
    pub fn legend(mut self, legend: Legend) -> Self {
        self.legend = legend;
        self
    }

    /// Logarithmic y axis with ticks written as powers of ten.
    #[must_use]
    pub fn log_y(mut self) -> Self {
        self.y_scale = Scale::Log;
        self
    }

    /// Fixed x range instead of the data's extent.
    #[must_use]
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = Some((lo, hi));
        self
    }

    /// Fixed y range instead of the padded data extent.
    #[must_use]
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }

    /// The y axis always includes 0 (forces, moduli).
    #[must_use]
    pub fn y_from_zero(mut self) -> Self {
        self.y_from_zero = true;
        self
    }

    /// The axis ranges: given ones, else from the drawable points — x their
    /// extent (padded when there are markers), y their extent (± sd for
    /// bands, with 0 if asked) padded by 4 % (linear) or a factor 1.5 (log).
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let pts: Vec<(f64, f64, f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.drawable(self.y_scale))
            .collect();
        let x = self.x_range.unwrap_or_else(|| {
            let pad = if self.series.iter().any(Series::is_marker) {
                PAD
            } else {
                0.0
            };
            padded(extent(pts.iter().map(|p| p.0)), pad)
        });
        let y = self.y_range.unwrap_or_else(|| match self.y_scale {
            Scale::Linear => {
                let zero = self.y_from_zero.then_some(0.0);
                let ys = pts.iter().flat_map(|p| [p.2, p.3]).chain(zero);
                padded(extent(ys), PAD)
            }
            Scale::Log => log_padded(extent(pts.iter().map(|p| p.1))),
        });
        (x, y)
    }

    /// The chart as an SVG document.
    ///
    /// # Errors
    /// [`FigureError::Draw`] when plotters fails.
    pub fn svg(&self) -> Result<String> {
        let mut out = String::new();
        {
            let root = SVGBackend::with_string(&mut out, self.size).into_drawing_area();
            root.fill(&WHITE).map_err(draw_err)?;
            self.draw_on(&root, &FULL)?;
            root.present().map_err(draw_err)?;
        }
        Ok(out)
    }

    /// Writes [`Chart::svg`] to `path`.
    ///
    /// # Errors
    /// As [`Chart::svg`]; [`FigureError::Io`] when the file cannot be written.
    pub fn write(&self, path: &Path) -> Result<()> {
        let svg = self.svg()?;
        nlvid_study::write_atomic(path, svg.as_bytes()).map_err(|e| FigureError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    }

    fn draw_on(&self, area: &DrawingArea<SVGBackend<'_>, Shift>, style: &Style) -> Result<()> {
        let (x, y) = self.ranges();
        match self.y_scale {
            Scale::Linear => self.draw_in(area, style, x, y.0..y.1),
            Scale::Log => self.draw_in(area, style, x, (y.0..y.1).log_scale()),
        }
    }

    fn draw_in<Y>(
        &self,
        area: &DrawingArea<SVGBackend<'_>, Shift>,
        style: &Style,
        x: (f64, f64),
        y: Y,
    ) -> Result<()>
    where
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, ("sans-serif", style.caption))
            .margin(style.margin)
            .x_label_area_size(style.x_area)
            .y_label_area_size(style.y_area)
            .build_cartesian_2d(x.0..x.1, y)
            .map_err(draw_err)?;
        let powers_of_ten = |v: &f64| format!("{v:.0e}");
        {
            let mut mesh = chart.configure_mesh();
            mesh.light_line_style(WHITE.mix(0.0));
            if !self.x_label.is_empty() {
                mesh.x_desc(self.x_label.as_str());
            }
            if !self.y_label.is_empty() {
                mesh.y_desc(self.y_label.as_str());
            }
            if let Some(t) = style.text {
                mesh.label_style(("sans-serif", t))
                    .axis_desc_style(("sans-serif", t));
            }
            if let Some(n) = style.ticks {
                mesh.x_labels(n).y_labels(n);
            }
            if self.y_scale == Scale::Log {
                mesh.y_label_formatter(&powers_of_ten);
            }
            mesh.draw().map_err(draw_err)?;
        }
        for s in &self.series {
            let c = RGBColor(s.colour.0, s.colour.1, s.colour.2);
            let pts = s.drawable(self.y_scale);
            let xy = || pts.iter().map(|&(x, y, _, _)| (x, y));
            let anno = match &s.mark {
                Mark::Line | Mark::Thin => {
                    let w = if s.mark == Mark::Line { 2 } else { 1 };
                    let a = chart
                        .draw_series(LineSeries::new(xy(), c.stroke_width(w)))
                        .map_err(draw_err)?;
                    a.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(w))
                    })
                }
                Mark::Dashed | Mark::Dotted => {
                    let (dash, gap) = if s.mark == Mark::Dashed {
                        (8, 5)
                    } else {
                        (2, 4)
                    };
                    let a = chart
                        .draw_series(DashedLineSeries::new(xy(), dash, gap, c.stroke_width(2)))
                        .map_err(draw_err)?;
                    a.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    })
                }
                Mark::Dots => {
                    let a = chart
                        .draw_series(xy().map(|p| Circle::new(p, 4, c.filled())))
                        .map_err(draw_err)?;
                    a.legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()))
                }
                Mark::Diamonds => {
                    let st = c.stroke_width(2);
                    let a = chart
                        .draw_series(xy().map(|p| {
                            EmptyElement::at(p)
                                + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], st)
                        }))
                        .map_err(draw_err)?;
                    a.legend(move |(x, y)| {
                        EmptyElement::at((x + 10, y))
                            + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], st)
                    })
                }
                Mark::Band(_) | Mark::Range(_) => {
                    let mut poly: Vec<(f64, f64)> =
                        pts.iter().map(|&(x, _, _, hi)| (x, hi)).collect();
                    poly.extend(pts.iter().rev().map(|&(x, _, lo, _)| (x, lo)));
                    chart
                        .draw_series(std::iter::once(Polygon::new(poly, c.mix(0.18).filled())))
                        .map_err(draw_err)?;
                    let a = chart
                        .draw_series(LineSeries::new(xy(), c.stroke_width(2)))
                        .map_err(draw_err)?;
                    a.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                    })
                }
            };
            if let Some(l) = &s.label {
                anno.label(l.as_str());
            }
        }
        let position = match self.legend {
            Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
            Legend::UpperRight => SeriesLabelPosition::UpperRight,
            Legend::LowerRight => SeriesLabelPosition::LowerRight,
            Legend::None => return Ok(()),
        };
        if self.series.iter().any(|s| s.label.is_some()) {
            chart
                .configure_series_labels()
                .position(position)
                .label_font(("sans-serif", style.legend_text))
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .draw()
                .map_err(draw_err)?;
        }
        Ok(())
    }
}

/// Small multiples: `charts` in rows of `cols` panels of [`PANEL_SIZE`] px,
/// each in the compact variant of the style (smaller text, four ticks).
///
/// # Errors
/// [`FigureError::Draw`] when plotters fails.
pub fn panels_svg(charts: &[Chart], cols: usize) -> Result<String> {
    let cols = cols.max(1);
    let rows = charts.len().div_ceil(cols).max(1);
    let size = (PANEL_SIZE.0 * cols as u32, PANEL_SIZE.1 * rows as u32);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        for (chart, area) in charts.iter().zip(root.split_evenly((rows, cols)).iter()) {
            chart.draw_on(area, &PANEL)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(out)
}
