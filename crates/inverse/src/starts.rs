//! Seeded Latin-hypercube start points inside the feasible region of a
//! [`Domain`] (the thesis used MATLAB `lhsdesign` with g1 + g2 < 1, §5.4.1).
//!
//! A Latin hypercube of size n is drawn in the scaled cube; points that
//! violate a linear constraint are dropped and further hypercubes are drawn
//! until n feasible points are collected (each batch is stratified, the union
//! is not exactly).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::domain::Domain;
use crate::error::{InverseError, Result};

/// Maximum number of Latin-hypercube batches before giving up.
const MAX_BATCHES: usize = 200;

/// One Latin hypercube of `n` points in [0, 1]^dim (stratum centres jittered
/// uniformly within each stratum).
pub fn latin_hypercube(n: usize, dim: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut points = vec![vec![0.0; dim]; n];
    for d in 0..dim {
        let mut perm: Vec<usize> = (0..n).collect();
        // Fisher–Yates
        for i in (1..n).rev() {
            let j = rng.random_range(0..=i);
            perm.swap(i, j);
        }
        for (i, p) in points.iter_mut().enumerate() {
            let jitter: f64 = rng.random();
            p[d] = (perm[i] as f64 + jitter) / n as f64;
        }
    }
    points
}

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
        for u in latin_hypercube(n, domain.len(), &mut rng) {
            let x = domain.from_unit(&u);
            if domain.constraints().iter().all(|c| c.value(&x) <= 0.0) {
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
    fn latin_hypercube_puts_one_point_in_each_stratum_per_dimension() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let pts = latin_hypercube(10, 3, &mut rng);
        for d in 0..3 {
            let mut strata: Vec<usize> = pts.iter().map(|p| (p[d] * 10.0) as usize).collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..10).collect::<Vec<_>>());
        }
    }

    #[test]
    fn starts_are_feasible_and_reproducible() {
        let d = Domain::prony2_table_5_3(0.01).expect("domain");
        let a = feasible_starts(&d, 16, 42).expect("starts");
        let b = feasible_starts(&d, 16, 42).expect("starts");
        assert_eq!(a, b);
        assert_eq!(a.len(), 16);
        for x in &a {
            assert!(d.contains(x, 0.0), "{x:?}");
            assert!(x[1] + x[3] <= 0.99);
        }
        assert_ne!(a, feasible_starts(&d, 16, 43).expect("starts"));
    }
}
