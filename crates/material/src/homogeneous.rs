//! Homogeneous deformations of an incompressible material under a loading
//! history: uniaxial tension/compression, equibiaxial extension and simple
//! shear (the verification cases of App. D.3).
//!
//! The material is exactly incompressible ([`Incompressible`]): the
//! deformation gradient is
//! - uniaxial `F = diag(λ, λ^{-1/2}, λ^{-1/2})`, lateral faces traction
//!   free: `σ22 = σ33 = 0` fixes the pressure `q`;
//! - equibiaxial `F = diag(λ, λ, λ^{-2})`, `σ33 = 0`;
//! - simple shear `F = I + γ e1⊗e2`, `σ33 = 0` (plane stress normal to the
//!   shear plane; `N1 = σ11 − σ22`, `N2 = σ22 − σ33` do not depend on it).
//!
//! The history is piecewise linear in time between knots; a jump is two knots
//! at the same time and is applied as a step with `dt = 0` (instantaneous
//! response), so step histories are represented exactly.

use crate::{Incompressible, Mat3, MaterialError, Result};

/// Which homogeneous deformation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Uniaxial stress, stretch λ along 1.
    Uniaxial,
    /// Equibiaxial stress, stretch λ along 1 and 2.
    Equibiaxial,
    /// Simple shear γ in the 1–2 plane.
    SimpleShear,
}

impl Mode {
    /// Name as written in study files (`uniaxial`, `equibiaxial`, `simple-shear`).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Uniaxial => "uniaxial",
            Mode::Equibiaxial => "equibiaxial",
            Mode::SimpleShear => "simple-shear",
        }
    }

    /// The undeformed value of the controlled quantity (λ = 1, γ = 0).
    pub fn rest_value(self) -> f64 {
        match self {
            Mode::SimpleShear => 0.0,
            _ => 1.0,
        }
    }

    /// Deformation gradient for stretch/shear `v`.
    pub fn deformation_gradient(self, v: f64) -> Mat3 {
        match self {
            Mode::Uniaxial => {
                let l = 1.0 / v.sqrt();
                Mat3::new(v, 0.0, 0.0, 0.0, l, 0.0, 0.0, 0.0, l)
            }
            Mode::Equibiaxial => Mat3::new(v, 0.0, 0.0, 0.0, v, 0.0, 0.0, 0.0, 1.0 / (v * v)),
            Mode::SimpleShear => Mat3::new(1.0, v, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        }
    }
}

/// A loading history of the controlled stretch λ (or shear γ).
#[derive(Debug, Clone, PartialEq)]
pub enum History {
    /// Jump at t = 0 to `value`, held for `hold` seconds.
    Step {
        /// Stretch or shear after the jump.
        value: f64,
        /// Hold duration in s.
        hold: f64,
    },
    /// Linear ramp to `value` over `ramp` s, then held for `hold` s.
    RampHold {
        /// Peak stretch or shear.
        value: f64,
        /// Ramp duration in s (> 0).
        ramp: f64,
        /// Hold duration in s (≥ 0).
        hold: f64,
    },
    /// Linear ramp to `value` over `ramp` s and back to rest at the same
    /// rate (total `2·ramp`).
    RampReverse {
        /// Peak stretch or shear.
        value: f64,
        /// Duration of each ramp in s (> 0).
        ramp: f64,
    },
    /// Piecewise-linear table of `(time_s, value)`, times non-decreasing and
    /// ≥ 0; a repeated time is a jump. If it does not start at
    /// `(0, rest value)` that point is prepended.
    Table(Vec<(f64, f64)>),
}

/// The most time steps one drive may take (about 110 MB of samples and
/// 150 MB of CSV); a history and `max_dt` needing more are refused before
/// any step with [`check_step_count`].
pub const MAX_STEPS: f64 = 1e6;

/// Time steps a drive through `knots` takes with steps no longer than
/// `max_dt` (each linear piece split evenly, a jump one step).
pub fn step_count(knots: &[(f64, f64)], max_dt: f64) -> f64 {
    knots
        .windows(2)
        .map(|w| {
            let len = w[1].0 - w[0].0;
            if len > 0.0 {
                (len / max_dt).ceil().max(1.0)
            } else {
                1.0
            }
        })
        .sum()
}

/// The time steps of a drive through `knots` (time, value): each linear
/// piece split evenly into steps no longer than `max_dt`, a jump applied
/// in one step of `dt = 0`; `(t, value)` at the end of each step.
fn steps(knots: &[(f64, f64)], max_dt: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
    knots.windows(2).flat_map(move |w| {
        let ((t0, v0), (t1, v1)) = (w[0], w[1]);
        let len = t1 - t0;
        let n = if len > 0.0 {
            (len / max_dt).ceil().max(1.0) as usize
        } else {
            1
        };
        (1..=n).map(move |i| {
            let s = i as f64 / n as f64;
            let t = if i == n { t1 } else { t0 + s * len };
            (t, v0 + s * (v1 - v0))
        })
    })
}

/// Refuses a drive of more than [`MAX_STEPS`] steps, with the estimate,
/// the memory it would need and the `max_dt` that fits.
///
/// # Errors
/// [`MaterialError::Loading`] naming the estimate and the setting.
pub fn check_step_count(knots: &[(f64, f64)], max_dt: f64) -> Result<()> {
    let n = step_count(knots, max_dt);
    if n <= MAX_STEPS {
        return Ok(());
    }
    let total = knots.last().map_or(0.0, |k| k.0) - knots.first().map_or(0.0, |k| k.0);
    let bytes = n * std::mem::size_of::<Sample>() as f64;
    Err(MaterialError::Loading(format!(
        "max_dt = {max_dt:e} s needs {n:.3e} time steps (≈ {:.1} GB of samples); the limit is \
         {MAX_STEPS:.0e}: raise max_dt to at least {:.3e} s",
        bytes / 1e9,
        total / (MAX_STEPS - knots.len() as f64).max(1.0)
    )))
}

fn positive(name: &str, x: f64) -> Result<()> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(MaterialError::Loading(format!(
            "`{name}` = {x} must be finite and > 0"
        )))
    }
}

fn non_negative(name: &str, x: f64) -> Result<()> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(MaterialError::Loading(format!(
            "`{name}` = {x} must be finite and ≥ 0"
        )))
    }
}

impl History {
    /// Knots `(t, value)` of the piecewise-linear history, starting at
    /// `(0, rest)`, checked for `mode`.
    ///
    /// # Errors
    /// [`MaterialError::Loading`] naming the field or table row.
    pub fn knots(&self, mode: Mode) -> Result<Vec<(f64, f64)>> {
        let r = mode.rest_value();
        let knots = match self {
            History::Step { value, hold } => {
                non_negative("hold", *hold)?;
                vec![(0.0, r), (0.0, *value), (*hold, *value)]
            }
            History::RampHold { value, ramp, hold } => {
                positive("ramp", *ramp)?;
                non_negative("hold", *hold)?;
                vec![(0.0, r), (*ramp, *value), (ramp + hold, *value)]
            }
            History::RampReverse { value, ramp } => {
                positive("ramp", *ramp)?;
                vec![(0.0, r), (*ramp, *value), (2.0 * ramp, r)]
            }
            History::Table(rows) => {
                if rows.is_empty() {
                    return Err(MaterialError::Loading("the table has no rows".into()));
                }
                let mut k = Vec::with_capacity(rows.len() + 1);
                if rows[0] != (0.0, r) {
                    k.push((0.0, r));
                }
                let mut last = 0.0;
                for (i, &(t, v)) in rows.iter().enumerate() {
                    if !t.is_finite() || t < last {
                        return Err(MaterialError::Loading(format!(
                            "table row {}: time {t} s must be finite, ≥ 0 and not \
                             before the previous row ({last} s)",
                            i + 1
                        )));
                    }
                    if !v.is_finite() {
                        return Err(MaterialError::Loading(format!(
                            "table row {}: value {v} is not finite",
                            i + 1
                        )));
                    }
                    last = t;
                    k.push((t, v));
                }
                k
            }
        };
        for (i, &(_, v)) in knots.iter().enumerate() {
            if !v.is_finite() || (mode != Mode::SimpleShear && v <= 0.0) {
                return Err(MaterialError::Loading(format!(
                    "value {v} at knot {} is inadmissible: a stretch must be finite and > 0, \
                     a shear finite",
                    i + 1
                )));
            }
        }
        Ok(knots)
    }
}

/// One output point of a homogeneous test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time in s.
    pub time: f64,
    /// Stretch λ or shear γ.
    pub value: f64,
    /// Full Cauchy stress in Pa with the boundary conditions of [`Mode`].
    pub cauchy: Mat3,
    /// Principal Cauchy stresses in Pa: `[σ11, σ22, σ33]` for uniaxial and
    /// equibiaxial, the in-plane eigenvalues (larger first) and σ33 = 0 for
    /// simple shear.
    pub principal: [f64; 3],
}

/// Drives `material` through `history` in `mode`, with time steps no
/// longer than `max_dt` (each linear piece is split evenly; jumps are
/// applied with `dt = 0`). Returns one [`Sample`] per time point, starting
/// with the undeformed state at t = 0 (a jump at t = 0 therefore gives two
/// samples at t = 0: before and after).
///
/// # Errors
/// [`MaterialError::Loading`] for a bad history or `max_dt`; any error of
/// the material update, with the time at which it happened.
pub fn drive<M: Incompressible>(
    material: &M,
    mode: Mode,
    history: &History,
    max_dt: f64,
) -> Result<Vec<Sample>> {
    positive("max_dt", max_dt)?;
    let knots = history.knots(mode)?;
    check_step_count(&knots, max_dt)?;
    let mut state = material.initial_state();
    let mut trial = state.clone();
    let mut out = Vec::new();
    let mut push = |time: f64, value: f64, t: &Mat3| {
        let cauchy = boundary_stress(mode, t);
        out.push(Sample {
            time,
            value,
            cauchy,
            principal: principal(mode, &cauchy),
        });
    };
    push(0.0, knots[0].1, &Mat3::zeros());
    let mut t_n = 0.0;
    for (t, v) in steps(&knots, max_dt) {
        let f = mode.deformation_gradient(v);
        let extra = material
            .extra_stress(&state, &f, t - t_n, &mut trial)
            .map_err(|e| MaterialError::Loading(format!("at t = {t} s, value {v}: {e}")))?;
        std::mem::swap(&mut state, &mut trial);
        t_n = t;
        push(t, v, &extra);
    }
    Ok(out)
}

/// Cauchy stress `T − q I` with `q` from the traction-free faces of `mode`.
fn boundary_stress(mode: Mode, t: &Mat3) -> Mat3 {
    let q = match mode {
        Mode::Uniaxial => 0.5 * (t[(1, 1)] + t[(2, 2)]),
        Mode::Equibiaxial | Mode::SimpleShear => t[(2, 2)],
    };
    let mut s = t - Mat3::identity() * q;
    if mode == Mode::Uniaxial {
        // σ22 = σ33 = 0 exactly (they agree up to rounding by symmetry).
        s[(1, 1)] = 0.0;
        s[(2, 2)] = 0.0;
    } else {
        s[(2, 2)] = 0.0;
    }
    s
}

/// Principal stresses: the axis values `[σ11, σ22, σ33]` for uniaxial and
/// equibiaxial (the axes are principal), the 1–2 block's eigenvalues
/// (larger first) and σ33 for simple shear.
fn principal(mode: Mode, s: &Mat3) -> [f64; 3] {
    if mode != Mode::SimpleShear {
        return [s[(0, 0)], s[(1, 1)], s[(2, 2)]];
    }
    let (a, b, c) = (s[(0, 0)], s[(1, 1)], s[(0, 1)]);
    let m = 0.5 * (a + b);
    let r = (0.25 * (a - b) * (a - b) + c * c).sqrt();
    [m + r, m - r, s[(2, 2)]]
}

/// Uniaxial tension of a compressible (penalty) [`crate::Material3`]: at each
/// step the lateral stretch μ of `F = diag(λ, μ, μ)` is found by Newton's
/// method on `P22(μ) = 0` (traction-free lateral faces) with the consistent
/// tangent `∂P22/∂F22 + ∂P22/∂F33`. Returns `(time, λ, μ, σ11)` per step,
/// starting from the undeformed state. This is the check that a 3D point
/// update used by finite elements reproduces the incompressible response
/// of [`drive`] as the penalty grows.
///
/// # Errors
/// [`MaterialError::Loading`] for a bad history, or when Newton does not
/// reach `|P22| ≤ 1e-10·max(|P11|, 1 Pa)` in 50 iterations (the message
/// gives the time and residual: reduce `max_dt`).
pub fn drive_uniaxial_3d<M: crate::Material3>(
    material: &M,
    history: &History,
    max_dt: f64,
) -> Result<Vec<[f64; 4]>> {
    positive("max_dt", max_dt)?;
    let knots = history.knots(Mode::Uniaxial)?;
    check_step_count(&knots, max_dt)?;
    let mut state = material.initial_state();
    let mut trial = state.clone();
    let mut out = vec![[0.0, knots[0].1, 1.0, 0.0]];
    let (mut t_n, mut mu) = (0.0, 1.0);
    for (t, l) in steps(&knots, max_dt) {
        let dt = t - t_n;
        // Start from the incompressible guess when the stretch jumps.
        if (mu * mu * l - 1.0).abs() > 0.1 {
            mu = 1.0 / l.sqrt();
        }
        let mut converged = None;
        for _ in 0..50 {
            let f = Mat3::from_diagonal(&nalgebra::Vector3::new(l, mu, mu));
            let r = material.update(&state, &f, dt, &mut trial)?;
            let p22 = r.first_piola[(1, 1)];
            if p22.abs() <= 1e-10 * r.first_piola[(0, 0)].abs().max(1.0) {
                converged = Some(r.cauchy[(0, 0)]);
                break;
            }
            let d = r.tangent[(4, 4)] + r.tangent[(4, 8)];
            let step = p22 / d;
            if !step.is_finite() {
                break;
            }
            // Keep μ positive: at most halve it per iteration.
            mu = (mu - step).max(0.5 * mu);
        }
        let s11 = converged.ok_or_else(|| {
            MaterialError::Loading(format!(
                "lateral traction did not vanish at t = {t} s (λ = {l}, μ = {mu}) \
                 within 50 Newton iterations; reduce max_dt"
            ))
        })?;
        std::mem::swap(&mut state, &mut trial);
        t_n = t;
        out.push([t, l, mu, s11]);
    }
    Ok(out)
}
