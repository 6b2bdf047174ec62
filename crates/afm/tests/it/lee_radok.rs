//! Lee–Radok Prony fit: recovery of known parameters from data made by a closed form
//! (the kernel itself, `nlvid_forward::LeeRadok`, is checked against closed forms,
//! quadrature and finite differences in `crates/forward/src/lee_radok.rs`), and the real
//! ramp-hold file.

use crate::common;

use common::*;
use nlvid_afm::{
    ContactMethod, LeeRadokSettings, fit_lee_radok, plot, prepare_ramp_hold, read_force_curve,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Tip radius used on the real file. The Battistella et al. 2022 value could not be found
/// with the tools at hand; 5 µm (a common colloidal probe) is an assumption. G scales
/// as R^{-1/2}; convergence, RMSE and monotonicity do not depend on it.
const R_SR: f64 = 5e-6;

/// G∞ = 100 Pa and two terms (G_k in Pa, τ_k in s): G0 = 650 Pa.
const G_INF: f64 = 100.0;
const TERMS: [(f64, f64); 2] = [(400.0, 0.05), (150.0, 2.0)];

/// Ramp-hold with u = δ^{3/2} = c·t on [0, t1], constant after: the hereditary integral
/// has the closed form F = K[G∞ u + Σ Gₖ c τₖ (1 − e^{−min(t,t1)/τₖ}) e^{−max(0,t−t1)/τₖ}].
fn closed_form(t: &[f64], c: f64, t1: f64, r: f64) -> (Vec<f64>, Vec<f64>) {
    let k = 16.0 / 3.0 * r.sqrt();
    let mut delta = Vec::new();
    let mut f = Vec::new();
    for &ti in t {
        let u = c * ti.min(t1);
        delta.push(u.powf(2.0 / 3.0));
        let mut g = G_INF * u;
        for (gk, tau) in &TERMS {
            g += gk
                * c
                * tau
                * (1.0 - (-ti.min(t1) / tau).exp())
                * (-(ti - t1).max(0.0) / tau).exp();
        }
        f.push(k * g);
    }
    (delta, f)
}

fn grid(dt: f64, t_end: f64) -> Vec<f64> {
    (0..=((t_end / dt).round() as usize))
        .map(|i| i as f64 * dt)
        .collect()
}

#[test]
fn prony_fit_recovers_known_parameters_from_noisy_ramp_hold() {
    let (r, t1) = (2.5e-6, 0.5);
    let t = grid(2e-3, 15.0);
    let (delta, mut f) = closed_form(&t, 1.5e-9 / t1, t1, r);
    let fmax = f.iter().copied().fold(0.0, f64::max);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for v in &mut f {
        *v += 0.002 * fmax * (rng.random::<f64>() - 0.5) * 12f64.sqrt();
    }
    let fit = fit_lee_radok(&t, &delta, &f, &LeeRadokSettings::new(r)).expect("fit");
    let p = &fit.relaxation;
    // Moduli G_k = G0 g_k (Pa), as in the closed form.
    let term = |k: usize| {
        let t = p.prony().terms()[k];
        (p.g0() * t.weight, t.tau)
    };
    assert!(rel(p.g_inf(), G_INF) < 0.02, "{p:?}");
    assert!(
        rel(term(0).0, TERMS[0].0) < 0.05 && rel(term(0).1, TERMS[0].1) < 0.05,
        "{p:?}"
    );
    assert!(
        rel(term(1).0, TERMS[1].0) < 0.05 && rel(term(1).1, TERMS[1].1) < 0.05,
        "{p:?}"
    );
    // residual is the injected noise: 0.2 % of the peak
    assert!(
        fit.rmse < 0.003 * fmax && fit.rmse > 0.001 * fmax,
        "rmse {}",
        fit.rmse
    );
}

#[test]
fn two_term_fit_of_real_ramp_hold_converges_with_monotone_modulus() {
    let c = read_force_curve(SR).expect("read");
    let rh = prepare_ramp_hold(&c, ContactMethod::default()).expect("prepare");
    // The force rises from the first extend samples: contact within the first 10 samples
    // (5 ms) of the extend, found against the baseline of the pause recorded before it.
    assert!(rh.contact.index < 10, "{:?}", rh.contact);
    assert!((rh.baseline.offset - -1.1667527118459774e-07).abs() < 1e-15);
    let fit = fit_lee_radok(
        &rh.time,
        &rh.indentation,
        &rh.force,
        &LeeRadokSettings::new(R_SR),
    )
    .expect("two-term fit converges");
    eprintln!(
        "sr_cell1, R = {R_SR} m: {:?}, range-normalised RMSE {:.4}, {} NM iterations",
        fit.relaxation, fit.range_normalised_rmse, fit.iterations
    );
    assert_eq!(fit.relaxation.prony().len(), 2);
    assert!(
        fit.range_normalised_rmse < 0.05,
        "{}",
        fit.range_normalised_rmse
    );
    assert!(
        fit.relaxation.g_inf() > 0.0
            && fit
                .relaxation
                .prony()
                .terms()
                .iter()
                .all(|t| t.weight >= 0.0 && t.tau > 0.0)
    );
    // G(t) decreases monotonically (strictly somewhere) over the record and beyond
    let g: Vec<f64> = (0..=600)
        .map(|i| fit.relaxation.value(0.1 * i as f64))
        .collect();
    assert!(g.windows(2).all(|w| w[1] <= w[0]));
    assert!(g[600] < g[0]);

    // data vs fit plot
    let dir = std::env::temp_dir().join(format!("nlvid-afm-lr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let svg = dir.join("sr_cell1_lee_radok.svg");
    let fd: Vec<f64> = rh.force.iter().map(|v| v * 1e9).collect();
    let ff: Vec<f64> = fit.force_fit.iter().map(|v| v * 1e9).collect();
    plot::write_svg(
        &svg,
        "sr_cell1: Lee–Radok 2-term Prony fit",
        "time since contact (s)",
        "force (nN)",
        &[
            plot::Series {
                label: "data",
                x: &rh.time,
                y: &fd,
            },
            plot::Series {
                label: "fit",
                x: &rh.time,
                y: &ff,
            },
        ],
    )
    .expect("plot");
    let text = std::fs::read_to_string(&svg).expect("svg");
    assert!(text.contains("<svg") && text.contains("polyline"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_lee_radok_input_is_rejected() {
    let t = grid(1e-2, 1.0);
    let d: Vec<f64> = t.iter().map(|x| x * 1e-6).collect();
    let f = d.clone();
    let mut s = LeeRadokSettings::new(1e-6);
    s.n_terms = 4;
    assert!(fit_lee_radok(&t, &d, &f, &s).is_err());
    assert!(fit_lee_radok(&t, &d, &f[..5], &LeeRadokSettings::new(1e-6)).is_err());
    assert!(fit_lee_radok(&t, &d, &f, &LeeRadokSettings::new(-1.0)).is_err());
    let backwards: Vec<f64> = t.iter().rev().copied().collect();
    let e = fit_lee_radok(&backwards, &d, &f, &LeeRadokSettings::new(1e-6)).unwrap_err();
    assert!(e.to_string().contains("increase strictly"), "{e}");
}
