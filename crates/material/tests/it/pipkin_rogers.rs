//! Pipkin–Rogers / QLV: exact identities of §2.2 and §2.5, and agreement with
//! an independent direct quadrature of eq. 2.1 (coded here from eq. 2.55
//! with its own Prony functions and Gauss–Legendre rule).

use nlvid_material::homogeneous::{History, Mode, Sample, drive};
use nlvid_material::{
    Eq256, HistoryRule, Incompressible, Mat3, MooneyRivlin, PipkinRogers, PointState,
};
use nlvid_model::{Prony, Relaxation};

// ---------------------------------------------------------------- reference

/// `G(t) = G0 [1 − Σ g + Σ g e^{−t/τ}]`, coded independently of the crate.
#[derive(Clone)]
struct G {
    g0: f64,
    terms: Vec<(f64, f64)>,
}

impl G {
    fn at(&self, t: f64) -> f64 {
        let ginf = 1.0 - self.terms.iter().map(|x| x.0).sum::<f64>();
        self.g0
            * (ginf
                + self
                    .terms
                    .iter()
                    .map(|&(g, tau)| g * (-t / tau).exp())
                    .sum::<f64>())
    }
    fn rate(&self, t: f64) -> f64 {
        -self.g0
            * self
                .terms
                .iter()
                .map(|&(g, tau)| g / tau * (-t / tau).exp())
                .sum::<f64>()
    }
}

/// Direct eq. 2.2 with eq. 2.55 for diagonal `C = diag(c)`, with moduli `g1`,
/// `g2` (either G or dG/dt): returns the diagonal of R.
fn r_diag(c: [f64; 3], a: f64, g1: f64, g2: f64) -> [f64; 3] {
    let i1 = c[0] + c[1] + c[2];
    let i2 = c[0] * c[1] + c[1] * c[2] + c[2] * c[0];
    let phi = (-a * (i1 - 3.0)).exp();
    let a0 = 2.0 * g1 * (1.0 - i2 * phi) + 2.0 * g2 * (i1 - 2.0 * i2 * phi);
    let a1 = 2.0 * g1 * i1 * phi + 2.0 * g2 * (2.0 * i1 * phi - 1.0);
    let a2 = -2.0 * phi * (g1 + 2.0 * g2);
    [0, 1, 2].map(|i| a0 + a1 * c[i] + a2 * c[i] * c[i])
}

fn uniaxial_c(l: f64) -> [f64; 3] {
    [l * l, 1.0 / l, 1.0 / l]
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// σ11 of uniaxial tension at time `t` for the stretch history `lam`
/// (smooth on the pieces between `kinks`), by composite Gauss–Legendre
/// quadrature of eq. 2.1.
fn sigma_direct(g1: &G, g2: &G, a: f64, lam: &dyn Fn(f64) -> f64, kinks: &[f64], t: f64) -> f64 {
    let gl = gauss_legendre(10);
    let taus = g1.terms.iter().chain(&g2.terms).map(|x| x.1);
    let width = 0.05 * taus.fold(f64::INFINITY, f64::min);
    let mut edges = vec![0.0];
    edges.extend(kinks.iter().copied().filter(|&k| k > 0.0 && k < t));
    edges.push(t);
    let mut integral = [0.0; 3];
    for w in edges.windows(2) {
        let n = ((w[1] - w[0]) / width).ceil().max(1.0) as usize;
        let h = (w[1] - w[0]) / n as f64;
        for p in 0..n {
            let mid = w[0] + (p as f64 + 0.5) * h;
            for &(x, wt) in &gl {
                let s = mid + 0.5 * h * x;
                let u = t - s;
                let r = r_diag(uniaxial_c(lam(s)), a, g1.rate(u), g2.rate(u));
                for i in 0..3 {
                    integral[i] += 0.5 * h * wt * r[i];
                }
            }
        }
    }
    let l = lam(t);
    let c = uniaxial_c(l);
    let r0 = r_diag(c, a, g1.at(0.0), g2.at(0.0));
    // σ = F {…} Fᵀ − q I, σ22 = 0: σ11 = C11 {…}11 − C22 {…}22 (F diagonal).
    c[0] * (r0[0] + integral[0]) - c[1] * (r0[1] + integral[1])
}

// ---------------------------------------------------------------- fixtures

fn fixture() -> (PipkinRogers, G, G, f64) {
    let g1 = G {
        g0: 1000.0,
        terms: vec![(0.4, 0.5), (0.3, 4.0)],
    };
    let g2 = G {
        g0: 120.0,
        terms: vec![(0.5, 0.2), (0.2, 2.0)],
    };
    let a = 0.15;
    let rel = |name, g: &G| {
        Relaxation::new(name, g.g0, Prony::new(name, &g.terms).expect("ok")).expect("ok")
    };
    let m = PipkinRogers::new(rel("G1", &g1), rel("G2", &g2), a, 0.0).expect("ok");
    (m, g1, g2, a)
}

fn at(samples: &[Sample], t: f64) -> &Sample {
    samples
        .iter()
        .rev()
        .find(|s| (s.time - t).abs() < 1e-9)
        .expect("time on the grid")
}

fn mr_uniaxial(c1: f64, c2: f64, l: f64) -> f64 {
    2.0 * (l * l - 1.0 / l) * (c1 + c2 / l)
}

// ---------------------------------------------------------------- tests

/// A history, its stretch function and its kinks.
type Case = (History, Box<dyn Fn(f64) -> f64>, Vec<f64>);

#[test]
fn uniaxial_step_and_ramp_hold_agree_with_direct_quadrature_of_eq_2_1() {
    let (m, g1, g2, a) = fixture();
    let (l1, tr, hold) = (2.5, 0.4, 6.0);
    let cases: Vec<Case> = vec![
        (
            History::Step {
                value: l1,
                hold: hold + tr,
            },
            Box::new(move |_| l1),
            vec![],
        ),
        (
            History::RampHold {
                value: l1,
                ramp: tr,
                hold,
            },
            Box::new(move |s: f64| {
                if s < tr {
                    1.0 + (l1 - 1.0) * s / tr
                } else {
                    l1
                }
            }),
            vec![tr],
        ),
    ];
    for (hist, lam, kinks) in &cases {
        let out = drive(&m, Mode::Uniaxial, hist, 1e-3).expect("drive");
        let mut worst: f64 = 0.0;
        for &t in &[0.1, 0.2, 0.4, 0.5, 1.0, 2.0, 4.0, 6.4] {
            let direct = sigma_direct(&g1, &g2, a, lam.as_ref(), kinks, t);
            let got = at(&out, t).principal[0];
            worst = worst.max(((got - direct) / direct).abs());
        }
        eprintln!("{hist:?}: worst relative error {worst:e}");
        assert!(worst < 1e-3, "{hist:?}: worst relative error {worst:e}");
    }
}

#[test]
fn ramp_hold_converges_at_least_first_order_for_both_rules() {
    let (m0, g1, g2, a) = fixture();
    let (l1, tr, hold) = (2.0, 0.4, 1.6);
    let lam = move |s: f64| {
        if s < tr {
            1.0 + (l1 - 1.0) * s / tr
        } else {
            l1
        }
    };
    let times = [0.2, 0.4, 0.8, 2.0];
    let exact: Vec<f64> = times
        .iter()
        .map(|&t| sigma_direct(&g1, &g2, a, &lam, &[tr], t))
        .collect();
    for rule in [HistoryRule::ExponentialLinear, HistoryRule::Trapezoid] {
        let m = m0.clone().with_rule(rule);
        let errs: Vec<f64> = [0.04, 0.02, 0.01]
            .iter()
            .map(|&dt| {
                let out = drive(
                    &m,
                    Mode::Uniaxial,
                    &History::RampHold {
                        value: l1,
                        ramp: tr,
                        hold,
                    },
                    dt,
                )
                .expect("drive");
                times
                    .iter()
                    .zip(&exact)
                    .map(|(&t, e)| ((at(&out, t).principal[0] - e) / e).abs())
                    .fold(0.0, f64::max)
            })
            .collect();
        let p1 = (errs[0] / errs[1]).log2();
        let p2 = (errs[1] / errs[2]).log2();
        eprintln!("{rule:?}: errors {errs:?}, observed orders {p1:.2} {p2:.2}");
        assert!(
            p1 > 1.0 && p2 > 1.0,
            "{rule:?}: errors {errs:?}, orders {p1} {p2}"
        );
    }
}

#[test]
fn qlv_step_relaxes_exactly_as_g_of_t_over_g0() {
    let g = Relaxation::new(
        "G1",
        800.0,
        Prony::new("G1", &[(0.5, 0.3), (0.3, 3.0)]).expect("ok"),
    )
    .expect("ok");
    let m = PipkinRogers::qlv(g.clone(), 0.25, 0.3, 0.0).expect("ok");
    for mode in [Mode::Uniaxial, Mode::Equibiaxial, Mode::SimpleShear] {
        let v = if mode == Mode::SimpleShear { 1.5 } else { 2.2 };
        // Coarse steps: the identity is exact, not a discretisation limit.
        let out = drive(
            &m,
            mode,
            &History::Step {
                value: v,
                hold: 10.0,
            },
            0.7,
        )
        .expect("drive");
        let s0 = out[1].cauchy;
        for s in &out[1..] {
            let expect = s0 * (g.value(s.time) / g.g0());
            let err = (s.cauchy - expect).abs().max() / s0.abs().max();
            assert!(err < 1e-13, "{mode:?} t = {}: {err:e}", s.time);
        }
    }
}

#[test]
fn qlv_normalised_relaxation_is_strain_independent_but_pipkin_rogers_is_not() {
    let (pr, ..) = fixture();
    let g = pr.g1().clone();
    let qlv = PipkinRogers::qlv(g, 0.12, 0.15, 0.0).expect("ok");
    let ratio = |m: &PipkinRogers, l: f64| {
        let out = drive(
            m,
            Mode::Uniaxial,
            &History::Step {
                value: l,
                hold: 1.0,
            },
            0.05,
        )
        .expect("ok");
        at(&out, 1.0).principal[0] / out[1].principal[0]
    };
    let (q1, q2) = (ratio(&qlv, 1.5), ratio(&qlv, 3.0));
    assert!((q1 - q2).abs() < 1e-13, "QLV: {q1} vs {q2}");
    let (p1, p2) = (ratio(&pr, 1.5), ratio(&pr, 3.0));
    assert!(
        (p1 - p2).abs() > 1e-3,
        "Pipkin–Rogers should depend on strain: {p1} vs {p2}"
    );
}

#[test]
fn two_step_history_gives_the_pipkin_rogers_superposition_exactly() {
    let (m, g1, g2, a) = fixture();
    let (la, lb, t1) = (1.8, 2.6, 0.7);
    let hist = History::Table(vec![(0.0, 1.0), (0.0, la), (t1, la), (t1, lb), (5.0, lb)]);
    let out = drive(&m, Mode::Uniaxial, &hist, 0.3).expect("drive");
    let (ca, cb) = (uniaxial_c(la), uniaxial_c(lb));
    for s in out.iter().filter(|s| s.time > t1 && s.value == lb) {
        let t = s.time;
        // R(C2, t − t1) + R(C1, t) − R(C1, t − t1), pushed forward with F2.
        let r = |c: [f64; 3], u: f64| r_diag(c, a, g1.at(u), g2.at(u));
        let (x, y, z) = (r(cb, t - t1), r(ca, t), r(ca, t - t1));
        let inner = [0, 1].map(|i| x[i] + y[i] - z[i]);
        let exact = cb[0] * inner[0] - cb[1] * inner[1];
        let err = ((s.principal[0] - exact) / exact).abs();
        assert!(
            err < 1e-12,
            "t = {t}: {} vs {exact} ({err:e})",
            s.principal[0]
        );
    }
}

fn eq256() -> Eq256 {
    Eq256 {
        g10: 1000.0,
        gamma0: 0.1,
        g1_fraction: 0.3,
        g2_fraction: 0.6,
        tau1: 1.0,
        c: 0.5,
        a: 0.4,
    }
}

#[test]
fn instantaneous_and_long_time_responses_are_mooney_rivlin_with_gamma0_and_gamma_inf() {
    let p = eq256();
    let m = PipkinRogers::from_eq_2_56(&p, 0.0).expect("ok");
    let gamma_inf = p.g2_fraction / p.g1_fraction * p.gamma0; // eq. 2.57
    let c1_inf = p.g1_fraction * p.g10;
    let mr0 = MooneyRivlin::new(p.g10, p.gamma0 * p.g10, 0.0).expect("ok");
    let mr_inf = MooneyRivlin::new(c1_inf, gamma_inf * c1_inf, 0.0).expect("ok");
    let t_end = 60.0 * p.tau1 / p.c; // e^{-60}: relaxation complete to rounding
    for mode in [Mode::Uniaxial, Mode::Equibiaxial, Mode::SimpleShear] {
        for &v in &[0.6, 1.5, 3.0] {
            let v = if mode == Mode::SimpleShear {
                v - 0.5
            } else {
                v
            };
            let out = drive(
                &m,
                mode,
                &History::Step {
                    value: v,
                    hold: t_end,
                },
                1.0,
            )
            .expect("ok");
            let f = mode.deformation_gradient(v);
            for (sample, mr) in [(&out[1], &mr0), (out.last().expect("sample"), &mr_inf)] {
                let e = mr.extra_stress(&(), &f, 0.0, &mut ()).expect("ok");
                let mut exact = e - Mat3::identity() * e[(2, 2)];
                if mode == Mode::Uniaxial {
                    exact = e - Mat3::identity() * e[(1, 1)];
                }
                let err = (sample.cauchy - exact).abs().max() / exact.abs().max();
                assert!(err < 1e-12, "{mode:?} v = {v} t = {}: {err:e}", sample.time);
            }
        }
    }
    // The same limits in closed form for uniaxial stretch 2.
    let out = drive(
        &m,
        Mode::Uniaxial,
        &History::Step {
            value: 2.0,
            hold: t_end,
        },
        1.0,
    )
    .expect("ok");
    let s0 = mr_uniaxial(p.g10, p.gamma0 * p.g10, 2.0);
    let sinf = mr_uniaxial(c1_inf, gamma_inf * c1_inf, 2.0);
    assert!((out[1].principal[0] - s0).abs() < 1e-12 * s0);
    assert!((out.last().expect("sample").principal[0] - sinf).abs() < 1e-12 * sinf);
}

#[test]
fn simple_shear_at_zero_plus_gives_mooney_rivlin_viscometric_functions() {
    let p = eq256();
    let m = PipkinRogers::from_eq_2_56(&p, 0.0).expect("ok");
    let (c1, c2) = (p.g10, p.gamma0 * p.g10);
    for &g in &[0.2, 1.0, 2.5] {
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
        let (n1, n2) = (s[(0, 0)] - s[(1, 1)], s[(1, 1)] - s[(2, 2)]);
        let tol = 1e-12 * c1 * (1.0 + g * g);
        assert!((s[(0, 1)] - 2.0 * (c1 + c2) * g).abs() < tol);
        assert!((n1 - 2.0 * (c1 + c2) * g * g).abs() < tol);
        assert!((n2 + 2.0 * c2 * g * g).abs() < tol);
    }
}

#[test]
fn eq_2_55_and_umat_d2_conventions_differ_by_exactly_two() {
    // D.2's coefficients have no factor 2: with G10_umat = 2 G10 they give the
    // same R as eq. 2.55 with G10. Both coded here from the thesis's text.
    let p = eq256();
    let ours = PipkinRogers::from_eq_2_56(&p, 0.0).expect("ok");
    let prony1 = ours.g1().prony().clone();
    let prony2 = ours.g2().prony().clone();
    let umat =
        PipkinRogers::from_umat_d2(2.0 * p.g10, p.gamma0, prony1, prony2, p.a, 0.0).expect("ok");
    let c = Mat3::new(2.0, 0.3, 0.1, 0.3, 0.9, -0.2, 0.1, -0.2, 0.7);
    let i1 = c.trace();
    let i2 = 0.5 * (i1 * i1 - (c * c).trace());
    let phi = (-p.a * (i1 - 3.0)).exp();
    for &t in &[0.0, 0.7, 5.0] {
        let (g1u, g2u) = (2.0 * ours.g1().value(t), 2.0 * ours.g2().value(t));
        // eq. D.2 with the UMAT moduli.
        let a0 = g1u * (1.0 - i2 * phi) + g2u * (i1 - 2.0 * i2 * phi);
        let a1 = g1u * i1 * phi + g2u * (2.0 * i1 * phi - 1.0);
        let a2 = -phi * (g1u + 2.0 * g2u);
        let r_d2 = Mat3::identity() * a0 + c * a1 + c * c * a2;
        for m in [&ours, &umat] {
            let err = (m.r_tensor(&c, t) - r_d2).abs().max() / r_d2.abs().max();
            assert!(err < 1e-13, "t = {t}: {err:e}");
        }
    }
    // Same stresses through the point update.
    let f = Mode::Uniaxial.deformation_gradient(2.0);
    let s1 = ours
        .extra_stress(&ours.initial_state(), &f, 0.0, &mut ours.initial_state())
        .expect("ok");
    let s2 = umat
        .extra_stress(&umat.initial_state(), &f, 0.0, &mut umat.initial_state())
        .expect("ok");
    assert!((s1 - s2).abs().max() < 1e-12 * s1.abs().max());
}

#[test]
fn recursive_trapezoid_equals_the_full_eq_2_48_sum() {
    let (m, ..) = fixture();
    let m = m.with_rule(HistoryRule::Trapezoid);
    let samples = rotating_history();
    let reference = nlvid_material::reference::pipkin_rogers_trapezoid(&m, &samples).expect("ok");
    let mut state = m.initial_state();
    let mut trial = state.clone();
    let mut t_n = 0.0;
    for ((t, f), r) in samples.iter().zip(&reference) {
        let got = m.extra_stress(&state, f, t - t_n, &mut trial).expect("ok");
        std::mem::swap(&mut state, &mut trial);
        t_n = *t;
        let err = (got - r).abs().max() / r.abs().max().max(1.0);
        assert!(err < 1e-12, "t = {t}: {err:e}");
    }
}

/// An isochoric 3D history with rotating principal axes, irregular steps and
/// a jump.
pub fn rotating_history() -> Vec<(f64, Mat3)> {
    let mut out = Vec::new();
    let mut t = 0.0;
    for n in 0..60 {
        t += 0.02 + 0.05 * ((n * 7 % 5) as f64);
        let l = 1.0 + 0.8 * (0.7 * t).sin().abs();
        let (s, c) = (0.4 * t).sin_cos();
        let rot = Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let u = Mat3::new(
            l,
            0.2,
            0.0,
            0.0,
            1.0 / l.sqrt(),
            0.0,
            0.0,
            0.0,
            1.0 / l.sqrt(),
        );
        out.push((t, rot * u));
        if n == 20 {
            out.push((
                t,
                rot * u * Mat3::new(1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            ));
        }
    }
    out
}

#[test]
fn appendix_d3_uniaxial_verification_case_matches_direct_quadrature() {
    // App. D.3: g1 = g2 = 0.99, τ1 = τ2 = 0.01 s, G10 = 100 (UMAT convention,
    // eq. D.2), a = 0, d = 1; stretch ramped to 2 in 0.01 s and held to
    // 0.15 s. (The text prints "λ = 1 + t" for the ramp, which cannot reach
    // 2 at t = 0.01; we read it as a linear ramp from 1 to 2.)
    let p = || Prony::new("G", &[(0.99, 0.01)]).expect("ok");
    let m = PipkinRogers::from_umat_d2(100.0, 1.0, p(), p(), 0.0, 0.0).expect("ok");
    let g = G {
        g0: 50.0,
        terms: vec![(0.99, 0.01)],
    };
    let (tr, l1) = (0.01, 2.0);
    let lam = move |s: f64| {
        if s < tr {
            1.0 + (l1 - 1.0) * s / tr
        } else {
            l1
        }
    };
    let out = drive(
        &m,
        Mode::Uniaxial,
        &History::RampHold {
            value: l1,
            ramp: tr,
            hold: 0.14,
        },
        2e-5,
    )
    .expect("ok");
    for &t in &[0.005, 0.01, 0.02, 0.05, 0.15] {
        let direct = sigma_direct(&g, &g, 0.0, &lam, &[tr], t);
        let got = at(&out, t).principal[0];
        assert!(
            ((got - direct) / direct).abs() < 1e-3,
            "t = {t}: {got} vs {direct}"
        );
    }
    // Long-time: Mooney–Rivlin with C1 = C2 = 0.01·50 Pa.
    let sinf = mr_uniaxial(0.5, 0.5, 2.0);
    let end = out.last().expect("sample").principal[0];
    assert!(((end - sinf) / sinf).abs() < 1e-3, "{end} vs {sinf}");
}
