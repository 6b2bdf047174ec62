//! Glue between the constitutive kernels and the public point-update traits:
//! one kernel per model gives `S` and its tangent; from it follow the 3D
//! update ([`Material3`]), the plane-stress membrane update
//! ([`MembraneMaterial`]) and the exactly incompressible extra stress used by
//! the homogeneous drivers ([`Incompressible`]).

use crate::kernel::{IsoStress, Kin};
use crate::{
    AxisymmetricResponse, F64x4, Lane, Mat3, Material3, MaterialError, MembraneMaterial,
    MembraneResponse, PointResponse3, PointState, Result,
};

/// A history-dependent, exactly incompressible material evaluated for an
/// isochoric deformation gradient (`det F = 1`): returns the *extra* Cauchy
/// stress `T` with `σ = −q I + T`, where the caller fixes `q` from boundary
/// conditions (eq. 2.1). Used by [`crate::homogeneous`].
pub trait Incompressible: PointState {
    /// Extra Cauchy stress at `t_n + dt` for `f` (the caller guarantees
    /// `det f = 1` up to rounding); the updated history goes to `trial`.
    ///
    /// # Errors
    /// [`MaterialError::Deformation`], [`MaterialError::TimeStep`].
    fn extra_stress(
        &self,
        state_n: &Self::State,
        f: &Mat3,
        dt: f64,
        trial: &mut Self::State,
    ) -> Result<Mat3>;
}

/// A model given by its second Piola–Kirchhoff kernel.
pub(crate) trait Kernel: PointState {
    /// Whether [`Kernel::eval_lanes`] is implemented.
    const LANES: bool = false;
    fn bulk(&self) -> f64;
    /// `S` at `t_n + dt` with volumetric penalty `bulk`; writes the history
    /// of `t_n + dt` into `trial`.
    fn eval(
        &self,
        state_n: &Self::State,
        k: &Kin,
        dt: f64,
        trial: &mut Self::State,
        bulk: f64,
    ) -> IsoStress;
    /// [`Kernel::eval`] of four points, one per lane ([`crate::Lane`]),
    /// each lane bitwise the scalar result. Called only if
    /// [`Kernel::LANES`].
    #[inline(always)]
    fn eval_lanes(
        &self,
        _state_n: [&Self::State; 4],
        _k: &Kin<F64x4>,
        _dt: f64,
        _trial: [&mut Self::State; 4],
        _bulk: f64,
    ) -> IsoStress<F64x4> {
        unreachable!("a kernel without a lane form (Kernel::LANES is false)")
    }
}

/// `P` and (if `tangent`) the 5×5 block of `∂P/∂F` on the axisymmetric
/// components from a kernel's stress (else `a` is left as it is); one
/// point or one per lane. Written in place: four points' are 960 bytes.
#[inline(always)]
fn axisymmetric_response<T: Lane>(
    k: &Kin<T>,
    iso: &IsoStress<T>,
    tangent: bool,
    p: &mut [T; 5],
    a: &mut [[T; 5]; 5],
) {
    let s = iso.pk2(k);
    *p = k.f_times_axisymmetric(&s);
    if tangent {
        iso.tangent_axisymmetric(k, &s, a);
    }
}

pub(crate) fn check_dt(dt: f64) -> Result<()> {
    if dt.is_finite() && dt >= 0.0 {
        Ok(())
    } else {
        Err(MaterialError::TimeStep(dt))
    }
}

/// The 3D update of a kernel model: `P = F S`, `σ = P Fᵀ / J` and the
/// consistent tangent from the kernel's `S` and `∂S/∂E`.
impl<M: Kernel> Material3 for M {
    fn update(
        &self,
        state_n: &M::State,
        f: &Mat3,
        dt: f64,
        trial: &mut M::State,
    ) -> Result<PointResponse3> {
        check_dt(dt)?;
        let k = Kin::new(f)?;
        let iso = self.eval(state_n, &k, dt, trial, self.bulk());
        let s = iso.pk2(&k);
        let p = f * s;
        Ok(PointResponse3 {
            cauchy: p * f.transpose() / k.j,
            first_piola: p,
            tangent: iso.tangent(&k, &s),
        })
    }

    /// The kinematics from 2×2 block algebra ([`Kin::axisymmetric`]), the
    /// kernel unchanged, `P` and the 5×5 block of `∂P/∂F`
    /// ([`IsoStress::tangent_axisymmetric`]); no Cauchy stress, no 9×9
    /// tangent. Inlined into the element kernel: the response (30 numbers)
    /// is then built in place instead of copied out twice per point.
    #[inline(always)]
    fn update_axisymmetric(
        &self,
        state_n: &M::State,
        f: &[f64; 5],
        dt: f64,
        trial: &mut M::State,
        tangent: bool,
    ) -> Result<AxisymmetricResponse> {
        check_dt(dt)?;
        let k = Kin::axisymmetric(f)?;
        let iso = self.eval(state_n, &k, dt, trial, self.bulk());
        let mut out = AxisymmetricResponse {
            first_piola: [0.0; 5],
            tangent: [[0.0; 5]; 5],
        };
        axisymmetric_response(&k, &iso, tangent, &mut out.first_piola, &mut out.tangent);
        Ok(out)
    }

    const AXISYMMETRIC_LANES: bool = M::LANES;

    /// The same steps as [`Material3::update_axisymmetric`] on four points
    /// in lanes; `None` if the kernel has no lane form or any lane fails a
    /// check (the caller then updates point by point, which reports the
    /// error).
    #[inline(always)]
    fn update_axisymmetric_lanes(
        &self,
        state_n: [&M::State; 4],
        f: &[F64x4; 5],
        dt: f64,
        trial: [&mut M::State; 4],
        tangent: bool,
        first_piola: &mut [F64x4; 5],
        tangent_out: &mut [[F64x4; 5]; 5],
    ) -> bool {
        if !M::LANES || check_dt(dt).is_err() || Kin::check_axisymmetric(f).is_err() {
            return false;
        }
        let k = Kin::axisymmetric_unchecked(f);
        let iso = self.eval_lanes(state_n, &k, dt, trial, self.bulk());
        axisymmetric_response(&k, &iso, tangent, first_piola, tangent_out);
        true
    }
}

/// The extra stress `F S Fᵀ` of a kernel model without volumetric penalty.
impl<M: Kernel> Incompressible for M {
    fn extra_stress(
        &self,
        state_n: &M::State,
        f: &Mat3,
        dt: f64,
        trial: &mut M::State,
    ) -> Result<Mat3> {
        check_dt(dt)?;
        let k = Kin::new(f)?;
        let s = self.eval(state_n, &k, dt, trial, 0.0).pk2(&k);
        Ok(f * s * f.transpose())
    }
}

/// Plane stress with `λ3 = 1/(λ1 λ2)`: `σ_α = τ_αα − τ_33`, and the chain
/// rule through `λ3(λ1, λ2)` for `∂σ_α/∂λ_β`.
impl<M: Kernel> MembraneMaterial for M {
    fn update(
        &self,
        state_n: &M::State,
        stretches: [f64; 2],
        dt: f64,
        trial: &mut M::State,
    ) -> Result<MembraneResponse> {
        check_dt(dt)?;
        let [l1, l2] = stretches;
        if !(l1.is_finite() && l2.is_finite() && l1 > 0.0 && l2 > 0.0) {
            return Err(MaterialError::Deformation(format!(
                "membrane stretches must be finite and > 0, got λ1 = {l1}, λ2 = {l2}"
            )));
        }
        let l3 = 1.0 / (l1 * l2);
        let lam = [l1, l2, l3];
        let f = Mat3::from_diagonal(&nalgebra::Vector3::new(l1, l2, l3));
        let k = Kin::new(&f)?;
        let iso = self.eval(state_n, &k, dt, trial, 0.0);
        let s = iso.pk2(&k);
        let p = f * s;
        let a = iso.tangent(&k, &s);
        // d[i][j] = ∂τ_ii/∂λ_j with the other stretches fixed.
        let mut d = [[0.0; 3]; 3];
        for (i, di) in d.iter_mut().enumerate() {
            for (j, dij) in di.iter_mut().enumerate() {
                *dij = a[(4 * i, 4 * j)] * lam[i] + if i == j { p[(i, i)] } else { 0.0 };
            }
        }
        let tau = [p[(0, 0)] * l1, p[(1, 1)] * l2, p[(2, 2)] * l3];
        let mut tangent = [[0.0; 2]; 2];
        for (al, row) in tangent.iter_mut().enumerate() {
            for (be, x) in row.iter_mut().enumerate() {
                let dl3 = -l3 / lam[be];
                *x = d[al][be] + d[al][2] * dl3 - d[2][be] - d[2][2] * dl3;
            }
        }
        Ok(MembraneResponse {
            cauchy: [tau[0] - tau[2], tau[1] - tau[2]],
            tangent,
        })
    }
}

impl PointState for crate::MooneyRivlin {
    type State = ();
    fn initial_state(&self) {}
}

impl Kernel for crate::MooneyRivlin {
    fn bulk(&self) -> f64 {
        self.bulk()
    }
    fn eval(&self, _: &(), k: &Kin, _dt: f64, _: &mut (), bulk: f64) -> IsoStress {
        let mut out = IsoStress::default();
        self.add_isochoric(k, 1.0, &mut out);
        crate::hyperelastic::add_volumetric(k, bulk, &mut out);
        out
    }
}
