//! Elastic (Mooney–Rivlin / neo-Hookean) limits of the squeezed membrane,
//! checked against closed forms and identities every equilibrium satisfies.
#![allow(clippy::unwrap_used)]

use std::f64::consts::PI;

use nlvid_membrane::{
    Control, Geometry, MembraneError, MembraneSolver, MooneyRivlinMembrane, Solution,
};

fn solver(gamma: f64, rs: f64, nodes: usize) -> MembraneSolver<MooneyRivlinMembrane> {
    let m = MooneyRivlinMembrane::new(1.0, gamma).unwrap();
    MembraneSolver::new(m, Geometry { rs, nodes }, 1.0).unwrap()
}

fn squeeze(gamma: f64, d: f64, nodes: usize) -> Solution {
    solver(gamma, 1.03, nodes)
        .equilibrium(0.0, Control::Displacement(d))
        .unwrap()
}

#[test]
fn free_inflation_satisfies_rivlin_identity_with_fourth_order_convergence() {
    for gamma in [0.0, 0.1, 0.3] {
        for rs in [1.03f64, 1.2, 1.5] {
            let rivlin: f64 = 4.0 * (1.0 / rs - f64::powi(rs, -7)) * (1.0 + gamma * rs * rs);
            let err = |n| {
                let sol = solver(gamma, rs, n)
                    .equilibrium(0.0, Control::Displacement(0.0))
                    .unwrap();
                approx::assert_relative_eq!(sol.record.lambda0, rs, max_relative = 1e-6);
                approx::assert_relative_eq!(sol.record.h1, rs, max_relative = 1e-6);
                assert_eq!(sol.record.force, 0.0);
                (sol.record.pressure - rivlin).abs() / rivlin
            };
            let (e32, e64) = (err(32), err(64));
            assert!(e64 < 1e-7, "γ={gamma} rs={rs}: error {e64:.2e}");
            // RK4: halving the step divides the error by ~16.
            assert!(
                e64 < e32 / 8.0 || e64 < 1e-12,
                "γ={gamma} rs={rs}: {e32:.2e} → {e64:.2e}"
            );
        }
    }
}

#[test]
fn squeezed_membrane_is_in_vertical_equilibrium_at_every_cut() {
    // Cap cut at any ψ in the free region: plate force + membrane tension =
    // fluid pressure on the projected area, F = π ρ² p − 2π ρ T1 sin θ.
    // At the equator (θ = π/2) this is p π (r_eq² − a²) = 2π r_eq T1.
    for gamma in [0.0, 0.1] {
        for d in [0.1, 0.28, 0.53, 0.78] {
            let sol = squeeze(gamma, d, 96);
            approx::assert_relative_eq!(
                sol.record.force,
                PI * sol.record.contact_radius.powi(2) * sol.record.pressure,
                max_relative = 1e-12
            );
            let cap = sol.record.pressure
                * PI
                * (sol.record.equator_radius.powi(2) - sol.record.contact_radius.powi(2));
            approx::assert_relative_eq!(
                cap,
                2.0 * PI * sol.record.equator_radius * sol.t1_equator,
                max_relative = 1e-6
            );
            for v in sol.profile.iter().filter(|v| v.psi > sol.record.psi_c) {
                let f = PI * v.rho * v.rho * sol.record.pressure
                    - 2.0 * PI * v.rho * v.t1 * v.theta.sin();
                approx::assert_relative_eq!(
                    f,
                    sol.record.force,
                    max_relative = 1e-6,
                    epsilon = 1e-9
                );
            }
            approx::assert_relative_eq!(
                sol.volume,
                4.0 / 3.0 * PI * 1.03f64.powi(3),
                max_relative = 1e-10
            );
        }
    }
}

/// Strain energy of the whole membrane (both halves) per G10 h0 r0²:
/// 2 · 2π ∫ W sin ψ dψ, W = (I1 − 3) + γ (I2 − 3), composite Simpson.
fn energy(sol: &Solution, gamma: f64) -> f64 {
    let w: Vec<f64> = sol
        .profile
        .iter()
        .map(|v| {
            let (a, b) = (v.lambda1 * v.lambda1, v.lambda2 * v.lambda2);
            let c = 1.0 / (a * b);
            ((a + b + c - 3.0) + gamma * (a * b + b * c + c * a - 3.0)) * v.psi.sin()
        })
        .collect();
    let n = w.len() - 1;
    let h = sol.profile[1].psi - sol.profile[0].psi;
    let mut s = w[0] + w[n];
    for (i, wi) in w.iter().enumerate().take(n).skip(1) {
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * wi;
    }
    4.0 * PI * s * h / 3.0
}

#[test]
fn contact_force_is_half_the_energy_derivative() {
    // Each plate moves by D and pushes with F; the fluid does no work at
    // constant volume: dU/dD = 2F (U of the whole membrane).
    let gamma = 0.1;
    for d in [0.28, 0.53] {
        let h = 2e-3;
        let up = squeeze(gamma, d + h, 192);
        let dn = squeeze(gamma, d - h, 192);
        let mid = squeeze(gamma, d, 192);
        let du = (energy(&up, gamma) - energy(&dn, gamma)) / (2.0 * h);
        approx::assert_relative_eq!(du, 2.0 * mid.record.force, max_relative = 2e-3);
    }
}

#[test]
fn fig_2_4_force_displacement_stiffens_with_gamma() {
    let ds = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.78];
    let mut prev_curve: Option<Vec<f64>> = None;
    for gamma in [0.0, 0.1, 0.2, 0.3] {
        let mut s = solver(gamma, 1.03, 96);
        let f: Vec<f64> = ds
            .iter()
            .map(|&d| {
                s.equilibrium(0.0, Control::Displacement(d))
                    .unwrap()
                    .record
                    .force
            })
            .collect();
        assert!(
            f.windows(2).all(|w| w[1] > w[0]),
            "γ={gamma}: F not increasing in D: {f:?}"
        );
        if let Some(p) = &prev_curve {
            assert!(
                f.iter().zip(p).all(|(a, b)| a > b),
                "γ={gamma} not stiffer than the previous γ"
            );
        }
        prev_curve = Some(f);
    }
}

#[test]
fn contact_angle_at_d078_matches_the_thesis_qlv_value() {
    // §2.5.1 / Fig. 2.10: ψc = 1.2917 at D/r0 = 0.78 (QLV, γ0 = γ∞ = 0.1;
    // the shape is the elastic one at any time).
    let sol = squeeze(0.1, 0.78, 96);
    approx::assert_relative_eq!(sol.record.psi_c, 1.2917, max_relative = 1e-3);
}

#[test]
fn force_grows_about_tenfold_from_d053_to_d078() {
    let ratio = squeeze(0.1, 0.78, 96).record.force / squeeze(0.1, 0.53, 96).record.force;
    // §2.5.1 says "by a factor of 10"; we obtain 8.7.
    assert!((8.0..11.0).contains(&ratio), "ratio {ratio}");
}

#[test]
fn displacement_and_force_control_give_the_same_equilibrium() {
    for d in [0.05, 0.28, 0.78] {
        let by_d = squeeze(0.1, d, 96);
        let by_f = solver(0.1, 1.03, 96)
            .equilibrium(0.0, Control::Force(by_d.record.force))
            .unwrap();
        approx::assert_relative_eq!(by_f.record.displacement, d, max_relative = 1e-7);
        approx::assert_relative_eq!(by_f.record.psi_c, by_d.record.psi_c, max_relative = 1e-7);
        approx::assert_relative_eq!(
            by_f.record.pressure,
            by_d.record.pressure,
            max_relative = 1e-7
        );
    }
}

#[test]
fn discretisation_error_at_default_nodes_is_below_one_per_mille() {
    let coarse = squeeze(0.1, 0.78, 96);
    let fine = squeeze(0.1, 0.78, 384);
    approx::assert_relative_eq!(coarse.record.force, fine.record.force, max_relative = 1e-3);
    approx::assert_relative_eq!(coarse.record.psi_c, fine.record.psi_c, max_relative = 1e-4);
}

#[test]
fn stress_free_membrane_reports_wrinkling_instead_of_panicking() {
    let m = MooneyRivlinMembrane::new(1.0, 0.1).unwrap();
    match MembraneSolver::new(m, Geometry { rs: 1.0, nodes: 32 }, 1.0) {
        Err(e @ MembraneError::Wrinkling { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("t = 0") && msg.contains("r_s"), "{msg}");
        }
        other => panic!("expected wrinkling, got {other:?}"),
    }
}

#[test]
fn excessive_displacement_is_a_typed_error_with_advice() {
    let mut s = solver(0.1, 1.03, 48);
    let e = s
        .equilibrium(0.0, Control::Displacement(1.025))
        .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            MembraneError::NoConvergence { .. } | MembraneError::Wrinkling { .. }
        ),
        "{msg}"
    );
    assert!(msg.contains("D/r0 = 1.025"), "{msg}");
    // The solver is still usable afterwards.
    assert!(s.equilibrium(0.0, Control::Displacement(0.5)).is_ok());
}
