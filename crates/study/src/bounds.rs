//! Allowed ranges for numbers read from a study, in SI units.

use std::ops::{Bound, RangeFrom, RangeFull, RangeInclusive, RangeToInclusive};

use crate::units::{Dimension, fmt_number};

/// An interval of allowed values in SI units; either end may be open,
/// closed or absent. Build it with the constructors or from `a..=b`, `a..`,
/// `..=b`, `..`.
///
/// ```
/// use nlvid_study::Bounds;
/// assert!(Bounds::positive().contains(1e-9));
/// assert!(!Bounds::positive().contains(0.0));
/// assert!(Bounds::from(0.0..=0.5).contains(0.5));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    lo: Bound<f64>,
    hi: Bound<f64>,
}

impl Bounds {
    /// Every finite value.
    pub const ANY: Self = Self {
        lo: Bound::Unbounded,
        hi: Bound::Unbounded,
    };

    /// Values `> 0`.
    pub const fn positive() -> Self {
        Self::greater_than(0.0)
    }
    /// Values `>= 0`.
    pub const fn non_negative() -> Self {
        Self::at_least(0.0)
    }
    /// Values `> a`.
    pub const fn greater_than(a: f64) -> Self {
        Self {
            lo: Bound::Excluded(a),
            hi: Bound::Unbounded,
        }
    }
    /// Values `>= a`.
    pub const fn at_least(a: f64) -> Self {
        Self {
            lo: Bound::Included(a),
            hi: Bound::Unbounded,
        }
    }
    /// Values `< b`.
    pub const fn less_than(b: f64) -> Self {
        Self {
            lo: Bound::Unbounded,
            hi: Bound::Excluded(b),
        }
    }
    /// Values `<= b`.
    pub const fn at_most(b: f64) -> Self {
        Self {
            lo: Bound::Unbounded,
            hi: Bound::Included(b),
        }
    }
    /// Values in `[a, b]`.
    pub const fn closed(a: f64, b: f64) -> Self {
        Self {
            lo: Bound::Included(a),
            hi: Bound::Included(b),
        }
    }
    /// Values in `(a, b)`.
    pub const fn open(a: f64, b: f64) -> Self {
        Self {
            lo: Bound::Excluded(a),
            hi: Bound::Excluded(b),
        }
    }
    /// Values in `[a, b)`.
    pub const fn closed_open(a: f64, b: f64) -> Self {
        Self {
            lo: Bound::Included(a),
            hi: Bound::Excluded(b),
        }
    }
    /// Values in `(a, b]`.
    pub const fn open_closed(a: f64, b: f64) -> Self {
        Self {
            lo: Bound::Excluded(a),
            hi: Bound::Included(b),
        }
    }

    /// Whether `x` is allowed (NaN never is).
    pub fn contains(&self, x: f64) -> bool {
        let lo = match self.lo {
            Bound::Included(a) => x >= a,
            Bound::Excluded(a) => x > a,
            Bound::Unbounded => !x.is_nan(),
        };
        let hi = match self.hi {
            Bound::Included(b) => x <= b,
            Bound::Excluded(b) => x < b,
            Bound::Unbounded => !x.is_nan(),
        };
        lo && hi
    }

    /// Human-readable description in SI units, e.g. `> 0 m` or `in [0, 0.5]`.
    pub fn describe(&self, dim: Dimension) -> String {
        let u = dim.si_unit();
        let unit = if u.is_empty() {
            String::new()
        } else {
            format!(" {u}")
        };
        let n = fmt_number;
        match (self.lo, self.hi) {
            (Bound::Unbounded, Bound::Unbounded) => "finite".to_string(),
            (Bound::Included(a), Bound::Unbounded) => format!(">= {}{unit}", n(a)),
            (Bound::Excluded(a), Bound::Unbounded) => format!("> {}{unit}", n(a)),
            (Bound::Unbounded, Bound::Included(b)) => format!("<= {}{unit}", n(b)),
            (Bound::Unbounded, Bound::Excluded(b)) => format!("< {}{unit}", n(b)),
            (lo, hi) => {
                let (l, a) = match lo {
                    Bound::Included(a) => ('[', a),
                    Bound::Excluded(a) => ('(', a),
                    Bound::Unbounded => ('(', f64::NEG_INFINITY),
                };
                let (r, b) = match hi {
                    Bound::Included(b) => (']', b),
                    Bound::Excluded(b) => (')', b),
                    Bound::Unbounded => (')', f64::INFINITY),
                };
                format!("in {l}{}, {}{r}{unit}", n(a), n(b))
            }
        }
    }
}

impl From<RangeInclusive<f64>> for Bounds {
    fn from(r: RangeInclusive<f64>) -> Self {
        Self::closed(*r.start(), *r.end())
    }
}
impl From<RangeFrom<f64>> for Bounds {
    fn from(r: RangeFrom<f64>) -> Self {
        Self::at_least(r.start)
    }
}
impl From<RangeToInclusive<f64>> for Bounds {
    fn from(r: RangeToInclusive<f64>) -> Self {
        Self::at_most(r.end)
    }
}
impl From<RangeFull> for Bounds {
    fn from(_: RangeFull) -> Self {
        Self::ANY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_and_closed_ends_are_respected() {
        let b = Bounds::open_closed(0.0, 1.0);
        assert!(!b.contains(0.0) && b.contains(1.0) && !b.contains(1.0 + 1e-15));
        assert!(!Bounds::ANY.contains(f64::NAN));
        assert_eq!(Bounds::positive().describe(Dimension::LENGTH), "> 0 m");
        assert_eq!(
            Bounds::from(0.0..=0.5).describe(Dimension::NONE),
            "in [0, 0.5]"
        );
        assert_eq!(
            Bounds::open(1.0, 2.0).describe(Dimension::TIME),
            "in (1, 2) s"
        );
    }
}
