//! The axisymmetric fast path `Material3::update_axisymmetric` against the
//! general 3D update (restricted to the five axisymmetric components, with
//! the same history) and against central finite differences of its own
//! first Piola stress.

use nlvid_material::{
    AXISYMMETRIC_COMPONENTS, HistoryRule, Mat3, Material3, MooneyRivlin, PipkinRogers,
    PronyViscoelastic,
};
use nlvid_model::{Prony, Relaxation};

use crate::common::{pipkin_rogers, prony_visco};

fn models() -> (MooneyRivlin, Vec<PronyViscoelastic>, Vec<PipkinRogers>) {
    let mr = MooneyRivlin::new(1000.0, 200.0, 3.0e4).expect("ok");
    let prony = [HistoryRule::ExponentialLinear, HistoryRule::Trapezoid].map(prony_visco);
    // The AFM cell model as the fem crate builds it (C1 = G0/2, κ = 200 G0).
    // The AFM cell model: G0 = 1 kPa, so C1 = 500 Pa and κ = 400 C1.
    let shear = Relaxation::new(
        "G0",
        1000.0,
        Prony::new("G", &[(0.3, 0.5), (0.3, 10.0)]).expect("ok"),
    )
    .expect("ok");
    let cell = PronyViscoelastic::cell(&shear, 2.0e5).expect("ok");
    let pr = pipkin_rogers(HistoryRule::default());
    let mut visco = prony.to_vec();
    visco.push(cell);
    (mr, visco, vec![pr])
}

fn full(f: &[f64; 5]) -> Mat3 {
    Mat3::new(f[0], f[1], 0.0, f[2], f[3], 0.0, 0.0, 0.0, f[4])
}

/// Axisymmetric gradients: large stretch, shear both ways, compression in
/// the hoop direction, near-isochoric and strongly volumetric.
fn gradients() -> Vec<[f64; 5]> {
    vec![
        [1.0, 0.0, 0.0, 1.0, 1.0],
        [2.5, 0.0, 0.0, 0.4, 1.0],
        [1.2, 0.35, -0.2, 0.85, 0.97],
        [0.9, -0.6, 0.3, 1.3, 1.4],
        [1.02, 0.01, 0.005, 0.97, 1.01],
        [0.7, 0.2, 0.1, 0.8, 0.6],
    ]
}

/// A converged history after a few steps along an axisymmetric path.
fn aged<M: Material3>(m: &M) -> M::State {
    let mut s = m.initial_state();
    let mut trial = s.clone();
    for n in 1..=4 {
        let x = n as f64 * 0.1;
        let f = [1.0 + x, 0.3 * x, -0.2 * x, 1.0 / (1.0 + x), 1.0 + 0.5 * x];
        m.update(&s, &full(&f), 0.3, &mut trial).expect("ok");
        s = trial.clone();
    }
    s
}

fn check<M: Material3>(m: &M, what: &str)
where
    M::State: PartialEq,
{
    let fresh = m.initial_state();
    let old = aged(m);
    for f in gradients() {
        for (state, dt) in [(&fresh, 0.0), (&fresh, 0.1), (&old, 0.05), (&old, 3.0)] {
            // General path, restricted by hand.
            let mut trial_g = state.clone();
            let g = m
                .update(state, &full(&f), dt, &mut trial_g)
                .expect("general");
            let mut trial_a = state.clone();
            let a = m
                .update_axisymmetric(state, &f, dt, &mut trial_a, true)
                .expect("fast");
            let pmax = g.first_piola.abs().max();
            let tmax = g.tangent.abs().max();
            // Rounding of J (≈ ε) moves P by ≈ |∂P/∂F| ε: with a stiff
            // volumetric penalty near J = 1 that exceeds ε |P| (K (J − 1)
            // cancels), so the stress is compared on the scale |A| as well.
            let p_scale = pmax + tmax;
            for (p, &(i, j)) in AXISYMMETRIC_COMPONENTS.iter().enumerate() {
                let d = (a.first_piola[p] - g.first_piola[(i, j)]).abs();
                assert!(
                    d <= 1e-13 * p_scale,
                    "{what}: F = {f:?}, dt = {dt}: P[{p}] {} vs {} (|P| {pmax:e})",
                    a.first_piola[p],
                    g.first_piola[(i, j)]
                );
                for (q, &(k, l)) in AXISYMMETRIC_COMPONENTS.iter().enumerate() {
                    let d = (a.tangent[p][q] - g.tangent[(3 * i + j, 3 * k + l)]).abs();
                    assert!(
                        d <= 1e-12 * tmax,
                        "{what}: F = {f:?}, dt = {dt}: A[{p}][{q}] {} vs {} (|A| {tmax:e})",
                        a.tangent[p][q],
                        g.tangent[(3 * i + j, 3 * k + l)]
                    );
                }
            }
            // The off-block stress the fast path drops is zero in the general path.
            for (i, j) in [(0, 2), (1, 2), (2, 0), (2, 1)] {
                assert!(g.first_piola[(i, j)].abs() <= 1e-14 * p_scale, "{what}");
            }
            // Same trial history (up to rounding of the kinematics).
            let mut trial_r = state.clone();
            let r = m
                .update_axisymmetric(state, &f, dt, &mut trial_r, false)
                .expect("residual only");
            assert_eq!(r.first_piola, a.first_piola, "{what}: residual-only P");
            assert_eq!(r.tangent, [[0.0; 5]; 5], "{what}: residual-only tangent");
            assert!(trial_r == trial_a, "{what}: residual-only history");
            // Central differences of the fast path's own P.
            let mut fd = [[0.0; 5]; 5];
            for q in 0..5 {
                let h = 1e-6;
                let (mut fp, mut fm) = (f, f);
                fp[q] += h;
                fm[q] -= h;
                let mut tr = state.clone();
                let pp = m
                    .update_axisymmetric(state, &fp, dt, &mut tr, false)
                    .expect("fd")
                    .first_piola;
                let pm = m
                    .update_axisymmetric(state, &fm, dt, &mut tr, false)
                    .expect("fd")
                    .first_piola;
                for p in 0..5 {
                    fd[p][q] = (pp[p] - pm[p]) / (2.0 * h);
                }
            }
            let err = (0..5)
                .flat_map(|p| (0..5).map(move |q| (p, q)))
                .map(|(p, q)| (fd[p][q] - a.tangent[p][q]).abs())
                .fold(0.0, f64::max);
            assert!(
                err <= 1e-6 * tmax,
                "{what}: F = {f:?}, dt = {dt}: |A − A_fd| = {err:e} of {tmax:e}"
            );
        }
    }
}

#[test]
fn axisymmetric_fast_path_matches_general_update_and_finite_differences() {
    let (mr, visco, pr) = models();
    check(&mr, "Mooney–Rivlin");
    for (k, m) in visco.iter().enumerate() {
        check(m, &format!("Prony viscoelastic #{k}"));
    }
    for m in &pr {
        check(m, "Pipkin–Rogers");
    }
}

#[test]
fn axisymmetric_fast_path_rejects_inverted_and_non_finite_gradients() {
    let (_, visco, _) = models();
    let mr = &visco[2];
    let s = nlvid_material::PointState::initial_state(mr);
    let mut t = s.clone();
    for f in [
        [1.0, 0.0, 0.0, -1.0, 1.0],
        [1.0, 0.0, 0.0, 1.0, 0.0],
        [f64::NAN, 0.0, 0.0, 1.0, 1.0],
    ] {
        let e = mr
            .update_axisymmetric(&s, &f, 0.1, &mut t, true)
            .expect_err("invalid F");
        assert!(e.to_string().contains("det F") || e.to_string().contains("non-finite"));
    }
    assert!(
        mr.update_axisymmetric(&s, &[1.0; 5], -1.0, &mut t, true)
            .is_err()
    );
}
