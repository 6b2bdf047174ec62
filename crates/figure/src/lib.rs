//! One figure style for every nlvid plot.
//!
//! A [`Chart`] is data — a title, two axis labels with units, and a list of
//! [`Series`] (lines, dashed or dotted lines, dots, diamonds, mean ± sd
//! bands) — and [`Chart::svg`] draws it with `plotters`' SVG backend in the
//! one house style: 720 × 440 px, sans-serif text (kept as text: no font
//! files, sharp when zoomed or printed), the colour-blind-safe Okabe–Ito
//! [`PALETTE`], axis titles, no fine grid, a legend on a translucent white box.
//! [`panels_svg`] draws small multiples of charts in a compact variant of the
//! same style. Every figure of `nlvid-report`, `nlvid-inverse`,
//! `nlvid-membrane` and `nlvid-afm` is drawn here.
//!
//! Cost: linear in the number of points (one pass to find the axis ranges,
//! one to write them); the SVG holds every finite point, so thin very long
//! records before plotting if file size matters.
//!
//! ```
//! use nlvid_figure::{Chart, Mark, Series, palette};
//!
//! let t: Vec<f64> = (0..20).map(|i| 0.5 * i as f64).collect();
//! let f: Vec<f64> = t.iter().map(|t| (-t).exp()).collect();
//! let svg = Chart::new("relaxation", "t (s)", "F (nN)")
//!     .with(Series::from_xy(Mark::Line, palette(0), &t, &f).labelled("fit"))
//!     .svg()?;
//! assert!(svg.starts_with("<svg") && svg.contains("t (s)") && svg.contains("fit"));
//! # Ok::<(), nlvid_figure::FigureError>(())
//! ```

#![warn(missing_docs)]

mod chart;
mod error;
mod range;

pub use chart::{Chart, Legend, Mark, Scale, Series, panels_svg};
pub use error::{FigureError, Result};

/// An RGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Colour(pub u8, pub u8, pub u8);

/// Group / series colours (Okabe–Ito, colour-blind friendly): blue,
/// vermilion, bluish green, reddish purple, orange, sky blue, grey.
pub const PALETTE: [Colour; 7] = [
    Colour(0, 114, 178),
    Colour(213, 94, 0),
    Colour(0, 158, 115),
    Colour(204, 121, 167),
    Colour(230, 159, 0),
    Colour(86, 180, 233),
    Colour(120, 120, 120),
];

/// Black: measured data and reference (thesis) values.
pub const BLACK: Colour = Colour(0, 0, 0);

/// Grey: reference levels and background data.
pub const GREY: Colour = Colour(120, 120, 120);

/// The `i`-th colour of [`PALETTE`], cycling.
pub fn palette(i: usize) -> Colour {
    PALETTE[i % PALETTE.len()]
}
