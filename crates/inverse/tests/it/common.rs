//! Helpers shared by the synthetic-recovery tests (`recovery`,
//! `surrogate_recovery`): the analytic ramp-hold model, seeded Gaussian
//! noise and random true parameter sets inside Table 5.3.

use nlvid_inverse::{LeeRadokHertz, ramp_hold_grid, ramp_hold_indentation};
use nlvid_model::Domain;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The analytic Lee–Radok Hertz model of a ramp-hold test: 10 um/s ramp
/// to 2 um (0.2 s), hold to t = 52 s, sphere R = 2.5 um; `n_ramp` and
/// `n_hold` set how many output times the ramp and the hold get.
pub fn lee_radok_ramp_hold(domain: &Domain, n_ramp: usize, n_hold: usize) -> LeeRadokHertz {
    let t = ramp_hold_grid(0.2, n_ramp, 52.0, n_hold, 1e-3).expect("grid");
    let delta = ramp_hold_indentation(&t, 10e-6, 2e-6);
    LeeRadokHertz::new(domain.clone(), t, &delta, 2.5e-6, 0.5).expect("model")
}

/// A standard normal number from `rng` (Box–Muller).
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// A random parameter set inside Table 5.3 with g1 + g2 <= 0.99, drawn
/// independently of the design and of the optimiser's starts, in the order
/// G0, g1, g2, tau1, tau2 (random numbers consumed as before the order was
/// unified: g1, g2, then G0, tau1, tau2 — the same ten cases).
pub fn draw(rng: &mut ChaCha8Rng) -> [f64; 5] {
    let log_uniform = |rng: &mut ChaCha8Rng, lo: f64, hi: f64| {
        (lo.ln() + rng.random::<f64>() * (hi.ln() - lo.ln())).exp()
    };
    loop {
        let g1 = 0.01 + 0.99 * rng.random::<f64>();
        let g2 = 0.01 + 0.99 * rng.random::<f64>();
        if g1 + g2 <= 0.99 {
            let g0 = log_uniform(rng, 80.0, 4000.0);
            let tau1 = log_uniform(rng, 0.01, 2.0);
            let tau2 = log_uniform(rng, 2.0, 40.0);
            return [g0, g1, g2, tau1, tau2];
        }
    }
}
