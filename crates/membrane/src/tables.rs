//! The reproduced ch. II data as text: each figure's curves as CSV and
//! Table 2.1 (initial unloading slopes) as CSV and as a printed table.

use crate::thesis::{Figure, SlopeRow};

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
    let mut t = String::from(
        "D_over_r0,unloading_rate,model,thesis_slope,tangent_slope,secant_slope_dD_0.01,secant_over_2_div_thesis\n",
    );
    for r in rows {
        t.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            r.d_max,
            r.unload_rate,
            r.model,
            opt(r.thesis),
            r.slope,
            r.secant,
            opt(r.ratio)
        ));
    }
    t
}

/// Table 2.1 for people, one line per row.
pub fn table2_1_text(rows: &[SlopeRow]) -> String {
    let mut t = String::from(
        "Table 2.1 (initial unloading slope dF̄/dD̄: tangent over the first step, secant over ΔD/r0 = 0.01; ratio = secant/2 ÷ thesis):\n",
    );
    for r in rows {
        t.push_str(&format!(
            "  D/r0 = {:.2}, s_u = {:.1}, {:<10} thesis {:>7}  tangent {:8.2}  secant {:8.2}  ratio {}\n",
            r.d_max,
            r.unload_rate,
            r.model,
            r.thesis.map_or("-".into(), |v| v.to_string()),
            r.slope,
            r.secant,
            r.ratio.map_or("-".into(), |v| format!("{v:.3}"))
        ));
    }
    t
}
