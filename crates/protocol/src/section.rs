//! The `[protocol]` section of a study file (format in docs/theory/protocol.md).
//!
//! ```toml
//! [protocol]
//! kind = "afm"                 # afm | step | constant-rate | ramp-hold |
//!                              # ramp-reverse | load-unload | table
//! depth = "2 um"               # afm keys, all optional (thesis ch. V values)
//! output_points = 5095         # optional uniform output grid
//! ```
//!
//! `sampling = "100 Hz"` may replace `output_points` (points = round(T·f) + 1).
//!
//! Non-AFM kinds take `control = "displacement" | "force" | "dimensionless"`
//! (default displacement): values are lengths, forces, or bare numbers
//! (D/r0), and rates their time derivatives; with `dimensionless`, times are
//! bare numbers too (t0 = t/τ1, eq. 2.47).

use nlvid_study::{Bounds, Dimension, FromSection, Section, StudyError};

use crate::{AfmScript, Engage, Program, Quantity, programs, read_table};

/// What the `[protocol]` section describes.
#[derive(Debug, Clone, PartialEq)]
pub enum Loading {
    /// The AFM two-step script.
    Afm(AfmScript),
    /// Any other loading program (including a CSV table).
    Program(Program),
}

/// Settings read from `[protocol]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ProtocolSettings {
    /// The loading.
    pub loading: Loading,
    /// Number of points of the uniform output grid, if given.
    pub output_points: Option<usize>,
}

impl ProtocolSettings {
    /// The driving program: piezo Z(t) of step 2 for the AFM script,
    /// otherwise the program itself.
    ///
    /// # Errors
    /// Invalid AFM parameters (already checked on reading).
    pub fn program(&self) -> crate::Result<Program> {
        match &self.loading {
            Loading::Afm(s) => s.piezo(),
            Loading::Program(p) => Ok(p.clone()),
        }
    }

    /// The uniform output grid over the driving program, if
    /// `output_points` was given.
    ///
    /// # Errors
    /// As [`ProtocolSettings::program`].
    pub fn output_grid(&self) -> crate::Result<Option<Vec<f64>>> {
        match self.output_points {
            None => Ok(None),
            Some(m) => self.program()?.uniform_grid(m).map(Some),
        }
    }
}

/// A required quantity that may be spelled several ways (`rate` or
/// `speed`); two spellings at once are an error at the second one.
fn req_alias(
    s: &mut Section,
    keys: &[&str],
    dim: Dimension,
    bounds: Bounds,
) -> Result<f64, StudyError> {
    let present: Vec<&str> = keys.iter().copied().filter(|k| s.has(k)).collect();
    match present.as_slice() {
        [] | [_] => s.req_quantity(present.first().copied().unwrap_or(keys[0]), dim, bounds),
        [first, second, ..] => Err(s.invalid(
            second,
            format!("`{second}` and `{first}` mean the same; give one"),
        )),
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Afm,
    Step,
    ConstantRate,
    RampHold,
    RampReverse,
    LoadUnload,
    Table,
}

fn read_afm(s: &mut Section) -> Result<AfmScript, StudyError> {
    let pos = Bounds::positive();
    let engage = Engage {
        setpoint_force: s.quantity_or("engage_force", Dimension::FORCE, pos, 0.48e-9)?,
        ramp_time: s.quantity_or("engage_time", Dimension::TIME, pos, 4.0)?,
        hold: s.quantity_or("engage_hold", Dimension::TIME, Bounds::non_negative(), 0.0)?,
    };
    let cycle_rates = s
        .opt_quantities("cycle_rates", Dimension::VELOCITY, pos)?
        .unwrap_or_else(|| vec![10e-6, 5e-6, 1e-6]);
    let depth = s.quantity_or("depth", Dimension::LENGTH, pos, 2e-6)?;
    let retract = s.quantity_or("retract", Dimension::LENGTH, pos, 1e-6)?;
    let final_rate = s.quantity_or("final_rate", Dimension::VELOCITY, pos, 10e-6)?;
    let final_depth = s.quantity_or("final_depth", Dimension::LENGTH, pos, depth)?;
    let hold = s.quantity_or("hold", Dimension::TIME, pos, 50.0)?;
    let script = AfmScript {
        engage,
        cycle_rates,
        depth,
        retract,
        final_rate,
        final_depth,
        hold,
    };
    if retract > depth {
        return Err(s.invalid("retract", "must not exceed `depth`"));
    }
    script
        .check()
        .map_err(|e| s.invalid("kind", e.to_string()))?;
    Ok(script)
}

/// Output points for a sampling frequency f over the program: one every
/// 1/f from the start, plus the end (round(duration · f) + 1 points).
fn points(s: &Section, sampling: Option<f64>, p: &Program) -> Result<Option<usize>, StudyError> {
    let Some(f) = sampling else { return Ok(None) };
    let n = (p.duration() * f).round();
    if !(1.0..1e8).contains(&n) {
        return Err(s.invalid(
            "sampling",
            format!(
                "gives {n} intervals over {} s; expected 1 to 1e8",
                p.duration()
            ),
        ));
    }
    Ok(Some(n as usize + 1))
}

impl FromSection for ProtocolSettings {
    fn from_section(s: &mut Section) -> Result<Self, StudyError> {
        let kind = s.req_enum(
            "kind",
            &[
                ("afm", Kind::Afm),
                ("step", Kind::Step),
                ("constant-rate", Kind::ConstantRate),
                ("ramp-hold", Kind::RampHold),
                ("ramp-reverse", Kind::RampReverse),
                ("load-unload", Kind::LoadUnload),
                ("table", Kind::Table),
            ],
        )?;
        let output_points = s.opt_usize("output_points", Bounds::at_least(2.0))?;
        let sampling = s.opt_quantity("sampling", Dimension::FREQUENCY, Bounds::positive())?;
        if sampling.is_some() && output_points.is_some() {
            return Err(s.invalid("sampling", "give `sampling` or `output_points`, not both"));
        }
        let q = if kind == Kind::Afm {
            Quantity::Displacement
        } else {
            s.opt_enum(
                "control",
                &[
                    ("displacement", Quantity::Displacement),
                    ("force", Quantity::Force),
                    ("dimensionless", Quantity::Dimensionless),
                ],
            )?
            .unwrap_or(Quantity::Displacement)
        };
        let (v, r, t) = match q {
            Quantity::Displacement => (Dimension::LENGTH, Dimension::VELOCITY, Dimension::TIME),
            Quantity::Force => (Dimension::FORCE, Dimension::FORCE_RATE, Dimension::TIME),
            Quantity::Dimensionless => (Dimension::NONE, Dimension::NONE, Dimension::NONE),
        };
        let pos = Bounds::positive();
        let any = Bounds::ANY;
        // The value key may also be spelled `displacement` under displacement
        // control, and `rate` may be spelled `speed` (as in the bundled
        // example study).
        let value_keys = |k: &'static str| -> Vec<&'static str> {
            if q == Quantity::Displacement {
                vec![k, "displacement"]
            } else {
                vec![k]
            }
        };
        let rate_keys = ["rate", "speed"];
        let built = match kind {
            Kind::Step => {
                let a = req_alias(s, &value_keys("amplitude"), v, any)?;
                let h = s.req_quantity("hold", t, pos)?;
                programs::step(q, a, h)
            }
            Kind::ConstantRate => {
                let rate = req_alias(s, &rate_keys, r, any)?;
                let d = s.req_quantity("duration", t, pos)?;
                programs::constant_rate(q, rate, d)
            }
            Kind::RampHold => {
                let target = req_alias(s, &value_keys("target"), v, any)?;
                let rate = req_alias(s, &rate_keys, r, pos)?;
                let h = s.req_quantity("hold", t, pos)?;
                programs::ramp_hold(q, target, rate, h)
            }
            Kind::RampReverse => {
                let peak = req_alias(s, &value_keys("peak"), v, any)?;
                let rate = req_alias(s, &rate_keys, r, pos)?;
                let end = s.quantity_or("end", v, any, 0.0)?;
                programs::ramp_reverse(q, peak, rate, end)
            }
            Kind::LoadUnload => {
                let peak = req_alias(s, &value_keys("peak"), v, any)?;
                let lr = s.req_quantity("load_rate", r, pos)?;
                let ur = s.req_quantity("unload_rate", r, pos)?;
                let end = s.quantity_or("end", v, any, 0.0)?;
                programs::load_unload(q, peak, lr, ur, end)
            }
            Kind::Table => {
                let file = s.req_input_file("file")?;
                let column = s.opt_str("column")?;
                let table = read_table(&file, q, column.as_deref())
                    .map_err(|e| s.invalid("file", e.to_string()))?;
                Ok(table)
            }
            Kind::Afm => {
                let script = read_afm(s)?;
                let program = script
                    .piezo()
                    .map_err(|e| s.invalid("kind", e.to_string()))?;
                return Ok(Self {
                    output_points: points(s, sampling, &program)?.or(output_points),
                    loading: Loading::Afm(script),
                });
            }
        };
        let program = built.map_err(|e| s.invalid("kind", e.to_string()))?;
        Ok(Self {
            output_points: points(s, sampling, &program)?.or(output_points),
            loading: Loading::Program(program),
        })
    }
}
