//! The one Lee–Radok kernel: linear-viscoelastic Hertz contact of a rigid
//! sphere of radius R on a half-space with a Prony shear relaxation modulus
//! (eq. 5.1, [`Relaxation`]),
//!
//! ```text
//! F(t) = 8√R / (3(1 − ν)) ∫₀ᵗ G(t − s) d(δ^{3/2})/ds ds
//!      = P G0 [g∞ ε(t) + Σ_k g_k h_k(t)],   ε = δ^{3/2},
//! h_k(t) = ∫₀ᵗ e^{−(t−s)/τ_k} dε(s),
//! ```
//!
//! with P = 8√R/(3(1 − ν)) = (16/3)√R at ν = ½ (Lee & Radok 1960; the
//! elastic limit is Hertz, eq. 1.1 with E = 2G(1 + ν)). Valid while the
//! contact grows (ramp, then hold).
//!
//! Two indentation histories, each evaluated exactly:
//! - [`LeeRadok::ramp_hold`]: δ = v·min(t, t_r) (the `hertz-prony` forward
//!   model, the demo's curves). With x = m/τ, m = min(t, t_r),
//!   h = (3/2) v^{3/2} τ^{3/2} e^{−(t−m)/τ} φ(x),
//!   φ(x) = e^{−x}∫₀ˣ eᵘ u^{1/2} du = √x − D(√x) (D: Dawson's integral),
//!   evaluated by its positive power series (x < 40) or the asymptotic
//!   series of D (x ≥ 40), both to rounding;
//! - [`LeeRadok::sampled`]: a measured δ(t_j), with ε piecewise linear
//!   between samples (the fits of measured curves, `nlvid inspect`):
//!   h(t_{j+1}) = e^{−Δ/τ} h(t_j) + (Δε/Δ) τ (1 − e^{−Δ/τ}); a jump at t₀
//!   loads instantaneously.
//!
//! [`LeeRadok::force_and_jacobian`] returns ∂F/∂(G0, g_k, τ_k) analytically
//! (∂h/∂τ by the same closed forms); tests check it against central
//! differences, and the ramp-hold forms against independent quadrature.
//! Cost: O(m · K) per force, m times and K Prony terms.

use nlvid_model::Relaxation;

use crate::error::{ForwardError, Result};

/// Which indentation history, with what its evaluation needs.
#[derive(Debug, Clone, PartialEq)]
enum History {
    /// δ = rate · min(t, ramp), t ≥ 0 (δ = 0 before).
    RampHold { rate: f64, ramp: f64 },
    /// ε = δ^{3/2} at the times, piecewise linear between them.
    Sampled,
}

/// The Lee–Radok hereditary integral on a fixed time grid for one sphere and
/// one indentation history (see the module documentation for the formulas).
#[derive(Debug, Clone, PartialEq)]
pub struct LeeRadok {
    times: Vec<f64>,
    /// ε(t_j) = δ(t_j)^{3/2}, m^{3/2} (δ ≤ 0: no contact, 0).
    eps: Vec<f64>,
    /// P = 8√R / (3(1 − ν)), m^{1/2}.
    prefactor: f64,
    history: History,
}

fn setting(message: String) -> ForwardError {
    ForwardError::Setting {
        model: "lee-radok",
        message,
    }
}

fn check_common(times: &[f64], radius: f64, poisson: f64) -> Result<()> {
    if times.is_empty() {
        return Err(setting("the time grid is empty".into()));
    }
    if let Some(j) = times.iter().position(|t| !t.is_finite()) {
        return Err(setting(format!("time {j} is {} (not finite)", times[j])));
    }
    if let Some(j) = times.windows(2).position(|w| w[1] <= w[0]) {
        return Err(setting(format!(
            "the time grid must increase strictly: t[{}] = {} s follows {} s",
            j + 1,
            times[j + 1],
            times[j]
        )));
    }
    if !(radius.is_finite() && radius > 0.0) {
        return Err(setting(format!(
            "the sphere radius must be > 0, got {radius} m"
        )));
    }
    if !(0.0..=0.5).contains(&poisson) {
        return Err(setting(format!(
            "Poisson's ratio must be in [0, 0.5], got {poisson}"
        )));
    }
    Ok(())
}

impl LeeRadok {
    /// A sphere of radius `radius` (m) pushed at `rate` (m/s) for `ramp`
    /// (s), then held; F at `times` (s, strictly increasing; t ≤ 0 is
    /// before contact). ν = `poisson` (½: incompressible).
    ///
    /// # Errors
    /// [`ForwardError::Setting`] for an empty or non-increasing grid,
    /// R ≤ 0, rate or ramp ≤ 0 (or not finite), ν ∉ [0, ½].
    pub fn ramp_hold(
        radius: f64,
        poisson: f64,
        rate: f64,
        ramp: f64,
        times: Vec<f64>,
    ) -> Result<Self> {
        check_common(&times, radius, poisson)?;
        if !(rate.is_finite() && rate > 0.0 && ramp.is_finite() && ramp > 0.0) {
            return Err(setting(format!(
                "the ramp needs a rate > 0 and a duration > 0, got {rate} m/s for {ramp} s"
            )));
        }
        let eps = times
            .iter()
            .map(|&t| (rate * t.clamp(0.0, ramp)).powf(1.5))
            .collect();
        Ok(Self {
            times,
            eps,
            prefactor: 8.0 * radius.sqrt() / (3.0 * (1.0 - poisson)),
            history: History::RampHold { rate, ramp },
        })
    }

    /// A measured indentation `indentation[j]` (m) at `times[j]` (s),
    /// δ^{3/2} linear between samples (δ ≤ 0 counts as no contact).
    ///
    /// # Errors
    /// [`ForwardError::Setting`] for different lengths, an empty or
    /// non-increasing grid, a non-finite indentation, R ≤ 0, ν ∉ [0, ½].
    pub fn sampled(
        radius: f64,
        poisson: f64,
        times: Vec<f64>,
        indentation: &[f64],
    ) -> Result<Self> {
        if times.len() != indentation.len() {
            return Err(setting(format!(
                "the time grid has {} samples, the indentation history {}",
                times.len(),
                indentation.len()
            )));
        }
        check_common(&times, radius, poisson)?;
        if let Some(j) = indentation.iter().position(|d| !d.is_finite()) {
            return Err(setting(format!(
                "indentation at sample {j} (t = {} s) is {} (not finite)",
                times[j], indentation[j]
            )));
        }
        Ok(Self {
            eps: indentation.iter().map(|d| d.max(0.0).powf(1.5)).collect(),
            times,
            prefactor: 8.0 * radius.sqrt() / (3.0 * (1.0 - poisson)),
            history: History::Sampled,
        })
    }

    /// The time grid (s).
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// P ε(t_j): the force per unit shear modulus of an elastic material
    /// (N/Pa), the g∞ column of the force.
    pub fn elastic(&self) -> Vec<f64> {
        self.eps.iter().map(|e| self.prefactor * e).collect()
    }

    /// P h(t_j; τ): the force per unit modulus of a term relaxing with time
    /// `tau` (N/Pa).
    pub fn hereditary(&self, tau: f64) -> Vec<f64> {
        let (h, _) = self.integrals(tau, false);
        h.into_iter().map(|v| self.prefactor * v).collect()
    }

    /// [`LeeRadok::hereditary`] for several relaxation times at once, equal to
    /// it to the bit; a sampled history takes one pass for all of them
    /// ([`exp_convolutions`]).
    pub fn hereditary_many(&self, taus: &[f64]) -> Vec<Vec<f64>> {
        match self.history {
            History::Sampled => {
                let mut hs = exp_convolutions(&self.times, &self.eps, taus);
                for h in &mut hs {
                    h.iter_mut().for_each(|v| *v *= self.prefactor);
                }
                hs
            }
            History::RampHold { .. } => taus.iter().map(|&t| self.hereditary(t)).collect(),
        }
    }

    /// F(t_j) (N) for the relaxation modulus `g` (eq. 5.1).
    pub fn force(&self, g: &Relaxation) -> Vec<f64> {
        let p = g.prony();
        let ginf = p.long_term_weight();
        let mut f: Vec<f64> = self.eps.iter().map(|e| ginf * e).collect();
        for term in p.terms() {
            let (h, _) = self.integrals(term.tau, false);
            for (fj, hj) in f.iter_mut().zip(h) {
                *fj += term.weight * hj;
            }
        }
        let c = self.prefactor * g.g0();
        f.iter_mut().for_each(|v| *v *= c);
        f
    }

    /// F(t_j) and its derivatives with respect to the parameters in the
    /// order G0, g_1 … g_K, τ_1 … τ_K (for two terms, `names::PRONY2`):
    /// `jacobian[k][j]` = ∂F(t_j)/∂p_k.
    ///
    /// ∂F/∂G0 = F/G0, ∂F/∂g_k = P G0 (h_k − ε),
    /// ∂F/∂τ_k = P G0 g_k ∂h_k/∂τ_k.
    pub fn force_and_jacobian(&self, g: &Relaxation) -> (Vec<f64>, Vec<Vec<f64>>) {
        let p = g.prony();
        let (g0, ginf, k) = (g.g0(), p.long_term_weight(), p.len());
        let pf = self.prefactor;
        let mut bracket: Vec<f64> = self.eps.iter().map(|e| ginf * e).collect();
        let mut jac = vec![Vec::new(); 1 + 2 * k];
        for (i, term) in p.terms().iter().enumerate() {
            let (h, dh) = self.integrals(term.tau, true);
            for (b, hj) in bracket.iter_mut().zip(&h) {
                *b += term.weight * hj;
            }
            jac[1 + i] = h
                .iter()
                .zip(&self.eps)
                .map(|(hj, e)| pf * g0 * (hj - e))
                .collect();
            jac[1 + k + i] = dh.iter().map(|d| pf * g0 * term.weight * d).collect();
        }
        jac[0] = bracket.iter().map(|b| pf * b).collect();
        let f = jac[0].iter().map(|v| g0 * v).collect();
        (f, jac)
    }

    /// h(t_j; τ) = ∫ e^{−(t_j−s)/τ} dε(s) and, if `with_dtau`, ∂h/∂τ
    /// (otherwise an empty vector).
    fn integrals(&self, tau: f64, with_dtau: bool) -> (Vec<f64>, Vec<f64>) {
        match self.history {
            History::RampHold { rate, ramp } => {
                let c = 1.5 * rate.powf(1.5);
                let mut h = Vec::with_capacity(self.times.len());
                let mut dh = Vec::with_capacity(if with_dtau { self.times.len() } else { 0 });
                for &t in &self.times {
                    let m = t.clamp(0.0, ramp);
                    let x = m / tau;
                    let decay = if t > m { (-(t - m) / tau).exp() } else { 1.0 };
                    let (phi, chi) = phi_chi(x);
                    let hj = c * tau.powf(1.5) * decay * phi;
                    h.push(hj);
                    if with_dtau {
                        // ∂h/∂τ = ((t − m)/τ²) h + c τ^{1/2} e^{−(t−m)/τ} χ(x).
                        dh.push((t - m) / (tau * tau) * hj + c * tau.sqrt() * decay * chi);
                    }
                }
                (h, dh)
            }
            History::Sampled => exp_convolution(&self.times, &self.eps, tau, with_dtau),
        }
    }
}

/// h(t_j) = ∫₀^{t_j} e^{−(t_j−s)/τ} dx(s) for a history x sampled at `times`
/// (strictly increasing) and linear between samples, x jumping from 0 to x(t₀)
/// at t₀ (an instantaneous load), and, if `with_dtau`, ∂h/∂τ (otherwise an
/// empty vector). Exact for piecewise-linear x, O(m):
/// h(t_{j+1}) = e^{−Δ/τ} h(t_j) + (Δx/Δ) τ (1 − e^{−Δ/τ}).
///
/// The Lee–Radok hereditary integral in displacement control takes
/// x = δ^{3/2} ([`LeeRadok::sampled`]); in force control (creep, the
/// compliance form δ^{3/2} = 3/(16√R) ∫ J(t − s) dF) it takes x = F.
pub fn exp_convolution(
    times: &[f64],
    x: &[f64],
    tau: f64,
    with_dtau: bool,
) -> (Vec<f64>, Vec<f64>) {
    let m = times.len().min(x.len());
    let mut h = vec![0.0; m];
    let mut dh = vec![0.0; if with_dtau { m } else { 0 }];
    if m == 0 {
        return (h, dh);
    }
    h[0] = x[0];
    // Equal steps (the usual instrument grid) share one exponential.
    let mut last = (f64::NAN, 0.0, 0.0);
    for j in 0..m - 1 {
        let dt = times[j + 1] - times[j];
        let rate = (x[j + 1] - x[j]) / dt;
        if dt != last.0 {
            // τ(1 − e^{−Δ/τ}), accurate for Δ ≪ τ.
            last = (dt, (-dt / tau).exp(), -tau * (-dt / tau).exp_m1());
        }
        let (_, a, b) = last;
        h[j + 1] = a * h[j] + rate * b;
        if with_dtau {
            let da = a * dt / (tau * tau);
            let db = -(-dt / tau).exp_m1() - a * dt / tau;
            dh[j + 1] = da * h[j] + a * dh[j] + rate * db;
        }
    }
    (h, dh)
}

/// [`exp_convolution`]'s h for several τ, equal to it to the bit (same
/// recurrence, same rounding). Up to four τ run in one pass: the recurrence is
/// a chain of dependent multiply–adds, and interleaving independent chains
/// hides their latency (a Lee–Radok or creep fit spends most of its time here).
pub fn exp_convolutions(times: &[f64], x: &[f64], taus: &[f64]) -> Vec<Vec<f64>> {
    taus.chunks(4)
        .flat_map(|chunk| match chunk {
            [a] => Vec::from(exp_convolutions_one_pass(times, x, [*a])),
            [a, b] => Vec::from(exp_convolutions_one_pass(times, x, [*a, *b])),
            [a, b, c] => Vec::from(exp_convolutions_one_pass(times, x, [*a, *b, *c])),
            [a, b, c, d] => Vec::from(exp_convolutions_one_pass(times, x, [*a, *b, *c, *d])),
            _ => unreachable!("chunks of 1..=4"),
        })
        .collect()
}

/// [`exp_convolutions`] of `M` relaxation times in one pass.
fn exp_convolutions_one_pass<const M: usize>(
    times: &[f64],
    x: &[f64],
    taus: [f64; M],
) -> [Vec<f64>; M] {
    let m = times.len().min(x.len());
    let mut h: [Vec<f64>; M] = std::array::from_fn(|_| Vec::with_capacity(m));
    if m == 0 {
        return h;
    }
    let mut state = [x[0]; M];
    for hk in &mut h {
        hk.push(x[0]);
    }
    let (mut last_dt, mut a, mut b) = (f64::NAN, [0.0; M], [0.0; M]);
    for j in 0..m - 1 {
        let dt = times[j + 1] - times[j];
        let rate = (x[j + 1] - x[j]) / dt;
        if dt != last_dt {
            last_dt = dt;
            for k in 0..M {
                a[k] = (-dt / taus[k]).exp();
                b[k] = -taus[k] * (-dt / taus[k]).exp_m1();
            }
        }
        for k in 0..M {
            state[k] = a[k] * state[k] + rate * b[k];
            h[k].push(state[k]);
        }
    }
    h
}

/// φ(x) = ∫₀ˣ e^{−(x−u)} u^{1/2} du and χ(x) = ∫₀ˣ (x − u) e^{−(x−u)} u^{1/2} du
/// (x ≥ 0), both positive.
///
/// x < 40: φ = e^{−x} Σ x^{n+3/2}/(n! (n + 3/2)),
/// χ = e^{−x} Σ x^{n+5/2}/(n! (n + 3/2)(n + 5/2)) (positive terms, summed to
/// rounding). x ≥ 40: φ = √x − D(√x) and χ = (3/2 + x)φ − x^{3/2} =
/// (3/2)√x − (3/2 + x) D(√x), with Dawson's D(y) ~ (1/2y) Σ (2k−1)!!/(2y²)^k,
/// truncated where its terms fall below 1e-17 (they do before k = 40, where
/// the series' smallest term is ~e^{−40}).
fn phi_chi(x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 0.0);
    }
    if x < 40.0 {
        let (mut term, mut sp, mut sc) = (1.0, 0.0, 0.0); // term = x^n / n!
        for n in 0..2000 {
            let a = n as f64 + 1.5;
            let (tp, tc) = (term / a, term / (a * (a + 1.0)));
            sp += tp;
            sc += tc;
            if tp <= 1e-17 * sp && n as f64 > x {
                break;
            }
            term *= x / (n as f64 + 1.0);
        }
        let e = (-x).exp();
        (e * x.powf(1.5) * sp, e * x.powf(2.5) * sc)
    } else {
        let y = x.sqrt();
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..60 {
            term *= (2 * k - 1) as f64 / (2.0 * x);
            sum += term;
            if term <= 1e-17 * sum {
                break;
            }
        }
        let dawson = sum / (2.0 * y);
        (y - dawson, 1.5 * y - (1.5 + x) * dawson)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_model::Prony;

    fn relaxation(g0: f64, terms: &[(f64, f64)]) -> Relaxation {
        Relaxation::new("G0", g0, Prony::new("G", terms).expect("prony")).expect("relaxation")
    }

    /// ∫₀ˣ e^{−(x−u)} u^{1/2} du by composite Gauss–Legendre in w = √u
    /// (u = w², du = 2w dw: a smooth integrand), an independent check.
    fn phi_quadrature(x: f64) -> (f64, f64) {
        const X: [f64; 5] = [
            -0.906_179_845_938_664,
            -0.538_469_310_105_683,
            0.0,
            0.538_469_310_105_683,
            0.906_179_845_938_664,
        ];
        const W: [f64; 5] = [
            0.236_926_885_056_189,
            0.478_628_670_499_366,
            0.568_888_888_888_889,
            0.478_628_670_499_366,
            0.236_926_885_056_189,
        ];
        let top = x.sqrt();
        let panels = 4000;
        let h = top / panels as f64;
        let (mut p, mut c) = (0.0, 0.0);
        for k in 0..panels {
            let mid = (k as f64 + 0.5) * h;
            for (xi, wi) in X.iter().zip(W) {
                let w = mid + 0.5 * h * xi;
                let u = w * w;
                let f = (-(x - u)).exp() * w * 2.0 * w * wi * 0.5 * h;
                p += f;
                c += (x - u) * f;
            }
        }
        (p, c)
    }

    #[test]
    fn phi_and_chi_match_quadrature_on_both_sides_of_the_series_switch() {
        for x in [
            1e-6, 1e-3, 0.3, 1.0, 7.5, 25.0, 39.9, 40.0, 40.1, 80.0, 400.0,
        ] {
            let (p, c) = phi_chi(x);
            let (pq, cq) = phi_quadrature(x);
            assert!((p / pq - 1.0).abs() < 1e-12, "phi({x}) = {p} vs {pq}");
            assert!((c / cq - 1.0).abs() < 1e-11, "chi({x}) = {c} vs {cq}");
        }
        // Small x: φ ≈ (2/3) x^{3/2}, χ ≈ (4/15) x^{5/2}.
        let (p, c) = phi_chi(1e-10);
        assert!((p / (2.0 / 3.0 * 1e-15) - 1.0).abs() < 1e-9);
        assert!((c / (4.0 / 15.0 * 1e-25) - 1.0).abs() < 1e-9);
    }

    /// F by direct quadrature of ∫ G(t − s) dε(s), dε/ds = 1.5 v^{3/2} s^{1/2},
    /// in s = w² (midpoint rule, many points): independent of the kernel.
    fn quadrature_force(g: &Relaxation, radius: f64, rate: f64, ramp: f64, t: f64) -> f64 {
        let upper = t.min(ramp).sqrt();
        let n = 200_000;
        let h = upper / n as f64;
        let mut acc = 0.0;
        for j in 0..n {
            let w = (j as f64 + 0.5) * h;
            acc += g.value(t - w * w) * 1.5 * rate.powf(1.5) * w * 2.0 * w * h;
        }
        16.0 / 3.0 * radius.sqrt() * acc
    }

    #[test]
    fn ramp_hold_force_matches_independent_quadrature() {
        let g = relaxation(800.0, &[(0.45, 0.05), (0.3, 4.0)]);
        let (r, v, tr) = (2.5e-6, 2e-6, 1.0);
        let times = vec![0.01, 0.1, 0.5, 1.0, 1.001, 1.3, 5.0, 52.0];
        let k = LeeRadok::ramp_hold(r, 0.5, v, tr, times.clone()).expect("kernel");
        let f = k.force(&g);
        for (t, fj) in times.iter().zip(&f) {
            let q = quadrature_force(&g, r, v, tr, *t);
            assert!((fj / q - 1.0).abs() < 1e-8, "t = {t}: {fj} vs {q}");
        }
    }

    #[test]
    fn elastic_limit_is_the_hertz_force() {
        // No relaxation: F = (16/3) G0 √R δ^{3/2} (eq. 1.1 with E = 3 G0).
        let g = relaxation(1000.0, &[(0.0, 0.3), (0.0, 8.0)]);
        let times: Vec<f64> = (1..=30).map(|i| 0.1 * i as f64).collect();
        let k = LeeRadok::ramp_hold(5e-6, 0.5, 1e-6, 1.0, times.clone()).expect("kernel");
        for (t, f) in times.iter().zip(k.force(&g)) {
            let hertz = 16.0 / 3.0 * 1000.0 * 5e-6f64.sqrt() * (1e-6 * t.min(1.0)).powf(1.5);
            assert!((f / hertz - 1.0).abs() < 1e-14, "t = {t}: {f} vs {hertz}");
        }
    }

    #[test]
    fn several_taus_in_one_pass_equal_one_tau_at_a_time_to_the_bit() {
        // An irregular grid with runs of equal steps (the shared-exponential
        // branch) and a history that is not piecewise linear; 1 to 9 τ cover
        // every chunk length of the one-pass form.
        let mut times = vec![0.0];
        for i in 1..400 {
            let dt = if i % 50 < 30 {
                1e-3
            } else {
                1e-3 * (1.0 + 0.01 * (i % 7) as f64)
            };
            times.push(times[i - 1] + dt);
        }
        let x: Vec<f64> = times
            .iter()
            .map(|t| (t * 3.0).sin().abs().powf(1.5))
            .collect();
        let taus: Vec<f64> = (0..9).map(|k| 1e-3 * 3f64.powi(k)).collect();
        for n in 1..=taus.len() {
            let many = exp_convolutions(&times, &x, &taus[..n]);
            assert_eq!(many.len(), n);
            for (h, &tau) in many.iter().zip(&taus[..n]) {
                let (one, _) = exp_convolution(&times, &x, tau, false);
                let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(h), bits(&one), "τ = {tau} of {n}");
            }
        }
        let k = LeeRadok::sampled(2.5e-6, 0.5, times.clone(), &x).expect("kernel");
        assert_eq!(
            k.hereditary_many(&taus[..3]),
            vec![
                k.hereditary(taus[0]),
                k.hereditary(taus[1]),
                k.hereditary(taus[2])
            ]
        );
    }

    #[test]
    fn sampled_history_is_exact_when_delta_to_three_halves_is_linear() {
        // ε = c·min(t, t_r): F = P G0 [g∞ ε + Σ g_k τ_k c (e^{−(t−m)/τ_k} − e^{−t/τ_k})],
        // with t_r on the grid (t = i/20 s) so that ε is linear between samples.
        let (tr, c, nu, r) = (0.5, 4e-9, 0.3, 2.5e-6);
        let times: Vec<f64> = (0..=600).map(|i| i as f64 / 20.0).collect();
        let delta: Vec<f64> = times
            .iter()
            .map(|&t| (c * t.min(tr)).powf(2.0 / 3.0))
            .collect();
        let g = relaxation(700.0, &[(0.5, 0.07), (0.3, 8.0)]);
        let k = LeeRadok::sampled(r, nu, times.clone(), &delta).expect("kernel");
        let p = 8.0 * r.sqrt() / (3.0 * (1.0 - nu));
        for (t, f) in times.iter().zip(k.force(&g)) {
            let m = t.min(tr);
            let term =
                |gk: f64, tau: f64| gk * tau * c * ((-(t - m) / tau).exp() - (-t / tau).exp());
            let exact = p * 700.0 * (0.2 * c * m + term(0.5, 0.07) + term(0.3, 8.0));
            assert!((f - exact).abs() <= 1e-12 * exact.abs() + 1e-30, "t = {t}");
        }
    }

    #[test]
    fn sampled_history_converges_to_the_exact_ramp_hold() {
        // δ = v t is not piecewise linear in δ^{3/2}: the sampled kernel
        // converges to the closed form as the samples get denser.
        let g = relaxation(1500.0, &[(0.4, 0.03), (0.3, 5.0)]);
        let (r, v, tr) = (2.5e-6, 10e-6, 0.2);
        let times: Vec<f64> = (0..=26_000).map(|i| 2e-3 * i as f64).collect();
        let delta: Vec<f64> = times.iter().map(|t| v * t.min(tr)).collect();
        let sampled = LeeRadok::sampled(r, 0.5, times.clone(), &delta)
            .expect("sampled")
            .force(&g);
        let exact = LeeRadok::ramp_hold(r, 0.5, v, tr, times)
            .expect("exact")
            .force(&g);
        let peak = exact.iter().copied().fold(0.0, f64::max);
        let worst = sampled
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-3 * peak, "{worst} vs peak {peak}");
    }

    fn fd_check(k: &LeeRadok, g0: f64, terms: &[(f64, f64)]) {
        let (_, jac) = k.force_and_jacobian(&relaxation(g0, terms));
        // Parameters G0, g1..gK, tau1..tauK.
        let nk = terms.len();
        let mut p = vec![g0];
        p.extend(terms.iter().map(|t| t.0));
        p.extend(terms.iter().map(|t| t.1));
        let eval = |p: &[f64]| {
            let t: Vec<(f64, f64)> = (0..nk).map(|i| (p[1 + i], p[1 + nk + i])).collect();
            k.force(&relaxation(p[0], &t))
        };
        for (col, jcol) in jac.iter().enumerate() {
            let h = 1e-6 * p[col].abs().max(1e-3);
            let (mut pp, mut pm) = (p.clone(), p.clone());
            pp[col] += h;
            pm[col] -= h;
            let (fp, fm) = (eval(&pp), eval(&pm));
            let fd: Vec<f64> = fp
                .iter()
                .zip(&fm)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect();
            let norm = fd.iter().map(|v| v * v).sum::<f64>().sqrt();
            let diff = fd
                .iter()
                .zip(jcol)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(diff <= 1e-6 * norm, "column {col}: {diff} vs {norm}");
        }
    }

    #[test]
    fn ramp_hold_jacobian_matches_central_differences() {
        let mut times: Vec<f64> = (1..=40).map(|i| 0.005 * i as f64).collect();
        times.extend((1..=60).map(|i| 0.2 + 0.9 * i as f64));
        let k = LeeRadok::ramp_hold(2.5e-6, 0.5, 10e-6, 0.2, times).expect("kernel");
        // τ1 well below and τ2 above the ramp time: both series branches.
        fd_check(&k, 650.0, &[(0.45, 0.003), (0.35, 9.0)]);
        fd_check(&k, 650.0, &[(0.45, 0.08), (0.35, 30.0)]);
    }

    #[test]
    fn sampled_jacobian_matches_central_differences() {
        let times: Vec<f64> = (0..=500)
            .map(|i| 0.01 * i as f64 * (1.0 + 0.01 * i as f64))
            .collect();
        let delta: Vec<f64> = times.iter().map(|t| 2e-6 * (t / 0.3).min(1.0)).collect();
        let k = LeeRadok::sampled(2.5e-6, 0.5, times, &delta).expect("kernel");
        fd_check(&k, 650.0, &[(0.45, 0.08), (0.35, 9.0)]);
        fd_check(&k, 650.0, &[(0.2, 0.5)]);
    }

    #[test]
    fn bad_settings_are_named() {
        let e = LeeRadok::ramp_hold(2.5e-6, 0.5, 1e-6, 1.0, vec![0.2, 0.1])
            .expect_err("decreasing")
            .to_string();
        assert!(e.contains("increase strictly"), "{e}");
        let e = LeeRadok::ramp_hold(-1.0, 0.5, 1e-6, 1.0, vec![0.1])
            .expect_err("radius")
            .to_string();
        assert!(e.contains("radius"), "{e}");
        let e = LeeRadok::sampled(1e-6, 0.5, vec![0.0, 1.0], &[0.0])
            .expect_err("lengths")
            .to_string();
        assert!(e.contains("2 samples"), "{e}");
        let e = LeeRadok::sampled(1e-6, 0.7, vec![0.0, 1.0], &[0.0, 1e-6])
            .expect_err("nu")
            .to_string();
        assert!(e.contains("Poisson"), "{e}");
    }
}
