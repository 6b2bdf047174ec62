//! What one element evaluation returns, shared by every element kind
//! (the F-bar kernel of [`crate::fbar`], the Q4 of [`crate::element`], the
//! hexahedron of [`crate::hex`], the membrane of [`crate::membrane`]) and
//! read by the model: the local residual and tangent, which part of the
//! tangent to compute, and where an evaluation failed.

use nlvid_material::F64x4;

/// Residual and tangent of one element with `ND` dofs (every element
/// kind's local output).
/// (`T` = [`nlvid_material::F64x4`]: four elements, one per lane.)
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalOutput<const ND: usize, T = f64> {
    /// Internal force ∂W/∂u (N).
    pub r: [T; ND],
    /// Tangent ∂r/∂u (N/m).
    pub k: [[T; ND]; ND],
}

impl<const ND: usize> LocalOutput<ND> {
    /// All zero.
    pub fn zero() -> Self {
        Self {
            r: [0.0; ND],
            k: [[0.0; ND]; ND],
        }
    }
}

impl<const ND: usize> Default for LocalOutput<ND> {
    fn default() -> Self {
        Self::zero()
    }
}

impl<const ND: usize> Default for LocalOutput<ND, F64x4> {
    fn default() -> Self {
        Self {
            r: [F64x4::default(); ND],
            k: [[F64x4::default(); ND]; ND],
        }
    }
}

/// What the model reads of an element's output ([`LocalOutput`]).
#[doc(hidden)]
pub trait Local: Clone + Send + Default {
    /// The element residual.
    fn residual(&self) -> &[f64];
    /// Row `a` of the element tangent.
    fn tangent_row(&self, a: usize) -> &[f64];
}

impl<const ND: usize> Local for LocalOutput<ND> {
    #[inline]
    fn residual(&self) -> &[f64] {
        &self.r
    }
    #[inline]
    fn tangent_row(&self, a: usize) -> &[f64] {
        &self.k[a]
    }
}

/// Which part of the element tangent to compute.
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TangentPart {
    /// Residual only.
    None,
    /// The full 8×8 matrix.
    Full,
    /// Entries `k[r][c]` with `c ≤ r` only (the rest is left zero): for a
    /// symmetric tangent stored as one triangle (test
    /// `lower_tangent_is_the_lower_triangle_of_a_symmetric_full_tangent`).
    Lower,
}

/// Where an element evaluation failed: Gauss point and the material error.
#[doc(hidden)]
pub type PointFailure = (usize, nlvid_material::MaterialError);

/// The error of a dof vector of the wrong length `n`.
pub(crate) fn bad_length(n: usize) -> PointFailure {
    (
        0,
        nlvid_material::MaterialError::Deformation(format!("element dof vector has {n} entries")),
    )
}
