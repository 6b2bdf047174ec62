//! A capsule between rigid plates driven by a plate-displacement program
//! (thesis §4.2–4.3): the RH (ramp, hold) and RR (ramp, reverse) tests, or
//! the measured history of the top plate (its overshoot matters, §4.3),
//! with the capsule's outputs ([`crate::capsule`]) at every converged step
//! and on given output times.
//!
//! The program is d(t), the plates' approach of the whole capsule (m,
//! compression positive; [`nlvid_protocol::Quantity::Displacement`]); the
//! modelled plate sits at `z_top − share · d(t)` ([`Symmetry::plate_share`]),
//! z_top the top of the measured surface. The run is split into stages at
//! the program's kinks (breakpoints where the rate changes by more than
//! [`PlateProgram::kink`] × the largest rate, so a measured table's noise
//! does not cut the run into its rows), each stepped with at most
//! 1/[`PlateProgram::min_steps`] of its duration, starting at
//! [`PlateProgram::first_step`] of it (relaxation right after a kink).
//!
//! **Output times** (e.g. the thesis's 1200): by default the converged
//! steps are interpolated linearly (the steps bracket every output time;
//! forcing a step onto each of 1200 times would multiply the cost); with
//! [`PlateProgram::exact_outputs`] the stages also end at every output
//! time, so the samples are converged states.
//!
//! **Bad input**: a program that is not a displacement, has a jump (a
//! displacement-controlled plate cannot jump), starts pressed (d(t₀) > 0),
//! or brings the plates closer than the two walls at the poles (it would
//! crush the capsule past its wall thickness), and output times that are
//! not increasing or outside the program are [`FemError::Program`] errors
//! naming the value, before anything runs. A plate that loses the capsule
//! (a retracting plate faster than the wall recovers, or d ≤ 0) is a
//! flagged output: [`PlateSample::in_contact`] false and a note in
//! [`PlateRun::notes`]. An element that inverts during the run is a typed
//! [`FemError::NonConvergence`] naming the element.

use crate::capsule::{CapsuleRecord, Footprint, PatchSpec};
use crate::kind::{ElementKind, Topology};
use crate::{Control, Counters, FemError, Model, Result, Stage};
use nlvid_material::Material3;
use nlvid_protocol::{Program, Quantity};
use std::fmt::Write as _;
use std::path::Path;

/// A plate program and how to run and sample it (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PlateProgram {
    /// The plates' approach d(t) (m, compression positive).
    pub program: Program,
    /// Output times (s), increasing, within the program.
    pub output_times: Vec<f64>,
    /// The measured plate and surface, with the model's symmetry.
    pub patch: PatchSpec,
    /// The wall's inner surface (node set), for the crushing check.
    pub inner: String,
    /// Steps per stage, at least (default 20).
    pub min_steps: usize,
    /// First step of each stage as a fraction of it (default 1/200).
    pub first_step: f64,
    /// Rate change that starts a new stage, as a fraction of the program's
    /// largest rate (default 0.05).
    pub kink: f64,
    /// End stages at every output time as well (default false:
    /// interpolate).
    pub exact_outputs: bool,
}

impl PlateProgram {
    /// A program with the default stepping (module docs).
    pub fn new(program: Program, output_times: Vec<f64>, patch: PatchSpec, inner: &str) -> Self {
        Self {
            program,
            output_times,
            patch,
            inner: inner.to_owned(),
            min_steps: 20,
            first_step: 1.0 / 200.0,
            kink: 0.05,
            exact_outputs: false,
        }
    }
}

/// The capsule at one output time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlateSample {
    /// Time (s).
    pub time: f64,
    /// Plates' approach d (m).
    pub plate_displacement: f64,
    /// Plate force, whole capsule (N).
    pub force: f64,
    /// Fluid pressure (Pa).
    pub pressure: f64,
    /// Fluid volume, whole capsule (m³).
    pub volume: f64,
    /// Area carrying positive contact pressure (m²).
    pub pressure_area: f64,
    /// Area of the ellipse through the contact edge (m²).
    pub ellipse_area: f64,
    /// Its semi-axes along the long and short axis (m).
    pub semi_axes: [f64; 2],
    /// Area flagged as lost contact inside the patch (m²).
    pub lost_area: f64,
    /// Contact is lost inside the patch (Fig. 4.16) at the nearest step.
    pub lost_contact: bool,
    /// The plate touches the capsule.
    pub in_contact: bool,
}

/// The result of [`run_plate_program`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlateRun {
    /// Every converged step (the first is the state at the program's start),
    /// with the plates' approach d.
    pub steps: Vec<(f64, CapsuleRecord)>,
    /// The capsule at the output times.
    pub samples: Vec<PlateSample>,
    /// Flagged events (loss of the capsule, loss of contact), in time order.
    pub notes: Vec<String>,
    /// Run counters.
    pub counters: Counters,
}

fn sample_of(d: f64, r: &CapsuleRecord) -> PlateSample {
    PlateSample {
        time: r.time,
        plate_displacement: d,
        force: r.force,
        pressure: r.pressure,
        volume: r.volume,
        pressure_area: r.patch.pressure_area,
        ellipse_area: r.patch.ellipse_area,
        semi_axes: r.patch.semi_axes,
        lost_area: r.patch.lost_area,
        lost_contact: r.patch.lost_contact(),
        in_contact: r.force > 0.0,
    }
}

impl PlateRun {
    /// Largest force over the steps (N).
    pub fn peak_force(&self) -> f64 {
        self.steps.iter().map(|s| s.1.force).fold(0.0, f64::max)
    }

    /// The samples as CSV (one header row, SI units, `lost_contact` and
    /// `in_contact` as 0/1).
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "time_s,plate_displacement_m,force_N,pressure_Pa,volume_m3,pressure_area_m2,\
             ellipse_area_m2,semi_axis_a_m,semi_axis_b_m,lost_area_m2,lost_contact,in_contact\n",
        );
        for p in &self.samples {
            let _ = writeln!(
                s,
                "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{}",
                p.time,
                p.plate_displacement,
                p.force,
                p.pressure,
                p.volume,
                p.pressure_area,
                p.ellipse_area,
                p.semi_axes[0],
                p.semi_axes[1],
                p.lost_area,
                u8::from(p.lost_contact),
                u8::from(p.in_contact)
            );
        }
        s
    }

    /// Writes [`PlateRun::to_csv`] to `path`.
    ///
    /// # Errors
    /// [`FemError::Io`] naming the file.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        nlvid_study::write_atomic(path, self.to_csv().as_bytes()).map_err(|source| FemError::Io {
            file: path.to_path_buf(),
            source,
        })
    }
}

fn program_error(message: String) -> FemError {
    FemError::Program(message)
}

/// Checks that `model` is fresh, then the program against its mesh
/// ([`PlateProgram::check`]); returns z_top and the stage ends.
fn check<M: Material3, K: ElementKind<M>>(
    model: &Model<M, K>,
    p: &PlateProgram,
) -> Result<(f64, Vec<f64>)> {
    if !model.records().is_empty() || (model.time() != 0.0 && model.time() != p.program.start()) {
        return Err(program_error(
            "run the plate program on a freshly built model".into(),
        ));
    }
    p.check(model.mesh())
}

impl PlateProgram {
    /// Checks the program, the stepping and the output times against the
    /// capsule mesh `mesh` before anything runs (module docs: not a
    /// displacement, a jump, starting pressed, output times not increasing
    /// or outside the program, plates closer than the two walls at the
    /// poles); returns the top of the measured surface z_top and the stage
    /// ends. [`run_plate_program`] calls it; a forward model calls it once
    /// when it is built, so that bad input is refused before a design runs.
    ///
    /// # Errors
    /// [`FemError::Program`] naming the value; a missing node set.
    pub fn check<T: Topology>(&self, mesh: &T) -> Result<(f64, Vec<f64>)> {
        check_program(mesh, self)
    }
}

fn check_program<T: Topology>(mesh: &T, p: &PlateProgram) -> Result<(f64, Vec<f64>)> {
    let prog = &p.program;
    if prog.quantity() != Quantity::Displacement {
        return Err(program_error(format!(
            "the plate program must be a displacement (m), not {:?}",
            prog.quantity()
        )));
    }
    if let Some(&t) = prog.jumps().first() {
        return Err(program_error(format!(
            "the plate jumps at t = {t} s; a displacement-controlled plate needs a finite rate"
        )));
    }
    let (t0, t1) = (prog.start(), prog.end());
    let d0 = prog.value(t0);
    if d0 > 0.0 {
        return Err(program_error(format!(
            "the plate starts pressed (d = {:.6} mm at t = {t0} s); start the table at d ≤ 0",
            d0 * 1e3
        )));
    }
    if p.min_steps == 0 || !(p.first_step > 0.0 && p.first_step <= 1.0) || !(p.kink >= 0.0) {
        return Err(program_error(format!(
            "stepping: min_steps = {} must be ≥ 1, first_step = {} in (0, 1], kink = {} ≥ 0",
            p.min_steps, p.first_step, p.kink
        )));
    }
    for (k, w) in p.output_times.windows(2).enumerate() {
        if !(w[1] > w[0]) {
            return Err(program_error(format!(
                "output times must increase: entry {} ({} s) follows {} s",
                k + 1,
                w[1],
                w[0]
            )));
        }
    }
    let tol = 1e-9 * (t1 - t0).abs().max(1.0);
    if let Some(&t) = p
        .output_times
        .iter()
        .find(|&&t| !t.is_finite() || t < t0 - tol || t > t1 + tol)
    {
        return Err(program_error(format!(
            "output time {t} s lies outside the program [{t0}, {t1}] s"
        )));
    }
    // Crushing: the plates' gap at the largest approach against the two
    // walls at the poles.
    let z = |set: &str| -> Result<(f64, f64)> {
        let nodes = mesh.node_set(set)?;
        Ok(nodes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &a| {
                let p = mesh.position(a);
                let z = p[p.len() - 1];
                (lo.min(z), hi.max(z))
            }))
    };
    let (outer_lo, outer_hi) = z(&p.patch.surface)?;
    let (inner_lo, inner_hi) = z(&p.inner)?;
    let (height, walls) = if p.patch.symmetry.plate_share < 1.0 {
        (2.0 * outer_hi, 2.0 * (outer_hi - inner_hi))
    } else {
        (
            outer_hi - outer_lo,
            (outer_hi - inner_hi) + (inner_lo - outer_lo),
        )
    };
    let (_, d_max) = prog.value_range();
    if height - d_max <= walls {
        return Err(program_error(format!(
            "d = {:.4} mm brings the plates to {:.4} mm apart, not more than the two walls at \
             the poles ({:.4} mm): it would crush the capsule (height {:.4} mm) past its wall \
             thickness",
            d_max * 1e3,
            (height - d_max) * 1e3,
            walls * 1e3,
            height * 1e3
        )));
    }
    let exact: &[f64] = if p.exact_outputs {
        &p.output_times
    } else {
        &[]
    };
    Ok((outer_hi, stage_ends(prog, p.kink, exact)))
}

/// Stage ends: the breakpoints where the rate changes by more than `kink`
/// × the largest rate, the times `extra`, and the end.
fn stage_ends(prog: &Program, kink: f64, extra: &[f64]) -> Vec<f64> {
    let (t0, t1) = (prog.start(), prog.end());
    let tol = 1e-9 * (t1 - t0).abs().max(1.0);
    let rate_max = prog
        .segments()
        .iter()
        .map(|s| s.rate().abs())
        .fold(0.0, f64::max);
    let mut ends: Vec<f64> = prog
        .breakpoints()
        .iter()
        .copied()
        .filter(|&b| b > t0 && b < t1)
        .filter(|&b| (prog.rate(b) - prog.rate_left(b)).abs() > kink * rate_max)
        .collect();
    ends.extend(extra.iter().copied().filter(|&t| t > t0 && t < t1));
    ends.push(t1);
    ends.sort_by(f64::total_cmp);
    ends.dedup_by(|a, b| (*a - *b).abs() <= tol);
    ends
}

/// Runs the plate program `p` on a freshly built capsule model (module
/// docs).
///
/// # Errors
/// [`FemError::Program`] for a program, output times or stepping that
/// cannot be run (before anything runs); [`FemError::NonConvergence`] and
/// the other run errors of [`Model::run_stage`]; the errors of
/// [`Model::capsule_record`].
pub fn run_plate_program<M: Material3, K: ElementKind<M>>(
    model: &mut Model<M, K>,
    p: &PlateProgram,
) -> Result<PlateRun>
where
    K::Mesh: Footprint,
{
    let (z_top, ends) = check(model, p)?;
    let prog = &p.program;
    let t0 = prog.start();
    model.set_time(t0);
    let share = p.patch.symmetry.plate_share;
    // The state at the start (no step yet: zero loads, fluid at V₀).
    let mut first = model.capsule_record(&p.patch)?;
    let v0 = model.cavity_reference_volume();
    first.pressure = v0.map_or(f64::NAN, |_| 0.0);
    first.volume = v0.map_or(f64::NAN, |v| p.patch.symmetry.volume_copies * v);
    first.plate_z = z_top - share * prog.value(t0);
    let mut steps = vec![(prog.value(t0), first)];
    let control = |t: f64| Control {
        plane_z: z_top - share * prog.value(t),
        ..Control::default()
    };
    for &end in &ends {
        let duration = end - model.time();
        if duration <= 0.0 {
            continue;
        }
        let dt_max = duration / p.min_steps as f64;
        let stage = Stage {
            name: "plate",
            end,
            dt_initial: (p.first_step * duration).min(dt_max),
            dt_max,
            control: &control,
        };
        model.run_stage_observed(&stage, &mut |m| {
            let r = m.capsule_record(&p.patch)?;
            steps.push((prog.value(r.time), r));
            Ok(())
        })?;
    }
    let samples = sample(&steps, &p.output_times);
    let notes = notes(&steps);
    Ok(PlateRun {
        steps,
        samples,
        notes,
        counters: model.counters(),
    })
}

/// Linear interpolation of the steps at `times` (flags from the nearer
/// step).
fn sample(steps: &[(f64, CapsuleRecord)], times: &[f64]) -> Vec<PlateSample> {
    let mut out = Vec::with_capacity(times.len());
    let mut k = 0;
    for &t in times {
        while k + 2 < steps.len() && steps[k + 1].1.time < t {
            k += 1;
        }
        let (a, b) = (&steps[k], &steps[(k + 1).min(steps.len() - 1)]);
        let span = b.1.time - a.1.time;
        let w = if span > 0.0 {
            ((t - a.1.time) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (sa, sb) = (sample_of(a.0, &a.1), sample_of(b.0, &b.1));
        let mix = |x: f64, y: f64| {
            if w == 0.0 {
                x
            } else if w == 1.0 {
                y
            } else {
                x + w * (y - x)
            }
        };
        let near = if w < 0.5 { sa } else { sb };
        let force = mix(sa.force, sb.force);
        out.push(PlateSample {
            time: t,
            plate_displacement: mix(sa.plate_displacement, sb.plate_displacement),
            force,
            pressure: mix(sa.pressure, sb.pressure),
            volume: mix(sa.volume, sb.volume),
            pressure_area: mix(sa.pressure_area, sb.pressure_area),
            ellipse_area: mix(sa.ellipse_area, sb.ellipse_area),
            semi_axes: [
                mix(sa.semi_axes[0], sb.semi_axes[0]),
                mix(sa.semi_axes[1], sb.semi_axes[1]),
            ],
            lost_area: mix(sa.lost_area, sb.lost_area),
            lost_contact: near.lost_contact,
            in_contact: force > 0.0,
        });
    }
    out
}

/// Notes on the intervals where the plate lost the capsule after touching
/// it, or contact was lost inside the patch.
fn notes(steps: &[(f64, CapsuleRecord)]) -> Vec<String> {
    let mut notes = Vec::new();
    let mut touched = false;
    let mut free_since: Option<(f64, f64)> = None;
    let mut lost_since: Option<f64> = None;
    for (d, r) in steps {
        let contact = r.force > 0.0;
        if contact {
            if let Some((t, dd)) = free_since.take() {
                notes.push(format!(
                    "the plate lost the capsule from t = {t:.4} s (d = {:.4} mm) to t = {:.4} s",
                    dd * 1e3,
                    r.time
                ));
            }
            touched = true;
        } else if touched && free_since.is_none() {
            free_since = Some((r.time, *d));
        }
        match (r.patch.lost_contact(), lost_since) {
            (true, None) => lost_since = Some(r.time),
            (false, Some(t)) => {
                notes.push(format!(
                    "contact lost inside the patch from t = {t:.4} s to t = {:.4} s",
                    r.time
                ));
                lost_since = None;
            }
            _ => {}
        }
    }
    let end = steps.last().map_or(0.0, |s| s.1.time);
    if let Some((t, dd)) = free_since {
        notes.push(format!(
            "the plate lost the capsule from t = {t:.4} s (d = {:.4} mm) to the end ({end:.4} s)",
            dd * 1e3
        ));
    }
    if !touched && steps.len() > 1 {
        notes.push("the plate never touched the capsule".into());
    }
    if let Some(t) = lost_since {
        notes.push(format!(
            "contact lost inside the patch from t = {t:.4} s to the end ({end:.4} s)"
        ));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_protocol::{Label, ProgramBuilder};

    #[test]
    fn stages_end_at_kinks_not_at_every_table_row() {
        // Ramp to 1.1 mm, back to 1 mm, then a noisy hold (rows every 10 ms,
        // ±0.1 µm): stages end at the two kinks, the start of the hold and
        // the end — not at the 100 noise rows.
        let mut b = ProgramBuilder::new(Quantity::Displacement, 0.0)
            .line_to(0.22, 1.1e-3, Label::Tabulated)
            .unwrap()
            .line_to(0.26, 1e-3, Label::Tabulated)
            .unwrap();
        for k in 1..=100 {
            let noise = if k % 2 == 0 { 1e-7 } else { -1e-7 };
            b = b
                .line_to(0.26 + 0.01 * k as f64, 1e-3 + noise, Label::Tabulated)
                .unwrap();
        }
        let prog = b.build().unwrap();
        assert_eq!(stage_ends(&prog, 0.05, &[]), vec![0.22, 0.26, 1.26]);
        // With kink = 0 every row is a stage; output times are added.
        assert_eq!(stage_ends(&prog, 0.0, &[]).len(), 102);
        assert_eq!(
            stage_ends(&prog, 0.05, &[0.1, 0.22]),
            vec![0.1, 0.22, 0.26, 1.26]
        );
    }
}
