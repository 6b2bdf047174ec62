//! The reproduced ch. II data as text: each figure's curves as CSV and
//! Table 2.1 (initial unloading slopes) as CSV and as a printed table.

use crate::Result;
use crate::thesis::{Figure, SlopeRow};

/// Every file of the ch. II reproduction as `(name, contents)`: each
/// figure's CSV and SVG, `table2_1.csv`, and `notes.txt`.
///
/// # Errors
/// A figure cannot be drawn.
pub fn reproduction_files(
    figs: &[Figure],
    rows: &[SlopeRow],
    notes: &[String],
) -> Result<Vec<(String, String)>> {
    let mut files = Vec::new();
    for f in figs {
        files.push((format!("{}.csv", f.id), f.to_csv()));
        files.push((format!("{}.svg", f.id), crate::plot::svg(f)?));
    }
    files.push(("table2_1.csv".into(), table2_1_csv(rows)));
    files.push((
        "notes.txt".into(),
        notes.iter().map(|n| format!("{n}\n")).collect(),
    ));
    Ok(files)
}

impl Figure {
    /// `series,x,y`, one row per point, the series label quoted.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("series,x,y\n");
        for ser in &self.series {
            let label = ser.label.replace('"', "'");
            for (x, y) in ser.x.iter().zip(&ser.y) {
                s.push_str(&format!("\"{label}\",{x},{y}\n"));
            }
        }
        s
    }
}

fn opt(v: Option<f64>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// Table 2.1 as CSV: `D_over_r0, unloading_rate, model, thesis_slope,
/// tangent_slope, secant_slope_dD_0.01, secant_over_2_div_thesis`
/// (dimensionless, eq. 2.47).
pub fn table2_1_csv(rows: &[SlopeRow]) -> String {
    table(
        "D_over_r0,unloading_rate,model,thesis_slope,tangent_slope,secant_slope_dD_0.01,secant_over_2_div_thesis\n",
        rows,
        |r| {
            let (thesis, ratio) = (opt(r.thesis), opt(r.ratio));
            let (d, s, m, k, sec) = (r.d_max, r.unload_rate, &r.model, r.slope, r.secant);
            format!("{d},{s},{m},{thesis},{k},{sec},{ratio}\n")
        },
    )
}

/// Table 2.1 for people, one line per row.
pub fn table2_1_text(rows: &[SlopeRow]) -> String {
    table(
        "Table 2.1 (initial unloading slope dF̄/dD̄: tangent over the first step, secant over ΔD/r0 = 0.01; ratio = secant/2 ÷ thesis):\n",
        rows,
        |r| {
            let thesis = r.thesis.map_or("-".into(), |v| v.to_string());
            let ratio = r.ratio.map_or("-".into(), |v| format!("{v:.3}"));
            let (d, s, m, k, sec) = (r.d_max, r.unload_rate, &r.model, r.slope, r.secant);
            format!(
                "  D/r0 = {d:.2}, s_u = {s:.1}, {m:<10} thesis {thesis:>7}  tangent {k:8.2}  secant {sec:8.2}  ratio {ratio}\n"
            )
        },
    )
}

/// `header` followed by one line per row.
fn table(header: &str, rows: &[SlopeRow], line: impl Fn(&SlopeRow) -> String) -> String {
    std::iter::once(header.to_owned())
        .chain(rows.iter().map(line))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_2_1_rows_print_as_csv_and_as_aligned_text() {
        let rows = [
            SlopeRow {
                d_max: 0.5,
                unload_rate: 10.0,
                model: "NLE".into(),
                thesis: Some(1.5),
                slope: 2.25,
                secant: 3.0,
                ratio: Some(1.0),
            },
            SlopeRow {
                d_max: 0.25,
                unload_rate: 0.5,
                model: "PR".into(),
                thesis: None,
                slope: -1.126,
                secant: 12.5,
                ratio: None,
            },
        ];
        let csv = table2_1_csv(&rows);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 3);
        assert!(lines[0].starts_with("D_over_r0,unloading_rate,model,"));
        assert_eq!(lines[1], "0.5,10,NLE,1.5,2.25,3,1");
        assert_eq!(lines[2], "0.25,0.5,PR,,-1.126,12.5,");
        let text = table2_1_text(&rows);
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].starts_with("Table 2.1 (initial unloading slope"));
        assert_eq!(
            lines[1],
            "  D/r0 = 0.50, s_u = 10.0, NLE        thesis     1.5  tangent     2.25  secant     3.00  ratio 1.000"
        );
        assert_eq!(
            lines[2],
            "  D/r0 = 0.25, s_u = 0.5, PR         thesis       -  tangent    -1.13  secant    12.50  ratio -"
        );
    }
}
