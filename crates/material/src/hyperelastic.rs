//! Mooney–Rivlin and neo-Hookean hyperelasticity (eq. 4.1), the elastic part
//! of every model in this crate and its `t = 0⁺` / `t → ∞` limit (eqs. 2.3–2.4).
//!
//! Strain energy with the isochoric/volumetric split used by ABAQUS and by
//! mixed or F-bar finite elements:
//! `W = C1 (Ī1 − 3) + C2 (Ī2 − 3) + K/2 (J − 1)²`, `Ī1 = J^{-2/3} I1`,
//! `Ī2 = J^{-4/3} I2`. The volumetric part gives the Kirchhoff pressure term
//! `K J (J − 1) I` of eqs. 2.50/D.5. At `J = 1` the Cauchy stress is eq. 4.1,
//! `σ = −p I + 2 (C1 + I1 C2) B − 2 C2 B²`, and the small-strain shear
//! modulus is `2 (C1 + C2)`. `K = 0` leaves the purely isochoric part, for
//! formulations that carry the pressure as an unknown of their own.

use crate::kernel::{IsoStress, Kin, XC, XCI, XI};
use crate::{Lane, MaterialError, Result};

/// Mooney–Rivlin solid (`C2 = 0`: neo-Hookean), eq. 4.1, with volumetric
/// penalty `K`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MooneyRivlin {
    c1: f64,
    c2: f64,
    bulk: f64,
}

pub(crate) fn check_bulk(bulk: f64) -> Result<()> {
    if !(bulk.is_finite() && bulk >= 0.0) {
        return Err(MaterialError::Parameter {
            name: "bulk_modulus",
            value: bulk,
            reason: "the volumetric penalty K must be finite and ≥ 0 (Pa); \
                     use K ≈ 10³·C1 for near-incompressibility, 0 for mixed formulations",
        });
    }
    Ok(())
}

impl MooneyRivlin {
    /// `C1 > 0`, `C2 ≥ 0` (thesis: "positive constants", eq. 2.4), `K ≥ 0`, in Pa.
    ///
    /// # Errors
    /// [`MaterialError::Parameter`] naming the offending constant.
    pub fn new(c1: f64, c2: f64, bulk: f64) -> Result<Self> {
        if !(c1.is_finite() && c1 > 0.0) {
            return Err(MaterialError::Parameter {
                name: "C1",
                value: c1,
                reason: "must be finite and > 0 (Pa)",
            });
        }
        if !(c2.is_finite() && c2 >= 0.0) {
            return Err(MaterialError::Parameter {
                name: "C2",
                value: c2,
                reason: "must be finite and ≥ 0 (Pa)",
            });
        }
        check_bulk(bulk)?;
        Ok(Self { c1, c2, bulk })
    }

    /// Neo-Hookean `W = C1 (Ī1 − 3) + K/2 (J − 1)²`.
    ///
    /// # Errors
    /// As [`MooneyRivlin::new`].
    pub fn neo_hookean(c1: f64, bulk: f64) -> Result<Self> {
        Self::new(c1, 0.0, bulk)
    }

    /// Capsule form of §4.3: `C2 = α C1`.
    ///
    /// # Errors
    /// As [`MooneyRivlin::new`]; `α` must be ≥ 0.
    pub fn with_ratio(c1: f64, alpha: f64, bulk: f64) -> Result<Self> {
        if !(alpha.is_finite() && alpha >= 0.0) {
            return Err(MaterialError::Parameter {
                name: "alpha",
                value: alpha,
                reason: "the Mooney–Rivlin ratio C2/C1 must be finite and ≥ 0",
            });
        }
        Self::new(c1, alpha * c1, bulk)
    }

    /// From the small-strain shear modulus `G0 = 2 (C1 + C2)` and
    /// `α = C2/C1`: `C1 = G0 / (2 (1 + α))`, `C2 = α C1` (eq. 4.1; the
    /// convention of `docs/theory/model.md`). `α = 0` is the neo-Hookean
    /// cell of eq. 5.1, `C1 = G0/2`.
    ///
    /// # Errors
    /// As [`MooneyRivlin::with_ratio`], naming `G0` when it is not > 0.
    pub fn from_shear_modulus(g0: f64, alpha: f64, bulk: f64) -> Result<Self> {
        if !(g0.is_finite() && g0 > 0.0) {
            return Err(MaterialError::Parameter {
                name: "G0",
                value: g0,
                reason: "the shear modulus G0 = 2(C1 + C2) must be finite and > 0 (Pa)",
            });
        }
        Self::with_ratio(g0 / (2.0 * (1.0 + alpha)), alpha, bulk)
    }

    /// Small-strain shear modulus `2 (C1 + C2)` in Pa (the `G0` of eq. 5.1).
    pub fn shear_modulus(&self) -> f64 {
        2.0 * (self.c1 + self.c2)
    }

    /// `C1` in Pa.
    pub fn c1(&self) -> f64 {
        self.c1
    }
    /// `C2` in Pa.
    pub fn c2(&self) -> f64 {
        self.c2
    }
    /// Volumetric penalty `K` in Pa.
    pub fn bulk(&self) -> f64 {
        self.bulk
    }

    /// Adds `scale ·` the isochoric second Piola–Kirchhoff stress
    /// `S_iso = 2∂/∂C [C1(Ī1−3) + C2(Ī2−3)]
    ///        = 2C1 J^{-2/3}(I − I1/3 C⁻¹) + 2C2 J^{-4/3}(I1 I − C − 2I2/3 C⁻¹)`.
    /// The material constants are `f64` and the kinematics `T`
    /// ([`crate::Lane`]): a product such as `2 C1 J^{-2/3}` is formed as
    /// `(2 C1) J^{-2/3}`, the scalar code's order.
    #[inline(always)]
    pub(crate) fn add_isochoric<T: Lane>(&self, k: &Kin<T>, scale: f64, out: &mut IsoStress<T>) {
        let (c1, c2) = (scale * self.c1, scale * self.c2);
        let c = T::splat;
        let zero = T::zero();
        let j23 = k.j23;
        let j43 = j23 * j23;
        let ij = T::one() / k.j;
        out.add(
            XI,
            c(2.0 * c1) * j23 + c(2.0 * c2) * j43 * k.i1,
            k.grad(
                c(2.0 * c2) * j43,
                zero,
                c(-4.0 / 3.0 * c1) * j23 * ij - c(8.0 / 3.0 * c2) * j43 * k.i1 * ij,
                zero,
            ),
        );
        out.add(
            XC,
            c(-2.0 * c2) * j43,
            k.grad(zero, zero, c(8.0 / 3.0 * c2) * j43 * ij, zero),
        );
        out.add(
            XCI,
            c(-2.0 / 3.0 * c1) * j23 * k.i1 - c(4.0 / 3.0 * c2) * j43 * k.i2,
            k.grad(
                c(-2.0 / 3.0 * c1) * j23,
                c(-4.0 / 3.0 * c2) * j43,
                c(4.0 / 9.0 * c1) * j23 * k.i1 * ij + c(16.0 / 9.0 * c2) * j43 * k.i2 * ij,
                zero,
            ),
        );
    }
}

/// Adds the volumetric penalty `S_vol = K J (J − 1) C⁻¹` (Kirchhoff
/// `K J (J − 1) I`, eqs. 2.50/D.5).
#[inline(always)]
pub(crate) fn add_volumetric<T: Lane>(k: &Kin<T>, bulk: f64, out: &mut IsoStress<T>) {
    if bulk != 0.0 {
        let zero = T::zero();
        out.add(
            XCI,
            T::splat(bulk) * k.j * (k.j - 1.0),
            k.grad(
                zero,
                zero,
                T::splat(bulk) * (T::splat(2.0) * k.j - 1.0),
                zero,
            ),
        );
    }
}
