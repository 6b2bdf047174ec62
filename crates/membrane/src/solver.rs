//! Newton on (λ0, ψc, p) around the shooting of [`crate::shooting`], and
//! time marching with the point histories stored at fixed material nodes ψj
//! (§2.3.3: "the final values … used as the initial estimates … at t_{i+1}").

use std::f64::consts::{FRAC_PI_2, PI};

use nlvid_material::MembraneMaterial;
use serde::{Deserialize, Serialize};

use crate::shooting::{NodeValue, Shooter, ShotEnd, ShotFail};
use crate::{MembraneError, Result};

/// Geometry and discretisation of the membrane (dimensionless, eq. 2.47).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Radius of the slightly inflated membrane r_s/r0 = λs (thesis: 1.03).
    pub rs: f64,
    /// Number of RK4 intervals (material nodes − 1) on 0 ≤ ψ ≤ π/2.
    pub nodes: usize,
}

impl Default for Geometry {
    fn default() -> Self {
        Self {
            rs: 1.03,
            nodes: 64,
        }
    }
}

impl Geometry {
    /// Validate.
    ///
    /// # Errors
    /// [`MembraneError::Input`] when r_s < 1 or fewer than 8 intervals.
    pub fn check(&self) -> Result<()> {
        if !(self.rs >= 1.0 && self.rs < 3.0) {
            return Err(MembraneError::Input {
                name: "rs",
                value: self.rs,
                reason: "inflated radius r_s/r0 must lie in [1, 3) (thesis: 1.03)".into(),
            });
        }
        if self.nodes < 8 || self.nodes > 100_000 {
            return Err(MembraneError::Input {
                name: "nodes",
                value: self.nodes as f64,
                reason: "use between 8 and 100000 RK4 intervals on [0, π/2]".into(),
            });
        }
        Ok(())
    }

    /// Enclosed volume V0/r0³ = 4π r_s³/3 (eq. 2.45).
    pub fn volume(&self) -> f64 {
        4.0 / 3.0 * PI * self.rs.powi(3)
    }
}

/// What the plates prescribe at a time (dimensionless, eq. 2.47).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Control {
    /// Plate displacement D/r0 = r_s − H1/r0 (eq. 2.43); D ≤ 0 means no contact.
    Displacement(f64),
    /// Contact force F/(G10 h0 r0) (eq. 2.44); F ≤ 0 means no contact.
    Force(f64),
    /// Contact angle ψc (rad, reference configuration): the well-conditioned
    /// parameter for elastic sweeps through first contact.
    ContactAngle(f64),
}

impl Control {
    fn value(&self) -> f64 {
        match *self {
            Control::Displacement(v) | Control::Force(v) | Control::ContactAngle(v) => v,
        }
    }
    fn touches(&self) -> bool {
        self.value() > 0.0
    }
}

impl std::fmt::Display for Control {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Control::Displacement(d) => write!(f, "D/r0 = {d:.6}"),
            Control::Force(v) => write!(f, "F/(G10 h0 r0) = {v:.6}"),
            Control::ContactAngle(v) => write!(f, "ψc = {v:.6} rad"),
        }
    }
}

/// The scalars of a converged equilibrium at one time (dimensionless,
/// eq. 2.47): one row of a run's time history, and the head of its
/// [`Solution`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepRecord {
    /// Time (material time units; t0 = t/τ1 when τ1 = 1).
    pub time: f64,
    /// Plate displacement D/r0: r_s − H1/r0 in contact; the prescribed plate
    /// position when the plates have lost contact (then H1 < r_s − D, F = 0).
    pub displacement: f64,
    /// Half-height H1/r0.
    pub h1: f64,
    /// Contact force F/(G10 h0 r0) = π a² p (eq. 2.44).
    pub force: f64,
    /// Pressure p r0/(G10 h0).
    pub pressure: f64,
    /// Contact angle ψc (rad, reference configuration).
    pub psi_c: f64,
    /// Crown stretch λ0.
    pub lambda0: f64,
    /// Contact radius a/r0 = ρ(ψc).
    pub contact_radius: f64,
    /// Equatorial radius ρ(π/2)/r0.
    pub equator_radius: f64,
    /// Smallest principal tension over the nodes, min(T1, T2)/(G10 h0).
    pub min_tension: f64,
}

/// A converged equilibrium at one time (dimensionless, eq. 2.47): its
/// [`StepRecord`] and the profile.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Solution {
    /// Time, displacement, force, pressure, contact and crown values.
    #[serde(flatten)]
    pub record: StepRecord,
    /// Meridional tension at the equator T1/(G10 h0).
    pub t1_equator: f64,
    /// Enclosed volume V/r0³.
    pub volume: f64,
    /// Newton iterations of the final solve.
    pub iterations: usize,
    /// Values at the material nodes ψ0 … ψN.
    pub profile: Vec<NodeValue>,
}

impl Solution {
    /// Angle (deg) from the axis of the radial line to the particle at ψc in the
    /// current configuration, atan(a/H1) (the "80.6°" of §2.5.1).
    pub fn current_contact_angle_deg(&self) -> f64 {
        self.record
            .contact_radius
            .atan2(self.record.h1)
            .to_degrees()
    }
}

/// Newton settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NewtonSettings {
    /// Max-norm tolerance on the scaled residuals.
    pub tol: f64,
    /// Iteration limit per solve.
    pub max_iter: usize,
    /// Maximum bisections of the control increment (continuation) per step.
    pub max_bisections: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            max_iter: 40,
            max_bisections: 10,
        }
    }
}

#[derive(Debug)]
enum NewtonFail {
    Shot(ShotFail),
    Stalled {
        residual: [f64; 3],
        iterations: usize,
        last_shot: Option<ShotFail>,
    },
}

const RES_NAMES: [&str; 3] = [
    "equator slope θ(π/2) − π/2 (eq. 2.42)",
    "volume V/V0 − 1 (eq. 2.45–2.46)",
    "control (height, eq. 2.43, or force, eq. 2.44)",
];

/// The semi-analytical solver of §2.3.3 for one membrane.
#[derive(Debug)]
pub struct MembraneSolver<M: MembraneMaterial> {
    material: M,
    geometry: Geometry,
    scale: f64,
    states: Vec<M::State>,
    trial: Vec<M::State>,
    uniform: bool,
    time: Option<f64>,
    x: [f64; 3],
    /// Previous committed unknowns and the time step that led to `x`.
    x_prev: Option<([f64; 3], f64)>,
    predicted: Option<[f64; 3]>,
    /// Plate displacement of a step in which the plates have lost contact.
    detached: Option<f64>,
    last_control: Control,
    jac: Option<[[f64; 3]; 3]>,
    /// Newton settings (public to tune).
    pub newton: NewtonSettings,
    /// Accept non-positive principal tensions in the flat contact region
    /// (default `false`: reported as [`MembraneError::Wrinkling`]). A
    /// membrane cannot carry compression, so `true` gives the solution of
    /// the equations of §2.3 without the tension check in 0 ≤ ψ ≤ ψc, i.e.
    /// what a solver in (λ1, λ2, w) that never looks at the sign of σ (the
    /// thesis's formulation, eqs. 2.38–2.39) computes; the free region
    /// must stay in tension either way (eq. 2.37 divides by σ1).
    pub allow_compression_in_contact: bool,
}

fn norm(r: &[f64; 3]) -> f64 {
    r.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let mut m = a;
    let mut v = b;
    for k in 0..3 {
        let piv = (k..3).max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))?;
        if m[piv][k].abs() < 1e-300 || !m[piv][k].is_finite() {
            return None;
        }
        m.swap(k, piv);
        v.swap(k, piv);
        for i in k + 1..3 {
            let f = m[i][k] / m[k][k];
            for c in k..3 {
                m[i][c] -= f * m[k][c];
            }
            v[i] -= f * v[k];
        }
    }
    let mut x = [0.0; 3];
    for k in (0..3).rev() {
        let s: f64 = (k + 1..3).map(|c| m[k][c] * x[c]).sum();
        x[k] = (v[k] - s) / m[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

impl<M: MembraneMaterial> MembraneSolver<M> {
    /// A solver for `material` whose stresses are divided by `stress_scale`
    /// (G10 of eq. 2.47; 1 for a dimensionless material). Solves the free
    /// inflation to r_s at once (the membrane is inflated instantaneously at
    /// t = 0; nothing is committed until the first [`Self::advance`]).
    ///
    /// # Errors
    /// [`MembraneError::Input`] for a bad geometry or scale;
    /// [`MembraneError::Wrinkling`] when the inflated membrane has no tension
    /// (r_s = 1); [`MembraneError::NoConvergence`] otherwise.
    pub fn new(material: M, geometry: Geometry, stress_scale: f64) -> Result<Self> {
        geometry.check()?;
        if !(stress_scale > 0.0 && stress_scale.is_finite()) {
            return Err(MembraneError::Input {
                name: "stress_scale",
                value: stress_scale,
                reason: "the stress scale G10 must be positive".into(),
            });
        }
        let s0 = material.initial_state();
        let states = vec![s0; geometry.nodes + 1];
        let trial = states.clone();
        let mut solver = Self {
            material,
            geometry,
            scale: stress_scale,
            states,
            trial,
            uniform: true,
            time: None,
            x: [geometry.rs, 0.0, 0.0],
            x_prev: None,
            predicted: None,
            detached: None,
            last_control: Control::Displacement(0.0),
            jac: None,
            newton: NewtonSettings::default(),
            allow_compression_in_contact: false,
        };
        // Sphere guess: p = 2 T/λs (Laplace), T = σ/λs².
        let rs = geometry.rs;
        let mut scratch = solver.material.initial_state();
        let resp = solver
            .material
            .update(&solver.states[0], [rs, rs], 0.0, &mut scratch)
            .map_err(|e| MembraneError::Material {
                psi: 0.0,
                time: 0.0,
                source: e,
            })?;
        let t = resp.cauchy[0] / stress_scale / (rs * rs);
        solver.x = [rs, 0.0, 2.0 * t / rs];
        let (x, _, _) = solver.solve_with_continuation(0.0, 0.0, Control::Displacement(0.0))?;
        solver.x = x;
        Ok(solver)
    }

    /// Geometry in use.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Time of the last committed step, if any.
    pub fn time(&self) -> Option<f64> {
        self.time
    }

    /// Last converged unknowns (λ0, ψc, p).
    pub fn unknowns(&self) -> [f64; 3] {
        self.x
    }

    fn residual(
        &self,
        sh: &mut Shooter<'_, M>,
        x: [f64; 3],
        control: Control,
    ) -> std::result::Result<([f64; 3], ShotEnd), ShotFail> {
        let psi_c = if control.touches() { x[1] } else { 0.0 };
        let end = sh.shoot(x[0], psi_c, x[2], None)?;
        let v0 = self.geometry.volume();
        let c = match control {
            Control::Displacement(d) if d > 0.0 => end.h1 - (self.geometry.rs - d),
            Control::Force(f) if f > 0.0 => {
                (PI * end.contact_radius * end.contact_radius * x[2] - f) / f.max(1.0)
            }
            _ => 0.0,
        };
        Ok(([end.theta_end - FRAC_PI_2, end.volume / v0 - 1.0, c], end))
    }

    /// Newton with forward-difference Jacobians (step 1e-7 relative); when that
    /// stalls, once more with step 1e-9: near slack states the shot is so
    /// sensitive (|∂θ(π/2)/∂λ0| ≈ 2e4) that 1e-7 leaves the linear range and
    /// gives ascent directions, while near first contact/loss of contact the
    /// larger step is the robust one.
    fn newton(
        &mut self,
        dt: f64,
        control: Control,
        x0: [f64; 3],
    ) -> std::result::Result<([f64; 3], usize), NewtonFail> {
        match self.newton_fd(dt, control, x0, 1e-7) {
            Err(first @ NewtonFail::Stalled { .. }) => {
                self.jac = None;
                // If both stall, report the first attempt (the usual step).
                self.newton_fd(dt, control, x0, 1e-9).map_err(|_| first)
            }
            r => r,
        }
    }

    fn newton_fd(
        &mut self,
        dt: f64,
        control: Control,
        x0: [f64; 3],
        fd_step: f64,
    ) -> std::result::Result<([f64; 3], usize), NewtonFail> {
        let fixed_psi = match control {
            Control::ContactAngle(v) => Some(v.max(0.0)),
            c if !c.touches() => Some(0.0),
            _ => None,
        };
        let touches = fixed_psi.is_none();
        let mat = &self.material;
        let mut sh = Shooter::new(mat, &self.states, self.uniform, dt, self.scale)
            .compression(self.allow_compression_in_contact);
        let mut x = x0;
        if let Some(v) = fixed_psi {
            x[1] = v;
        }
        let clamp = |mut x: [f64; 3]| {
            x[0] = x[0].max(1e-3);
            x[1] = match fixed_psi {
                Some(v) => v,
                None => x[1].clamp(0.0, FRAC_PI_2 - 1e-6),
            };
            x
        };
        let (mut r, _) = self
            .residual(&mut sh, x, control)
            .map_err(NewtonFail::Shot)?;
        let mut jac = self.jac;
        let mut fresh = false;
        let mut last_shot = None;
        for it in 0..self.newton.max_iter {
            if norm(&r) <= self.newton.tol {
                self.jac = jac;
                return Ok((x, it));
            }
            if jac.is_none() {
                let mut j = [[0.0; 3]; 3];
                for k in 0..3 {
                    if k == 1 && !touches {
                        j[1][1] = 1.0;
                        continue;
                    }
                    let h = fd_step * (1.0 + x[k].abs());
                    let mut xp = x;
                    xp[k] += h;
                    let (rp, _) = match self.residual(&mut sh, xp, control) {
                        Ok(v) => v,
                        Err(_) => {
                            xp[k] = x[k] - h;
                            let (rm, _) = self
                                .residual(&mut sh, xp, control)
                                .map_err(NewtonFail::Shot)?;
                            for i in 0..3 {
                                j[i][k] = (r[i] - rm[i]) / h;
                            }
                            continue;
                        }
                    };
                    for i in 0..3 {
                        j[i][k] = (rp[i] - r[i]) / h;
                    }
                }
                jac = Some(j);
                fresh = true;
            }
            let j = jac.unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
            let dx = if touches {
                solve3(j, [-r[0], -r[1], -r[2]])
            } else {
                // 2×2 system in (λ0, p) from the slope and volume residuals.
                solve3(
                    [
                        [j[0][0], 0.0, j[0][2]],
                        [0.0, 1.0, 0.0],
                        [j[1][0], 0.0, j[1][2]],
                    ],
                    [-r[0], 0.0, -r[1]],
                )
            };
            let Some(dx) = dx else {
                if fresh {
                    return Err(NewtonFail::Stalled {
                        residual: r,
                        iterations: it,
                        last_shot,
                    });
                }
                jac = None;
                continue;
            };
            let mut alpha = 1.0;
            let mut accepted = false;
            while alpha >= 1.0 / 1024.0 {
                let xt = clamp([
                    x[0] + alpha * dx[0],
                    x[1] + alpha * dx[1],
                    x[2] + alpha * dx[2],
                ]);
                match self.residual(&mut sh, xt, control) {
                    Ok((rt, _)) if norm(&rt) < (1.0 - 1e-4 * alpha) * norm(&r) => {
                        // A reused Jacobian that contracts slowly is refreshed next time;
                        // otherwise it gets Broyden's rank-one update.
                        if !fresh && norm(&rt) > 0.3 * norm(&r) {
                            jac = None;
                        } else if let Some(jm) = jac.as_mut() {
                            let d = [xt[0] - x[0], xt[1] - x[1], xt[2] - x[2]];
                            let dd: f64 = d.iter().map(|v| v * v).sum();
                            if dd > 0.0 {
                                for i in 0..3 {
                                    let jd: f64 = (0..3).map(|k| jm[i][k] * d[k]).sum();
                                    let u = (rt[i] - r[i] - jd) / dd;
                                    for k in 0..3 {
                                        jm[i][k] += u * d[k];
                                    }
                                }
                            }
                        }
                        x = xt;
                        r = rt;
                        accepted = true;
                        break;
                    }
                    Ok(_) => {}
                    Err(e) => last_shot = Some(e),
                }
                alpha *= 0.5;
            }
            if !accepted {
                if fresh {
                    return Err(NewtonFail::Stalled {
                        residual: r,
                        iterations: it + 1,
                        last_shot,
                    });
                }
                jac = None;
            }
        }
        Err(NewtonFail::Stalled {
            residual: r,
            iterations: self.newton.max_iter,
            last_shot,
        })
    }

    fn guess_for(&self, control: Control) -> [f64; 3] {
        let mut x = self.x;
        if let Some(p) = self.predicted
            && p[1] > 0.0
            && x[1] > 0.0
            && control.touches()
        {
            x = p;
        }
        if let Control::ContactAngle(v) = control {
            x[1] = v;
        } else if control.touches() && x[1] <= 0.0 {
            let rs = self.geometry.rs;
            x[1] = match control {
                Control::Displacement(d) => ((rs - d.min(rs)) / rs).clamp(-1.0, 1.0).acos(),
                Control::Force(f) => {
                    let a = (f / (PI * x[2].max(1e-12))).sqrt();
                    (a / rs).min(0.99).asin()
                }
                Control::ContactAngle(v) => v,
            }
            .max(1e-3);
        }
        x
    }

    fn fail_to_error(&self, time: f64, control: Control, fail: NewtonFail) -> MembraneError {
        let tension = |f: &ShotFail| match f {
            ShotFail::Tension { psi, which, value } => Some((*psi, *which, *value)),
            _ => None,
        };
        let wrinkle = |psi, which, value| MembraneError::Wrinkling {
            time,
            psi,
            which,
            tension: value,
            control: control.to_string(),
            advice: "increase the initial inflation r_s (thesis: 1.03), reduce the plate \
                     displacement/force, or use a tension-field (wrinkling) model",
        };
        match fail {
            NewtonFail::Shot(ShotFail::Material { psi, err }) => MembraneError::NoConvergence {
                time,
                control: control.to_string(),
                quantity: "material point update",
                residual: f64::NAN,
                iterations: 0,
                advice: format!("the material update failed at ψ = {psi:.4}: {err}"),
            },
            NewtonFail::Shot(f) => match tension(&f) {
                Some((psi, which, value)) => wrinkle(psi, which, value),
                None => MembraneError::NoConvergence {
                    time,
                    control: control.to_string(),
                    quantity: "shooting from the crown",
                    residual: f64::NAN,
                    iterations: 0,
                    advice: format!(
                        "{f:?}; reduce the time step or the load increment, or refine `nodes`"
                    ),
                },
            },
            NewtonFail::Stalled {
                residual,
                iterations,
                last_shot,
            } => {
                if let Some((psi, which, value)) = last_shot.as_ref().and_then(tension)
                    && norm(&residual) > 1e-4
                {
                    return wrinkle(psi, which, value);
                }
                let k = (0..3)
                    .max_by(|&a, &b| residual[a].abs().total_cmp(&residual[b].abs()))
                    .unwrap_or(0);
                MembraneError::NoConvergence {
                    time,
                    control: control.to_string(),
                    quantity: RES_NAMES[k],
                    residual: residual[k],
                    iterations,
                    advice: "reduce the time step or the load increment; for D/r0 close to r_s \
                             the membrane is squeezed flat (no solution): reduce D"
                        .into(),
                }
            }
        }
    }

    /// Control quantity (D or F) of a shot end.
    fn control_value(&self, control: Control, x: &[f64; 3], end: &ShotEnd) -> f64 {
        match control {
            Control::Displacement(_) => self.geometry.rs - end.h1,
            Control::Force(_) => PI * end.contact_radius * end.contact_radius * x[2],
            Control::ContactAngle(_) => x[1],
        }
    }

    /// Solve at time increment `dt` for `control`: Newton from the last
    /// solution; if that fails, sweep the contact angle ψc (well conditioned,
    /// 2 unknowns) from the last solution until the control quantity passes
    /// the target, then Newton from the interpolated guess.
    fn solve_with_continuation(
        &mut self,
        time: f64,
        dt: f64,
        control: Control,
    ) -> Result<([f64; 3], usize, Control)> {
        self.detached = None;
        if let Control::Displacement(d) = control
            && d > 0.0
            && self.x[1] <= 0.0
        {
            // Not in contact: does the free membrane (relaxing at this dt) reach the plate?
            if let Some(x) = self.detached_solution(dt, d) {
                return Ok((x, 0, Control::Displacement(0.0)));
            }
        }
        match self.solve_in_contact(time, dt, control) {
            Ok(v) => {
                if let Control::Displacement(d) = control
                    && d <= 0.0
                {
                    self.detached = Some(d);
                }
                Ok(v)
            }
            Err(e) => match control {
                // Fast unloading: the membrane recovers more slowly than the plates retreat.
                Control::Displacement(d) if d > 0.0 => match self.detached_solution(dt, d) {
                    Some(x) => Ok((x, 0, Control::Displacement(0.0))),
                    None => Err(e),
                },
                _ => Err(e),
            },
        }
    }

    /// The free (no-contact) equilibrium at this dt if its height lies below
    /// the plate at displacement `d`.
    fn detached_solution(&mut self, dt: f64, d: f64) -> Option<[f64; 3]> {
        let saved = (self.x, self.jac);
        let free = self.sweep_psi(dt, 0.0, |_, _| false).ok().map(|(_, x)| x);
        let free = free.and_then(|x| {
            self.newton(dt, Control::Displacement(0.0), x)
                .ok()
                .map(|(x, _)| x)
        });
        self.x = saved.0;
        self.jac = None;
        let x = free?;
        let mut sh = Shooter::new(&self.material, &self.states, self.uniform, dt, self.scale)
            .compression(self.allow_compression_in_contact);
        let end = sh.shoot(x[0], 0.0, x[2], None).ok()?;
        if self.geometry.rs - end.h1 >= d - 1e-12 {
            self.detached = Some(d);
            Some(x)
        } else {
            None
        }
    }

    fn solve_in_contact(
        &mut self,
        time: f64,
        dt: f64,
        control: Control,
    ) -> Result<([f64; 3], usize, Control)> {
        let saved = self.x;
        // From no contact to contact the direct Newton has no usable guess for
        // ψc (and the shot is very sensitive): go straight to the ψc sweep.
        let first_contact = self.x[1] <= 0.0 && control.touches();
        let first = if first_contact && !matches!(control, Control::ContactAngle(_)) {
            NewtonFail::Stalled {
                residual: [f64::NAN; 3],
                iterations: 0,
                last_shot: None,
            }
        } else {
            match self.newton(dt, control, self.guess_for(control)) {
                Ok((x, it)) => return Ok((x, it, control)),
                Err(e) => e,
            }
        };
        self.jac = None;
        let target = control.value();
        let result = (|| -> std::result::Result<([f64; 3], usize), NewtonFail> {
            if let Control::ContactAngle(v) = control {
                let (_, cur) = self.sweep_psi(dt, v.max(0.0), |_, _| false)?;
                return self.newton(dt, control, cur);
            }
            if target <= 0.0 {
                let (_, cur) = self.sweep_psi(dt, 0.0, |_, _| false)?;
                return self.newton(dt, control, cur);
            }
            // Equilibrium at this dt and the current contact angle decides the direction.
            let q0 = if self.x[1] > 0.0 {
                let (_, x0) = self.sweep_psi(dt, self.x[1], |_, _| false)?;
                self.x = x0;
                let mut sh =
                    Shooter::new(&self.material, &self.states, self.uniform, dt, self.scale)
                        .compression(self.allow_compression_in_contact);
                match sh.shoot(x0[0], x0[1], x0[2], None) {
                    Ok(end) => self.control_value(control, &x0, &end),
                    Err(_) => 0.0,
                }
            } else {
                0.0
            };
            let up = target > q0;
            let psi_end = if up { FRAC_PI_2 - 0.02 } else { 0.0 };
            let mut qs = (q0, q0);
            let rs = self.geometry.rs;
            let (prev, cur) = self.sweep_psi(dt, psi_end, |x, end| {
                let q = match control {
                    Control::Displacement(_) => rs - end.h1,
                    _ => PI * end.contact_radius * end.contact_radius * x[2],
                };
                qs = (qs.1, q);
                (q >= target) == up
            })?;
            let (qa, qb) = qs;
            let f = if (qb - qa).abs() > 1e-300 {
                ((target - qa) / (qb - qa)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let mut guess = [0.0; 3];
            for k in 0..3 {
                guess[k] = prev[k] + f * (cur[k] - prev[k]);
            }
            self.jac = None;
            match self.newton(dt, control, guess) {
                Ok(v) => Ok(v),
                // Near first contact D, F ∝ ψc² and the 3×3 Jacobian is nearly
                // singular: solve q(ψc) = target by the Illinois method with the
                // well-conditioned fixed-ψc problem inside.
                Err(e) => {
                    let eval = |s: &mut Self, psi: f64, g: [f64; 3]| -> Option<([f64; 3], f64)> {
                        s.jac = None;
                        let (x, _) = s.newton(dt, Control::ContactAngle(psi), g).ok()?;
                        let mut sh = Shooter::new(&s.material, &s.states, s.uniform, dt, s.scale)
                            .compression(s.allow_compression_in_contact);
                        let end = sh.shoot(x[0], x[1], x[2], None).ok()?;
                        Some((x, s.control_value(control, &x, &end) - target))
                    };
                    let (Some((mut xa, mut fa)), Some((mut xb, mut fb))) =
                        (eval(self, prev[1], prev), eval(self, cur[1], cur))
                    else {
                        return Err(e);
                    };
                    if fa * fb > 0.0 {
                        return Err(e);
                    }
                    let tol = 1e-11 * target.abs().max(1.0);
                    let mut side = 0;
                    for it in 0..100 {
                        let psi = (xa[1] * fb - xb[1] * fa) / (fb - fa);
                        let w = (psi - xa[1]) / (xb[1] - xa[1]);
                        let g = [0, 1, 2].map(|k| xa[k] + w * (xb[k] - xa[k]));
                        let Some((x, fx)) = eval(self, psi, g) else {
                            return Err(e);
                        };
                        if fx.abs() <= tol || (xb[1] - xa[1]).abs() < 1e-14 {
                            return Ok((x, it + 1));
                        }
                        if fx * fb < 0.0 {
                            xa = xb;
                            fa = fb;
                            side = 0;
                        } else {
                            side += 1;
                            if side >= 2 {
                                fa *= 0.5;
                            }
                        }
                        xb = x;
                        fb = fx;
                    }
                    Err(e)
                }
            }
        })();
        self.x = saved;
        match result {
            Ok((x, it)) => Ok((x, it, control)),
            Err(e) => {
                let err = self.fail_to_error(time, control, e);
                match err {
                    MembraneError::Wrinkling { .. } => Err(err),
                    // No direct attempt was made at first contact: report the sweep's failure.
                    _ if first_contact => Err(err),
                    _ => Err(self.fail_to_error(time, control, first)),
                }
            }
        }
    }

    /// Sweep the contact angle from the last converged state toward `psi_end`
    /// (adaptive steps, secant predictor) at fixed dt and history, calling
    /// `stop(x, end)` after each converged point; returns the last two points.
    fn sweep_psi(
        &mut self,
        dt: f64,
        psi_end: f64,
        mut stop: impl FnMut(&[f64; 3], &ShotEnd) -> bool,
    ) -> std::result::Result<([f64; 3], [f64; 3]), NewtonFail> {
        let mut cur = self.x;
        if !matches!(self.last_control, Control::ContactAngle(_)) && cur[1] <= 0.0 {
            cur[1] = 0.0;
        }
        // Start from the equilibrium at this dt and the current contact angle:
        // the shot is too sensitive to start from the previous step's state.
        // At dt = 0 the committed state solves the problem exactly, so the
        // equilibrium at dt is reached by continuation in the time increment.
        let start = if cur[1] > 0.0 {
            Control::ContactAngle(cur[1])
        } else {
            Control::Displacement(0.0)
        };
        let (mut s, mut ds) = (0.0_f64, 1.0_f64);
        let (mut xs, mut xs_prev, mut ds_prev) = (cur, cur, 0.0_f64);
        while s < 1.0 {
            let st = (s + ds).min(1.0);
            let mut guess = xs;
            if ds_prev > 0.0 {
                let f = (st - s) / ds_prev;
                for k in 0..3 {
                    guess[k] = xs[k] + f * (xs[k] - xs_prev[k]);
                }
            }
            self.jac = None;
            match self.newton(dt * st, start, guess) {
                Ok((x, _)) => {
                    xs_prev = xs;
                    xs = x;
                    ds_prev = st - s;
                    s = st;
                    ds *= 2.0;
                }
                Err(e) => {
                    ds *= 0.25;
                    if ds < 1e-5 {
                        return Err(e);
                    }
                }
            }
        }
        cur = xs;
        let mut prev = xs;
        let dir = if psi_end >= cur[1] { 1.0 } else { -1.0 };
        let mut h: f64 = 2e-3;
        let mut last_step = 0.0_f64;
        let mut guard = 0;
        while (psi_end - cur[1]) * dir > 1e-12 {
            guard += 1;
            if guard > 20_000 {
                break;
            }
            let step = (h * dir).clamp(-(psi_end - cur[1]).abs(), (psi_end - cur[1]).abs());
            let target = cur[1] + step;
            let mut guess = cur;
            if last_step != 0.0 {
                let f = step / last_step;
                for k in 0..3 {
                    guess[k] = cur[k] + f * (cur[k] - prev[k]);
                }
            }
            guess[1] = target;
            match self.newton(dt, Control::ContactAngle(target), guess) {
                Ok((x, it)) => {
                    prev = cur;
                    cur = x;
                    last_step = step;
                    if it <= 3 {
                        h = (h * 2.0).min(0.1);
                    } else if it <= 5 {
                        h = (h * 1.3).min(0.1);
                    }
                    let mut sh =
                        Shooter::new(&self.material, &self.states, self.uniform, dt, self.scale)
                            .compression(self.allow_compression_in_contact);
                    if let Ok(end) = sh.shoot(cur[0], cur[1], cur[2], None)
                        && stop(&cur, &end)
                    {
                        return Ok((prev, cur));
                    }
                }
                Err(e) => {
                    self.jac = None;
                    h *= 0.25;
                    if h < 1e-6 {
                        return Err(e);
                    }
                }
            }
        }
        Ok((prev, cur))
    }

    fn build_solution(
        &self,
        time: f64,
        dt: f64,
        x: [f64; 3],
        control: Control,
        iterations: usize,
    ) -> Result<Solution> {
        let mut sh = Shooter::new(&self.material, &self.states, self.uniform, dt, self.scale)
            .compression(self.allow_compression_in_contact);
        let psi_c = if control.touches() { x[1] } else { 0.0 };
        let mut prof = Vec::with_capacity(self.geometry.nodes + 1);
        let end = sh
            .shoot(x[0], psi_c, x[2], Some(&mut prof))
            .map_err(|f| self.fail_to_error(time, control, NewtonFail::Shot(f)))?;
        let force = if control.touches() {
            PI * end.contact_radius * end.contact_radius * x[2]
        } else {
            0.0
        };
        let min_tension = prof
            .iter()
            .fold(f64::INFINITY, |m, v| m.min(v.t1).min(v.t2));
        Ok(Solution {
            record: StepRecord {
                time,
                displacement: self.detached.unwrap_or(self.geometry.rs - end.h1),
                h1: end.h1,
                force,
                pressure: x[2],
                psi_c,
                lambda0: x[0],
                contact_radius: end.contact_radius,
                equator_radius: end.rho_equator,
                min_tension,
            },
            t1_equator: end.t1_equator,
            volume: end.volume,
            iterations,
            profile: prof,
        })
    }

    fn dt_to(&self, t: f64) -> Result<f64> {
        match self.time {
            None => Ok(0.0),
            Some(tn) if t > tn => Ok(t - tn),
            Some(tn) => Err(MembraneError::Input {
                name: "time",
                value: t,
                reason: format!("times must increase; the last step was at t = {tn}"),
            }),
        }
    }

    /// Equilibrium at time `t` for `control` with the histories held at the
    /// last committed step, without committing (elastic sweeps, trial loads).
    ///
    /// # Errors
    /// As [`Self::advance`].
    pub fn equilibrium(&mut self, t: f64, control: Control) -> Result<Solution> {
        let dt = if self.time.is_none() {
            0.0
        } else {
            self.dt_to(t)?
        };
        let (x, it, c) = self.solve_with_continuation(t, dt, control)?;
        self.x = x;
        self.last_control = c;
        self.build_solution(t, dt, x, c, it)
    }

    /// Solve at time `t` (> last committed time; the first call is the
    /// instantaneous response, dt = 0) and commit the node histories.
    ///
    /// # Errors
    /// [`MembraneError::Wrinkling`] when a principal tension turns
    /// non-positive; [`MembraneError::NoConvergence`] when Newton fails even
    /// after bisecting the control increment; [`MembraneError::Input`] when
    /// `t` does not increase.
    pub fn advance(&mut self, t: f64, control: Control) -> Result<Solution> {
        let dt = self.dt_to(t)?;
        // Secant predictor in time (§2.3.3 uses the last solution as the guess).
        self.predicted = match self.x_prev {
            Some((xp, dtp))
                if dtp > 0.0
                    && dt > 0.0
                    && std::mem::discriminant(&control)
                        == std::mem::discriminant(&self.last_control) =>
            {
                let f = (dt / dtp).min(2.0);
                Some([0, 1, 2].map(|k| self.x[k] + f * (self.x[k] - xp[k])))
            }
            _ => None,
        };
        let solved = self.solve_with_continuation(t, dt, control);
        self.predicted = None;
        let (x, it, c) = solved?;
        let sol = self.build_solution(t, dt, x, c, it)?;
        for (j, v) in sol.profile.iter().enumerate() {
            self.material
                .update(
                    &self.states[j],
                    [v.lambda1, v.lambda2],
                    dt,
                    &mut self.trial[j],
                )
                .map_err(|e| MembraneError::Material {
                    psi: v.psi,
                    time: t,
                    source: e,
                })?;
        }
        std::mem::swap(&mut self.states, &mut self.trial);
        let p0 = sol.profile[0];
        self.uniform = self.uniform
            && sol.profile.iter().all(|v| {
                (v.lambda1 - p0.lambda1).abs() <= 1e-13 * p0.lambda1
                    && (v.lambda2 - p0.lambda2).abs() <= 1e-13 * p0.lambda2
            });
        self.time = Some(t);
        self.x_prev = Some((self.x, dt));
        self.x = x;
        self.last_control = c;
        Ok(sol)
    }
}
