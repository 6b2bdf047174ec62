//! Meta-model domain checks (issue 14): before a fit on a meta-model, compare the data
//! with what the meta-model was built for — protocol (ramp time, hold, depth), time span,
//! geometry (probe radius, cell size) — and after it, the parameter domain (an optimum
//! on a bound). Each difference is said with its size and the build-study key that would
//! remove it. Data that end before the meta-model's grid are fitted on the overlap
//! (the later grid points get weight 0) when the overlap holds the whole ramp and at
//! least half the grid; otherwise the fit is refused with how to build a matching
//! meta-model. Thesis §4.4.1: a meta-model stands for one protocol and geometry.

use nlvid_model::{BoundHit, BoundSide, BuildConditions, Domain};

/// Relative difference above which a protocol or geometry quantity is reported.
pub const REPORT_ABOVE: f64 = 0.01;

/// The measured side, in the quantities of [`BuildConditions`]; `None` where unknown.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DataFacts {
    /// Time span of the data from their first sample, s.
    pub end_time_s: f64,
    /// Ramp time of the experiment, s.
    pub ramp_time_s: Option<f64>,
    /// Largest indentation (or controlled travel), m.
    pub depth_m: Option<f64>,
    /// Probe radius the fit assumes, m.
    pub probe_radius_m: Option<f64>,
    /// Cell height, m.
    pub cell_height_m: Option<f64>,
    /// Cell diameter, m.
    pub cell_diameter_m: Option<f64>,
}

/// What the checks found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DomainCheck {
    /// One sentence per difference (with its size and the study key to change).
    pub notes: Vec<String>,
    /// `Some(t)`: the data end at `t` before the grid does; fit grid points ≤ t only.
    pub overlap_end: Option<f64>,
}

/// (quantity, [`BuildConditions`] field, data, meta-model, display scale, display unit).
type Compared<'a> = (&'a str, &'a str, Option<f64>, Option<f64>, f64, &'a str);

/// Signed relative difference of the data from the meta-model, in %.
fn percent(data: f64, built: f64) -> f64 {
    100.0 * (data / built - 1.0)
}

/// Compare `data` with the meta-model's build `conditions` (from its `meta.json`, named
/// `meta` in messages) on the output `grid` (s, from the first sample).
///
/// # Errors
/// The data end before the meta-model's ramp does, or cover less than half its grid:
/// a message saying by how much and which build-study keys give a matching meta-model.
pub fn check(
    data: &DataFacts,
    conditions: Option<&BuildConditions>,
    grid: &[f64],
    meta: &str,
) -> Result<DomainCheck, String> {
    let mut out = DomainCheck::default();
    let grid_end = grid.last().copied().unwrap_or(0.0);
    let Some(c) = conditions else {
        out.notes.push(format!(
            "{meta} does not say what the meta-model was built for (exported before its \
             build conditions were stored): protocol and geometry are not checked; re-export \
             it with `nlvid build <build-study.toml> --export <dir>` (finished runs are reused)"
        ));
        if data.end_time_s < grid_end * (1.0 - 1e-9) {
            return Err(format!(
                "the curve covers 0 … {:.6} s but the meta-model's grid ({meta}) runs to {grid_end:.6} s",
                data.end_time_s
            ));
        }
        return Ok(out);
    };
    let mut differ: Vec<&str> = Vec::new();
    // time span: fit the overlap, or say how to build a meta-model that ends in time
    if data.end_time_s < grid_end * (1.0 - 1e-9) {
        let ramp = c.ramp_time_s.or(data.ramp_time_s).unwrap_or(0.0);
        let used = grid.iter().filter(|t| **t <= data.end_time_s).count();
        if data.end_time_s > ramp && 2 * used >= grid.len() {
            out.overlap_end = Some(data.end_time_s);
            out.notes.push(format!(
                "time span: the data end at t = {:.6} s, before the meta-model's grid \
                 (to {grid_end:.6} s, {:+.3} %): fitting the overlap 0 … {:.6} s ({used} of \
                 {} grid points; the last {} left out)",
                data.end_time_s,
                percent(data.end_time_s, grid_end),
                data.end_time_s,
                grid.len(),
                grid.len() - used
            ));
        } else {
            return Err(format!(
                "time span: the curve covers 0 … {:.6} s but the meta-model ({meta}) was built \
                 for 0 … {grid_end:.6} s (ramp {ramp:.6} s); too little overlap to fit \
                 ({used} of {} grid points{}). Build a matching meta-model: change {} so \
                 that its grid ends by t = {:.6} s, rebuild (`nlvid build`) and refit the \
                 surrogate (`nlvid surrogate fit`)",
                data.end_time_s,
                grid.len(),
                if data.end_time_s <= ramp {
                    ", the data end before the ramp does"
                } else {
                    ""
                },
                c.key("end_time_s"),
                data.end_time_s
            ));
        }
    } else if data.end_time_s > grid_end * (1.0 + 1e-9) {
        out.notes.push(format!(
            "time span: the data run to t = {:.6} s, past the meta-model's grid end \
             {grid_end:.6} s; only 0 … {grid_end:.6} s is fitted (a longer hold: {})",
            data.end_time_s,
            c.key("end_time_s")
        ));
    }
    let pairs: [Compared<'_>; 5] = [
        (
            "ramp time",
            "ramp_time_s",
            data.ramp_time_s,
            c.ramp_time_s,
            1.0,
            "s",
        ),
        (
            "depth (travel)",
            "depth_m",
            data.depth_m,
            c.depth_m,
            1e6,
            "µm",
        ),
        (
            "probe radius",
            "probe_radius_m",
            data.probe_radius_m,
            c.probe_radius_m,
            1e6,
            "µm",
        ),
        (
            "cell height",
            "cell_height_m",
            data.cell_height_m,
            c.cell_height_m,
            1e6,
            "µm",
        ),
        (
            "cell diameter",
            "cell_diameter_m",
            data.cell_diameter_m,
            c.cell_diameter_m,
            1e6,
            "µm",
        ),
    ];
    for (what, key, d, b, scale, unit) in pairs {
        let (Some(d), Some(b)) = (d, b) else {
            continue;
        };
        if b > 0.0 && (d / b - 1.0).abs() > REPORT_ABOVE {
            out.notes.push(format!(
                "{what}: data {:.4} {unit}, meta-model built for {:.4} {unit} ({:+.1} %; {})",
                d * scale,
                b * scale,
                percent(d, b),
                c.key(key)
            ));
            differ.push(key);
        }
    }
    if !differ.is_empty() {
        let keys: Vec<String> = differ.iter().map(|k| c.key(k)).collect();
        out.notes.push(format!(
            "the data lie outside what this {} meta-model was built for: its fit and \
             re-check may disagree. For a matching meta-model change {} in the build study, \
             rebuild (`nlvid build`) and refit the surrogate (`nlvid surrogate fit`)",
            c.model,
            keys.join(", ")
        ));
    }
    Ok(out)
}

/// The parameter-domain check after a fit: one note per parameter on a bound of the
/// meta-model's domain, with the bound and the domain's range.
pub fn bound_notes(domain: &Domain, hits: &[BoundHit], x: &[f64]) -> Vec<String> {
    hits.iter()
        .map(|h| {
            let i = domain.params().iter().position(|p| p.name == h.name);
            let (lo, hi, unit) = i.map_or((f64::NAN, f64::NAN, ""), |i| {
                let p = &domain.params()[i];
                (p.lower, p.upper, p.unit.as_str())
            });
            let v = i.and_then(|i| x.get(i)).copied().unwrap_or(f64::NAN);
            let side = match h.side {
                BoundSide::Lower => "lower",
                BoundSide::Upper => "upper",
            };
            format!(
                "parameter domain: {} = {v:.4e} {unit} landed on its {side} bound (the \
                 meta-model covers {lo:.4e} … {hi:.4e} {unit}); the best fit may lie outside \
                 it: widen `{}` in the build study's [design] domain and rebuild",
                h.name, h.name
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_model::ForwardModel as _;

    /// A hertz-prony meta-model: R = 5 µm, ramp 1 s at 10 µm/s (depth 10 µm), grid to
    /// 30.99 s in 0.01 s steps (3099 points).
    fn built() -> (BuildConditions, Vec<f64>) {
        let m = nlvid_forward::HertzProny::new(5e-6, 1e-5, 1.0, 30.99, 3099).expect("model");
        (m.conditions().expect("conditions"), m.time_grid().to_vec())
    }

    fn facts(end: f64) -> DataFacts {
        DataFacts {
            end_time_s: end,
            ramp_time_s: Some(1.0),
            depth_m: Some(10e-6),
            probe_radius_m: Some(5e-6),
            cell_height_m: None,
            cell_diameter_m: None,
        }
    }

    #[test]
    fn hertz_prony_states_its_protocol_and_geometry() {
        let (c, grid) = built();
        assert_eq!(c.model, "hertz-prony");
        assert_eq!(c.probe_radius_m, Some(5e-6));
        assert_eq!(c.ramp_time_s, Some(1.0));
        assert_eq!(c.depth_m, Some(1e-5));
        assert!((c.end_time_s - 30.99).abs() < 1e-12);
        assert!((c.hold_time_s.expect("hold") - 29.99).abs() < 1e-12);
        assert_eq!(grid.len(), 3099);
        assert_eq!(c.key("ramp_time_s"), "[forward] ramp");
    }

    #[test]
    fn matching_data_give_no_notes() {
        let (c, grid) = built();
        let mut d = facts(30.99);
        d.depth_m = Some(10.05e-6); // 0.5 %: below the 1 % reported
        let found = check(&d, Some(&c), &grid, "meta.json").expect("check");
        assert_eq!(found, DomainCheck::default());
    }

    #[test]
    fn data_ending_just_before_the_grid_are_fitted_on_the_overlap() {
        let (c, grid) = built();
        let found = check(&facts(30.971), Some(&c), &grid, "meta.json").expect("overlap");
        assert_eq!(found.overlap_end, Some(30.971));
        // grid points 0.01 … 30.97 are ≤ 30.971: 3097 of 3099
        let n = &found.notes[0];
        assert!(n.contains("fitting the overlap 0 … 30.971000 s"), "{n}");
        assert!(
            n.contains("3097 of 3099 grid points; the last 2 left out"),
            "{n}"
        );
        assert!(n.contains("-0.061 %"), "{n}"); // 30.971/30.99 − 1 = −0.0613 %
    }

    #[test]
    fn data_ending_within_the_ramp_are_refused_with_the_keys_to_change() {
        let (c, grid) = built();
        let e = check(&facts(0.8), Some(&c), &grid, "mm/meta.json").expect_err("refused");
        assert!(e.contains("the data end before the ramp does"), "{e}");
        assert!(e.contains("[forward] hold"), "{e}");
        assert!(e.contains("ends by t = 0.800000 s"), "{e}");
        // past the ramp but under half the grid: refused too
        let e = check(&facts(10.0), Some(&c), &grid, "mm/meta.json").expect_err("refused");
        assert!(e.contains("1000 of 3099 grid points"), "{e}");
    }

    #[test]
    fn protocol_and_geometry_differences_are_said_with_their_size_and_key() {
        let (mut c, grid) = built();
        c.cell_height_m = Some(10e-6);
        c.keys
            .push(("cell_height_m".into(), "[forward] height".into()));
        let mut d = facts(30.99);
        d.ramp_time_s = Some(2.0);
        d.depth_m = Some(20e-6);
        d.probe_radius_m = Some(2.5e-6);
        d.cell_height_m = Some(8e-6);
        let found = check(&d, Some(&c), &grid, "meta.json").expect("check");
        let all = found.notes.join("\n");
        assert!(
            all.contains(
                "ramp time: data 2.0000 s, meta-model built for 1.0000 s (+100.0 %; [forward] ramp)"
            ),
            "{all}"
        );
        assert!(
            all.contains(
                "depth (travel): data 20.0000 µm, meta-model built for 10.0000 µm (+100.0 %"
            ),
            "{all}"
        );
        assert!(
            all.contains("probe radius: data 2.5000 µm, meta-model built for 5.0000 µm (-50.0 %; [forward] probe_radius)"),
            "{all}"
        );
        assert!(all.contains("cell height: data 8.0000 µm, meta-model built for 10.0000 µm (-20.0 %; [forward] height)"), "{all}");
        assert!(
            all.contains("For a matching meta-model change [forward] ramp"),
            "{all}"
        );
        assert_eq!(found.overlap_end, None);
    }

    #[test]
    fn a_meta_model_without_conditions_is_said_and_short_data_refused() {
        let (_, grid) = built();
        let found = check(&facts(30.99), None, &grid, "meta.json").expect("check");
        assert!(found.notes[0].contains("does not say what the meta-model was built for"));
        let e = check(&facts(30.971), None, &grid, "meta.json").expect_err("refused");
        assert!(e.contains("runs to 30.990000 s"), "{e}");
    }

    #[test]
    fn a_parameter_on_its_bound_is_named_with_the_domain_range() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let p = &d.params()[0];
        let mut x: Vec<f64> = d
            .params()
            .iter()
            .map(|p| 0.5 * (p.lower + p.upper))
            .collect();
        x[0] = p.upper;
        let hits = d.on_bounds(&x, 1e-6);
        assert_eq!(hits.len(), 1);
        let notes = bound_notes(&d, &hits, &x);
        let want = format!(
            "{} = {:.4e} {} landed on its upper bound (the meta-model covers {:.4e} … {:.4e}",
            p.name, p.upper, p.unit, p.lower, p.upper
        );
        assert!(notes[0].contains(&want), "{}", notes[0]);
    }
}
