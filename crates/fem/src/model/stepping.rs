//! Adaptive time stepping over the stages of a loading program, the step
//! records the written curves are interpolated from (dense output,
//! [`crate::dense`]) and the run's counters.

use super::*;

/// One loading stage: the control as a function of time up to `end`.
pub struct Stage<'a> {
    /// Name for reports.
    pub name: &'a str,
    /// End time (s).
    pub end: f64,
    /// First step size (s).
    pub dt_initial: f64,
    /// Largest step size (s).
    pub dt_max: f64,
    /// Loads at time t.
    pub control: &'a dyn Fn(f64) -> Control,
}

/// State after a converged step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    /// Time (s).
    pub time: f64,
    /// Probe displacement w (m, z up).
    pub probe_w: f64,
    /// Spring free-end displacement (m); NaN without a spring.
    pub free_end: f64,
    /// Upward force of the body on the probe from contact (N).
    pub contact_force: f64,
    /// Upward force of the body on the plane(s) above it (N).
    pub plane_force: f64,
    /// Downward force of the body on the plane(s) below it (N).
    pub base_force: f64,
    /// Deepest penetration into the probe (m, ≥ 0).
    pub penetration: f64,
    /// Cavity pressure p (Pa); NaN without a cavity.
    pub cavity_pressure: f64,
    /// Cavity volume V (m³); NaN without a cavity.
    pub cavity_volume: f64,
    /// Newton iterations of the step.
    pub iterations: usize,
    /// Stage of the step (1, 2, … in the order run; 0: the initial state).
    /// Dense output does not interpolate across stages.
    pub stage: usize,
}

/// Counters of a run. Times are CPU time of the calling thread
/// (`CLOCK_THREAD_CPUTIME_ID`), so they do not grow when other processes
/// load the machine.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Counters {
    /// Assembly in total (element loop + contact + loads), s.
    pub assembly_seconds: f64,
    /// Part of `assembly_seconds` in the element loop (kinematics, material
    /// updates, scatter into the sparse matrix), s.
    pub element_seconds: f64,
    /// Numeric factorisations and solves, s.
    pub solve_seconds: f64,
    /// Converged steps.
    pub steps: usize,
    /// Failed attempts that were cut back.
    pub cutbacks: usize,
    /// Converged steps rejected for their dense-output error and redone
    /// smaller.
    pub rejected_steps: usize,
    /// Newton iterations (linear solves) in total.
    pub iterations: usize,
    /// Global assemblies in total (including line-search trials).
    pub assemblies: usize,
    /// Part of `assemblies` without the tangent (residual only).
    pub residual_only_assemblies: usize,
    /// Numeric factorisations of the tangent (Newton iterations less the
    /// chord steps).
    pub factorisations: usize,
    /// Numeric factorisations that fell back from LDLᵀ to LU.
    pub lu_fallbacks: usize,
}

/// Output times must be finite and strictly increasing.
///
/// # Errors
/// [`FemError::Setting`] naming the first offending time.
pub(crate) fn check_output_times(times: &[f64]) -> Result<()> {
    match (0..times.len()).find(|&i| !times[i].is_finite() || (i > 0 && !(times[i] > times[i - 1])))
    {
        Some(i) => Err(FemError::Setting {
            name: "output times",
            value: times[i],
            reason: "must be finite and strictly increasing",
        }),
        None => Ok(()),
    }
}

impl<M: Material3, K: ElementKind<M>> Model<M, K> {
    pub(super) fn push_record(
        &mut self,
        time: f64,
        ctl: &Control,
        asm: &Assembly,
        iterations: usize,
    ) {
        let free_end = match ctl.probe {
            ProbeDrive::Spring { free_end, .. } => free_end,
            _ => f64::NAN,
        };
        let has_cavity = self.cavity.is_some();
        self.records.push(StepRecord {
            time,
            probe_w: self.u[K::DIM * self.mesh.node_count()],
            free_end,
            contact_force: asm.contact_force,
            plane_force: asm.plane_force,
            base_force: asm.base_force,
            penetration: asm.penetration,
            cavity_pressure: if has_cavity { asm.pressure } else { f64::NAN },
            cavity_volume: if has_cavity { asm.volume } else { f64::NAN },
            iterations,
            stage: self.stage,
        });
    }

    /// Dense-output error of a candidate step to `t_new` with force
    /// `force` (probe or plane), relative to `output_tolerance` × the
    /// force scale, and the step that would meet the tolerance (from the
    /// third-order error law, ×0.9, between ×0.2 and ×2); (0, ∞) when the
    /// stage has fewer than three earlier points or control is off.
    pub(super) fn output_error(&self, t_new: f64, force: f64, dt: f64) -> (f64, f64) {
        let tol = self.settings.output_tolerance;
        let n = self.records.len();
        if !(tol > 0.0) || n < 3 {
            return (0.0, f64::INFINITY);
        }
        // The stage's records and its start point.
        let in_stage = self.records[n - 3..]
            .iter()
            .skip(1)
            .all(|r| r.stage == self.stage);
        if !in_stage {
            return (0.0, f64::INFINITY);
        }
        let value = |r: &StepRecord| {
            if self.probe.is_some() {
                r.contact_force
            } else {
                r.plane_force
            }
        };
        let p = &self.records[n - 3..];
        let ts = [p[0].time, p[1].time, p[2].time, t_new];
        let ys = [value(&p[0]), value(&p[1]), value(&p[2]), force];
        let scale = ys[2].abs().max(force.abs()) + self.output_floor;
        let ratio = crate::dense::interpolation_error(ts, ys) / (tol * scale);
        let factor = if ratio > 0.0 {
            (0.9 * ratio.powf(-1.0 / 3.0)).clamp(0.2, 2.0)
        } else {
            2.0
        };
        (ratio, dt * factor)
    }

    /// The times at which the records will be read (the written curve's
    /// samples). The dense-output control then only governs steps that
    /// have a sample strictly inside: a step that would end short of the
    /// next sample is lengthened to land on it (never beyond the step
    /// Newton's growth allows), and a converged step without a sample
    /// inside is kept whatever its interpolation error, since no value is
    /// interpolated on it. A step that lands on a sample writes that sample
    /// exactly, as a run with a breakpoint at every sample would.
    ///
    /// # Errors
    /// [`FemError::Setting`] if the times are not finite and increasing.
    pub fn set_output_times(&mut self, times: &[f64]) -> Result<()> {
        check_output_times(times)?;
        self.output_times = times.to_vec();
        Ok(())
    }

    /// The first output time after `t` (beyond `eps`), if any.
    fn next_sample(&self, t: f64, eps: f64) -> Option<f64> {
        let k = self.output_times.partition_point(|&s| s <= t + eps);
        self.output_times.get(k).copied()
    }

    /// Whether a step from `t0` to `t1` has an output time strictly inside,
    /// i.e. a written value interpolated on it (always, when the model has
    /// no output times).
    fn interpolates_a_sample(&self, t0: f64, t1: f64, eps: f64) -> bool {
        self.output_times.is_empty() || self.next_sample(t0, eps).is_some_and(|s| s < t1 - eps)
    }

    /// Advances through `stage` with adaptive steps: a failed attempt is
    /// cut back by `Settings::cutback`, easy steps grow by
    /// `Settings::growth` up to `stage.dt_max`.
    ///
    /// # Errors
    /// [`FemError::NonConvergence`] when the step falls below
    /// `min_step_fraction × stage duration` without converging; the model
    /// keeps the last converged state.
    pub fn run_stage(&mut self, stage: &Stage<'_>) -> Result<()> {
        self.run_stage_observed(stage, &mut |_| Ok(()))
    }

    /// [`Model::run_stage`], calling `observe` after every converged step
    /// (e.g. to record outputs that need the full state).
    ///
    /// # Errors
    /// As [`Model::run_stage`]; an error of `observe` ends the stage.
    pub fn run_stage_observed(
        &mut self,
        stage: &Stage<'_>,
        observe: &mut dyn FnMut(&Self) -> Result<()>,
    ) -> Result<()> {
        let duration = stage.end - self.time;
        if !(duration >= 0.0) || !(stage.dt_max > 0.0) || !(stage.dt_initial > 0.0) {
            return Err(FemError::Setting {
                name: "stage",
                value: duration,
                reason: "stage must end after the current time with positive steps",
            });
        }
        if duration == 0.0 {
            return Ok(());
        }
        let dt_min = self.settings.min_step_fraction * duration;
        // Times closer than this are one time (a step landing on a sample).
        let eps = 1e-12 * (duration + stage.end.abs());
        let mut dt = stage.dt_initial.min(stage.dt_max);
        let mut first = true;
        // Length of the last step rejected by the output control, while its
        // state (`u_rejected`) is the end of the interval being retried.
        let mut rejected: Option<f64> = None;
        // The last attempt of the current step that met an inadmissible
        // deformation (reported if the step finally fails for another cause).
        let mut inadmissible: Option<String> = None;
        if self.records.is_empty() {
            // The initial state, the start point of the first stage.
            let ctl = (stage.control)(self.time);
            self.u.copy_from_slice(&self.u_committed);
            let asm = self.assemble(&ctl, 0.0, false)?;
            self.push_record(self.time, &ctl, &asm, 0);
        }
        self.stage += 1;
        while self.time < stage.end - 1e-12 * duration {
            let remaining = stage.end - self.time;
            if dt > remaining || remaining - dt < 0.01 * dt {
                dt = remaining;
            }
            let mut t_new = self.time + dt;
            if let Some(sample) = self.next_sample(self.time, eps)
                && (sample - t_new).abs() <= eps
            {
                t_new = sample;
            }
            let ctl = (stage.control)(t_new);
            // Predictor.
            if self.settings.tangent_predictor
                && self.factors_current
                && self.tangent_predictor(&ctl)
            {
                // u set from the converged state and the load increment.
            } else if let Some(dt_rejected) = rejected.filter(|&h| dt < h) {
                self.rejected_step_predictor(dt, dt_rejected);
            } else if self.settings.extrapolate && !first && self.last_dt > 0.0 {
                let s = dt / self.last_dt;
                for d in 0..self.u.len() {
                    self.u[d] =
                        self.u_committed[d] + s * (self.u_committed[d] - self.u_previous[d]);
                }
            } else {
                self.u.copy_from_slice(&self.u_committed);
            }
            match self.newton(&ctl, dt) {
                Ok((iterations, asm)) => {
                    if trace() {
                        eprintln!(
                            "step t={t_new:.5} dt={dt:.3e} its={iterations} F={:.4e}",
                            asm.contact_force
                        );
                    }
                    // Dense-output error of the new interval (module
                    // `dense`): reject and retry smaller if it is too large.
                    let force = if self.probe.is_some() {
                        asm.contact_force
                    } else {
                        asm.plane_force
                    };
                    let (ratio, dt_error) = self.output_error(t_new, force, dt);
                    if ratio > self.settings.output_rejection
                        && dt > dt_min * (1.0 + 1e-9)
                        && self.interpolates_a_sample(self.time, t_new, eps)
                    {
                        if trace() {
                            eprintln!(
                                "reject t={t_new:.5} dt={dt:.3e} output error {ratio:.2} × tolerance"
                            );
                        }
                        self.counters.rejected_steps += 1;
                        self.factors_current = false;
                        // Its converged state predicts the shorter retry.
                        self.u_rejected.copy_from_slice(&self.u);
                        rejected = Some(dt);
                        self.u.copy_from_slice(&self.u_committed);
                        dt = dt_error.max(dt_min);
                        continue;
                    }
                    rejected = None;
                    self.history.commit();
                    self.u_previous.copy_from_slice(&self.u_committed);
                    self.u_committed.copy_from_slice(&self.u);
                    self.time = t_new;
                    self.last_dt = dt;
                    first = false;
                    self.counters.steps += 1;
                    self.control = ctl;
                    self.factors_current = true;
                    self.push_record(t_new, &ctl, &asm, iterations);
                    inadmissible = None;
                    observe(self)?;
                    if iterations <= self.settings.easy_iterations {
                        dt *= self.settings.growth;
                    }
                    let dt_newton = dt.min(stage.dt_max);
                    dt = dt_newton.min(dt_error);
                    // The output control does not stop a step short of the
                    // next sample (`Model::set_output_times`).
                    if let Some(sample) = self.next_sample(self.time, eps)
                        && self.time + dt < sample - eps
                    {
                        dt = dt_newton.min(sample - self.time);
                    }
                }
                Err((residual, tolerance, iterations, cause)) => {
                    if trace() {
                        eprintln!("cutback t={:.5} dt={dt:.3e} {cause}", self.time);
                    }
                    self.counters.cutbacks += 1;
                    self.factors_current = false;
                    self.u.copy_from_slice(&self.u_committed);
                    if cause.starts_with("material at element") {
                        inadmissible = Some(cause.clone());
                    }
                    if dt <= dt_min * (1.0 + 1e-9) {
                        // Leave the residual vector of the converged state.
                        let _ = self.assemble(&(stage.control)(self.time), 0.0, false);
                        let mut cause = format!("stage `{}`: {cause}", stage.name);
                        if let Some(m) = inadmissible.filter(|m| !cause.ends_with(m.as_str())) {
                            cause.push_str(&format!("; an earlier attempt: {m}"));
                        }
                        if let Some((e, j)) = self.smallest_jacobian().filter(|x| x.1 < 0.1) {
                            cause.push_str(&format!(
                                "; element {e} has det F = {j:.3e} at the last converged state (collapsing)"
                            ));
                        }
                        return Err(FemError::NonConvergence(Box::new(NonConvergence {
                            // + 0.0: a clock started at −0.0 prints as 0.
                            time: self.time + 0.0,
                            dt,
                            residual,
                            tolerance,
                            iterations,
                            cause,
                        })));
                    }
                    // The retry keeps the extrapolation predictor (the last
                    // converged increment scaled to the smaller step): without
                    // it a displacement-driven probe jumps alone into a
                    // surface left where it was and inverts the contact
                    // elements even at 1/16 of the step (the elastic dome:
                    // 7 → 0 cut-back cascades; docs/theory/fem.md).
                    dt = (dt * self.settings.cutback).max(dt_min);
                }
            }
        }
        Ok(())
    }
}
