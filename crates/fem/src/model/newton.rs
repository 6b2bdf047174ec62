//! Newton's method for one step: convergence test, predictors (tangent,
//! force-driven first touch, rejected-step), line search on a model of the
//! residual, chord steps.

use super::*;

impl<M: Material3, K: ElementKind<M>> Model<M, K> {
    /// Residual norm reported as the tolerance: `rtol` × the gross force
    /// of the assembly, or the round-off floor if that is larger.
    pub(super) fn tolerance(&self, asm: &Assembly) -> f64 {
        (self.settings.rtol * asm.scale)
            .max(self.settings.atol)
            .max(self.force_floor)
    }

    /// Convergence test of a Newton iterate with residual norm `norm`
    /// (`previous` before the last correction; `corrected`: at least one
    /// correction made): after a correction, `norm` ≤ `rtol` × the gross
    /// force of the assembly (element forces, contact, spring, applied
    /// force) — a predictor within the tolerance is still corrected once,
    /// because an accepted predictor is a step with no equilibrium
    /// iteration, and in a hold such steps drift (rtol 3e-4 accepted them
    /// late in the thesis run's hold: 2.8e-3 off a finely stepped run
    /// there, 7e-4 with the correction); or, when the
    /// forces are so small that this is below round-off (t = 0, first
    /// touch, a probe out of contact, any bulk modulus), `norm` below the
    /// round-off floor 32 ε K L² *and* stagnating (the last correction
    /// gained less than 10×), so a Newton iteration that is still
    /// converging quadratically is never cut short by the floor, and a
    /// predictor is never accepted because its forces are tiny.
    pub(super) fn converged(
        &self,
        norm: f64,
        previous: f64,
        asm: &Assembly,
        corrected: bool,
    ) -> bool {
        norm == 0.0
            || (corrected && norm <= (self.settings.rtol * asm.scale).max(self.settings.atol))
            || (corrected && norm <= self.force_floor && norm > 0.1 * previous)
    }

    pub(super) fn rhs_norm(&self) -> f64 {
        self.rhs.iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    pub(super) fn apply_prescribed(&mut self, ctl: &Control) {
        for &(dof, v) in &self.prescribed {
            self.u[dof] = v * ctl.support_scale;
        }
        if let (Some(_), ProbeDrive::Displacement(w)) = (&self.probe, ctl.probe) {
            self.u[K::DIM * self.mesh.node_count()] = w;
        }
    }

    /// A force-driven probe that touches the body at most at a point (first
    /// touch) or not at all has no contact stiffness, and Newton cannot
    /// start there. Predictor: lower the probe to first contact and then by
    /// the Hertz depth of the set force on an incompressible half-space,
    /// δ = (3F / (16 G √R))^{2/3} (eq. 1.1 with E = 3G); Newton then starts
    /// in contact and converges from there.
    ///
    /// Only when the last converged state carries (almost) no contact
    /// force: a probe already pressed in has its contact stiffness, and
    /// lowering it by the Hertz depth of the full set force would indent it
    /// that much deeper at once (the gap test alone misses this: with
    /// segment-integrated contact the penalty penetration of a soft, relaxed
    /// cell is below 1e-3 of the Hertz depth, which inverted the contact
    /// elements of 5 of the 100 setup-1 checking runs).
    pub(super) fn force_drive_predictor(&mut self, ctl: &Control) {
        let (ProbeDrive::Force(force), Some((probe, surface))) = (ctl.probe, &self.probe) else {
            return;
        };
        if !(force > 0.0) {
            return;
        }
        let carried = self.records.last().map_or(0.0, |r| r.contact_force);
        if carried > 1e-3 * force {
            return;
        }
        let wdof = K::DIM * self.mesh.node_count();
        let obstacle = Obstacle::Sphere {
            centre_z: probe.centre_z + self.u[wdof],
            radius: probe.radius,
        };
        let gap = surface.min_gap(&self.positions2, &self.u, obstacle);
        let depth = (3.0 * force / (16.0 * self.modulus * probe.radius.sqrt())).powf(2.0 / 3.0);
        // Touching (|gap| at round-off) or above: no usable stiffness yet.
        if gap.is_finite() && gap > -1e-3 * depth {
            self.u[wdof] -= gap + depth;
        }
    }

    /// Tangent (Euler) predictor: u = u_c + Δu with K Δu = −(∂R/∂λ) Δλ, K
    /// the last factorised tangent and λ the probe's drive (the prescribed
    /// probe displacement, the spring's free end, or the applied force),
    /// from the loads of the
    /// last converged step to `ctl`. Only for a probe step with the other
    /// loads unchanged; false (u untouched) otherwise.
    pub(super) fn tangent_predictor(&mut self, ctl: &Control) -> bool {
        let old = self.control;
        if old.plane_z != ctl.plane_z
            || old.support_scale != ctl.support_scale
            || old.fluid_injected != ctl.fluid_injected
            || self.cavity.is_some()
        {
            return false;
        }
        let wdof = K::DIM * self.mesh.node_count();
        let mut b = vec![0.0; self.rhs.len()];
        match (old.probe, ctl.probe, &mut self.probe) {
            (
                ProbeDrive::Spring {
                    stiffness: k0,
                    free_end: z0,
                },
                ProbeDrive::Spring {
                    stiffness: k1,
                    free_end: z1,
                },
                Some(_),
            ) if k0 == k1 && z1 != z0 => {
                // R_w = … + k (w − z): −∂R_w/∂z Δz = k Δz.
                b[self.dof_eq[wdof]] = k1 * (z1 - z0);
            }
            (ProbeDrive::Force(f0), ProbeDrive::Force(f1), Some(_)) if f1 != f0 => {
                // R_w = … + F: −∂R_w/∂F ΔF = −ΔF.
                b[self.dof_eq[wdof]] = -(f1 - f0);
            }
            (
                ProbeDrive::Displacement(w0),
                ProbeDrive::Displacement(w1),
                Some((probe, surface)),
            ) if w1 != w0 => {
                // The w row is the identity and its column is not stored:
                // −(∂R_u/∂w) Δw by central differences of the contact
                // residual at the converged state (contact only, cheap).
                let dw = w1 - w0;
                let h = 1e-6 * dw;
                let mut rp = vec![0.0; self.u.len()];
                let mut rm = vec![0.0; self.u.len()];
                for (r, sign) in [(&mut rp, 1.0), (&mut rm, -1.0)] {
                    surface.assemble(
                        &self.positions2,
                        &self.u_committed,
                        wdof,
                        Obstacle::Sphere {
                            centre_z: probe.centre_z + w0 + sign * h,
                            radius: probe.radius,
                        },
                        false,
                        false,
                        r,
                        &mut [],
                    );
                }
                for (d, &eq) in self.dof_eq.iter().enumerate() {
                    if eq != NO_SLOT && d != wdof {
                        b[eq] = -(rp[d] - rm[d]) / (2.0 * h) * dw;
                    }
                }
                b[self.dof_eq[wdof]] = dw * self.probe_diag;
            }
            _ => return false,
        }
        if !self.system.solve_with_last_factors(&mut b) {
            return false;
        }
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            self.u[d] = self.u_committed[d] + if eq != NO_SLOT { b[eq] } else { 0.0 };
        }
        true
    }

    /// Predictor of the retry of a step rejected by the output control:
    /// the rejected step converged to `u_rejected` at `dt_rejected` after
    /// the committed state, so the retry of length `dt` < `dt_rejected`
    /// lies inside a known interval. u(dt) is interpolated by the quadratic
    /// through the previous committed state (at −`last_dt`), the committed
    /// state (0) and the rejected one (linear before the model's first
    /// committed step).
    /// Extrapolating the last increment instead ignores the rejected state;
    /// the tangent predictor is unavailable (the last factors belong to the
    /// rejected attempt).
    pub(super) fn rejected_step_predictor(&mut self, dt: f64, dt_rejected: f64) {
        let (h0, h1) = (self.last_dt, dt_rejected);
        // Lagrange weights at t = dt of the nodes −h0, 0, h1.
        let (w_prev, w_committed, w_rejected) = if h0 > 0.0 {
            (
                dt * (dt - h1) / (h0 * (h0 + h1)),
                (dt + h0) * (h1 - dt) / (h0 * h1),
                (dt + h0) * dt / ((h0 + h1) * h1),
            )
        } else {
            (0.0, 1.0 - dt / h1, dt / h1)
        };
        for d in 0..self.u.len() {
            self.u[d] = w_prev * self.u_previous[d]
                + w_committed * self.u_committed[d]
                + w_rejected * self.u_rejected[d];
        }
    }

    pub(super) fn add_increment(&mut self, du: &[f64], alpha: f64, base: &[f64]) {
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            if eq != NO_SLOT {
                self.u[d] = base[d] + alpha * du[eq];
            }
        }
    }

    /// Newton iterations for one step; Ok((iterations, assembly)) or the
    /// failure (residual, tolerance, iterations, cause).
    pub(super) fn newton(
        &mut self,
        ctl: &Control,
        dt: f64,
    ) -> std::result::Result<(usize, Assembly), (f64, f64, usize, String)> {
        self.apply_prescribed(ctl);
        self.force_drive_predictor(ctl);
        let mut asm = match self.assemble(ctl, dt, true) {
            Ok(a) => a,
            Err(e) => return Err((f64::NAN, 0.0, 0, e.to_string())),
        };
        let mut norm = self.rhs_norm();
        let mut previous_norm = f64::INFINITY;
        let mut du = vec![0.0; self.rhs.len()];
        let mut base = self.u.clone();
        // −R at `base`, kept for the line search's residual model.
        let mut rhs_base = vec![0.0; self.rhs.len()];
        let growth_limit = self.settings.residual_growth;
        // No tangent at the current point (it was assembled residual-only
        // near convergence): the next correction is a chord step with the
        // last factors.
        let mut chord = false;
        // Chord steps in a row (at most `MAX_CHORD_STEPS`, then a tangent:
        // a chord step converges only linearly).
        let mut chords = 0;
        for it in 0..=self.settings.max_iterations {
            let tol = self.tolerance(&asm);
            if trace() {
                let (mut rmax, mut dmax) = (0.0, 0);
                for (d, &eq) in self.dof_eq.iter().enumerate() {
                    if eq != NO_SLOT && self.rhs[eq].abs() > rmax {
                        rmax = self.rhs[eq].abs();
                        dmax = d;
                    }
                }
                let node = if dmax / K::DIM < self.mesh.node_count() {
                    let x = self.mesh.position(dmax / K::DIM);
                    [x[0], x[x.len() - 1]]
                } else {
                    [f64::NAN; 2]
                };
                eprintln!(
                    "    it {it} |R| {norm:.3e} tol {tol:.3e} active {} F {:.5e} max |R| {rmax:.2e} at dof {dmax} (node at {:.3e}, {:.3e})",
                    asm.active, asm.contact_force, node[0], node[1]
                );
            }
            if self.converged(norm, previous_norm, &asm, it > 0) {
                return Ok((it, asm));
            }
            if !norm.is_finite() {
                return Err((norm, tol, it, "non-finite residual".into()));
            }
            if it == self.settings.max_iterations {
                return Err((norm, tol, it, "iteration limit".into()));
            }
            du.copy_from_slice(&self.rhs);
            let clock = cpu_time::ThreadTime::now();
            let chord_step = chord && self.system.solve_with_last_factors(&mut du);
            let solved = if chord_step {
                Ok(true)
            } else {
                if chord {
                    // No factors to reuse: the tangent here after all.
                    asm = match self.assemble(ctl, dt, true) {
                        Ok(a) => a,
                        Err(e) => return Err((norm, tol, it, e.to_string())),
                    };
                    du.copy_from_slice(&self.rhs);
                }
                self.counters.factorisations += 1;
                self.system.solve(&mut du)
            };
            chords = if chord_step { chords + 1 } else { 0 };
            chord = false;
            self.counters.solve_seconds += clock.elapsed().as_secs_f64();
            match solved {
                Ok(true) => {}
                Ok(false) => self.counters.lu_fallbacks += 1,
                Err(e) => return Err((norm, tol, it, e.to_string())),
            }
            self.counters.iterations += 1;
            // Near-incompressible pressures leave a round-off floor in the
            // residual above rtol·scale when the forces are tiny: a Newton
            // correction below the round-off level of the coordinates means
            // the state cannot be improved and counts as converged — also at
            // the first iteration (a step that starts at equilibrium).
            let du_max = du.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
            if du_max <= 1e-12 * self.length && norm <= 1e-4 * asm.scale {
                return Ok((it, asm));
            }
            base.copy_from_slice(&self.u);
            if std::env::var_os("NLVID_FEM_CHECK_TANGENT").is_some() {
                let rhs0 = self.rhs.clone();
                let h = 1e-5;
                self.add_increment(&du, h, &base);
                let _ = self.assemble(ctl, dt, false);
                let rp = self.rhs.clone();
                self.add_increment(&du, -h, &base);
                let _ = self.assemble(ctl, dt, false);
                let mut err = 0.0;
                let mut den = 0.0;
                let mut worst = (0.0, 0);
                for i in 0..rp.len() {
                    let fd = (rp[i] - self.rhs[i]) / (2.0 * h);
                    let e = (fd + rhs0[i]).abs();
                    err += e * e;
                    den += rhs0[i] * rhs0[i];
                    if e > worst.0 {
                        worst = (e, i);
                    }
                }
                eprintln!(
                    "      tangent check: |fd − K du| / |K du| = {:.3e}, worst eq {} ({:.3e} of {:.3e})",
                    (err / den).sqrt(),
                    worst.1,
                    worst.0,
                    rhs0[worst.1]
                );
                self.u.copy_from_slice(&base);
                let _ = self.assemble(ctl, dt, true);
            }
            let mut alpha = 1.0;
            let mut accepted = false;
            let mut last_err = String::new();
            let lazy = chord_step || norm <= self.settings.lazy_tangent * tol;
            let trials = if chord_step {
                0
            } else {
                self.settings.line_search
            };
            if trials > 0 {
                rhs_base.copy_from_slice(&self.rhs);
            }
            for _ in 0..=trials {
                self.add_increment(&du, alpha, &base);
                let mut next_alpha = 0.5 * alpha;
                match self.assemble(ctl, dt, !lazy) {
                    Ok(a) => {
                        let n = self.rhs_norm();
                        // Monotone residual decrease by default: a full step
                        // that raises it is cut back (measured: fewer
                        // iterations and cut-backs than accepting 10× rises).
                        let limit = if chord_step {
                            // A chord step must contract as the Newton step
                            // it stands in for would.
                            self.settings.chord_contraction * norm
                        } else if alpha == 1.0 {
                            growth_limit * norm
                        } else {
                            norm
                        };
                        if n.is_finite() && n <= limit {
                            asm = a;
                            previous_norm = norm;
                            norm = n;
                            accepted = true;
                            break;
                        }
                        last_err = format!("line search: residual {n:.3e} ≥ {norm:.3e}");
                        if trace() {
                            eprintln!("      line search: α = {alpha} rejected ({last_err})");
                        }
                        if n.is_finite() {
                            next_alpha = backtrack_step(&rhs_base, &self.rhs, alpha);
                        }
                    }
                    Err(e) => last_err = e.to_string(),
                }
                alpha = next_alpha;
            }
            if !accepted && chord_step {
                // The old factors no longer do: a Newton step from the
                // same point with its own tangent (same residual, bitwise).
                self.u.copy_from_slice(&base);
                asm = match self.assemble(ctl, dt, true) {
                    Ok(a) => a,
                    Err(e) => return Err((norm, tol, it + 1, e.to_string())),
                };
                continue;
            }
            if !accepted {
                if norm <= self.force_floor {
                    // No direction improves a residual already at round-off
                    // level: the state cannot be made better; keep it.
                    self.u.copy_from_slice(&base);
                    return match self.assemble(ctl, dt, false) {
                        Ok(a) => Ok((it + 1, a)),
                        Err(e) => Err((norm, tol, it + 1, e.to_string())),
                    };
                }
                return Err((norm, tol, it + 1, last_err));
            }
            if lazy && !self.converged(norm, previous_norm, &asm, true) {
                if norm <= self.settings.chord_contraction * previous_norm
                    && chords < MAX_CHORD_STEPS
                    // Chord steps must not eat the iteration budget of a
                    // step that converges only slowly.
                    && it + 1 + MAX_CHORD_STEPS + 2 <= self.settings.max_iterations
                {
                    // Still contracting fast: the tangent of the last
                    // factorisation is as good as a new one for the rest
                    // (chord steps, residual-only assemblies).
                    chord = true;
                    continue;
                }
                // Predicted convergence did not happen: the next iteration
                // needs the tangent at this point.
                asm = match self.assemble(ctl, dt, true) {
                    Ok(a) => a,
                    Err(e) => return Err((norm, tol, it + 1, e.to_string())),
                };
                norm = self.rhs_norm();
            }
        }
        Err((
            norm,
            0.0,
            self.settings.max_iterations,
            "iteration limit".into(),
        ))
    }
}

/// Step length of the next line-search trial after the trial at `alpha`
/// was rejected; `r0` and `r_alpha` are the residual vectors (either sign,
/// the same for both) at the start point and at the trial.
///
/// Safeguarded interpolation (Dennis & Schnabel, *Numerical Methods for
/// Unconstrained Optimization and Nonlinear Equations*, 1983, ch. 6), on the
/// residual vector instead of a scalar merit: along a Newton direction
/// (K du = −R₀), R(β) = (1 − β) R₀ + O(β²), so R(β) ≈ (1 − β) R₀ + β² Q with
/// Q fitted to the trial, Q = (R_α − (1 − α) R₀)/α². The next trial
/// minimises |R(β)|² = (1 − β)² a + 2 (1 − β) β² b + β⁴ c (a = |R₀|²,
/// b = R₀·Q, c = |Q|²) over the safeguard [0.1 α, 0.5 α] (on a grid of 41
/// points). Plain halving (session 2) kept the bad direction's second-order
/// term at ¼ of the trial's: where the residual rose 10–30× (the
/// near-incompressible solid under the first contact steps of the elastic
/// dome), it took 3–5 halvings, often to no decrease.
pub(super) fn backtrack_step(r0: &[f64], r_alpha: &[f64], alpha: f64) -> f64 {
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (&x0, &xa) in r0.iter().zip(r_alpha) {
        let q = (xa - (1.0 - alpha) * x0) / (alpha * alpha);
        a += x0 * x0;
        b += x0 * q;
        c += q * q;
    }
    let phi = |x: f64| {
        let y = 1.0 - x;
        y * y * a + 2.0 * y * x * x * b + x.powi(4) * c
    };
    let (lo, hi) = (0.1 * alpha, 0.5 * alpha);
    let mut best = (hi, phi(hi));
    for k in 0..40 {
        let x = lo + (hi - lo) * f64::from(k) / 40.0;
        let v = phi(x);
        if v < best.1 {
            best = (x, v);
        }
    }
    best.0
}
