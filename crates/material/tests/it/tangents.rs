//! Consistent tangents of the viscoelastic models against central finite
//! differences of the stress update, with non-trivial history, 3D and
//! membrane, stretches up to 3.

use crate::common::{self, pipkin_rogers, prony_visco};

use nlvid_material::{HistoryRule, Mat3, Material3, MembraneMaterial};

/// Drives `m` through a few steps of a rotating, stretching history so the
/// state is generic, and returns the converged state.
fn aged_state<M: Material3>(m: &M) -> M::State {
    let mut s = m.initial_state();
    let mut trial = s.clone();
    for n in 1..=4 {
        let x = n as f64 * 0.3;
        let f = Mat3::new(
            1.0 + x,
            0.2 * x,
            0.0,
            -0.1 * x,
            1.0 / (1.0 + 0.5 * x),
            0.1 * x,
            0.0,
            0.05,
            1.0,
        );
        m.update(&s, &f, 0.2, &mut trial).expect("ok");
        s = trial.clone();
    }
    s
}

fn aged_membrane<M: MembraneMaterial>(m: &M) -> M::State {
    let mut s = m.initial_state();
    let mut trial = s.clone();
    for n in 1..=4 {
        let x = n as f64 * 0.4;
        m.update(&s, [1.0 + x, 1.0 + 0.3 * x], 0.2, &mut trial)
            .expect("ok");
        s = trial.clone();
    }
    s
}

fn check_3d<M: Material3>(m: &M, what: &str) {
    let fresh = m.initial_state();
    let aged = aged_state(m);
    for f in common::test_gradients() {
        for (state, dt) in [(&fresh, 0.0), (&fresh, 0.1), (&aged, 0.05), (&aged, 2.0)] {
            let e = common::tangent_error_3d(m, state, &f, dt);
            assert!(e < 1e-6, "{what}: F = {f}, dt = {dt}: relative error {e:e}");
        }
    }
}

fn check_membrane<M: MembraneMaterial>(m: &M, what: &str) {
    let fresh = m.initial_state();
    let aged = aged_membrane(m);
    for l in [[1.0, 1.0], [3.0, 1.0], [1.5, 2.5], [3.0, 3.0], [0.8, 2.0]] {
        for (state, dt) in [(&fresh, 0.0), (&aged, 0.05), (&aged, 2.0)] {
            let e = common::tangent_error_membrane(m, state, l, dt);
            assert!(
                e < 1e-6,
                "{what}: λ = {l:?}, dt = {dt}: relative error {e:e}"
            );
        }
    }
}

#[test]
fn pipkin_rogers_3d_tangent_matches_central_differences() {
    for rule in [HistoryRule::ExponentialLinear, HistoryRule::Trapezoid] {
        check_3d(&pipkin_rogers(rule), &format!("PR {rule:?}"));
    }
}

#[test]
fn pipkin_rogers_membrane_tangent_matches_central_differences() {
    check_membrane(
        &pipkin_rogers(HistoryRule::ExponentialLinear),
        "PR membrane",
    );
}

#[test]
fn prony_viscoelastic_3d_tangent_matches_central_differences() {
    for rule in [HistoryRule::ExponentialLinear, HistoryRule::Trapezoid] {
        check_3d(&prony_visco(rule), &format!("ABAQUS-form {rule:?}"));
    }
}

#[test]
fn prony_viscoelastic_membrane_tangent_matches_central_differences() {
    check_membrane(
        &prony_visco(HistoryRule::ExponentialLinear),
        "ABAQUS-form membrane",
    );
}
