//! Contact point and Hertz fit: on the real approach/retract file against JPK Data
//! Processing's published result, and on synthetic curves made here from eq. 1.1.

use crate::common;

use common::*;
use nlvid_afm::{
    AfmError, Baseline, ContactMethod, HertzSettings, contact_point, fit_hertz, hertz_baseline,
    indentation, prepare_approach, read_force_curve, tip_sample_separation,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn hertz_fit_on_real_file_matches_jpk_data_processing() {
    let c = read_force_curve(FD).expect("read");
    for method in [ContactMethod::default(), ContactMethod::PiecewiseLinear] {
        let a = prepare_approach(&c, method).expect("prepare");
        let fit = fit_hertz(&a.separation, &a.force, &HertzSettings::new(40e-9, 0.5)).expect("fit");
        let e_err = rel(fit.youngs_modulus, 233.1e3);
        assert!(e_err < 0.01, "{method:?}: E = {} Pa", fit.youngs_modulus);
        assert!(
            (fit.contact_point - 18.03e-6).abs() < 0.05e-6,
            "{method:?}: contact {} m",
            fit.contact_point
        );
        // the contact estimate itself is near the fitted one too
        assert!((a.contact.separation - fit.contact_point).abs() < 0.05e-6);
    }
    let fit = hertz_baseline(&c, &HertzSettings::new(40e-9, 0.5)).expect("baseline");
    assert!(rel(fit.youngs_modulus, 233.1e3) < 0.01);
}

/// Synthetic approach: baseline noise, contact at `sc`, Hertz force written out here
/// (independently of the crate's `hertz_force`).
fn synthetic(e: f64, r: f64, nu: f64, sc: f64, noise: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = 1500;
    let (s0, s1) = (sc + 3e-6, sc - 0.6e-6);
    let mut s = Vec::with_capacity(n);
    let mut f = Vec::with_capacity(n);
    for i in 0..n {
        let si = s0 + (s1 - s0) * i as f64 / (n - 1) as f64;
        let d = (sc - si).max(0.0);
        let fi = 4.0 * e * r.sqrt() * d * d.sqrt() / (3.0 * (1.0 - nu * nu));
        let u: f64 = rng.random::<f64>() - 0.5;
        s.push(si);
        f.push(fi + 2e-12 + noise * u * 12f64.sqrt());
    }
    (s, f)
}

#[test]
fn hertz_fit_recovers_known_modulus_and_contact_with_noise() {
    let (e, r, nu, sc) = (5.0e3, 2.5e-6, 0.5, 12.0e-6);
    let (s, f) = synthetic(e, r, nu, sc, 20e-12, 7);
    let fit = fit_hertz(&s, &f, &HertzSettings::new(r, nu)).expect("fit");
    assert!(
        rel(fit.youngs_modulus, e) < 0.01,
        "E = {}",
        fit.youngs_modulus
    );
    assert!(
        (fit.contact_point - sc).abs() < 5e-9,
        "sc = {}",
        fit.contact_point
    );
    assert!((fit.offset - 2e-12).abs() < 2e-12);
    // noise-free data are reproduced to rounding
    let (s, f) = synthetic(e, r, nu, sc, 0.0, 7);
    let fit = fit_hertz(&s, &f, &HertzSettings::new(r, nu)).expect("fit");
    assert!(
        rel(fit.youngs_modulus, e) < 1e-6,
        "E = {}",
        fit.youngs_modulus
    );
    assert!((fit.contact_point - sc).abs() < 1e-12);
}

#[test]
fn contact_methods_find_synthetic_contact() {
    let sc = 12.0e-6;
    let (s, f) = synthetic(5.0e3, 2.5e-6, 0.5, sc, 10e-12, 3);
    let dev = contact_point(&s, &f, ContactMethod::default()).expect("dev");
    let pw = contact_point(&s, &f, ContactMethod::PiecewiseLinear).expect("pw");
    // deviation lags the true contact (it needs 5σ of force); both within 0.2 µm
    assert!(
        dev.separation <= sc + 1e-9 && sc - dev.separation < 0.2e-6,
        "{dev:?}"
    );
    assert!((pw.separation - sc).abs() < 0.2e-6, "{pw:?}");
}

#[test]
fn flat_curve_has_no_contact() {
    let s: Vec<f64> = (0..100).map(|i| 1e-5 - 1e-8 * i as f64).collect();
    let f: Vec<f64> = (0..100).map(|i| 1e-12 * ((i * 7919) % 13) as f64).collect();
    assert!(matches!(
        contact_point(&s, &f, ContactMethod::default()),
        Err(AfmError::NoContact(_))
    ));
}

#[test]
fn separation_adds_deflection_and_indentation_is_positive_in_contact() {
    let h = [10e-6, 9e-6, 8e-6];
    let f = [0.0, 0.1e-9, 0.5e-9];
    let s = tip_sample_separation(&h, &f, 0.05).expect("sep");
    assert_eq!(s, vec![10e-6, 9e-6 + 2e-9, 8e-6 + 10e-9]);
    let d = indentation(&s, 9.5e-6);
    assert!(d[0] < 0.0 && d[1] > 0.0 && d[2] > d[1]);
    assert!(tip_sample_separation(&h, &f, 0.0).is_err());
    assert!(tip_sample_separation(&h, &f[..2], 1.0).is_err());
}

#[test]
fn baseline_with_slope_removes_a_tilt_exactly() {
    let x: Vec<f64> = (0..50).map(|i| i as f64 * 1e-8).collect();
    let f: Vec<f64> = x.iter().map(|v| 3e-10 + 2e-3 * v).collect();
    let b = Baseline::fit(&x, &f, 0..50, true).expect("fit");
    assert!(rel(b.slope, 2e-3) < 1e-9 && rel(b.offset, 3e-10) < 1e-9);
    assert!(b.subtract(&x, &f).iter().all(|r| r.abs() < 1e-20));
    assert!(Baseline::fit(&x, &f, 40..60, false).is_err());
}

#[test]
fn bad_hertz_settings_are_rejected() {
    let (s, f) = synthetic(5.0e3, 2.5e-6, 0.5, 12e-6, 0.0, 1);
    for bad in [HertzSettings::new(0.0, 0.5), HertzSettings::new(1e-6, 0.7)] {
        assert!(matches!(
            fit_hertz(&s, &f, &bad),
            Err(AfmError::InvalidInput(_))
        ));
    }
    assert!(fit_hertz(&s[..5], &f[..5], &HertzSettings::new(1e-6, 0.5)).is_err());
}
