//! Reading the `[material]` and `[loading]` sections of a study file
//! (format: `docs/cli/material.md`). Quantities carry units and are
//! converted to SI by `nlvid_study`; every error names file, line and key.

use std::path::Path;

use nlvid_study::{Bounds, Dimension, FromSection, Section, StudyError, parse_unit};

use nlvid_model::{Prony, Relaxation, names};

use crate::homogeneous::{History, Mode, Sample, drive};
use crate::{Eq256, MaterialError, MooneyRivlin, PipkinRogers, PronyViscoelastic};

/// A material model read from `[material]`.
#[derive(Debug, Clone, PartialEq)]
pub enum MaterialSpec {
    /// `model = "mooney-rivlin"` or `"neo-hookean"` (eq. 4.1).
    Elastic(MooneyRivlin),
    /// `model = "mooney-rivlin-prony"` or `"neo-hookean-prony"` (§4.3, eq. 5.1).
    PronyViscoelastic(PronyViscoelastic),
    /// `model = "pipkin-rogers"` or `"qlv"` (eqs. 2.1–2.2, 2.53–2.56).
    PipkinRogers(PipkinRogers),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Model {
    MooneyRivlin,
    NeoHookean,
    MooneyRivlinProny,
    NeoHookeanProny,
    PipkinRogers,
    Qlv,
}

/// Maps a material-model error to a study error at `key`.
fn at(s: &Section, key: &str, e: MaterialError) -> StudyError {
    s.invalid(key, e.to_string())
}

/// Why ch. II's moduli are not called `C1`/`G0` (for renamed-key errors).
const CH2_MODULUS: &str = "ch. II's instantaneous modulus G1(0) is `G10`; `C1` names the \
                           Mooney–Rivlin constant of eq. 4.1 and `G0` the shear modulus \
                           (docs/theory/model.md)";

/// `g = [...]`, `tau = [...]` of a Prony table (weights, eq. 4.2).
fn read_prony(s: &mut Section, series: &str) -> Result<Prony, StudyError> {
    let g = s.req_f64s("g", Bounds::open(0.0, 1.0))?;
    let tau = s.req_quantities("tau", Dimension::TIME, Bounds::positive())?;
    if g.len() != tau.len() {
        return Err(s.invalid(
            "tau",
            format!(
                "{} relaxation times for {} weights `g`: give one per term",
                tau.len(),
                g.len()
            ),
        ));
    }
    let terms: Vec<(f64, f64)> = g.into_iter().zip(tau).collect();
    Prony::new(series, &terms).map_err(|e| at(s, "g", e.into()))
}

/// A ch. II relaxation table `[material.<table>]` with the instantaneous
/// value under `key` (`G10` or `G20`), `g = [...]`, `tau = [...]`.
fn read_relaxation(parent: &mut Section, table: &str, key: &str) -> Result<Relaxation, StudyError> {
    let mut s = parent.subsection(table)?;
    s.renamed(names::G0, key, CH2_MODULUS)?;
    let g0 = s.req_quantity(key, Dimension::PRESSURE, Bounds::non_negative())?;
    let prony = read_prony(&mut s, table)?;
    let r = Relaxation::new(key, g0, prony).map_err(|e| at(&s, key, e.into()))?;
    s.finish()?;
    Ok(r)
}

/// The elastic part of eq. 4.1: either the shear modulus `G0` (with `alpha`
/// for Mooney–Rivlin; `C1 = G0 / (2(1 + α))`) or `C1` (with `C2` or
/// `alpha`) — one quantity per key, never both.
fn read_elastic(s: &mut Section, neo: bool, bulk: f64) -> Result<MooneyRivlin, StudyError> {
    if s.has(names::G0) && s.has(names::C1) {
        return Err(s.invalid(
            names::G0,
            "give either the shear modulus `G0` or the Mooney–Rivlin constant `C1` of eq. 4.1 \
             (G0 = 2(C1 + C2)), not both",
        ));
    }
    if !s.has(names::G0) && !s.has(names::C1) {
        return Err(s.invalid(
            names::G0,
            "missing: give the shear modulus `G0` (Pa) or the Mooney–Rivlin constant `C1` \
             of eq. 4.1 (G0 = 2(C1 + C2))",
        ));
    }
    if neo && (s.has("alpha") || s.has(names::C2)) {
        let key = if s.has("alpha") { "alpha" } else { names::C2 };
        return Err(s.invalid(
            key,
            "a neo-Hookean material has C2 = 0; use model = \"mooney-rivlin\"",
        ));
    }
    if s.has("alpha") && s.has(names::C2) {
        return Err(s.invalid("alpha", "give either `C2` or `alpha` (= C2/C1), not both"));
    }
    if s.has(names::G0) {
        if s.has(names::C2) {
            return Err(s.invalid(
                names::C2,
                "with the shear modulus `G0` give `alpha` (= C2/C1), or give `C1` and `C2`",
            ));
        }
        let g0 = s.req_quantity(names::G0, Dimension::PRESSURE, Bounds::positive())?;
        let alpha = s.f64_or("alpha", Bounds::non_negative(), 0.0)?;
        return MooneyRivlin::from_shear_modulus(g0, alpha, bulk).map_err(|e| at(s, names::G0, e));
    }
    let c1 = s.req_quantity(names::C1, Dimension::PRESSURE, Bounds::positive())?;
    let c2 = match s.opt_f64("alpha", Bounds::non_negative())? {
        Some(alpha) => alpha * c1,
        None => s.quantity_or(names::C2, Dimension::PRESSURE, Bounds::non_negative(), 0.0)?,
    };
    MooneyRivlin::new(c1, c2, bulk).map_err(|e| at(s, names::C1, e))
}

impl FromSection for MaterialSpec {
    fn from_section(s: &mut Section) -> Result<Self, StudyError> {
        let model = s.req_enum(
            "model",
            &[
                ("mooney-rivlin", Model::MooneyRivlin),
                ("neo-hookean", Model::NeoHookean),
                ("mooney-rivlin-prony", Model::MooneyRivlinProny),
                ("neo-hookean-prony", Model::NeoHookeanProny),
                ("pipkin-rogers", Model::PipkinRogers),
                ("qlv", Model::Qlv),
            ],
        )?;
        let bulk = s.quantity_or(
            "bulk_modulus",
            Dimension::PRESSURE,
            Bounds::non_negative(),
            0.0,
        )?;
        Ok(match model {
            Model::MooneyRivlin | Model::NeoHookean => {
                MaterialSpec::Elastic(read_elastic(s, model == Model::NeoHookean, bulk)?)
            }
            Model::MooneyRivlinProny | Model::NeoHookeanProny => {
                let el = read_elastic(s, model == Model::NeoHookeanProny, bulk)?;
                let mut p = s.subsection("prony")?;
                let prony = read_prony(&mut p, "G")?;
                p.finish()?;
                MaterialSpec::PronyViscoelastic(PronyViscoelastic::new(el, prony))
            }
            Model::Qlv => {
                s.renamed(
                    "G",
                    "G1",
                    "QLV takes G1(t) with `G10`, and G2 = beta G1 (eq. 2.16)",
                )?;
                let a = s.f64_or("a", Bounds::non_negative(), 0.0)?;
                let beta = s.req_f64("beta", Bounds::non_negative())?;
                let g = read_relaxation(s, "G1", names::G10)?;
                MaterialSpec::PipkinRogers(
                    PipkinRogers::qlv(g, beta, a, bulk).map_err(|e| at(s, "G1", e))?,
                )
            }
            Model::PipkinRogers => {
                s.renamed(names::C1, names::G10, CH2_MODULUS)?;
                let a = s.f64_or("a", Bounds::non_negative(), 0.0)?;
                let m = if s.has("G1") || s.has("G2") {
                    let g1 = read_relaxation(s, "G1", names::G10)?;
                    let g2 = read_relaxation(s, "G2", "G20")?;
                    PipkinRogers::new(g1, g2, a, bulk).map_err(|e| at(s, "G1", e))?
                } else {
                    let p = Eq256 {
                        g10: s.req_quantity(names::G10, Dimension::PRESSURE, Bounds::positive())?,
                        gamma0: s.req_f64(names::GAMMA0, Bounds::non_negative())?,
                        g1_fraction: s.req_f64("g1_long_term", Bounds::open_closed(0.0, 1.0))?,
                        g2_fraction: s.req_f64("g2_long_term", Bounds::open_closed(0.0, 1.0))?,
                        tau1: s.req_quantity("tau1", Dimension::TIME, Bounds::positive())?,
                        c: s.req_f64("c", Bounds::positive())?,
                        a,
                    };
                    PipkinRogers::from_eq_2_56(&p, bulk).map_err(|e| at(s, names::G10, e))?
                };
                MaterialSpec::PipkinRogers(m)
            }
        })
    }
}

impl MaterialSpec {
    /// Runs the homogeneous driver ([`drive`]) for this material.
    ///
    /// # Errors
    /// As [`drive`].
    pub fn drive(&self, mode: Mode, history: &History, max_dt: f64) -> crate::Result<Vec<Sample>> {
        match self {
            MaterialSpec::Elastic(m) => drive(m, mode, history, max_dt),
            MaterialSpec::PronyViscoelastic(m) => drive(m, mode, history, max_dt),
            MaterialSpec::PipkinRogers(m) => drive(m, mode, history, max_dt),
        }
    }

    /// Model name and parameters in SI, `(name, value, SI unit)`, for
    /// reports. Every name is one quantity (`docs/theory/model.md`): the
    /// elastic and Prony models list the shear modulus `G0 = 2(C1 + C2)`
    /// and the constants `C1`, `C2` of eq. 4.1; Pipkin–Rogers lists ch. II's
    /// `G10 = G1(0)`, `G20 = G2(0)` and their Prony terms.
    pub fn parameters(&self) -> (&'static str, Vec<(String, f64, &'static str)>) {
        let mut out = Vec::new();
        let prony = |out: &mut Vec<(String, f64, &'static str)>, pre: &str, p: &Prony| {
            for (k, t) in p.terms().iter().enumerate() {
                out.push((format!("{pre}{}", names::weight(k + 1)), t.weight, ""));
                out.push((format!("{pre}{}", names::time(k + 1)), t.tau, "s"));
            }
        };
        let elastic = |out: &mut Vec<(String, f64, &'static str)>, m: &MooneyRivlin| {
            out.push((names::G0.into(), m.shear_modulus(), "Pa"));
            out.push((names::C1.into(), m.c1(), "Pa"));
            out.push((names::C2.into(), m.c2(), "Pa"));
        };
        match self {
            MaterialSpec::Elastic(m) => {
                elastic(&mut out, m);
                let name = if m.c2() == 0.0 {
                    "neo-hookean"
                } else {
                    "mooney-rivlin"
                };
                (name, out)
            }
            MaterialSpec::PronyViscoelastic(m) => {
                elastic(&mut out, m.elastic());
                prony(&mut out, "", m.prony());
                let name = if m.elastic().c2() == 0.0 {
                    "neo-hookean-prony"
                } else {
                    "mooney-rivlin-prony"
                };
                (name, out)
            }
            MaterialSpec::PipkinRogers(m) => {
                out.push((names::G10.into(), m.g1().g0(), "Pa"));
                prony(&mut out, "G1_", m.g1().prony());
                out.push(("G20".into(), m.g2().g0(), "Pa"));
                prony(&mut out, "G2_", m.g2().prony());
                out.push(("a".into(), m.a(), ""));
                ("pipkin-rogers", out)
            }
        }
    }
}

/// The `[loading]` section: deformation mode, history and time step.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadingSpec {
    /// Homogeneous deformation.
    pub mode: Mode,
    /// Stretch or shear history.
    pub history: History,
    /// Largest time step in s.
    pub max_dt: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Step,
    RampHold,
    RampReverse,
    Table,
}

impl FromSection for LoadingSpec {
    fn from_section(s: &mut Section) -> Result<Self, StudyError> {
        let mode = s.req_enum(
            "mode",
            &[
                ("uniaxial", Mode::Uniaxial),
                ("equibiaxial", Mode::Equibiaxial),
                ("simple-shear", Mode::SimpleShear),
            ],
        )?;
        let kind = s.req_enum(
            "history",
            &[
                ("step", Kind::Step),
                ("ramp-hold", Kind::RampHold),
                ("ramp-reverse", Kind::RampReverse),
                ("table", Kind::Table),
            ],
        )?;
        let (vkey, column) = match mode {
            Mode::SimpleShear => ("shear", "shear"),
            _ => ("stretch", "stretch"),
        };
        let value = |s: &mut Section| match mode {
            Mode::SimpleShear => s.req_f64(vkey, Bounds::ANY),
            _ => s.req_f64(vkey, Bounds::positive()),
        };
        let history = match kind {
            Kind::Step => History::Step {
                value: value(s)?,
                hold: s.req_quantity("hold", Dimension::TIME, Bounds::non_negative())?,
            },
            Kind::RampHold => History::RampHold {
                value: value(s)?,
                ramp: s.req_quantity("ramp", Dimension::TIME, Bounds::positive())?,
                hold: s.req_quantity("hold", Dimension::TIME, Bounds::non_negative())?,
            },
            Kind::RampReverse => History::RampReverse {
                value: value(s)?,
                ramp: s.req_quantity("ramp", Dimension::TIME, Bounds::positive())?,
            },
            Kind::Table => {
                let path = s.req_input_file("table")?;
                let rows = read_table(&path, column).map_err(|m| s.invalid("table", m))?;
                History::Table(rows)
            }
        };
        let knots = history.knots(mode).map_err(|e| {
            let key = match kind {
                Kind::Table => "table",
                _ => vkey,
            };
            at(s, key, e)
        })?;
        let total = knots.last().map_or(0.0, |k| k.0);
        let max_dt = match s.opt_quantity("max_dt", Dimension::TIME, Bounds::positive())? {
            Some(dt) => dt,
            None if total > 0.0 => total / 2000.0,
            None => 1.0,
        };
        crate::homogeneous::check_step_count(&knots, max_dt)
            .map_err(|e| at(s, if s.has("max_dt") { "max_dt" } else { "hold" }, e))?;
        Ok(LoadingSpec {
            mode,
            history,
            max_dt,
        })
    }
}

/// Reads a `(time, value)` CSV: a header with a time column `time_<unit>`
/// (e.g. `time_s`, `time_ms`) and a `value_column` (`stretch` or `shear`);
/// other columns are ignored.
///
/// # Errors
/// A message naming the file, the row (1-based, header = row 1) and column.
pub fn read_table(path: &Path, value_column: &str) -> Result<Vec<(f64, f64)>, String> {
    let name = path.display();
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| format!("{name}: cannot read: {e}"))?;
    let headers = r
        .headers()
        .map_err(|e| format!("{name}: row 1: {e}"))?
        .clone();
    let fields: Vec<&str> = headers.iter().collect();
    if let Some(hint) = nlvid_study::delimiter_hint(&fields) {
        return Err(format!("{name}: row 1: {hint}"));
    }
    let mut time = None;
    for (i, h) in headers.iter().enumerate() {
        if let Some(unit) = h.strip_prefix("time_") {
            let (factor, dim) = parse_unit(unit)
                .map_err(|e| format!("{name}: row 1: column `{h}`: unit `{unit}`: {e}"))?;
            if dim != Dimension::TIME {
                return Err(format!(
                    "{name}: row 1: column `{h}`: `{unit}` is not a time unit"
                ));
            }
            time = Some((i, factor));
        }
    }
    let (ti, factor) = time.ok_or_else(|| {
        format!("{name}: row 1: no time column; expected a header `time_s` (or `time_ms`, …)")
    })?;
    let vi = headers
        .iter()
        .position(|h| h == value_column)
        .ok_or_else(|| {
            format!(
                "{name}: row 1: no `{value_column}` column (found: {})",
                headers.iter().collect::<Vec<_>>().join(", ")
            )
        })?;
    let mut rows = Vec::new();
    for (n, rec) in r.records().enumerate() {
        let row = n + 2;
        let rec = rec.map_err(|e| format!("{name}: row {row}: {e}"))?;
        let cell = |i: usize, col: &str| -> Result<f64, String> {
            let text = rec.get(i).unwrap_or("");
            text.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    format!("{name}: row {row}: column `{col}`: `{text}` is not a finite number")
                })
        };
        let t = cell(ti, &headers[ti])? * factor;
        let v = cell(vi, value_column)?;
        let last = rows.last().map_or(0.0, |r: &(f64, f64)| r.0);
        if t < last {
            return Err(format!(
                "{name}: row {row}: column `{}`: time {t} s is negative or before the previous row ({last} s)",
                &headers[ti]
            ));
        }
        rows.push((t, v));
    }
    if rows.is_empty() {
        return Err(format!("{name}: no data rows"));
    }
    Ok(rows)
}
