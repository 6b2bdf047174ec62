//! The Lee–Radok fit finds the global optimum (issue 14): on the relaxation curves of
//! the fig. 5d set its RMSE equals the best of ≥ 200 seeded random starts of the same
//! local fit (`fit_lee_radok_from`) within 0.1 %. The default test checks two curves
//! where the earlier single-start fit stopped at a local optimum (G(0) ≈ 1 kPa, τ₁ of
//! milliseconds) against 24 seeded random starts each (a debug build under load: ~1 s per
//! local fit); the ignored test checks all 15 curves for 2 and 3 terms against 200
//! (`cargo test -p nlvid-afm --release --test it lee_radok_global:: -- --ignored`).
//!
//! Each RMSE is recomputed here from the data and the kernel's force for the returned
//! G(t), independently of the optimiser's own objective.

use crate::common;

use common::*;
use nlvid_afm::{
    ContactMethod, LeeRadokFit, LeeRadokSettings, RampHold, ReadOptions, fit_lee_radok,
    fit_lee_radok_from, prepare_ramp_hold, read_jpk_bytes,
};
use nlvid_forward::LeeRadok;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Assumed probe radius (not stored in the files; see docs/theory/afm.md choice 8).
const R: f64 = 5e-6;

fn ramp_hold(name: &str, bytes: &[u8]) -> RampHold {
    let curve = read_jpk_bytes(bytes, name, &ReadOptions::default())
        .expect("curve")
        .remove(0);
    prepare_ramp_hold(&curve, ContactMethod::default()).expect("ramp-hold")
}

/// RMSE (N) of the fit's G(t) on the data, by the kernel's forward force.
fn rmse(rh: &RampHold, fit: &LeeRadokFit) -> f64 {
    let k = LeeRadok::sampled(R, 0.5, rh.time.clone(), &rh.indentation).expect("kernel");
    let f = k.force(&fit.relaxation);
    let sse: f64 = f.iter().zip(&rh.force).map(|(a, b)| (a - b).powi(2)).sum();
    (sse / f.len() as f64).sqrt()
}

/// Best RMSE of `starts` local fits from log-uniform random τ in [Δt, 10 T] (seeded).
fn best_of_random(rh: &RampHold, terms: usize, starts: usize, seed: u64) -> (f64, LeeRadokFit) {
    let n = rh.time.len();
    let dt = rh
        .time
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let (lo, hi) = (dt.ln(), (10.0 * (rh.time[n - 1] - rh.time[0])).ln());
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let draws: Vec<Vec<f64>> = (0..starts)
        .map(|_| {
            (0..terms)
                .map(|_| {
                    (lo + (hi - lo) * rng.random::<f64>())
                        .exp()
                        .clamp(dt, hi.exp())
                })
                .collect()
        })
        .collect();
    let s = LeeRadokSettings::new(R);
    draws
        .par_iter()
        .filter_map(|taus| {
            let fit = fit_lee_radok_from(&rh.time, &rh.indentation, &rh.force, &s, taus).ok()?;
            Some((rmse(rh, &fit), fit))
        })
        .reduce_with(|a, b| if b.0 < a.0 { b } else { a })
        .expect("some random start fits")
}

fn check(name: &str, bytes: &[u8], terms: usize, starts: usize) -> (String, LeeRadokFit) {
    let rh = ramp_hold(name, bytes);
    let mut s = LeeRadokSettings::new(R);
    s.n_terms = terms;
    let fit = fit_lee_radok(&rh.time, &rh.indentation, &rh.force, &s).expect("fit");
    let ours = rmse(&rh, &fit);
    assert!(
        (ours / fit.rmse - 1.0).abs() < 1e-9,
        "{name}: reported RMSE {} vs recomputed {ours}",
        fit.rmse
    );
    let (reference, ref_fit) = best_of_random(&rh, terms, starts, 2026);
    let line = format!(
        "{name} {terms} terms: RMSE {ours:.6e} N (G0 {:.1} Pa, taus {:?}, {} collapsed) vs best of {starts} random {reference:.6e} N (G0 {:.1} Pa, taus {:?})",
        fit.relaxation.g0(),
        fit.relaxation
            .prony()
            .terms()
            .iter()
            .map(|t| t.tau)
            .collect::<Vec<_>>(),
        fit.collapsed,
        ref_fit.relaxation.g0(),
        ref_fit
            .relaxation
            .prony()
            .terms()
            .iter()
            .map(|t| t.tau)
            .collect::<Vec<_>>(),
    );
    eprintln!("{line}");
    assert!(ours <= reference * 1.001, "{line}");

    // G(t) positive and non-increasing over the record and beyond
    let g: Vec<f64> = (0..=400)
        .map(|i| fit.relaxation.value(0.1 * i as f64))
        .collect();
    assert!(g.iter().all(|v| *v > 0.0) && g.windows(2).all(|w| w[1] <= w[0]));
    (line, fit)
}

#[test]
fn two_term_fit_equals_the_best_of_random_starts_on_two_fig5d_curves() {
    let curves = fig5d();
    // cell1-0008 (the documented example) and cell1-0015
    for i in [7, 14] {
        let (name, bytes) = &curves[i];
        let (line, fit) = check(name, bytes, 2, 24);
        // the global optimum of issue 14's multistart: τ ≈ 1.6–1.9 s and 6.9–9.5 s,
        // G(0) = 305–343 Pa (R = 5 µm), not the local one at G(0) ≈ 1 kPa
        let g0 = fit.relaxation.g0();
        let tau1 = fit.relaxation.prony().terms()[0].tau;
        assert!(
            (300.0..350.0).contains(&g0) && (1.0..3.0).contains(&tau1),
            "{line}"
        );
    }
}

#[test]
#[ignore = "slow: 15 curves × 2 fits × 200 random starts; run with --release"]
fn two_and_three_term_fits_equal_the_best_of_200_random_starts_on_every_fig5d_curve() {
    let curves = fig5d();
    assert_eq!(curves.len(), 15);
    for (name, bytes) in &curves {
        for terms in [2, 3] {
            check(name, bytes, terms, 200);
        }
    }
}
