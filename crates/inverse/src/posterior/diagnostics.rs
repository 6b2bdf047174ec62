//! Convergence diagnostics of MCMC chains: split R̂ (Gelman et al., BDA3
//! §11.4, eqs. 11.1–11.4) and the effective sample size with Geyer's
//! initial monotone sequence on the multi-chain autocorrelation (BDA3
//! §11.5; the estimator of Stan's reference manual, "Effective sample
//! size"). Each walker of an ensemble is taken as one chain, as ArviZ does
//! for emcee output.

/// Split R̂ of `chains` (M chains of equal length N ≥ 4): each chain is cut
/// into halves, then R̂ = √(var⁺/W), var⁺ = (n−1)/n·W + B/n over the 2M
/// half-chains of length n. NaN for constant draws.
pub fn split_rhat(chains: &[Vec<f64>]) -> f64 {
    let halves = split(chains);
    let (w, b, n) = within_between(&halves);
    let var_plus = (n - 1.0) / n * w + b / n;
    (var_plus / w).sqrt()
}

fn split(chains: &[Vec<f64>]) -> Vec<&[f64]> {
    let n = chains.iter().map(Vec::len).min().unwrap_or(0) / 2;
    chains
        .iter()
        .flat_map(|c| [&c[..n], &c[c.len() - n..]])
        .collect()
}

/// (W, B, n): mean within-chain variance, between-chain variance of the
/// means times n, chain length.
fn within_between(chains: &[&[f64]]) -> (f64, f64, f64) {
    let m = chains.len() as f64;
    let n = chains.first().map_or(0, |c| c.len()) as f64;
    let means: Vec<f64> = chains.iter().map(|c| c.iter().sum::<f64>() / n).collect();
    let grand = means.iter().sum::<f64>() / m;
    let b = n / (m - 1.0) * means.iter().map(|x| (x - grand).powi(2)).sum::<f64>();
    let w = chains
        .iter()
        .zip(&means)
        .map(|(c, mu)| c.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n - 1.0))
        .sum::<f64>()
        / m;
    (w, b, n)
}

/// Effective sample size of `chains` (M chains of length N, split into
/// halves as for R̂): M·N / τ with τ = −1 + 2 Σ P_t, P_t = ρ_{2t} +
/// ρ_{2t+1} summed while positive and made monotone, ρ_t = 1 − (W −
/// mean autocovariance at lag t)/var⁺. NaN for constant draws.
pub fn effective_sample_size(chains: &[Vec<f64>]) -> f64 {
    let halves = split(chains);
    let (w, b, n) = within_between(&halves);
    let nn = n as usize;
    let m = halves.len();
    let var_plus = (n - 1.0) / n * w + b / n;
    let means: Vec<f64> = halves.iter().map(|c| c.iter().sum::<f64>() / n).collect();
    // Mean over chains of the (biased, 1/n) autocovariance at lag t.
    let acov = |t: usize| {
        halves
            .iter()
            .zip(&means)
            .map(|(c, mu)| {
                (0..nn - t)
                    .map(|i| (c[i] - mu) * (c[i + t] - mu))
                    .sum::<f64>()
                    / n
            })
            .sum::<f64>()
            / m as f64
    };
    let rho = |t: usize| 1.0 - (w - acov(t)) / var_plus;
    let mut sum = 0.0;
    let mut prev = f64::INFINITY;
    let mut t = 0;
    while t + 1 < nn {
        let p = rho(t) + rho(t + 1);
        if !(p > 0.0) {
            break;
        }
        let p = p.min(prev);
        sum += p;
        prev = p;
        t += 2;
    }
    let tau = (-1.0 + 2.0 * sum).max(1.0 / (m as f64 * n).log10().max(1.0));
    m as f64 * n / tau
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn normal(rng: &mut ChaCha8Rng) -> f64 {
        let u1: f64 = 1.0 - rng.random::<f64>();
        let u2: f64 = rng.random();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// AR(1) chains x_t = φ x_{t−1} + e_t have integrated autocorrelation
    /// time τ = (1 + φ)/(1 − φ) (closed form): ESS ≈ M·N/τ, and R̂ ≈ 1.
    #[test]
    fn ess_of_ar1_chains_matches_the_closed_form() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for phi in [0.0, 0.5, 0.9] {
            let (m, n) = (16, 4000);
            let chains: Vec<Vec<f64>> = (0..m)
                .map(|_| {
                    let mut x = normal(&mut rng) / (1.0f64 - phi * phi).sqrt();
                    (0..n)
                        .map(|_| {
                            x = phi * x + normal(&mut rng);
                            x
                        })
                        .collect()
                })
                .collect();
            let tau = (1.0 + phi) / (1.0 - phi);
            let expected = (m * n) as f64 / tau;
            let ess = effective_sample_size(&chains);
            assert!(
                (ess / expected - 1.0).abs() < 0.12,
                "phi {phi}: ESS {ess} vs {expected}"
            );
            let r = split_rhat(&chains);
            assert!(r < 1.01, "phi {phi}: R-hat {r}");
        }
    }

    /// Chains stuck around different values, or drifting, give R̂ well
    /// above 1: here two groups of chains 3 sd apart, and a trend that only
    /// the split detects.
    #[test]
    fn rhat_flags_separated_and_drifting_chains() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let apart: Vec<Vec<f64>> = (0..8)
            .map(|k| {
                (0..500)
                    .map(|_| normal(&mut rng) + if k < 4 { 0.0 } else { 3.0 })
                    .collect()
            })
            .collect();
        assert!(split_rhat(&apart) > 1.5);
        let drift: Vec<Vec<f64>> = (0..8)
            .map(|_| {
                (0..500)
                    .map(|i| normal(&mut rng) + 4.0 * i as f64 / 500.0)
                    .collect()
            })
            .collect();
        assert!(split_rhat(&drift) > 1.2, "{}", split_rhat(&drift));
    }

    /// B and W written out by hand for two short chains: halves [1,2],[3,4],
    /// [2,2],[4,6] have means 1.5, 3.5, 2, 5 (grand 3), variances 0.5, 0.5,
    /// 0, 2 → W = 0.75, B = 2/3·(2.25 + 0.25 + 1 + 4) = 5, n = 2:
    /// var⁺ = 0.375 + 2.5, R̂ = √(2.875/0.75).
    #[test]
    fn rhat_of_a_hand_example() {
        let chains = vec![vec![1.0, 2.0, 3.0, 4.0], vec![2.0, 2.0, 4.0, 6.0]];
        let r = split_rhat(&chains);
        assert!((r - (2.875f64 / 0.75).sqrt()).abs() < 1e-12, "{r}");
    }
}
