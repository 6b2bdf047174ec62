//! ABAQUS-form finite-strain viscoelasticity (§4.3): exact identities and
//! agreement of the recursive history with the full eq. 2.48 sum.

use nlvid_material::homogeneous::{History, Mode, drive};
use nlvid_material::{
    HistoryRule, Incompressible, Mat3, MooneyRivlin, PointState, PronyViscoelastic,
};
use nlvid_model::{Relaxation, names};

fn capsule() -> PronyViscoelastic {
    PronyViscoelastic::capsule(2000.0, 0.3, (0.35, 0.4), (0.25, 5.0), 0.0).expect("ok")
}

#[test]
fn step_relaxes_exactly_as_normalised_prony_series() {
    let m = capsule();
    for mode in [Mode::Uniaxial, Mode::Equibiaxial, Mode::SimpleShear] {
        let out = drive(
            &m,
            mode,
            &History::Step {
                value: 1.8,
                hold: 20.0,
            },
            0.9,
        )
        .expect("ok");
        let s0 = out[1].cauchy;
        for s in &out[1..] {
            let expect = s0 * m.prony().value(s.time);
            let err = (s.cauchy - expect).abs().max() / s0.abs().max();
            assert!(err < 1e-13, "{mode:?} t = {}: {err:e}", s.time);
        }
    }
}

#[test]
fn instantaneous_and_long_time_responses_are_mooney_rivlin() {
    let m = capsule();
    let ginf = 1.0 - 0.35 - 0.25;
    let mr0 = MooneyRivlin::new(2000.0, 600.0, 0.0).expect("ok");
    let mr_inf = MooneyRivlin::new(ginf * 2000.0, ginf * 600.0, 0.0).expect("ok");
    for &l in &[0.5, 1.7, 3.0] {
        let out = drive(
            &m,
            Mode::Uniaxial,
            &History::Step {
                value: l,
                hold: 400.0,
            },
            5.0,
        )
        .expect("ok");
        let f = Mode::Uniaxial.deformation_gradient(l);
        for (s, mr) in [(&out[1], &mr0), (out.last().expect("sample"), &mr_inf)] {
            let e = mr.extra_stress(&(), &f, 0.0, &mut ()).expect("ok");
            let exact = e[(0, 0)] - e[(1, 1)];
            assert!(
                (s.principal[0] - exact).abs() < 1e-12 * exact.abs(),
                "λ = {l}"
            );
        }
    }
}

#[test]
fn simple_shear_at_zero_plus_gives_mooney_rivlin_viscometric_functions() {
    let m = capsule();
    let (c1, c2) = (2000.0, 600.0);
    for &g in &[0.3, 1.0, 3.0] {
        let out = drive(
            &m,
            Mode::SimpleShear,
            &History::Step {
                value: g,
                hold: 0.0,
            },
            1.0,
        )
        .expect("ok");
        let s = out[1].cauchy;
        let tol = 1e-12 * c1 * (1.0 + g * g);
        assert!((s[(0, 1)] - 2.0 * (c1 + c2) * g).abs() < tol);
        assert!((s[(0, 0)] - s[(1, 1)] - 2.0 * (c1 + c2) * g * g).abs() < tol);
        assert!((s[(1, 1)] - s[(2, 2)] + 2.0 * c2 * g * g).abs() < tol);
    }
}

#[test]
fn recursive_trapezoid_equals_the_full_eq_2_48_sum() {
    let m = capsule().with_rule(HistoryRule::Trapezoid);
    let mut samples = Vec::new();
    let mut t = 0.0;
    for n in 0..50 {
        t += 0.03 + 0.04 * ((n * 3 % 4) as f64);
        let l = 1.0 + 1.2 * (0.5 * t).sin().abs();
        let (s, c) = (0.3 * t).sin_cos();
        let rot = Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        samples.push((
            t,
            rot * Mat3::new(
                l,
                0.3,
                0.0,
                0.0,
                1.0 / l.sqrt(),
                0.0,
                0.0,
                0.0,
                1.0 / l.sqrt(),
            ),
        ));
    }
    let reference =
        nlvid_material::reference::prony_viscoelastic_trapezoid(&m, &samples).expect("ok");
    let mut state = m.initial_state();
    let mut trial = state.clone();
    let mut t_n = 0.0;
    for ((t, f), r) in samples.iter().zip(&reference) {
        let got = m.extra_stress(&state, f, t - t_n, &mut trial).expect("ok");
        std::mem::swap(&mut state, &mut trial);
        t_n = *t;
        let err = (got - r).abs().max() / r.abs().max();
        assert!(err < 1e-12, "t = {t}: {err:e}");
    }
}

/// The cell of eq. 5.1 is built from its shear relaxation modulus
/// G(t) = G0 g(t) (`nlvid_model::Relaxation`), and simple shear of the
/// material gives back that modulus: σ12(t)/γ = G(t) at small γ, at 0⁺ and
/// through the hold. Reading G0 as the neo-Hookean C1 (the factor-2 error)
/// would make σ12/γ twice G(t).
#[test]
fn cell_model_in_simple_shear_relaxes_with_the_shear_modulus_it_was_built_from() {
    let shear = Relaxation::from_named(&names::PRONY2, &[1000.0, 0.4, 0.3, 0.5, 10.0]).expect("ok");
    let m = PronyViscoelastic::cell(&shear, 0.0).expect("ok");
    assert_eq!(m.elastic().c1(), 500.0, "C1 = G0/2 (eq. 4.1)");
    assert_eq!(m.elastic().c2(), 0.0);
    assert_eq!(m.shear_relaxation().expect("ok"), shear);
    let g = 1e-6;
    let out = drive(
        &m,
        Mode::SimpleShear,
        &History::Step {
            value: g,
            hold: 30.0,
        },
        0.05,
    )
    .expect("ok");
    let mut checked = 0;
    for s in out.iter().skip(1) {
        // Independent: eq. 5.1 typed here, G0 = 1 kPa.
        let by_hand =
            1000.0 * (0.3 + 0.4 * (-s.time / 0.5f64).exp() + 0.3 * (-s.time / 10.0f64).exp());
        let measured = s.cauchy[(0, 1)] / g;
        assert!(
            (measured - by_hand).abs() < 1e-5 * 1000.0,
            "t = {}: sigma12/gamma = {measured}, G(t) = {by_hand}",
            s.time
        );
        checked += 1;
    }
    assert!(checked > 100, "{checked}");
}

#[test]
fn cell_model_parameters_are_checked_and_named() {
    let e = Relaxation::from_named(&names::PRONY2, &[1000.0, 0.6, 0.5, 0.5, 10.0])
        .expect_err("g1+g2 ≥ 1");
    assert!(
        e.to_string().contains("term 2") && e.to_string().contains("g_inf"),
        "{e}"
    );
    let zero = Relaxation::from_named(&names::PRONY2, &[0.0, 0.1, 0.1, 0.5, 10.0]).expect("G0 ≥ 0");
    let e = PronyViscoelastic::cell(&zero, 0.0).expect_err("G0 = 0");
    assert!(e.to_string().contains("`G0`"), "{e}");
}

#[test]
fn penalty_3d_updates_reproduce_the_incompressible_response_under_ramp_hold() {
    use nlvid_material::PipkinRogers;
    use nlvid_material::homogeneous::drive_uniaxial_3d;
    use nlvid_model::Prony;
    let hist = History::RampHold {
        value: 2.5,
        ramp: 0.5,
        hold: 3.0,
    };
    let pv_inc = capsule();
    let pv_pen =
        PronyViscoelastic::capsule(2000.0, 0.3, (0.35, 0.4), (0.25, 5.0), 2.0e8).expect("ok");
    let g1 = Relaxation::new(
        "G1",
        1000.0,
        Prony::new("G1", &[(0.4, 0.5), (0.3, 4.0)]).expect("ok"),
    )
    .expect("ok");
    let g2 =
        Relaxation::new("G2", 120.0, Prony::new("G2", &[(0.5, 0.2)]).expect("ok")).expect("ok");
    let pr_inc = PipkinRogers::new(g1.clone(), g2.clone(), 0.15, 0.0).expect("ok");
    let pr_pen = PipkinRogers::new(g1, g2, 0.15, 1.0e8).expect("ok");
    let a = drive(&pv_inc, Mode::Uniaxial, &hist, 0.01).expect("ok");
    let b = drive_uniaxial_3d(&pv_pen, &hist, 0.01).expect("ok");
    let c = drive(&pr_inc, Mode::Uniaxial, &hist, 0.01).expect("ok");
    let d = drive_uniaxial_3d(&pr_pen, &hist, 0.01).expect("ok");
    assert_eq!(a.len(), b.len());
    for (inc, pen) in [(&a, &b), (&c, &d)] {
        let peak = inc.iter().map(|s| s.principal[0].abs()).fold(0.0, f64::max);
        for (x, y) in inc.iter().zip(pen.iter()) {
            assert!((x.time - y[0]).abs() < 1e-12);
            // J − 1 = O(σ/K): relative agreement O(1e-5) with K = 1e5·C1.
            assert!(
                (x.principal[0] - y[3]).abs() < 1e-4 * peak,
                "t = {}: {} vs {}",
                x.time,
                x.principal[0],
                y[3]
            );
            assert!(
                (y[2] * y[2] * y[1] - 1.0).abs() < 1e-4,
                "J = {}",
                y[2] * y[2] * y[1]
            );
        }
    }
}
