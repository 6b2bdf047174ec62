//! One shot from the crown to the equator for assumed (λ0, ψc, p): the
//! first-order system of §2.3.2 integrated by RK4 on the fixed grid of
//! material nodes ψj = j π/(2N), the step containing ψc split at ψc.
//!
//! State y = (T1, λ2, θ, η, V) with T = σ λ3 (dimensionless T/(G10 h0),
//! eq. 2.27), θ the angle of the normal to the axis (eq. 2.29, w = λ1 cos θ),
//! η the accumulated height drop ∫ λ1 sin θ dψ (eq. 2.43) and V the
//! accumulated volume 2π ∫ ρ² λ1 sin θ dψ (eq. 2.46):
//!
//! - T1' = −(T1 − T2) w/(λ2 sin ψ)            (eq. 2.33)
//! - λ2' = (w − λ2 cos ψ)/sin ψ               (eq. 2.31/2.36)
//! - θ'  = λ1 (p − T2 sin θ/(λ2 sin ψ))/T1    (eq. 2.26/2.34), θ ≡ 0 in contact
//!
//! λ1 is recovered from T1 by inverting the point update at fixed λ2 and
//! history, so the ψ-derivative of the history (the F̂2 term of eq. 2.35)
//! never has to be formed. Between nodes the stresses of the two adjacent
//! nodes' histories are blended linearly at the same current stretches.

use nlvid_material::MembraneMaterial;

/// Why a shot could not reach the equator.
#[derive(Debug, Clone)]
#[allow(dead_code)] // fields are read through Debug in error messages
pub(crate) enum ShotFail {
    /// A principal tension is not positive (wrinkling).
    Tension {
        psi: f64,
        which: &'static str,
        value: f64,
    },
    /// λ1 could not be recovered from T1, or values became non-finite.
    Breakdown { psi: f64, what: &'static str },
    /// The material point update failed.
    Material { psi: f64, err: String },
}

/// Values at a material node of a converged shot.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct NodeValue {
    /// Reference angle ψ (rad).
    pub psi: f64,
    /// Meridional stretch λ1.
    pub lambda1: f64,
    /// Circumferential stretch λ2.
    pub lambda2: f64,
    /// Meridional Cauchy stress σ1/G10.
    pub sigma1: f64,
    /// Circumferential Cauchy stress σ2/G10.
    pub sigma2: f64,
    /// Meridional tension T1/(G10 h0).
    pub t1: f64,
    /// Circumferential tension T2/(G10 h0).
    pub t2: f64,
    /// Angle θ of the normal with the axis (rad).
    pub theta: f64,
    /// Radius ρ/r0.
    pub rho: f64,
    /// Height η/r0 above the equatorial plane.
    pub eta: f64,
}

/// End values of a shot.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ShotEnd {
    pub theta_end: f64,
    pub h1: f64,
    pub volume: f64,
    pub contact_radius: f64,
    pub t1_equator: f64,
    pub rho_equator: f64,
}

pub(crate) struct Shooter<'a, M: MembraneMaterial> {
    pub mat: &'a M,
    pub states: &'a [M::State],
    pub uniform: bool,
    pub dt: f64,
    pub scale: f64,
    pub scratch: M::State,
    /// Accept non-positive tensions in the flat contact region (see
    /// [`crate::MembraneSolver::allow_compression_in_contact`]).
    pub allow_compression_in_contact: bool,
    lam1_guess: f64,
}

const Y: usize = 5;

impl<'a, M: MembraneMaterial> Shooter<'a, M> {
    pub fn new(mat: &'a M, states: &'a [M::State], uniform: bool, dt: f64, scale: f64) -> Self {
        Self {
            mat,
            states,
            uniform,
            dt,
            scale,
            scratch: mat.initial_state(),
            allow_compression_in_contact: false,
            lam1_guess: 1.0,
        }
    }

    /// Sets [`Self::allow_compression_in_contact`].
    pub fn compression(mut self, allow: bool) -> Self {
        self.allow_compression_in_contact = allow;
        self
    }

    fn intervals(&self) -> usize {
        self.states.len() - 1
    }

    fn dpsi(&self) -> f64 {
        std::f64::consts::FRAC_PI_2 / self.intervals() as f64
    }

    fn eval_node(&mut self, j: usize, l: [f64; 2], psi: f64) -> Result<([f64; 2], f64), ShotFail> {
        let r = self
            .mat
            .update(&self.states[j], l, self.dt, &mut self.scratch)
            .map_err(|e| ShotFail::Material {
                psi,
                err: e.to_string(),
            })?;
        let s = 1.0 / self.scale;
        Ok(([r.cauchy[0] * s, r.cauchy[1] * s], r.tangent[0][0] * s))
    }

    /// Dimensionless σ1, σ2 and ∂σ1/∂λ1 at ψ for current stretches `l`.
    pub fn stress(&mut self, psi: f64, l: [f64; 2]) -> Result<([f64; 2], f64), ShotFail> {
        if self.uniform {
            return self.eval_node(0, l, psi);
        }
        let n = self.intervals();
        let x = psi / self.dpsi();
        let j = (x.floor() as usize).min(n - 1);
        let w = x - j as f64;
        if w <= 1e-12 {
            return self.eval_node(j, l, psi);
        }
        if w >= 1.0 - 1e-12 {
            return self.eval_node(j + 1, l, psi);
        }
        let (sa, da) = self.eval_node(j, l, psi)?;
        let (sb, db) = self.eval_node(j + 1, l, psi)?;
        Ok((
            [(1.0 - w) * sa[0] + w * sb[0], (1.0 - w) * sa[1] + w * sb[1]],
            (1.0 - w) * da + w * db,
        ))
    }

    /// λ1 with T1(λ1, λ2) = t1 at ψ; returns (λ1, σ1, σ2).
    fn invert(
        &mut self,
        psi: f64,
        t1: f64,
        l2: f64,
        contact: bool,
    ) -> Result<(f64, [f64; 2]), ShotFail> {
        let compression_ok = contact && self.allow_compression_in_contact;
        let admissible = t1 > 0.0 || (compression_ok && t1.is_finite());
        if !admissible {
            return Err(ShotFail::Tension {
                psi,
                which: "T1",
                value: t1,
            });
        }
        let mut l1 = if self.lam1_guess > 0.0 {
            self.lam1_guess
        } else {
            l2
        };
        for _ in 0..60 {
            let (s, ds1) = self.stress(psi, [l1, l2])?;
            let f = s[0] / (l1 * l2) - t1;
            if f.abs() <= 1e-13 * t1.abs() {
                self.lam1_guess = l1;
                return Ok((l1, s));
            }
            let fp = (ds1 - s[0] / l1) / (l1 * l2);
            if !(fp > 0.0) || !f.is_finite() {
                return Err(ShotFail::Breakdown {
                    psi,
                    what: "meridional tension is not increasing with λ1 (cannot recover λ1 from T1)",
                });
            }
            let step = f / fp;
            // As T1 → 0 the relative test above asks for more than rounding
            // allows (σ1 is a difference of O(1) terms): a Newton step below
            // 1e-13 λ1 is convergence too.
            if step.abs() <= 1e-13 * l1 {
                self.lam1_guess = l1;
                return Ok((l1, s));
            }
            l1 = (l1 - step).max(0.5 * l1).min(2.0 * l1);
        }
        Err(ShotFail::Breakdown {
            psi,
            what: "Newton for λ1 from T1 did not converge",
        })
    }

    fn rhs(&mut self, psi: f64, y: &[f64; Y], p: f64, contact: bool) -> Result<[f64; Y], ShotFail> {
        let [t1, l2, theta, _, _] = *y;
        if !(l2 > 0.0) || !y.iter().all(|v| v.is_finite()) {
            return Err(ShotFail::Breakdown {
                psi,
                what: "circumferential stretch or state became non-positive/non-finite",
            });
        }
        let (l1, s) = self.invert(psi, t1, l2, contact)?;
        let t2 = s[1] / (l1 * l2);
        let admissible = t2 > 0.0 || (contact && self.allow_compression_in_contact);
        if !admissible {
            return Err(ShotFail::Tension {
                psi,
                which: "T2",
                value: t2,
            });
        }
        if psi <= 1e-14 {
            // Crown limits (eqs. 2.40–2.41): λ1 = λ2, all slopes zero, curvature p/(2T).
            let dth = if contact { 0.0 } else { 0.5 * l1 * p / t1 };
            return Ok([0.0, 0.0, dth, 0.0, 0.0]);
        }
        let (sp, cp) = psi.sin_cos();
        let (st, ct) = if contact { (0.0, 1.0) } else { theta.sin_cos() };
        let w = l1 * ct;
        let rho = l2 * sp;
        let dt1 = -(t1 - t2) * w / rho;
        let dl2 = (w - l2 * cp) / sp;
        let dth = if contact {
            0.0
        } else {
            l1 * (p - t2 * st / rho) / t1
        };
        let deta = l1 * st;
        let dv = 2.0 * std::f64::consts::PI * rho * rho * l1 * st;
        Ok([dt1, dl2, dth, deta, dv])
    }

    fn rk4(
        &mut self,
        a: f64,
        b: f64,
        y: &mut [f64; Y],
        p: f64,
        contact: bool,
    ) -> Result<(), ShotFail> {
        let h = b - a;
        if h <= 0.0 {
            return Ok(());
        }
        let add = |y: &[f64; Y], k: &[f64; Y], s: f64| {
            let mut o = *y;
            for i in 0..Y {
                o[i] += s * k[i];
            }
            o
        };
        let k1 = self.rhs(a, y, p, contact)?;
        let k2 = self.rhs(a + 0.5 * h, &add(y, &k1, 0.5 * h), p, contact)?;
        let k3 = self.rhs(a + 0.5 * h, &add(y, &k2, 0.5 * h), p, contact)?;
        let k4 = self.rhs(b, &add(y, &k3, h), p, contact)?;
        for i in 0..Y {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        Ok(())
    }

    fn node_value(&mut self, psi: f64, y: &[f64; Y], contact: bool) -> Result<NodeValue, ShotFail> {
        let (l1, s) = self.invert(psi, y[0], y[1], contact)?;
        Ok(NodeValue {
            psi,
            lambda1: l1,
            lambda2: y[1],
            sigma1: s[0],
            sigma2: s[1],
            t1: y[0],
            t2: s[1] / (l1 * y[1]),
            theta: if contact { 0.0 } else { y[2] },
            rho: y[1] * psi.sin(),
            eta: y[3], // accumulated; turned into height by the caller
        })
    }

    /// Integrate from the crown to the equator. With `record`, the node
    /// values at ψ0..ψN are pushed (η as height above the equator).
    pub fn shoot(
        &mut self,
        lambda0: f64,
        psi_c: f64,
        p: f64,
        mut record: Option<&mut Vec<NodeValue>>,
    ) -> Result<ShotEnd, ShotFail> {
        if !(lambda0 > 0.0) {
            return Err(ShotFail::Breakdown {
                psi: 0.0,
                what: "crown stretch λ0 not positive",
            });
        }
        let n = self.intervals();
        let h = self.dpsi();
        self.lam1_guess = lambda0;
        let (s0, _) = self.stress(0.0, [lambda0, lambda0])?;
        let mut y = [s0[0] / (lambda0 * lambda0), lambda0, 0.0, 0.0, 0.0];
        if let Some(r) = record.as_deref_mut() {
            r.clear();
            let v = self.node_value(0.0, &y, psi_c > 0.0)?;
            r.push(v);
        }
        let mut contact_radius = 0.0;
        let mut psi = 0.0;
        for j in 0..n {
            let b = (j + 1) as f64 * h;
            if psi_c > psi && psi_c < b {
                self.rk4(psi, psi_c, &mut y, p, true)?;
                contact_radius = y[1] * psi_c.sin();
                y[2] = 0.0;
                psi = psi_c;
            }
            let contact = b <= psi_c;
            self.rk4(psi, b, &mut y, p, contact)?;
            if contact && (psi_c - b).abs() < 1e-15 {
                contact_radius = y[1] * b.sin();
            }
            psi = b;
            if let Some(r) = record.as_deref_mut() {
                let v = self.node_value(b, &y, contact)?;
                r.push(v);
            }
        }
        let h1 = y[3];
        if let Some(r) = record {
            for v in r.iter_mut() {
                v.eta = h1 - v.eta;
            }
        }
        Ok(ShotEnd {
            theta_end: y[2],
            h1,
            volume: y[4],
            contact_radius,
            t1_equator: y[0],
            rho_equator: y[1],
        })
    }
}
