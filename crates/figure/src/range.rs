//! Axis ranges from the data: the one rule every figure uses.

/// Smallest and largest of the finite values, `None` when there are none.
pub(crate) fn extent(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    (lo <= hi).then_some((lo, hi))
}

/// `(lo, hi)` widened by `pad` of the span on each side; a single value
/// becomes `value ± 0.5`, no value `(0, 1)`.
pub(crate) fn padded(e: Option<(f64, f64)>, pad: f64) -> (f64, f64) {
    match e {
        Some((lo, hi)) if hi > lo => {
            let span = hi - lo;
            (lo - pad * span, hi + pad * span)
        }
        Some((lo, _)) => (lo - 0.5, lo + 0.5),
        None => (0.0, 1.0),
    }
}

/// Log-axis range: the positive extent widened by a factor 1.5 each side;
/// `(1e-3, 1)` when nothing is positive.
pub(crate) fn log_padded(e: Option<(f64, f64)>) -> (f64, f64) {
    match e {
        Some((lo, hi)) if lo > 0.0 && hi > lo => (lo / 1.5, hi * 1.5),
        Some((lo, _)) if lo > 0.0 => (lo / 10.0, lo * 10.0),
        _ => (1e-3, 1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extent_skips_non_finite_values() {
        let e = extent([f64::NAN, 2.0, -1.0, f64::INFINITY].into_iter());
        assert_eq!(e, Some((-1.0, 2.0)));
        assert_eq!(extent([f64::NAN].into_iter()), None);
    }

    #[test]
    fn padding_widens_by_the_fraction_of_the_span() {
        assert_eq!(padded(Some((0.0, 10.0)), 0.04), (-0.4, 10.4));
        assert_eq!(padded(Some((3.0, 3.0)), 0.04), (2.5, 3.5));
        assert_eq!(padded(None, 0.04), (0.0, 1.0));
        assert_eq!(log_padded(Some((1e-4, 1.0))), (1e-4 / 1.5, 1.5));
        assert_eq!(log_padded(None), (1e-3, 1.0));
    }
}
