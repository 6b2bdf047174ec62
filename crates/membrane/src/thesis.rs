//! The data behind Figs. 2.3–2.14 and Table 2.1 of the thesis (§2.5.1),
//! regenerated with this crate's solver, for side-by-side comparison.
//!
//! Every case uses r_s = 1.03, G10 = τ1 = 1 (dimensionless, eq. 2.47) and the
//! default [`Geometry`]. Where the thesis is ambiguous the choice is stated
//! in the series label and in `docs/theory/membrane.md`.

use nlvid_protocol::{Quantity, programs};
use serde::Serialize;

use crate::{
    Control, ControlKind, Geometry, Loading, MembraneError, MembraneRun, MembraneSolver,
    MooneyRivlinMembrane, PipkinRogersParams, Result, Solution, simulate,
};

/// How a [`Series`] is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SeriesKind {
    /// Computed curve (line).
    #[default]
    Line,
    /// Computed isolated points (e.g. the contact edge).
    Points,
    /// Values quoted in the thesis text or tables, for comparison.
    Thesis,
}

/// One curve.
#[derive(Debug, Clone, Serialize)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates.
    pub y: Vec<f64>,
    /// How to draw it.
    pub kind: SeriesKind,
}

impl Series {
    /// A computed curve.
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            kind: SeriesKind::Line,
        }
    }
    /// Computed isolated points.
    pub fn points(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            kind: SeriesKind::Points,
            ..Self::line(label, x, y)
        }
    }
    /// Values quoted by the thesis.
    pub fn thesis(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            kind: SeriesKind::Thesis,
            ..Self::line(label, x, y)
        }
    }
}

/// One figure's data.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    /// File stem, e.g. `fig2_4`.
    pub id: String,
    /// Title (thesis caption, shortened).
    pub title: String,
    /// Abscissa label.
    pub x_label: String,
    /// Ordinate label.
    pub y_label: String,
    /// Curves.
    pub series: Vec<Series>,
}

/// One row of Table 2.1 as reproduced (serialised with the column names
/// of `table2_1.csv`, dimensionless quantities of eq. 2.47).
#[derive(Debug, Clone, Serialize)]
pub struct SlopeRow {
    /// Maximum displacement D/r0.
    #[serde(rename = "D_over_r0")]
    pub d_max: f64,
    /// Unloading rate s_u.
    #[serde(rename = "unloading_rate")]
    pub unload_rate: f64,
    /// Model label.
    pub model: String,
    /// Thesis value (None where the table is blank).
    #[serde(rename = "thesis_slope")]
    pub thesis: Option<f64>,
    /// Tangent dF̄/dD̄ over the first unloading step (ΔD = s_u·5e-5).
    #[serde(rename = "tangent_slope")]
    pub slope: f64,
    /// Secant from the peak over the first ΔD/r0 = 0.01 of unloading,
    /// [`SECANT_WINDOW`].
    #[serde(rename = "secant_slope_dD_0.01")]
    pub secant: f64,
    /// `secant / 2 / thesis`: the secant in the App. D force scale
    /// F/(G10_umat h0 r0) with App. D's UMAT modulus G10_umat = 2 G10 (eq. D.2
    /// drops the 2 of eq. 2.55), over
    /// the thesis value. The NLE rows give 1.00; see docs/theory/membrane.md.
    #[serde(rename = "secant_over_2_div_thesis")]
    pub ratio: Option<f64>,
}

/// Unloading window ΔD/r0 of [`SlopeRow::secant`].
pub const SECANT_WINDOW: f64 = 0.01;

fn fig(id: &str, title: &str, x: &str, y: &str, series: Vec<Series>) -> Figure {
    Figure {
        id: id.into(),
        title: title.into(),
        x_label: x.into(),
        y_label: y.into(),
        series,
    }
}

fn mr(gamma: f64) -> Result<MembraneSolver<MooneyRivlinMembrane>> {
    MembraneSolver::new(
        MooneyRivlinMembrane::new(1.0, gamma)?,
        Geometry::default(),
        1.0,
    )
}

fn step_run(p: &PipkinRogersParams, d: f64, profiles: bool) -> Result<MembraneRun> {
    let prog = programs::step(Quantity::Dimensionless, d, 10.0).map_err(proto)?;
    let times: Vec<f64> = (0..=100).map(|k| 0.1 * k as f64).collect();
    let mut l = Loading::new(ControlKind::Displacement, prog, times.clone())?;
    if profiles {
        l = l.with_profiles(&times);
    }
    simulate(p, &Geometry::default(), &l)
}

fn proto(e: nlvid_protocol::ProtocolError) -> MembraneError {
    MembraneError::Input {
        name: "program",
        value: f64::NAN,
        reason: e.to_string(),
    }
}

/// Linear interpolation of a node quantity at reference angle `psi`.
pub fn at_psi(sol: &Solution, psi: f64, f: impl Fn(&crate::NodeValue) -> f64) -> f64 {
    let p = &sol.profile;
    let h = p[1].psi - p[0].psi;
    let j = ((psi / h).floor() as usize).min(p.len() - 2);
    let w = psi / h - j as f64;
    (1.0 - w) * f(&p[j]) + w * f(&p[j + 1])
}

fn load_unload(
    p: Option<&PipkinRogersParams>,
    d_max: f64,
    su: f64,
) -> Result<(MembraneRun, usize, Option<String>)> {
    let prog =
        programs::load_unload(Quantity::Dimensionless, d_max, 1.0, su, 0.0).map_err(proto)?;
    let t_peak = d_max;
    let t_end = t_peak + d_max / su;
    let mut times: Vec<f64> = (0..=100).map(|k| t_peak * k as f64 / 100.0).collect();
    times.extend((1..=20).map(|k| t_peak + 1e-3 * k as f64 / 20.0));
    times.extend((1..=100).map(|k| t_peak + 1e-3 + (t_end - t_peak - 1e-3) * k as f64 / 100.0));
    times.push(t_peak + SECANT_WINDOW / su);
    times.sort_by(f64::total_cmp);
    let l = Loading::new(ControlKind::Displacement, prog, times)?;
    let params = p.copied().unwrap_or(PipkinRogersParams {
        g1: 1.0,
        g2: 1.0,
        ..PipkinRogersParams::chapter2(1.0, 1.0, 1.0)
    });
    // A step that fails (e.g. wrinkling late in a slow unloading) ends the
    // curve there; the failure is returned as a note.
    let mut solver = MembraneSolver::new(params.check()?, Geometry::default(), params.g10)?;
    let mut history = Vec::new();
    let mut note = None;
    for &t in &l.times {
        match solver.advance(t, Control::Displacement(l.program.value(t))) {
            Ok(sol) => history.push(sol.record),
            Err(e) => {
                note = Some(e.to_string());
                break;
            }
        }
    }
    let run = MembraneRun {
        history,
        profiles: Vec::new(),
    };
    let i = run
        .history
        .iter()
        .position(|r| (r.time - t_peak).abs() < 1e-12)
        .unwrap_or(0);
    Ok((run, i, note))
}

/// Regenerate the data of Figs. 2.3–2.14 and Table 2.1 (a few seconds in
/// release builds). Returns figures, Table 2.1 rows and notes on curves that
/// ended early.
///
/// # Errors
/// Any solver error, with the case in the message.
pub fn reproduce() -> Result<(Vec<Figure>, Vec<SlopeRow>, Vec<String>)> {
    let mut figs = Vec::new();
    let mut notes = Vec::new();

    // Fig. 2.3: NLE profiles, γ = 0.1.
    let mut s = mr(0.1)?;
    let mut series = Vec::new();
    for d in [0.1, 0.28, 0.53, 0.78] {
        let sol = s.equilibrium(0.0, Control::Displacement(d))?;
        series.push(Series::line(
            format!("D/r0 = {d}"),
            sol.profile.iter().map(|v| v.rho).collect(),
            sol.profile.iter().map(|v| v.eta).collect(),
        ));
        series.push(Series::points(
            format!("contact edge, D/r0 = {d}"),
            vec![sol.record.contact_radius],
            vec![sol.record.h1],
        ));
    }
    figs.push(fig(
        "fig2_3",
        "Fig. 2.3: NLE profiles, γ = 0.1",
        "ρ/r0",
        "η/r0",
        series,
    ));

    // Fig. 2.4: F–D for several γ.
    let ds: Vec<f64> = (1..=39).map(|k| 0.02 * k as f64).collect();
    let mut series = Vec::new();
    for gamma in [0.0, 0.1, 0.2, 0.3] {
        let mut s = mr(gamma)?;
        let mut f = Vec::new();
        for &d in &ds {
            f.push(s.equilibrium(0.0, Control::Displacement(d))?.record.force);
        }
        series.push(Series::line(format!("γ = {gamma}"), ds.clone(), f));
    }
    figs.push(fig(
        "fig2_4",
        "Fig. 2.4: NLE force vs displacement",
        "D/r0",
        "F/(G10 h0 r0)",
        series,
    ));

    // Fig. 2.5: NLE vs QLV at D = 2t, t, t/2.
    let qlv = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    let mut series = vec![Series::line(
        "NLE γ = 0.1",
        ds.clone(),
        figs[1].series[1].y.clone(),
    )];
    for rate in [2.0, 1.0, 0.5] {
        let prog =
            programs::constant_rate(Quantity::Dimensionless, rate, 0.78 / rate).map_err(proto)?;
        let times = (0..=100).map(|k| 0.78 / rate * k as f64 / 100.0).collect();
        let run = simulate(
            &qlv,
            &Geometry::default(),
            &Loading::new(ControlKind::Displacement, prog, times)?,
        )?;
        series.push(Series::line(
            format!("QLV g1 = g2 = 0.2, D = {rate} t"),
            run.history.iter().map(|r| r.displacement).collect(),
            run.force(),
        ));
    }
    figs.push(fig(
        "fig2_5",
        "Fig. 2.5: NLE vs QLV at constant rates",
        "D/r0",
        "F/(G10 h0 r0)",
        series,
    ));

    // Fig. 2.6: relaxation at two displacements.
    let nlv6 = PipkinRogersParams::chapter2(0.2, 0.3, 0.5);
    let mut series = Vec::new();
    for d in [0.53, 0.78] {
        for (name, p) in [
            ("QLV g1=g2=0.2, c=1", &qlv),
            ("NLV g1=0.2, g2=0.3, c=1/2", &nlv6),
        ] {
            let run = step_run(p, d, false)?;
            series.push(Series::line(
                format!("{name}, D/r0 = {d}"),
                run.times(),
                run.force(),
            ));
        }
    }
    figs.push(fig(
        "fig2_6",
        "Fig. 2.6: force relaxation",
        "t/τ1",
        "F/(G10 h0 r0)",
        series,
    ));

    // Figs. 2.7–2.11 at D/r0 = 0.78.
    let cases_c = [
        ("c = 1 (QLV)", PipkinRogersParams::chapter2(0.2, 0.2, 1.0)),
        ("c = 1/2", PipkinRogersParams::chapter2(0.2, 0.2, 0.5)),
        ("c = 2", PipkinRogersParams::chapter2(0.2, 0.2, 2.0)),
    ];
    let cases_g = [
        (
            "g2 = 0.2 (QLV)",
            PipkinRogersParams::chapter2(0.2, 0.2, 1.0),
        ),
        ("g2 = 0.1", PipkinRogersParams::chapter2(0.2, 0.1, 1.0)),
        ("g2 = 0.3", PipkinRogersParams::chapter2(0.2, 0.3, 1.0)),
    ];
    let mut runs_c = Vec::new();
    for (n, p) in &cases_c {
        runs_c.push((*n, step_run(p, 0.78, true)?));
    }
    let mut runs_g = Vec::new();
    for (n, p) in &cases_g {
        runs_g.push((*n, step_run(p, 0.78, true)?));
    }
    let force = |runs: &[(&str, MembraneRun)]| {
        runs.iter()
            .map(|(n, r)| Series::line(n.to_string(), r.times(), r.force()))
            .collect::<Vec<_>>()
    };
    figs.push(fig(
        "fig2_7",
        "Fig. 2.7: relaxation, g1 = g2 = 0.2, varying c",
        "t/τ1",
        "F/(G10 h0 r0)",
        force(&runs_c),
    ));
    figs.push(fig(
        "fig2_8",
        "Fig. 2.8: relaxation, c = 1, varying g2",
        "t/τ1",
        "F/(G10 h0 r0)",
        force(&runs_g),
    ));
    let mut psic: Vec<Series> = runs_c
        .iter()
        .chain(runs_g.iter().skip(1))
        .map(|(n, r)| {
            Series::line(
                n.to_string(),
                r.times(),
                r.history.iter().map(|h| h.psi_c).collect(),
            )
        })
        .collect();
    psic.push(Series::thesis(
        "thesis §2.5.1: QLV ψc = 1.2917, constant",
        vec![0.0, 2.5, 5.0, 7.5, 10.0],
        vec![1.2917; 5],
    ));
    figs.push(fig(
        "fig2_9",
        "Fig. 2.9: contact angle ψc(t), D/r0 = 0.78",
        "t/τ1",
        "ψc (rad)",
        psic,
    ));
    let stretches = |runs: &[(&str, MembraneRun)]| {
        let mut v = Vec::new();
        for (n, r) in runs {
            for (k, name) in [(0, "λ1"), (1, "λ2")] {
                v.push(Series::line(
                    format!("{name}, {n}"),
                    r.profiles.iter().map(|s| s.record.time).collect(),
                    r.profiles
                        .iter()
                        .map(|s| at_psi(s, 0.25, |p| if k == 0 { p.lambda1 } else { p.lambda2 }))
                        .collect(),
                ));
            }
        }
        v
    };
    figs.push(fig(
        "fig2_10",
        "Fig. 2.10: stretches at ψ = 0.25, varying c",
        "t/τ1",
        "stretch",
        stretches(&runs_c),
    ));
    figs.push(fig(
        "fig2_11",
        "Fig. 2.11: stretches at ψ = 0.25, varying g2",
        "t/τ1",
        "stretch",
        stretches(&runs_g),
    ));

    // Fig. 2.12: distributions at t = 10 for g2 = 0.3.
    let last = runs_g[2]
        .1
        .profiles
        .last()
        .ok_or_else(|| MembraneError::Input {
            name: "profiles",
            value: 10.0,
            reason: "no profile at t = 10".into(),
        })?;
    let col = |f: fn(&crate::NodeValue) -> f64| last.profile.iter().map(f).collect::<Vec<_>>();
    let psi = col(|v| v.psi);
    figs.push(fig(
        "fig2_12",
        "Fig. 2.12: stretches and stresses at t = 10, g1 = 0.2, g2 = 0.3, c = 1",
        "ψ (rad)",
        "λ, σ/G10",
        vec![
            Series::line("λ1", psi.clone(), col(|v| v.lambda1)),
            Series::line("λ2", psi.clone(), col(|v| v.lambda2)),
            Series::line("σ1/G10", psi.clone(), col(|v| v.sigma1)),
            Series::line("σ2/G10", psi.clone(), col(|v| v.sigma2)),
            Series::points(
                "ψc",
                vec![last.record.psi_c],
                vec![at_psi(last, last.record.psi_c, |v| v.lambda2)],
            ),
            Series::thesis(
                "thesis §2.5.1: λ2 = 1.1551 (crown), 1.7564 (edge, ψc = 73.7°)",
                vec![0.0, 73.7_f64.to_radians()],
                vec![1.1551, 1.7564],
            ),
        ],
    ));

    // Figs. 2.13–2.14 and Table 2.1.
    let nlv13 = PipkinRogersParams::chapter2(0.2, 0.6, 0.5);
    let mut rows = Vec::new();
    let thesis = |d: f64, su: f64, m: &str| -> Option<f64> {
        match (d > 0.5, su < 0.5, m) {
            (_, true, "NLE") => None,
            (false, false, "NLE") => Some(4.7),
            (true, false, "NLE") => Some(324.5),
            (false, false, "QLV") => Some(4.6),
            (false, true, "QLV") => Some(6.0),
            (true, false, "QLV") => Some(257.0),
            (true, true, "QLV") => Some(297.0),
            (false, false, _) => Some(4.5),
            (false, true, _) => Some(6.0),
            (true, false, _) => Some(241.0),
            (true, true, _) => Some(287.5),
        }
    };
    // bound here: Rust 1.88 (the declared minimum) does not extend the
    // lifetime of a temporary borrowed inside the array below
    let nlv11 = PipkinRogersParams::chapter2(0.2, 0.6, 1.0);
    for (id, d_max) in [("fig2_13", 0.28), ("fig2_14", 0.78)] {
        let mut series = Vec::new();
        for su in [1.0, 0.2] {
            let models: [(&str, Option<&PipkinRogersParams>); 4] = [
                ("NLE", None),
                ("QLV", Some(&qlv)),
                ("NLV c=1/2", Some(&nlv13)),
                ("NLV c=1", Some(&nlv11)),
            ];
            for (m, p) in models {
                if m == "NLE" && su < 0.5 {
                    continue;
                }
                let (run, i, note) = load_unload(p, d_max, su)?;
                if let Some(n) = &note {
                    notes.push(format!("{id} {m} s_u = {su}: curve ends early: {n}"));
                }
                let h = &run.history;
                if h.len() < i + 2 {
                    continue;
                }
                let slope =
                    (h[i].force - h[i + 1].force) / (h[i].displacement - h[i + 1].displacement);
                let t_sec = d_max + SECANT_WINDOW / su;
                let secant = h
                    .iter()
                    .find(|r| (r.time - t_sec).abs() < 1e-9)
                    .map(|r| (h[i].force - r.force) / (h[i].displacement - r.displacement))
                    .unwrap_or(f64::NAN);
                let th = thesis(d_max, su, m.split(' ').next().unwrap_or(m));
                rows.push(SlopeRow {
                    d_max,
                    unload_rate: su,
                    model: m.into(),
                    thesis: th,
                    slope,
                    secant,
                    ratio: th.map(|v| secant / 2.0 / v),
                });
                if m != "QLV" && m != "NLV c=1" {
                    let x: Vec<f64> = h.iter().map(|r| r.displacement).collect();
                    let y: Vec<f64> = h.iter().map(|r| r.force).collect();
                    if let (Some(true), Some(&xe), Some(&ye)) =
                        (note.as_ref().map(|_| true), x.last(), y.last())
                    {
                        series.push(Series::points(
                            format!("{m}, s_u = {su}: wrinkling (curve ends)"),
                            vec![xe],
                            vec![ye],
                        ));
                    }
                    series.push(Series::line(format!("{m}, s_u = {su}"), x, y));
                }
            }
        }
        figs.push(fig(
            id,
            &format!(
                "Fig. {}: loading–unloading to D/r0 = {d_max}, s_l = 1",
                if d_max < 0.5 { "2.13" } else { "2.14" }
            ),
            "D/r0",
            "F/(G10 h0 r0)",
            series,
        ));
    }
    let with_thesis: Vec<&SlopeRow> = rows.iter().filter(|r| r.thesis.is_some()).collect();
    let idx: Vec<f64> = (1..=with_thesis.len()).map(|k| k as f64).collect();
    let ratio = |f: &dyn Fn(&SlopeRow) -> f64| -> Vec<f64> {
        with_thesis
            .iter()
            .map(|r| f(r) / 2.0 / r.thesis.unwrap_or(f64::NAN))
            .collect()
    };
    figs.push(fig(
        "table2_1_ratio",
        "Table 2.1: our slope / 2 over the thesis value, per row (see table2_1.csv)",
        "row of table2_1.csv (thesis entries only)",
        "slope/2 ÷ thesis",
        vec![
            Series::points("tangent (first step)", idx.clone(), ratio(&|r| r.slope)),
            Series::points(
                format!("secant over ΔD/r0 = {SECANT_WINDOW}"),
                idx.clone(),
                ratio(&|r| r.secant),
            ),
            Series::thesis("thesis (ratio 1)", idx.clone(), vec![1.0; idx.len()]),
        ],
    ));
    Ok((figs, rows, notes))
}
