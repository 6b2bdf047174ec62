//! Probe geometries of elastic indentation: force on a rigid axisymmetric (or pyramidal)
//! probe pressed a depth δ into an elastic half-space of Young's modulus E and Poisson
//! ratio ν (thesis eq. 1.1–1.3 for the paraboloid; Sneddon 1965 for the others).
//!
//! Every model is `F = E/(1 − ν²) · shape(δ)`, linear in the reduced modulus
//! E* = E/(1 − ν²) (eq. 1.3, rigid probe), which is what lets the fit profile E out
//! analytically for each trial contact point ([`crate::fit_hertz`]).
//!
//! | indenter | shape(δ) | source |
//! |---|---|---|
//! | paraboloid, radius R | (4/3) √R δ^{3/2} | eq. 1.1; Sneddon (1965) eq. 6.9 |
//! | sphere, radius R (exact) | R²[(1 + u²) artanh u − u], δ = R u artanh u, u = a/R | Sneddon (1965) eqs. 6.13, 6.15 |
//! | cone, half-opening angle α | (2/π) tan α δ² | Sneddon (1965) eq. 6.4 |
//! | four-sided pyramid, face angle α | (tan α/√2) δ² | Bilodeau (1992), as used by Rico et al. (2005) |
//! | flat punch, radius a | 2 a δ | Sneddon (1965) |
//!
//! The exact sphere is written with u = a/R, a the contact radius:
//! `(R + a)/(R − a) = (1 + u)/(1 − u)` and `½ ln((1 + u)/(1 − u)) = artanh u`, so
//! Sneddon's `δ = (a/2) ln((R + a)/(R − a))` and `F = E*[(R² + a²)/2 · ln((R + a)/(R − a)) − aR]`
//! become the table's forms.

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_2_PI};

use crate::error::{AfmError, Result};

/// A rigid probe geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Indenter {
    /// Paraboloid of apex radius R (m): Hertz, eq. 1.1. Approximates a sphere for δ ≪ R.
    Paraboloid {
        /// Apex radius R, m.
        radius: f64,
    },
    /// Sphere of radius R (m), Sneddon's exact solution (any contact radius a < R).
    Sphere {
        /// Sphere radius R, m.
        radius: f64,
    },
    /// Cone of half-opening angle α (rad, between axis and flank).
    Cone {
        /// Half-opening angle α, rad.
        half_angle: f64,
    },
    /// Regular four-sided pyramid of face angle α (rad, between axis and face).
    Pyramid {
        /// Face angle α, rad.
        face_angle: f64,
    },
    /// Flat cylindrical punch of radius a (m).
    FlatPunch {
        /// Punch radius a, m.
        radius: f64,
    },
}

/// Ratio δ/R below which a model is considered valid, where it has one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Validity {
    /// The length δ is compared with (R), m.
    pub length: f64,
    /// Largest δ/length inside the model's validity.
    pub max_ratio: f64,
    /// What breaks beyond it.
    pub reason: &'static str,
}

impl Indenter {
    /// Short name, as in result tables (`paraboloid`, `sphere`, `cone`, `pyramid`, `flat-punch`).
    pub fn name(&self) -> &'static str {
        match self {
            Indenter::Paraboloid { .. } => "paraboloid",
            Indenter::Sphere { .. } => "sphere",
            Indenter::Cone { .. } => "cone",
            Indenter::Pyramid { .. } => "pyramid",
            Indenter::FlatPunch { .. } => "flat-punch",
        }
    }

    /// Check the geometry: radii positive and finite, angles in (0, π/2).
    ///
    /// # Errors
    /// [`AfmError::InvalidInput`] naming the bad parameter.
    pub fn check(&self) -> Result<()> {
        let (what, v, ok) = match *self {
            Indenter::Paraboloid { radius }
            | Indenter::Sphere { radius }
            | Indenter::FlatPunch { radius } => {
                ("radius (m)", radius, radius.is_finite() && radius > 0.0)
            }
            Indenter::Cone { half_angle: a } | Indenter::Pyramid { face_angle: a } => (
                "angle (rad)",
                a,
                a.is_finite() && a > 0.0 && a < std::f64::consts::FRAC_PI_2,
            ),
        };
        if ok {
            Ok(())
        } else {
            Err(AfmError::InvalidInput(format!(
                "{} indenter: {what} must be positive{}, got {v}",
                self.name(),
                if what.starts_with("angle") {
                    " and below π/2"
                } else {
                    ""
                }
            )))
        }
    }

    /// `shape(δ) = F/E*` (m² for δ in m): the force per unit reduced modulus; 0 for δ ≤ 0.
    pub fn shape(&self, delta: f64) -> f64 {
        if delta.is_nan() || delta <= 0.0 {
            return 0.0;
        }
        match *self {
            Indenter::Paraboloid { radius } => 4.0 / 3.0 * radius.sqrt() * delta * delta.sqrt(),
            Indenter::Sphere { radius } => {
                let u = sphere_contact_ratio(delta / radius);
                radius * radius * sphere_force_kernel(u)
            }
            Indenter::Cone { half_angle } => FRAC_2_PI * half_angle.tan() * delta * delta,
            Indenter::Pyramid { face_angle } => FRAC_1_SQRT_2 * face_angle.tan() * delta * delta,
            Indenter::FlatPunch { radius } => 2.0 * radius * delta,
        }
    }

    /// Force (N) at indentation `delta` (m) on a half-space of Young's modulus `e` (Pa)
    /// and Poisson ratio `nu`: `E/(1 − ν²) · shape(δ)`; 0 for δ ≤ 0.
    pub fn force(&self, delta: f64, e: f64, nu: f64) -> f64 {
        e / (1.0 - nu * nu) * self.shape(delta)
    }

    /// Contact radius a (m) at indentation `delta`, where the model defines one.
    pub fn contact_radius(&self, delta: f64) -> Option<f64> {
        let d = delta.max(0.0);
        match *self {
            Indenter::Paraboloid { radius } => Some((radius * d).sqrt()),
            Indenter::Sphere { radius } => Some(radius * sphere_contact_ratio(d / radius)),
            Indenter::Cone { half_angle } => {
                Some(2.0 / std::f64::consts::PI * half_angle.tan() * d)
            }
            Indenter::Pyramid { .. } => None,
            Indenter::FlatPunch { radius } => Some(radius),
        }
    }

    /// The depth range inside which the model holds, where it has one: the paraboloid
    /// stands for a sphere only while δ/R ≤ 0.1 (the exact sphere's force is then within
    /// 1 %); the exact sphere while δ/R ≤ 1 (contact radius ≤ 0.83 R, the probe's
    /// lower half). Cones, pyramids and punches have no length scale here.
    pub fn validity(&self) -> Option<Validity> {
        match *self {
            Indenter::Paraboloid { radius } => Some(Validity {
                length: radius,
                max_ratio: 0.1,
                reason: "a paraboloid stands for a sphere only while δ ≪ R (1 % at δ/R = 0.1); use the sphere model",
            }),
            Indenter::Sphere { radius } => Some(Validity {
                length: radius,
                max_ratio: 1.0,
                reason: "the contact then reaches beyond the lower half of the bead",
            }),
            _ => None,
        }
    }
}

/// Thesis eq. 1.1: force of a paraboloidal probe of radius `r` indenting by `delta` a
/// half-space of Young's modulus `e` and Poisson ratio `nu` (eq. 1.3); zero for δ ≤ 0.
pub fn hertz_force(delta: f64, e: f64, r: f64, nu: f64) -> f64 {
    Indenter::Paraboloid { radius: r }.force(delta, e, nu)
}

/// `(1 + u²) artanh u − u`, the exact sphere's force over E*R² (series for small u,
/// where the closed form cancels).
fn sphere_force_kernel(u: f64) -> f64 {
    if u < 0.1 {
        // Σ_{k≥1} 4k/(4k² − 1) u^{2k+1}; ratio of terms ≤ u² = 0.01, 10 terms < 1e-20.
        let u2 = u * u;
        let mut term = u * u2;
        let mut sum = 0.0;
        for k in 1..=10 {
            let k = f64::from(k);
            sum += 4.0 * k / (4.0 * k * k - 1.0) * term;
            term *= u2;
        }
        sum
    } else {
        (1.0 + u * u) * u.atanh() - u
    }
}

/// Contact radius over sphere radius, u = a/R, at relative depth d = δ/R: the root of
/// `u artanh u = d` in [0, 1) (Sneddon eq. 6.13), by safeguarded Newton.
fn sphere_contact_ratio(d: f64) -> f64 {
    if d.is_nan() || d <= 0.0 {
        return 0.0;
    }
    // f(u) = u artanh u − d is increasing and convex on [0, 1): Newton from the right of
    // the root converges monotonically. u artanh u ≥ u², so √d lies right of the root.
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let mut u = d.sqrt().min(1.0 - 1e-12);
    for _ in 0..200 {
        let f = u * u.atanh() - d;
        if f > 0.0 {
            hi = u;
        } else {
            lo = u;
        }
        let df = u.atanh() + u / (1.0 - u * u);
        let mut next = u - f / df;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - u).abs() <= 1e-15 * u {
            return next;
        }
        u = next;
    }
    u
}
