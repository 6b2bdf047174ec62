//! The independence proposal of the ensemble sampler: a multivariate t
//! fitted to a rung's recent positions, or a two-component mixture of t's
//! where the positions form two clusters (module docs of
//! [`ensemble`](super::ensemble), "independence" and "pooled proposals").

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The independence proposal of a rung: one multivariate t fitted to the
/// rung's recent positions, or — when the positions are far better
/// described by two Gaussian clusters than by one (BIC, below) — a
/// two-component mixture of t's, one per cluster. A posterior with two
/// arms (e.g. a weak fast Prony term against a term faster than the time
/// grid) then gets proposals that land in either arm, so a walker can
/// change arm in one accepted step; a single t spread over both puts most
/// of its mass in the empty corner between them. Either is a valid
/// independence proposal (exact Metropolis–Hastings with its own q).
#[derive(Clone)]
pub(super) enum Proposal {
    Single(TProposal),
    /// ln w_k and the components.
    Mixture([(f64, TProposal); 2]),
}

impl Proposal {
    /// One t fitted to `points` (covariance × `scale`², [`TProposal`]), or
    /// the mixture when the two-cluster Gaussian fit
    /// ([`two_gaussian_clusters`]) has the lower BIC, −2 ln L + k ln n
    /// with k = d + d(d+1)/2 parameters per Gaussian plus one weight.
    /// None when not even one t can be fitted (a collapsed ensemble).
    pub(super) fn fit(points: &[Vec<f64>], scale: f64) -> Option<Self> {
        let (mean, cov) = moments(points)?;
        let single = TProposal::from_moments(mean.clone(), &cov, scale)?;
        let n = points.len() as f64;
        let d = mean.len() as f64;
        let k1 = d + d * (d + 1.0) / 2.0;
        // The mixture is taken when its BIC is the lower, i.e. when its ln L
        // exceeds the single Gaussian's by (k + 1)·ln n / 2.
        let to_beat = gaussian_log_likelihood(points, &mean, &cov)? + 0.5 * (k1 + 1.0) * n.ln();
        let Some((ln_l2, parts)) = two_gaussian_clusters(points, &mean, &cov, to_beat) else {
            return Some(Self::Single(single));
        };
        if ln_l2 <= to_beat {
            return Some(Self::Single(single));
        }
        let [(w0, m0, c0), (w1, m1, c1)] = parts;
        match (
            TProposal::from_moments(m0, &c0, scale),
            TProposal::from_moments(m1, &c1, scale),
        ) {
            (Some(a), Some(b)) => Some(Self::Mixture([(w0.ln(), a), (w1.ln(), b)])),
            _ => Some(Self::Single(single)),
        }
    }

    /// ln q(y) up to a constant (the same constant for every y).
    pub(super) fn log_density(&self, y: &[f64]) -> f64 {
        match self {
            Self::Single(t) => t.log_density(y),
            Self::Mixture(parts) => {
                let term = |(lw, t): &(f64, TProposal)| lw + t.log_density(y) - t.log_det_l();
                let terms = [term(&parts[0]), term(&parts[1])];
                let top = terms[0].max(terms[1]);
                top + terms.iter().map(|v| (v - top).exp()).sum::<f64>().ln()
            }
        }
    }

    /// A draw and its ln q (a single t uses the same random numbers as before the
    /// mixture existed: no extra random number).
    pub(super) fn draw(&self, rng: &mut ChaCha8Rng) -> (Vec<f64>, f64) {
        match self {
            Self::Single(t) => t.draw(rng),
            Self::Mixture(parts) => {
                let pick = usize::from(rng.random::<f64>() >= parts[0].0.exp());
                let (y, _) = parts[pick].1.draw(rng);
                let lq = self.log_density(&y);
                (y, lq)
            }
        }
    }
}

/// Mean and covariance (1/(n − 1)) of `points`; None for fewer than d + 2.
fn moments(points: &[Vec<f64>]) -> Option<(Vec<f64>, nalgebra::DMatrix<f64>)> {
    let n = points.len();
    let d = points.first()?.len();
    if n <= d + 1 {
        return None;
    }
    let mean: Vec<f64> = (0..d)
        .map(|i| points.iter().map(|p| p[i]).sum::<f64>() / n as f64)
        .collect();
    let mut cov = nalgebra::DMatrix::zeros(d, d);
    for p in points {
        for i in 0..d {
            for j in 0..d {
                cov[(i, j)] += (p[i] - mean[i]) * (p[j] - mean[j]);
            }
        }
    }
    cov /= n as f64 - 1.0;
    Some((mean, cov))
}

/// ln N(x; μ, Σ) for each point, from Σ's Cholesky factor L: c − ½|L⁻¹(x −
/// μ)|² by forward substitution into one reused buffer (EM evaluates this
/// for every point at every iteration). None if Σ is not positive
/// definite.
fn gaussian_log_densities(
    points: &[Vec<f64>],
    mean: &[f64],
    cov: &nalgebra::DMatrix<f64>,
) -> Option<Vec<f64>> {
    let d = mean.len();
    let chol = cov.clone().cholesky()?;
    let l = chol.l();
    let log_det: f64 = 2.0 * l.diagonal().iter().map(|v| v.ln()).sum::<f64>();
    let c = -0.5 * (log_det + d as f64 * (2.0 * std::f64::consts::PI).ln());
    let mut z = vec![0.0; d];
    Some(
        points
            .iter()
            .map(|p| {
                for i in 0..d {
                    let mut v = p[i] - mean[i];
                    for j in 0..i {
                        v -= l[(i, j)] * z[j];
                    }
                    z[i] = v / l[(i, i)];
                }
                c - 0.5 * z.iter().map(|v| v * v).sum::<f64>()
            })
            .collect(),
    )
}

/// Σ_i ln N(x_i; μ, Σ).
fn gaussian_log_likelihood(
    points: &[Vec<f64>],
    mean: &[f64],
    cov: &nalgebra::DMatrix<f64>,
) -> Option<f64> {
    Some(gaussian_log_densities(points, mean, cov)?.iter().sum())
}

/// EM stops when an iteration raises ln L by at most this much: the BIC
/// choice it feeds compares ln L against a penalty of (k + 1)·ln n / 2 ≈ 90
/// (d = 5, n ≈ 4000), so ln L is needed to far better than 1 but not to
/// round-off.
const EM_TOLERANCE: f64 = 1e-3;
/// At most this many EM iterations.
const EM_MAX_ITERATIONS: usize = 100;

/// A two-Gaussian mixture fitted to `points` by EM (Dempster, Laird &
/// Rubin 1977), started deterministically from the split of the points by
/// the side of the mean they lie on along the covariance's principal axis
/// (no random numbers: the sampler's stream is untouched). Returns the
/// mixture's ln L and each cluster's (weight, mean, covariance), or None
/// when a cluster collapses (weight·n < 2(d + 1) or a covariance not
/// positive definite) or when ln L is so far below `to_beat` that the
/// iterations left cannot close the gap at the current gain (a single
/// cloud: EM then creeps by ≈ 0.04 per iteration, far from the ≈ 90
/// needed).
#[allow(clippy::type_complexity)]
fn two_gaussian_clusters(
    points: &[Vec<f64>],
    mean: &[f64],
    cov: &nalgebra::DMatrix<f64>,
    to_beat: f64,
) -> Option<(f64, [(f64, Vec<f64>, nalgebra::DMatrix<f64>); 2])> {
    let n = points.len();
    let d = mean.len();
    let eig = cov.clone().symmetric_eigen();
    let top = eig.eigenvalues.imax();
    let axis = eig.eigenvectors.column(top);
    // Responsibility of cluster 0 for each point.
    let mut r: Vec<f64> = points
        .iter()
        .map(|p| {
            let s: f64 = (0..d).map(|i| (p[i] - mean[i]) * axis[i]).sum();
            if s < 0.0 { 1.0 } else { 0.0 }
        })
        .collect();
    let mut ln_l = f64::NEG_INFINITY;
    let mut parts = None;
    for iteration in 0..EM_MAX_ITERATIONS {
        // M step.
        let mut fitted = Vec::with_capacity(2);
        for k in 0..2 {
            let wk: Vec<f64> = r
                .iter()
                .map(|&v| if k == 0 { v } else { 1.0 - v })
                .collect();
            let total: f64 = wk.iter().sum();
            if total < 2.0 * (d as f64 + 1.0) {
                return None;
            }
            let mu: Vec<f64> = (0..d)
                .map(|i| points.iter().zip(&wk).map(|(p, w)| w * p[i]).sum::<f64>() / total)
                .collect();
            let mut c = nalgebra::DMatrix::zeros(d, d);
            for (p, w) in points.iter().zip(&wk) {
                for i in 0..d {
                    for j in 0..d {
                        c[(i, j)] += w * (p[i] - mu[i]) * (p[j] - mu[j]);
                    }
                }
            }
            c /= total;
            fitted.push((total / n as f64, mu, c));
        }
        // E step and the mixture's ln L.
        let l0 = gaussian_log_densities(points, &fitted[0].1, &fitted[0].2)?;
        let l1 = gaussian_log_densities(points, &fitted[1].1, &fitted[1].2)?;
        let (lw0, lw1) = (fitted[0].0.ln(), fitted[1].0.ln());
        let mut new_ln_l = 0.0;
        for i in 0..n {
            let (a, b) = (lw0 + l0[i], lw1 + l1[i]);
            let top = a.max(b);
            let lse = top + ((a - top).exp() + (b - top).exp()).ln();
            new_ln_l += lse;
            r[i] = (a - lse).exp();
        }
        let [f0, f1]: [(f64, Vec<f64>, nalgebra::DMatrix<f64>); 2] = fitted.try_into().ok()?;
        parts = Some([f0, f1]);
        let gain = new_ln_l - ln_l;
        ln_l = new_ln_l;
        if gain <= EM_TOLERANCE {
            break;
        }
        // Short of `to_beat` by more than the remaining iterations can add
        // at the current gain (EM's gains shrink): the mixture cannot win.
        if iteration >= 3 && to_beat - ln_l > gain * (EM_MAX_ITERATIONS - iteration) as f64 {
            return None;
        }
    }
    Some((ln_l, parts?))
}

/// Multivariate Student t with ν = 5: mean μ, scale matrix L Lᵀ.
#[derive(Clone)]
pub(super) struct TProposal {
    mean: Vec<f64>,
    /// Lower Cholesky factor, row-major d × d.
    l: Vec<f64>,
}

impl TProposal {
    const NU: f64 = 5.0;

    /// Mean `mean`, scale matrix `cov` × `scale`²; None when `cov` is not
    /// positive definite.
    fn from_moments(mean: Vec<f64>, cov: &nalgebra::DMatrix<f64>, scale: f64) -> Option<Self> {
        let d = mean.len();
        let chol = (cov * (scale * scale)).cholesky()?;
        let lm = chol.l();
        let l = (0..d * d).map(|k| lm[(k / d, k % d)]).collect();
        Some(Self { mean, l })
    }

    /// ln det L (the normalisation of [`TProposal::log_density`] up to a
    /// constant shared by every t of the same dimension).
    fn log_det_l(&self) -> f64 {
        let d = self.dim();
        (0..d).map(|i| self.l[i * d + i].ln()).sum()
    }

    fn dim(&self) -> usize {
        self.mean.len()
    }

    /// ln q(y) up to a constant: −(ν + d)/2 · ln(1 + |L⁻¹(y − μ)|²/ν).
    fn log_density(&self, y: &[f64]) -> f64 {
        let d = self.dim();
        let mut z = vec![0.0; d];
        for i in 0..d {
            let mut s = y[i] - self.mean[i];
            for j in 0..i {
                s -= self.l[i * d + j] * z[j];
            }
            z[i] = s / self.l[i * d + i];
        }
        let q: f64 = z.iter().map(|v| v * v).sum();
        -0.5 * (Self::NU + d as f64) * (1.0 + q / Self::NU).ln()
    }

    /// A draw and its ln q: μ + L z·√(ν/χ²_ν), z ~ N(0, I).
    fn draw(&self, rng: &mut ChaCha8Rng) -> (Vec<f64>, f64) {
        let d = self.dim();
        let z: Vec<f64> = (0..d).map(|_| normal(rng)).collect();
        let chi2: f64 = (0..Self::NU as usize).map(|_| normal(rng).powi(2)).sum();
        let f = (Self::NU / chi2).sqrt();
        let y: Vec<f64> = (0..d)
            .map(|i| self.mean[i] + f * (0..=i).map(|j| self.l[i * d + j] * z[j]).sum::<f64>())
            .collect();
        let lq = self.log_density(&y);
        (y, lq)
    }
}

pub(super) fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller; u1 in (0, 1].
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Points of two separated Gaussian clusters (weights 0.3 / 0.7) are
    /// fitted with a two-component mixture whose weights and means are the
    /// clusters'; one elongated Gaussian cloud keeps the single t.
    #[test]
    fn two_clusters_get_a_mixture_proposal_and_one_cloud_a_single_t() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let cluster = |rng: &mut ChaCha8Rng, c: [f64; 3], n: usize| -> Vec<Vec<f64>> {
            (0..n)
                .map(|_| {
                    let z = [normal(rng), normal(rng), normal(rng)];
                    vec![
                        c[0] + 0.1 * z[0],
                        c[1] + 0.05 * z[1] + 0.02 * z[0],
                        c[2] + 0.2 * z[2],
                    ]
                })
                .collect()
        };
        let mut two = cluster(&mut rng, [0.2, 0.5, 0.5], 600);
        two.extend(cluster(&mut rng, [0.8, 0.1, 0.4], 1400));
        let Some(Proposal::Mixture(parts)) = Proposal::fit(&two, 1.2) else {
            panic!("two clusters: expected a mixture");
        };
        let mut found: Vec<(f64, f64)> =
            parts.iter().map(|(lw, t)| (lw.exp(), t.mean[0])).collect();
        found.sort_by(|a, b| a.1.total_cmp(&b.1));
        assert!(
            (found[0].0 - 0.3).abs() < 0.01 && (found[0].1 - 0.2).abs() < 0.01,
            "{found:?}"
        );
        assert!(
            (found[1].0 - 0.7).abs() < 0.01 && (found[1].1 - 0.8).abs() < 0.01,
            "{found:?}"
        );
        let one = cluster(&mut rng, [0.5, 0.5, 0.5], 2000);
        assert!(matches!(
            Proposal::fit(&one, 1.2),
            Some(Proposal::Single(_))
        ));
    }

    /// The mixture's ln q differs between two points by the log-ratio of
    /// the normalised t mixture written out from its formula,
    /// Σ_k w_k Γ((ν+d)/2) / (Γ(ν/2) (νπ)^{d/2} |Σ_k|^{1/2}) (1 + δ_k/ν)^{−(ν+d)/2},
    /// with |Σ_k| from a fresh Cholesky factor of L_k L_kᵀ (second method).
    #[test]
    fn mixture_log_density_is_the_normalised_t_mixture() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut pts: Vec<Vec<f64>> = (0..800)
            .map(|_| vec![0.2 + 0.05 * normal(&mut rng), 0.3 + 0.1 * normal(&mut rng)])
            .collect();
        pts.extend(
            (0..1200).map(|_| vec![0.7 + 0.2 * normal(&mut rng), 0.8 + 0.03 * normal(&mut rng)]),
        );
        let q = Proposal::fit(&pts, 1.2).expect("fit");
        let Proposal::Mixture(parts) = &q else {
            panic!("expected a mixture");
        };
        let nu = TProposal::NU;
        let density = |y: &[f64]| -> f64 {
            parts
                .iter()
                .map(|(lw, t)| {
                    let l = nalgebra::DMatrix::from_row_slice(2, 2, &t.l);
                    let sigma = &l * l.transpose();
                    let det = sigma.clone().cholesky().expect("spd").determinant();
                    let r = nalgebra::DVector::from_iterator(
                        2,
                        y.iter().zip(&t.mean).map(|(a, b)| a - b),
                    );
                    let delta = r.dot(&(sigma.try_inverse().expect("inverse") * &r));
                    // Γ((ν+2)/2)/Γ(ν/2) = ν/2 for d = 2.
                    lw.exp() * (nu / 2.0) / (nu * std::f64::consts::PI * det.sqrt())
                        * (1.0 + delta / nu).powf(-(nu + 2.0) / 2.0)
                })
                .sum()
        };
        for (a, b) in [
            ([0.2, 0.3], [0.7, 0.8]),
            ([0.5, 0.5], [0.1, 0.9]),
            ([0.72, 0.79], [0.21, 0.33]),
        ] {
            let ours = q.log_density(&a) - q.log_density(&b);
            let direct = (density(&a) / density(&b)).ln();
            assert!(
                (ours - direct).abs() < 1e-10,
                "{a:?} vs {b:?}: {ours} vs {direct}"
            );
        }
        // A draw's ln q is the density at the drawn point.
        let (y, lq) = q.draw(&mut rng);
        assert_eq!(lq.to_bits(), q.log_density(&y).to_bits());
    }
}
