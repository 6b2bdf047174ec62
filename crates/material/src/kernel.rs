//! Kinematics and the tangent kernel shared by every 3D model.
//!
//! Every second Piola–Kirchhoff stress in this crate has the form
//! `S = s_I I + s_C C + s_Ci C⁻¹ + s_H H` with scalar coefficients that depend
//! on `C` only through `I1`, `I2`, `J` and `H:C`, where `H` is a constant
//! symmetric tensor (frozen history). Its material tangent is
//! `2∂S/∂C = Σ_ab m_ab X_a ⊗ X_b + 2 s_C 𝕀ˢ + 2 s_Ci ∂C⁻¹/∂C`
//! with `X = (I, C, C⁻¹, H)` and `m_a·` the basis coefficients of `2∂s_a/∂C`
//! (from `∂I1/∂C = I`, `∂I2/∂C = I1 I − C`, `∂J/∂C = J C⁻¹/2`,
//! `∂(H:C)/∂C = H`). The first Piola tangent then is
//! `∂P_iJ/∂F_kL = δ_ik S_LJ + F_iM (2∂S/∂C)_MJLQ F_kQ` (eq. 2.52 before the
//! push-forward of D.12).

use crate::{Lane, Mat3, MaterialError, Result, Tangent3};
use nalgebra::Matrix3;

/// Kinematic quantities of a deformation gradient (of one point, `T =
/// f64`, or of one point per lane, [`crate::Lane`]).
#[derive(Debug, Clone)]
pub(crate) struct Kin<T: Lane = f64> {
    pub f: Matrix3<T>,
    pub c: Matrix3<T>,
    pub cinv: Matrix3<T>,
    /// F⁻ᵀ
    pub fit: Matrix3<T>,
    pub b: Matrix3<T>,
    pub j: T,
    /// `J^{-2/3}`, computed once (every isochoric term uses it).
    pub j23: T,
    pub i1: T,
    pub i2: T,
}

/// `J^{-2/3}`, the factor of every isochoric term.
#[inline(always)]
fn j_minus_two_thirds<T: Lane>(j: T) -> T {
    let c = j.cube_root();
    T::one() / (c * c)
}

impl Kin {
    pub fn new(f: &Mat3) -> Result<Self> {
        if f.iter().any(|x| !x.is_finite()) {
            return Err(MaterialError::Deformation(format!(
                "deformation gradient has a non-finite entry: {f:?}"
            )));
        }
        let j = f.determinant();
        if j <= 0.0 || j.is_nan() {
            return Err(MaterialError::Deformation(format!(
                "det F = {j} ≤ 0 (inverted or degenerate element)"
            )));
        }
        let finv = f.try_inverse().ok_or_else(|| {
            MaterialError::Deformation(format!("deformation gradient is singular (det F = {j})"))
        })?;
        let c = f.transpose() * f;
        let i1 = c.trace();
        let trc2 = c.component_mul(&c).sum();
        Ok(Self {
            f: *f,
            c,
            cinv: finv * finv.transpose(),
            fit: finv.transpose(),
            b: f * f.transpose(),
            j,
            j23: j_minus_two_thirds(j),
            i1,
            i2: 0.5 * (i1 * i1 - trc2),
        })
    }
}

impl<T: Lane> Kin<T> {
    /// [`Kin::new`] for an axisymmetric `F` given by its components
    /// [`crate::AXISYMMETRIC_COMPONENTS`] (rR, rZ, zR, zZ, θθ): the same
    /// quantities from 2×2 block algebra instead of general 3×3 operations.
    /// Always inlined: the `Result<Kin>` (≈ 400 bytes) is then built in
    /// place instead of copied once per point update.
    #[inline(always)]
    pub fn axisymmetric(f5: &[T; 5]) -> Result<Self> {
        Self::check_axisymmetric(f5)?;
        Ok(Self::axisymmetric_unchecked(f5))
    }

    /// The checks of [`Kin::axisymmetric`]: every component finite and
    /// `det F > 0` (in every lane).
    #[inline(always)]
    pub fn check_axisymmetric(f5: &[T; 5]) -> Result<()> {
        let [a, b, c, d, h] = *f5;
        if f5.iter().any(|x| !x.all_finite()) {
            return Err(MaterialError::Deformation(format!(
                "deformation gradient has a non-finite entry: {f5:?} (rR, rZ, zR, zZ, θθ)"
            )));
        }
        let j = (a * d - b * c) * h;
        if !j.all_positive() {
            return Err(MaterialError::Deformation(format!(
                "det F = {j} ≤ 0 (inverted or degenerate element)"
            )));
        }
        Ok(())
    }

    /// [`Kin::axisymmetric`] without its checks (for an `f5` that passed
    /// [`Kin::check_axisymmetric`]; the lanes build it in place).
    #[inline(always)]
    pub fn axisymmetric_unchecked(f5: &[T; 5]) -> Self {
        let [a, b, c, d, h] = *f5;
        let j2 = a * d - b * c;
        let j = j2 * h;
        // F⁻¹ blocks.
        let ij2 = T::one() / j2;
        let (ia, ib, ic, id) = (d * ij2, -b * ij2, -c * ij2, a * ij2);
        let ih = T::one() / h;
        let (c00, c01, c11, c22) = (a * a + c * c, a * b + c * d, b * b + d * d, h * h);
        let i1 = c00 + c11 + c22;
        let trc2 = c00 * c00 + T::splat(2.0) * c01 * c01 + c11 * c11 + c22 * c22;
        let z = T::zero();
        let block = |xx, xy, yx, yy, zz| Matrix3::new(xx, xy, z, yx, yy, z, z, z, zz);
        Self {
            f: block(a, b, c, d, h),
            c: block(c00, c01, c01, c11, c22),
            // C⁻¹ = F⁻¹ F⁻ᵀ.
            cinv: {
                let x01 = ia * ic + ib * id;
                block(ia * ia + ib * ib, x01, x01, ic * ic + id * id, ih * ih)
            },
            fit: block(ia, ic, ib, id, ih),
            b: {
                let x01 = a * c + b * d;
                block(a * a + b * b, x01, x01, c * c + d * d, c22)
            },
            j,
            j23: j_minus_two_thirds(j),
            i1,
            i2: T::splat(0.5) * (i1 * i1 - trc2),
        }
    }

    /// The axisymmetric components ([`crate::AXISYMMETRIC_COMPONENTS`]) of
    /// `F X` for an axisymmetric (block-diagonal) `F`: the products with
    /// F's zero off-block entries are left out (they add exact zeros).
    #[inline(always)]
    pub fn f_times_axisymmetric(&self, x: &Matrix3<T>) -> [T; 5] {
        let f = &self.f;
        [
            f[(0, 0)] * x[(0, 0)] + f[(0, 1)] * x[(1, 0)],
            f[(0, 0)] * x[(0, 1)] + f[(0, 1)] * x[(1, 1)],
            f[(1, 0)] * x[(0, 0)] + f[(1, 1)] * x[(1, 0)],
            f[(1, 0)] * x[(0, 1)] + f[(1, 1)] * x[(1, 1)],
            f[(2, 2)] * x[(2, 2)],
        ]
    }

    /// Basis coefficients of `2∂s/∂C` for a scalar `s(I1, I2, J, H:C)` with
    /// the given partial derivatives.
    #[inline(always)]
    pub fn grad(&self, d_i1: T, d_i2: T, d_j: T, d_hc: T) -> [T; 4] {
        [
            T::splat(2.0) * (d_i1 + self.i1 * d_i2),
            T::splat(-2.0) * d_i2,
            self.j * d_j,
            T::splat(2.0) * d_hc,
        ]
    }
}

/// Index of each basis tensor in [`IsoStress`].
pub(crate) const XI: usize = 0;
pub(crate) const XC: usize = 1;
pub(crate) const XCI: usize = 2;
pub(crate) const XH: usize = 3;

/// `S = Σ s_a X_a` plus the dyadic part of its tangent, see the module doc.
#[derive(Debug, Clone)]
pub(crate) struct IsoStress<T: Lane = f64> {
    pub s: [T; 4],
    pub m: [[T; 4]; 4],
    pub h: Matrix3<T>,
}

impl<T: Lane> Default for IsoStress<T> {
    #[inline(always)]
    fn default() -> Self {
        Self {
            s: [T::zero(); 4],
            m: [[T::zero(); 4]; 4],
            h: Matrix3::zeros(),
        }
    }
}

impl<T: Lane> IsoStress<T> {
    /// Adds `value · X_a` whose coefficient has gradient `grad` (from [`Kin::grad`]).
    #[inline(always)]
    pub fn add(&mut self, a: usize, value: T, grad: [T; 4]) {
        self.s[a] += value;
        for (m, g) in self.m[a].iter_mut().zip(grad) {
            *m += g;
        }
    }

    /// Second Piola–Kirchhoff stress.
    #[inline(always)]
    pub fn pk2(&self, k: &Kin<T>) -> Matrix3<T> {
        Matrix3::identity() * self.s[XI]
            + k.c * self.s[XC]
            + k.cinv * self.s[XCI]
            + self.h * self.s[XH]
    }

    /// Adds `scale ·` another stress that does not use the `H` basis tensor.
    #[inline(always)]
    pub fn add_scaled(&mut self, other: &IsoStress<T>, scale: f64) {
        for a in 0..4 {
            self.s[a] += other.s[a] * scale;
            for b in 0..4 {
                self.m[a][b] += other.m[a][b] * scale;
            }
        }
    }

    /// The entries of [`IsoStress::tangent`] on the axisymmetric components
    /// [`crate::AXISYMMETRIC_COMPONENTS`] (a 5×5 block of the 9×9 matrix),
    /// term by term the same formula restricted to those rows and columns.
    /// Exact for any `H`; `F` must be axisymmetric (zero off-block entries).
    /// Zero coefficients are added like the others (exact zeros, see the
    /// comment in the body), so the lanes ([`crate::Lane`]) need no masks.
    /// Written to `t` (four points' are 800 bytes).
    #[inline(always)]
    pub fn tangent_axisymmetric(&self, k: &Kin<T>, s: &Matrix3<T>, t: &mut [[T; 5]; 5]) {
        use crate::AXISYMMETRIC_COMPONENTS as IDX;
        // The components in IDX order, written out: `IDX.map(..)` stays an
        // out-of-line call (`array::try_map`, compiled for the baseline
        // instruction set, with two copies of the array) in the element
        // kernel's SIMD dispatch.
        let pick = |m: &Matrix3<T>| [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)], m[(2, 2)]];
        let u = [
            pick(&k.f),
            k.f_times_axisymmetric(&k.c),
            pick(&k.fit),
            k.f_times_axisymmetric(&self.h),
        ];
        // Every coefficient is added, zero or not: the sums start at +0
        // and only accumulate (a round-to-nearest sum is −0 only if both
        // terms are), so they never hold −0, and adding `0 · y = ±0` (y
        // finite: u is F, F C, F⁻ᵀ, F H of a finite F with det F > 0)
        // leaves them bitwise unchanged. Skipping zero coefficients (as
        // [`IsoStress::tangent`] does) therefore gives the same numbers; in
        // lanes it took a mask per product, and branches per coefficient
        // cost more than the products they skip.
        let m = &self.m;
        let (sc, sci) = (self.s[XC], self.s[XCI]);
        let diag = s - k.cinv * sci;
        // Column by column: `v[a][q] = Σ_b m_ab u[b][q]` for the column's
        // q only (four numbers, no 4×5 array), then the column of
        // `Σ_a u[a] ⊗ v[a]` and the other terms; each entry is the same sum
        // in the same order as row by row, and `t` is written once (no
        // zeroed temporaries: the memsets cost ≈ 5 % of the kernel).
        for (q, &(kk, l)) in IDX.iter().enumerate() {
            let mut vq = [T::zero(); 4];
            for a in 0..4 {
                let mut x = T::zero();
                for b in 0..4 {
                    x += m[a][b] * u[b][q];
                }
                vq[a] = x;
            }
            for (p, &(i, jj)) in IDX.iter().enumerate() {
                let mut y = T::zero();
                for a in 0..4 {
                    y += u[a][p] * vq[a];
                }
                y += sc * (k.f[(i, l)] * k.f[(kk, jj)]) - sci * (k.fit[(i, l)] * k.fit[(kk, jj)]);
                if jj == l {
                    y += sc * k.b[(i, kk)];
                }
                if i == kk {
                    y += diag[(jj, l)];
                }
                t[p][q] = y;
            }
        }
    }
}

impl IsoStress {
    /// `∂P/∂F` for `P = F S`, row `3i+J`, column `3k+L`.
    pub fn tangent(&self, k: &Kin, s: &Mat3) -> Tangent3 {
        let u = [k.f, k.f * k.c, k.fit, k.f * self.h];
        let mut v = [Mat3::zeros(); 4];
        for (a, va) in v.iter_mut().enumerate() {
            for (b, ub) in u.iter().enumerate() {
                let m = self.m[a][b];
                if m != 0.0 {
                    *va += ub * m;
                }
            }
        }
        let (sc, sci) = (self.s[XC], self.s[XCI]);
        let f = rows(&k.f);
        let fit = rows(&k.fit);
        let b = rows(&k.b);
        // δ_ik block: S_LJ − s_Ci C⁻¹_JL (S, C⁻¹ symmetric).
        let diag = rows(&(s - k.cinv * sci));
        let ua = u.map(|x| flat(&x));
        let va = v.map(|x| flat(&x));
        let mut t = [[0.0f64; 9]; 9];
        for (a, (ur, vr)) in ua.iter().zip(&va).enumerate() {
            if self.m[a].iter().all(|&m| m == 0.0) {
                continue;
            }
            for (row, &x) in t.iter_mut().zip(ur) {
                for (y, &z) in row.iter_mut().zip(vr) {
                    *y += x * z;
                }
            }
        }
        for i in 0..3 {
            for jj in 0..3 {
                let row = &mut t[3 * i + jj];
                for kk in 0..3 {
                    for l in 0..3 {
                        row[3 * kk + l] +=
                            sc * (f[i][l] * f[kk][jj]) - sci * (fit[i][l] * fit[kk][jj]);
                    }
                    row[3 * kk + jj] += sc * b[i][kk];
                }
                for l in 0..3 {
                    row[3 * i + l] += diag[jj][l];
                }
            }
        }
        Tangent3::from_fn(|r, c| t[r][c])
    }
}

/// Row-major copy of a 3×3 matrix.
fn rows(m: &Mat3) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]])
}

/// Row-major flattening, index `3i + J`.
fn flat(m: &Mat3) -> [f64; 9] {
    let r = rows(m);
    [
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    ]
}
