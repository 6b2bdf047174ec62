//! Reference implementations of the hereditary integrals by the thesis's
//! trapezoidal sum over the whole past (eq. 2.48; D.2.1): O(N) work per
//! step, O(N²) per history. They exist to check the O(terms) recursive
//! updates ([`crate::HistoryRule::Trapezoid`] must agree to rounding) and are
//! written without the Cayley–Hamilton rewriting the point updates use.
//!
//! A history is a list of samples `(t_i, F_i)` with non-decreasing
//! `t_i ≥ 0` and `det F_i = 1`; before the first sample `F = I` (a virtual
//! sample `(0, I)` is prepended). The result is the extra Cauchy stress
//! `T_n` (`σ = −q I + T`) at every sample.

use crate::kernel::{IsoStress, Kin};
use crate::{Mat3, MaterialError, PipkinRogers, PronyViscoelastic, Result};

fn with_origin(samples: &[(f64, Mat3)]) -> Result<Vec<(f64, Mat3)>> {
    let mut out = Vec::with_capacity(samples.len() + 1);
    out.push((0.0, Mat3::identity()));
    let mut last = 0.0;
    for (i, &(t, f)) in samples.iter().enumerate() {
        if !t.is_finite() || t < last {
            return Err(MaterialError::Loading(format!(
                "sample {}: time {t} s is before the previous one ({last} s)",
                i + 1
            )));
        }
        last = t;
        out.push((t, f));
    }
    Ok(out)
}

/// Trapezoidal sum `Σ_j (Δ_j/2) [f(j+1, t_n − t_{j+1}) + f(j, t_n − t_j)]`
/// of eq. 2.48 for every `n`.
fn trapezoid_all<K: Fn(usize, f64) -> Mat3>(times: &[f64], integrand: K) -> Vec<Mat3> {
    (0..times.len())
        .map(|n| {
            let mut sum = Mat3::zeros();
            for j in 0..n {
                let d = times[j + 1] - times[j];
                if d > 0.0 {
                    sum += (integrand(j + 1, times[n] - times[j + 1])
                        + integrand(j, times[n] - times[j]))
                        * (0.5 * d);
                }
            }
            sum
        })
        .collect()
}

/// Pipkin–Rogers extra stress
/// `T(t_n) = F {R[C(t_n), 0] + ∫_0^{t_n} ∂R[C(s), t_n − s]/∂(t_n − s) ds} Fᵀ`
/// (eq. 2.1) with the integral by eq. 2.48.
///
/// # Errors
/// [`MaterialError::Loading`] when sample times decrease.
pub fn pipkin_rogers_trapezoid(m: &PipkinRogers, samples: &[(f64, Mat3)]) -> Result<Vec<Mat3>> {
    let h = with_origin(samples)?;
    let times: Vec<f64> = h.iter().map(|s| s.0).collect();
    let cs: Vec<Mat3> = h.iter().map(|s| s.1.transpose() * s.1).collect();
    let sums = trapezoid_all(&times, |j, u| m.r_rate(&cs[j], u));
    Ok(h.iter()
        .zip(cs.iter().zip(sums))
        .skip(1)
        .map(|((_, f), (c, sum))| f * (m.r_tensor(c, 0.0) + sum) * f.transpose())
        .collect())
}

/// ABAQUS-form extra stress (§4.3)
/// `T(t_n) = dev{F [S̄0(t_n) + ∫_0^{t_n} Ġ(t_n − s)/G0 S̄0(s) ds] Fᵀ}`
/// with the integral by eq. 2.48 (`det F = 1`, so `F̄ = F`).
///
/// # Errors
/// [`MaterialError::Loading`] when sample times decrease;
/// [`MaterialError::Deformation`] for a sample with `det F ≤ 0`.
pub fn prony_viscoelastic_trapezoid(
    m: &PronyViscoelastic,
    samples: &[(f64, Mat3)],
) -> Result<Vec<Mat3>> {
    let h = with_origin(samples)?;
    let times: Vec<f64> = h.iter().map(|s| s.0).collect();
    let mut sbar = Vec::with_capacity(h.len());
    for (_, f) in &h {
        let k = Kin::new(f)?;
        let mut iso = IsoStress::default();
        m.elastic().add_isochoric(&k, 1.0, &mut iso);
        sbar.push(iso.pk2(&k) * k.j.powf(2.0 / 3.0));
    }
    let sums = trapezoid_all(&times, |j, u| sbar[j] * m.prony().derivative(u));
    Ok(h.iter()
        .zip(sbar.iter().zip(sums))
        .skip(1)
        .map(|((_, f), (s0, sum))| {
            let t = f * (s0 + sum) * f.transpose();
            t - Mat3::identity() * (t.trace() / 3.0)
        })
        .collect())
}
