//! The figure helper draws well-formed SVG with the title, axis labels and
//! series asked for. Well-formedness is checked by a small XML reader written
//! here, independent of plotters.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use nlvid_figure::{Chart, FigureError, Legend, Mark, Series, palette, panels_svg};

/// A start or end tag, or a self-closing one, with its attributes.
#[derive(Debug)]
struct Tag {
    name: String,
    attrs: Vec<(String, String)>,
    end: bool,
}

/// Reads `doc` as XML: every tag closed in order, attributes quoted, no raw
/// `<` or bare `&` in text. Returns the tags and the text runs.
fn parse_xml(doc: &str) -> (Vec<Tag>, Vec<String>) {
    let mut tags = Vec::new();
    let mut texts = Vec::new();
    let mut open: Vec<String> = Vec::new();
    let mut rest = doc.trim();
    if rest.starts_with("<?xml") {
        rest = &rest[rest.find("?>").expect("declaration closed") + 2..];
    }
    while let Some(lt) = rest.find('<') {
        let text = &rest[..lt];
        check_text(text);
        if !text.trim().is_empty() {
            texts.push(text.to_string());
        }
        let gt = rest[lt..].find('>').expect("tag closed") + lt;
        let inner = &rest[lt + 1..gt];
        rest = &rest[gt + 1..];
        let end = inner.starts_with('/');
        let empty = inner.ends_with('/');
        let body = inner.trim_start_matches('/').trim_end_matches('/');
        let name: String = body.chars().take_while(|c| !c.is_whitespace()).collect();
        assert!(
            !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_alphanumeric() || c == '-' || c == ':')
        );
        let attrs = parse_attrs(&body[name.len()..]);
        if end {
            assert_eq!(
                open.pop().as_deref(),
                Some(name.as_str()),
                "</{name}> out of order"
            );
        } else if !empty {
            open.push(name.clone());
        }
        tags.push(Tag { name, attrs, end });
    }
    check_text(rest);
    assert!(open.is_empty(), "unclosed: {open:?}");
    (tags, texts)
}

fn check_text(text: &str) {
    for (i, _) in text.match_indices('&') {
        let entity = &text[i..];
        assert!(
            ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;", "&#"]
                .iter()
                .any(|e| entity.starts_with(e)),
            "bare & in {text:?}"
        );
    }
}

fn parse_attrs(mut s: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    loop {
        s = s.trim_start();
        if s.is_empty() {
            return out;
        }
        let eq = s.find('=').expect("attribute has a value");
        let key = s[..eq].trim().to_string();
        let q = s[eq + 1..].chars().next().expect("quote");
        assert!(q == '"' || q == '\'', "unquoted attribute {key}");
        let close = s[eq + 2..].find(q).expect("quote closed") + eq + 2;
        let value = s[eq + 2..close].to_string();
        check_text(&value);
        out.push((key, value));
        s = &s[close + 1..];
    }
}

fn attr<'a>(t: &'a Tag, key: &str) -> Option<&'a str> {
    t.attrs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

/// The `points` of every polyline stroked in `colour` (`#RRGGBB`; axes and
/// ticks are black polylines too), as pixel pairs.
fn polylines(tags: &[Tag], colour: &str) -> Vec<Vec<(f64, f64)>> {
    tags.iter()
        .filter(|t| t.name == "polyline" && !t.end)
        .filter(|t| attr(t, "stroke").is_some_and(|s| s.eq_ignore_ascii_case(colour)))
        .map(|t| {
            attr(t, "points")
                .unwrap()
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

const BLUE: &str = "#0072B2";
const VERMILION: &str = "#D55E00";
const GREEN: &str = "#009E73";

fn t_and_f() -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..5).map(|i| i as f64).collect();
    let f: Vec<f64> = t.iter().map(|t| 10.0 - 2.0 * t).collect();
    (t, f)
}

#[test]
fn a_chart_is_well_formed_svg_with_title_axis_labels_and_its_series() {
    let (t, f) = t_and_f();
    let svg = Chart::new("G(t) & <cell 1>", "t (s)", "F (nN)")
        .with(Series::from_xy(Mark::Line, palette(0), &t, &f).labelled("fit"))
        .svg()
        .unwrap();
    let (tags, texts) = parse_xml(&svg);
    let root = &tags[0];
    assert_eq!(root.name, "svg");
    assert_eq!(attr(root, "width"), Some("720"));
    assert_eq!(attr(root, "height"), Some("440"));
    for want in ["G(t) &amp; &lt;cell 1&gt;", "t (s)", "F (nN)", "fit"] {
        assert!(
            texts.iter().any(|x| x.trim() == want),
            "no text {want:?} in {texts:?}"
        );
    }
    // One series: one polyline in the first palette colour through the five
    // points, left to right and (the force falls) top to bottom in pixels.
    // (The second blue polyline is the 20 px stroke in the legend.)
    let lines = polylines(&tags, BLUE);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(lines[1].len(), 2);
    assert_eq!(lines[1][1].0 - lines[1][0].0, 20.0);
    let p = &lines[0];
    assert_eq!(p.len(), 5);
    assert!(
        p.windows(2).all(|w| w[1].0 > w[0].0 && w[1].1 > w[0].1),
        "{p:?}"
    );
    // Equal steps in data are equal steps in pixels (a linear axis).
    let dx: Vec<f64> = p.windows(2).map(|w| w[1].0 - w[0].0).collect();
    assert!(dx.iter().all(|d| (d - dx[0]).abs() <= 1.0), "{dx:?}");
}

#[test]
fn non_finite_points_are_skipped_not_written() {
    let (t, mut f) = t_and_f();
    f[2] = f64::NAN;
    let svg = Chart::new("x", "t (s)", "F (nN)")
        .with(Series::from_xy(Mark::Thin, palette(1), &t, &f))
        .svg()
        .unwrap();
    assert!(!svg.contains("NaN") && !svg.contains("inf"));
    let (tags, _) = parse_xml(&svg);
    assert_eq!(polylines(&tags, VERMILION)[0].len(), 4);
}

#[test]
fn a_log_axis_drops_non_positive_values_and_writes_powers_of_ten() {
    let t = [0.0, 1.0, 2.0, 3.0];
    let p = [0.5, 1e-3, 0.0, 0.04];
    let svg = Chart::new("p", "t (s)", "p")
        .log_y()
        .y_range(1e-4, 1.5)
        .with(Series::from_xy(Mark::Line, palette(0), &t, &p).labelled("A vs B"))
        .svg()
        .unwrap();
    let (tags, texts) = parse_xml(&svg);
    assert_eq!(polylines(&tags, BLUE)[0].len(), 3);
    for want in ["1e-3", "1e-2", "1e-1", "1e0"] {
        assert!(
            texts.iter().any(|x| x.trim() == want),
            "no tick {want} in {texts:?}"
        );
    }
}

#[test]
fn a_band_is_a_translucent_polygon_under_its_mean_line() {
    let (t, m) = t_and_f();
    let sd = vec![1.0; t.len()];
    let svg = Chart::new("bands", "t (s)", "F (nN)")
        .y_from_zero()
        .with(Series::band(palette(2), &t, &m, &sd).labelled("A (mean ± sd)"))
        .svg()
        .unwrap();
    let (tags, texts) = parse_xml(&svg);
    let band = tags
        .iter()
        .filter(|t| t.name == "polygon")
        .find(|t| attr(t, "opacity").is_some() || attr(t, "fill-opacity").is_some())
        .expect("a translucent polygon");
    // Upper edge then lower edge: twice the points of the mean line.
    assert_eq!(
        attr(band, "points").unwrap().split_whitespace().count(),
        2 * t.len()
    );
    assert_eq!(polylines(&tags, GREEN)[0].len(), t.len());
    assert!(texts.iter().any(|x| x.trim() == "A (mean ± sd)"));
}

/// An asymmetric (credible) band: its polygon follows the given lower and
/// upper limits, and the y axis reaches the upper limit (not mid ± anything).
#[test]
fn a_range_band_spans_its_own_lower_and_upper_limits() {
    let (t, m) = t_and_f();
    let lower: Vec<f64> = m.iter().map(|v| v - 0.5).collect();
    let upper: Vec<f64> = m.iter().map(|v| v + 30.0).collect();
    let svg = Chart::new("range", "t (s)", "G (Pa)")
        .with(Series::range(palette(2), &t, &m, &lower, &upper).labelled("A (90 % band)"))
        .svg()
        .unwrap();
    let (tags, texts) = parse_xml(&svg);
    let band = tags
        .iter()
        .filter(|t| t.name == "polygon")
        .find(|t| attr(t, "opacity").is_some() || attr(t, "fill-opacity").is_some())
        .expect("a translucent polygon");
    let pts: Vec<(f64, f64)> = attr(band, "points")
        .unwrap()
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    assert_eq!(pts.len(), 2 * t.len());
    // SVG y grows downwards: the upper edge is far above the median line
    // (30 units) and the lower edge just below it (0.5 units).
    let line = &polylines(&tags, GREEN)[0];
    let above = line[0].1 - pts[0].1;
    let below = pts[2 * t.len() - 1].1 - line[0].1;
    assert!(
        above > 10.0 * below && below > 0.0,
        "above {above}, below {below}"
    );
    assert!(texts.iter().any(|x| x.trim() == "A (90 % band)"));
}

#[test]
fn markers_are_drawn_as_circles_and_diamonds_with_legend_entries() {
    let svg = Chart::new("m", "D/r0", "F/(C1 h0 r0)")
        .legend(Legend::UpperLeft)
        .with(Series::new(Mark::Dots, palette(0), vec![(0.5, 1.0)]).labelled("edge"))
        .with(Series::new(Mark::Diamonds, nlvid_figure::BLACK, vec![(1.0, 4.2)]).labelled("thesis"))
        .svg()
        .unwrap();
    let (tags, texts) = parse_xml(&svg);
    // One marker in the plot and one in the legend for each.
    assert_eq!(tags.iter().filter(|t| t.name == "circle").count(), 2);
    assert_eq!(tags.iter().filter(|t| t.name == "polygon").count(), 2);
    assert!(texts.iter().any(|x| x.trim() == "edge"));
    assert!(texts.iter().any(|x| x.trim() == "thesis"));
}

#[test]
fn panels_are_laid_out_in_rows_of_cols() {
    let (t, f) = t_and_f();
    let charts: Vec<Chart> = (0..3)
        .map(|i| {
            Chart::new(format!("cell {i}"), "", "F (nN)").with(Series::from_xy(
                Mark::Line,
                palette(i),
                &t,
                &f,
            ))
        })
        .collect();
    let svg = panels_svg(&charts, 2).unwrap();
    let (tags, texts) = parse_xml(&svg);
    assert_eq!(attr(&tags[0], "width"), Some("480"));
    assert_eq!(attr(&tags[0], "height"), Some("340"));
    let n: usize = [BLUE, VERMILION, GREEN]
        .iter()
        .map(|c| polylines(&tags, c).len())
        .sum();
    assert_eq!(n, 3);
    for i in 0..3 {
        assert!(texts.iter().any(|x| x.trim() == format!("cell {i}")));
    }
}

#[test]
fn writing_into_a_missing_directory_names_the_file() {
    let path = std::env::temp_dir()
        .join("nlvid-figure-no-such-dir")
        .join("f.svg");
    let err = Chart::new("x", "a", "b").write(&path).unwrap_err();
    assert!(
        matches!(&err, FigureError::Io { path: p, .. } if *p == path),
        "{err:?}"
    );
    assert!(err.to_string().contains("f.svg"));
}
