//! Seeded Latin-hypercube start points inside the feasible region of a
//! [`Domain`] (the thesis used MATLAB `lhsdesign` with g1 + g2 < 1, §5.4.1),
//! from the pipeline's one Latin hypercube,
//! `nlvid_surrogate::doe::latin_hypercube_unit`.
//!
//! A Latin hypercube of size n is drawn in the scaled cube; points that
//! violate a linear constraint are dropped and further hypercubes are drawn
//! until n feasible points are collected (each batch is stratified, the union
//! is not exactly).

use nlvid_model::Domain;
use nlvid_surrogate::doe::latin_hypercube_unit;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::error::{InverseError, Result};

/// Maximum number of Latin-hypercube batches before giving up.
const MAX_BATCHES: usize = 200;

/// `n` feasible start points (physical units) from seeded Latin hypercubes.
///
/// # Errors
/// [`InverseError::InvalidSetting`] if n = 0 or the feasible region is so
/// small that 200 hypercubes do not yield n points.
pub fn feasible_starts(domain: &Domain, n: usize, seed: u64) -> Result<Vec<Vec<f64>>> {
    if n == 0 {
        return Err(InverseError::InvalidSetting(
            "the number of start points must be at least 1".into(),
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    for _ in 0..MAX_BATCHES {
        for u in latin_hypercube_unit(n, domain.len(), &mut rng) {
            let x = domain.from_unit(&u);
            if domain.feasible(&x, 0.0) {
                out.push(x);
                if out.len() == n {
                    return Ok(out);
                }
            }
        }
    }
    Err(InverseError::InvalidSetting(format!(
        "only {} of {n} feasible start points found in {MAX_BATCHES} Latin hypercubes: \
         the constraints leave almost no room in the domain; widen the bounds",
        out.len()
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_are_feasible_and_reproducible() {
        let d = Domain::table_5_3(0.01).expect("domain");
        let a = feasible_starts(&d, 16, 42).expect("starts");
        let b = feasible_starts(&d, 16, 42).expect("starts");
        assert_eq!(a, b);
        assert_eq!(a.len(), 16);
        for x in &a {
            assert!(d.contains(x, 0.0), "{x:?}");
            assert!(x[1] + x[2] <= 0.99);
        }
        assert_ne!(a, feasible_starts(&d, 16, 43).expect("starts"));
    }
}
