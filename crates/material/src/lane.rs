//! The scalar type of the point update and of the element kernel of
//! `nlvid-fem`: `f64` for one point, [`F64x4`] for four points of four
//! elements at once (one per lane of an AVX2 register).
//!
//! The point update and the kernel are written once, generic over [`Lane`]:
//! every lane of an [`F64x4`] goes through exactly the operations of the
//! `f64` code in the same order (elementwise IEEE arithmetic, never fused,
//! no reassociation), so each lane's result is bitwise the scalar one. The
//! kernels avoid data-dependent branches: where the scalar code would skip a
//! term with a zero coefficient, the generic code adds 0·y, which leaves a
//! sum that started at +0 bitwise unchanged (y finite; such a sum never
//! holds −0). [`Lane::select`] blends per lane where a branch cannot be
//! avoided. A check that fails in any lane (a non-finite F, det F ≤ 0)
//! fails the whole group, and the caller evaluates its elements one by
//! one.

use std::fmt::{Debug, Display};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real number or a group of them processed in lockstep (module docs).
pub trait Lane:
    Copy
    + Debug
    + Display
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
    + num_traits::Zero
    + num_traits::One
{
    /// Number of lanes.
    const WIDTH: usize;
    /// One flag per lane.
    type Mask: Copy;
    /// Every lane `x`.
    fn splat(x: f64) -> Self;
    /// Lane `i` is `f(i)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// The value of lane `i`.
    fn lane(self, i: usize) -> f64;
    /// Per lane: `x != 0`.
    fn nonzero(self) -> Self::Mask;
    /// Per lane: either flag.
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Whether any lane's flag is set.
    fn any(m: Self::Mask) -> bool;
    /// Per lane: `a` where the flag is set, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Whether every lane is finite.
    fn all_finite(self) -> bool;
    /// Whether every lane is `> 0` (NaN is not).
    fn all_positive(self) -> bool;
    /// [`crate::cube_root`] of every lane.
    fn cube_root(self) -> Self;
}

impl Lane for f64 {
    const WIDTH: usize = 1;
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn nonzero(self) -> bool {
        self != 0.0
    }
    #[inline(always)]
    fn or(a: bool, b: bool) -> bool {
        a || b
    }
    #[inline(always)]
    fn any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn all_finite(self) -> bool {
        self.is_finite()
    }
    #[inline(always)]
    fn all_positive(self) -> bool {
        self > 0.0
    }
    #[inline(always)]
    fn cube_root(self) -> Self {
        crate::cube_root(self)
    }
}

/// Four `f64` in the lanes of one AVX2 register (module docs). Its
/// operations are elementwise and always inlined, so inside a function
/// compiled for AVX2 (the element kernel's runtime dispatch) LLVM turns them
/// into single vector instructions.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[repr(C, align(32))]
pub struct F64x4(pub [f64; 4]);

impl Display for F64x4 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.0)
    }
}

macro_rules! elementwise {
    ($tr:ident, $f:ident, $atr:ident, $af:ident, $op:tt) => {
        impl $tr for F64x4 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                let (a, b) = (self.0, o.0);
                Self([a[0] $op b[0], a[1] $op b[1], a[2] $op b[2], a[3] $op b[3]])
            }
        }
        impl $tr<f64> for F64x4 {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: f64) -> Self {
                let a = self.0;
                Self([a[0] $op o, a[1] $op o, a[2] $op o, a[3] $op o])
            }
        }
        impl $atr for F64x4 {
            #[inline(always)]
            fn $af(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}

elementwise!(Add, add, AddAssign, add_assign, +);
elementwise!(Sub, sub, SubAssign, sub_assign, -);
elementwise!(Mul, mul, MulAssign, mul_assign, *);
elementwise!(Div, div, DivAssign, div_assign, /);

impl Neg for F64x4 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let a = self.0;
        Self([-a[0], -a[1], -a[2], -a[3]])
    }
}

impl num_traits::Zero for F64x4 {
    #[inline(always)]
    fn zero() -> Self {
        Self([0.0; 4])
    }
    fn is_zero(&self) -> bool {
        self.0 == [0.0; 4]
    }
}

impl num_traits::One for F64x4 {
    #[inline(always)]
    fn one() -> Self {
        Self([1.0; 4])
    }
}

impl Lane for F64x4 {
    const WIDTH: usize = 4;
    type Mask = [bool; 4];
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Self([x; 4])
    }
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Self(std::array::from_fn(f))
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.0[i]
    }
    #[inline(always)]
    fn nonzero(self) -> [bool; 4] {
        self.0.map(|x| x != 0.0)
    }
    #[inline(always)]
    fn or(a: [bool; 4], b: [bool; 4]) -> [bool; 4] {
        [a[0] | b[0], a[1] | b[1], a[2] | b[2], a[3] | b[3]]
    }
    #[inline(always)]
    fn any(m: [bool; 4]) -> bool {
        m[0] | m[1] | m[2] | m[3]
    }
    #[inline(always)]
    fn select(m: [bool; 4], a: Self, b: Self) -> Self {
        Self(std::array::from_fn(|i| if m[i] { a.0[i] } else { b.0[i] }))
    }
    #[inline(always)]
    fn all_finite(self) -> bool {
        self.0.iter().all(|x| x.is_finite())
    }
    #[inline(always)]
    fn all_positive(self) -> bool {
        let a = self.0;
        (a[0] > 0.0) & (a[1] > 0.0) & (a[2] > 0.0) & (a[3] > 0.0)
    }
    /// The guess lane by lane (integer division), the Halley steps 4 wide;
    /// lanes out of the fast range all go to [`crate::cube_root`].
    #[inline(always)]
    fn cube_root(self) -> Self {
        if !self.0.iter().all(|&x| crate::cube_root::in_fast_range(x)) {
            return Self(self.0.map(crate::cube_root));
        }
        crate::cube_root::halley(self, Self(self.0.map(crate::cube_root::guess)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_are_the_scalar_operations() {
        let a = F64x4([1.5, -2.0, 3e-300, 0.7]);
        let b = F64x4([0.3, 7.0, 1e10, -0.0]);
        for i in 0..4 {
            let (x, y) = (a.0[i], b.0[i]);
            assert_eq!((a + b).0[i].to_bits(), (x + y).to_bits());
            assert_eq!((a - b).0[i].to_bits(), (x - y).to_bits());
            assert_eq!((a * b).0[i].to_bits(), (x * y).to_bits());
            assert_eq!((a / b).0[i].to_bits(), (x / y).to_bits());
            assert_eq!((a * 3.1).0[i].to_bits(), (x * 3.1).to_bits());
        }
        let x = F64x4([0.9, 1.0, 1.3e-5, 27.0]);
        for i in 0..4 {
            assert_eq!(x.cube_root().0[i], crate::cube_root(x.0[i]));
        }
        let y = F64x4([0.9, 0.0, -8.0, 1e200]);
        for i in 0..4 {
            assert_eq!(y.cube_root().0[i], crate::cube_root(y.0[i]));
        }
    }
}
