//! The material-point contract shared by every forward model.
//!
//! Conventions (SI units throughout):
//! - [`Mat3`] is a 3×3 tensor; `F` is the deformation gradient at t_{n+1}.
//! - [`Tangent3`] is the consistent tangent `A[3i+J][3k+L] = ∂P_iJ/∂F_kL` of
//!   the *algorithmic* first Piola–Kirchhoff stress `P` at t_{n+1}, history
//!   at t_n held fixed. Total-Lagrangian finite elements use `P` and `A`
//!   directly; other tangents (material `∂S/∂E`, the spatial/Jaumann form of
//!   App. D eqs. D.8–D.12) are push-forwards of it.
//! - A membrane point is plane stress with `λ3 = 1/(λ1 λ2)`; it returns the
//!   principal Cauchy stresses σ1, σ2 and `∂σ_α/∂λ_β`.

use crate::Result;

/// A 3×3 tensor.
pub type Mat3 = nalgebra::Matrix3<f64>;

/// Consistent tangent `∂P_iJ/∂F_kL`, row `3i+J`, column `3k+L`.
pub type Tangent3 = nalgebra::SMatrix<f64, 9, 9>;

/// Stress and consistent tangent at one 3D material point.
#[derive(Debug, Clone, PartialEq)]
pub struct PointResponse3 {
    /// Cauchy stress σ at t_{n+1}.
    pub cauchy: Mat3,
    /// First Piola–Kirchhoff stress P = J σ F⁻ᵀ at t_{n+1}.
    pub first_piola: Mat3,
    /// Consistent tangent ∂P/∂F of the algorithmic update.
    pub tangent: Tangent3,
}

/// The history a material carries at each point (deal.II's
/// `PointHistory`): shared by every point update ([`Material3`],
/// [`MembraneMaterial`], [`crate::Incompressible`]), so one model has one
/// state type whichever update a caller uses.
pub trait PointState: Send + Sync {
    /// History at one material point (O(number of Prony terms) in size).
    type State: Clone + Send + Sync + std::fmt::Debug;

    /// History of a point that has never been deformed (F = I for t < 0).
    fn initial_state(&self) -> Self::State;
}

/// A history-dependent 3D material (incompressibility by a volumetric
/// penalty, or nearly incompressible: see the implementing type).
pub trait Material3: PointState {
    /// Stress and consistent tangent at `t_{n+1} = t_n + dt` for the
    /// deformation gradient `f`, given the converged history `state_n` at
    /// `t_n`. The updated history is written to `trial`; the caller commits
    /// it (copies it over `state_n`, or swaps the two) once the global step
    /// converges. What `trial` held on entry is unspecified (a rejected
    /// trial, an older converged state, a copy of `state_n`): an update
    /// must not depend on it, except through a cache it validates itself
    /// ([`crate::PronyViscoelastic`]'s step cache).
    ///
    /// # Errors
    /// [`crate::MaterialError::Deformation`] when `det f ≤ 0` or the update
    /// cannot be evaluated.
    fn update(
        &self,
        state_n: &Self::State,
        f: &Mat3,
        dt: f64,
        trial: &mut Self::State,
    ) -> Result<PointResponse3>;

    /// The axisymmetric special case of [`Material3::update`]: `f` holds the
    /// components [`AXISYMMETRIC_COMPONENTS`] of a deformation gradient
    /// `F = [[F_rR, F_rZ, 0], [F_zR, F_zZ, 0], [0, 0, F_θθ]]` (frame r, z, θ),
    /// and the response holds the same components of `P` and of `∂P/∂F` —
    /// exactly the entries an axisymmetric element reads. With
    /// `tangent = false` the tangent is left zero (residual-only updates).
    ///
    /// The default builds the 3×3 `F` and restricts [`Material3::update`];
    /// the models of this crate override it with a path that never forms
    /// the 9×9 tangent or the Cauchy stress (same values to round-off; test
    /// `axisymmetric_fast_path_matches_general_update_and_finite_differences`).
    ///
    /// # Errors
    /// As [`Material3::update`].
    fn update_axisymmetric(
        &self,
        state_n: &Self::State,
        f: &[f64; 5],
        dt: f64,
        trial: &mut Self::State,
        tangent: bool,
    ) -> Result<AxisymmetricResponse> {
        let full = Mat3::new(f[0], f[1], 0.0, f[2], f[3], 0.0, 0.0, 0.0, f[4]);
        let r = self.update(state_n, &full, dt, trial)?;
        let mut out = AxisymmetricResponse {
            first_piola: AXISYMMETRIC_COMPONENTS.map(|(i, j)| r.first_piola[(i, j)]),
            tangent: [[0.0; 5]; 5],
        };
        if tangent {
            for (row, &(i, j)) in out.tangent.iter_mut().zip(&AXISYMMETRIC_COMPONENTS) {
                for (x, &(k, l)) in row.iter_mut().zip(&AXISYMMETRIC_COMPONENTS) {
                    *x = r.tangent[(3 * i + j, 3 * k + l)];
                }
            }
        }
        Ok(out)
    }

    /// Whether [`Material3::update_axisymmetric_lanes`] is implemented (the
    /// models of this crate whose kernel has a lane form).
    #[doc(hidden)]
    const AXISYMMETRIC_LANES: bool = false;

    /// [`Material3::update_axisymmetric`] of four points at once, one per
    /// lane of [`crate::F64x4`] (e.g. the same Gauss point of four
    /// elements), each lane bitwise the result of the one-point update:
    /// `P` to `first_piola`, `∂P/∂F` to `tangent_out` if `tangent` (else it
    /// is left as it is). `false` if not implemented (the default) or if any
    /// lane fails a check; the caller then updates the points one by one
    /// (which reports the error).
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    fn update_axisymmetric_lanes(
        &self,
        _state_n: [&Self::State; 4],
        _f: &[crate::F64x4; 5],
        _dt: f64,
        _trial: [&mut Self::State; 4],
        _tangent: bool,
        _first_piola: &mut [crate::F64x4; 5],
        _tangent_out: &mut [[crate::F64x4; 5]; 5],
    ) -> bool {
        false
    }
}

/// The (row, column) indices in the 3×3 tensor of the five components an
/// axisymmetric (r, z, θ) deformation gradient can have, in the order used
/// by [`Material3::update_axisymmetric`]: rR, rZ, zR, zZ, θθ.
pub const AXISYMMETRIC_COMPONENTS: [(usize, usize); 5] = [(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)];

/// Stress and tangent at one axisymmetric 3D material point (the entries of
/// [`PointResponse3`] on [`AXISYMMETRIC_COMPONENTS`]).
/// `T` = [`crate::F64x4`]: four points, one per lane
/// ([`Material3::update_axisymmetric_lanes`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisymmetricResponse<T = f64> {
    /// First Piola–Kirchhoff stress components P_rR, P_rZ, P_zR, P_zZ, P_θθ.
    pub first_piola: [T; 5],
    /// `tangent[p][q] = ∂P_p/∂F_q` over the same components (zero if not
    /// requested).
    pub tangent: [[T; 5]; 5],
}

/// Principal stresses and tangent at one membrane (plane-stress) point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembraneResponse {
    /// Principal Cauchy stresses σ1, σ2 (σ3 = 0).
    pub cauchy: [f64; 2],
    /// `∂σ_α/∂λ_β` of the algorithmic update, history held fixed.
    pub tangent: [[f64; 2]; 2],
}

/// A history-dependent incompressible membrane in principal stretches.
pub trait MembraneMaterial: PointState {
    /// Principal Cauchy stresses and tangent at `t_{n+1} = t_n + dt` for the
    /// principal stretches `[λ1, λ2]` (λ3 = 1/(λ1 λ2)), given the converged
    /// history `state_n`; the updated history goes to `trial`.
    ///
    /// # Errors
    /// [`crate::MaterialError::Deformation`] when a stretch is not positive.
    fn update(
        &self,
        state_n: &Self::State,
        stretches: [f64; 2],
        dt: f64,
        trial: &mut Self::State,
    ) -> Result<MembraneResponse>;
}
