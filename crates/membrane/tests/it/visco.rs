//! Viscoelastic time marching: QLV step identities, the Fig. 2.12 case,
//! the ψc(t) trends of Fig. 2.9 and force control.
#![allow(clippy::unwrap_used)]

use nlvid_membrane::{
    Control, ControlKind, Geometry, Loading, MembraneSolver, PipkinRogersParams, simulate,
    simulate_with,
};
use nlvid_protocol::{Quantity, programs};

use crate::reference_pr;

fn step_run(
    p: PipkinRogersParams,
    d: f64,
    t_end: f64,
    steps: usize,
) -> nlvid_membrane::MembraneRun {
    let prog = programs::step(Quantity::Dimensionless, d, t_end).unwrap();
    let times = (0..=steps)
        .map(|k| t_end * k as f64 / steps as f64)
        .collect();
    let l = Loading::new(ControlKind::Displacement, prog, times)
        .unwrap()
        .with_profiles(&[t_end]);
    simulate(&p, &Geometry::default(), &l).unwrap()
}

fn qlv_step(nodes: usize) -> nlvid_membrane::MembraneRun {
    let p = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    let prog = programs::step(Quantity::Dimensionless, 0.78, 5.0).unwrap();
    let times = (0..=50).map(|k| 0.1 * k as f64).collect();
    let l = Loading::new(ControlKind::Displacement, prog, times).unwrap();
    simulate(&p, &Geometry { rs: 1.03, nodes }, &l).unwrap()
}

/// Largest relative change of (F/G_trap, ψc, λ0) over the hold.
fn qlv_deviation(run: &nlvid_membrane::MembraneRun) -> f64 {
    let h = &run.history;
    let dt = 0.1;
    // G_trap(t)/G(0) of eq. 2.48 for the kernel of eq. 2.56, written out here.
    let k = |tau: f64| -(1.0 - 0.2) * (-tau).exp();
    let mut dev: f64 = 0.0;
    for (i, r) in h.iter().enumerate() {
        let t = i as f64 * dt;
        let g = 1.0
            + (0..i)
                .map(|j| 0.5 * dt * (k(t - j as f64 * dt) + k(t - (j + 1) as f64 * dt)))
                .sum::<f64>();
        dev = dev
            .max((r.force / h[0].force / g - 1.0).abs())
            .max((r.psi_c / h[0].psi_c - 1.0).abs())
            .max((r.lambda0 / h[0].lambda0 - 1.0).abs());
    }
    dev
}

#[test]
fn qlv_step_keeps_the_shape_and_scales_force_by_the_discrete_relaxation_function() {
    // Exact for the continuous problem (§2.2 case 3). Discretely, stresses at
    // RK4 stage points blend the two neighbouring node histories linearly,
    // which breaks separability at O(Δψ²): the deviation must be small and
    // shrink ~4× when the node spacing halves.
    let (coarse, fine) = (qlv_step(96), qlv_step(192));
    let (d96, d192) = (qlv_deviation(&coarse), qlv_deviation(&fine));
    eprintln!("QLV step deviation: {d96:.2e} (96 intervals), {d192:.2e} (192)");
    assert!(d96 < 1e-4, "deviation {d96:.2e}");
    assert!(
        d192 < d96 / 3.0,
        "no O(Δψ²) convergence: {d96:.2e} → {d192:.2e}"
    );
    approx::assert_relative_eq!(coarse.history[0].psi_c, 1.2917, max_relative = 1e-3);
    // Against the exact G(t) of eq. 2.56 the trapezoid (eq. 2.48) over-relaxes by
    // the factor (x/2) coth(x/2) − 1 ≈ x²/12 on G0 − G∞, x = Δt/τ = 0.1: −0.33 % at t0 = 5.
    let last = coarse.history.last().unwrap();
    approx::assert_relative_eq!(
        last.force / coarse.history[0].force,
        0.2 + 0.8 * (-5.0f64).exp(),
        max_relative = 5e-3
    );
}

#[test]
fn fig_2_12_case_matches_thesis_stretches_and_angles() {
    // D/r0 = 0.78, g1 = 0.2, g2 = 0.3, c = 1, γ0 = 0.1, t0 = 10.
    let p = PipkinRogersParams::chapter2(0.2, 0.3, 1.0);
    let run = step_run(p, 0.78, 10.0, 100);
    let sol = &run.profiles[0];
    assert_eq!(sol.record.time, 10.0);
    let crown = sol.profile[0].lambda2;
    let edge = sol.profile[sol.profile.len() - 1].lambda2;
    approx::assert_relative_eq!(crown, 1.1551, max_relative = 0.01);
    approx::assert_relative_eq!(edge, 1.7564, max_relative = 0.01);
    approx::assert_relative_eq!(sol.record.psi_c.to_degrees(), 73.7, max_relative = 0.01);
    approx::assert_relative_eq!(sol.current_contact_angle_deg(), 80.6, max_relative = 0.01);
    // λ2 > λ1 and σ2 > σ1 everywhere (§2.5.1).
    for v in &sol.profile[1..] {
        assert!(
            v.lambda2 >= v.lambda1 - 1e-9 && v.sigma2 >= v.sigma1 - 1e-9,
            "{v:?}"
        );
    }
}

fn psi_c_history(p: PipkinRogersParams) -> Vec<f64> {
    step_run(p, 0.78, 10.0, 100)
        .history
        .iter()
        .map(|r| r.psi_c)
        .collect()
}

#[test]
fn fig_2_9_contact_angle_trends() {
    let base = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    // g2 < g1 (γ∞ = 0.05): ψc increases monotonically; g2 > g1: decreases.
    let up = psi_c_history(PipkinRogersParams { g2: 0.1, ..base });
    assert!(
        up.windows(2).all(|w| w[1] >= w[0] - 1e-12) && up[100] > up[0] + 1e-3,
        "{up:?}"
    );
    let down = psi_c_history(PipkinRogersParams { g2: 0.3, ..base });
    assert!(
        down.windows(2).all(|w| w[1] <= w[0] + 1e-12) && down[100] < down[0] - 1e-3,
        "{down:?}"
    );
    // g1 = g2, c = 1/2: ψc first decreases, then returns towards its t = 0 value; c = 2: opposite.
    // The return is slow (creep time ~ τ/g); by t0 = 10 at least 40 % of the excursion is undone.
    for (c, sign) in [(0.5, -1.0), (2.0, 1.0)] {
        let h = psi_c_history(PipkinRogersParams { c, ..base });
        let (imin, ext) = h
            .iter()
            .enumerate()
            .map(|(i, v)| (i, sign * (v - h[0])))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert!(
            ext > 1e-3 && imin > 0 && imin < 100,
            "c={c}: extreme {ext} at {imin}"
        );
        let back = sign * (h[100] - h[0]);
        assert!(
            back >= 0.0 && back < 0.6 * ext,
            "c={c}: does not return: {} vs {}",
            h[100],
            h[0]
        );
    }
}

#[test]
fn displacement_and_force_controlled_relaxation_agree() {
    // Drive the same NLV material by the force history of a displacement-
    // controlled run; the displacement must come back constant.
    let p = PipkinRogersParams::chapter2(0.2, 0.3, 2.0);
    let run = step_run(p, 0.53, 2.0, 20);
    let mut s = MembraneSolver::new(p.check().unwrap(), Geometry::default(), 1.0).unwrap();
    for r in &run.history {
        let sol = s.advance(r.time, Control::Force(r.force)).unwrap();
        approx::assert_relative_eq!(sol.record.displacement, 0.53, max_relative = 1e-6);
        approx::assert_relative_eq!(sol.record.psi_c, r.psi_c, max_relative = 1e-6);
    }
}

#[test]
fn pipkin_rogers_adapter_agrees_with_a_separate_principal_stretch_implementation() {
    // The crate's PipkinRogersMembrane delegates to nlvid_material::PipkinRogers
    // (3D kernel in plane stress); the reference is written directly in principal
    // stretches (tests/common/reference_pr.rs). Both use the trapezoid of eq. 2.48.
    let p = PipkinRogersParams::chapter2(0.2, 0.3, 2.0);
    let m = reference_pr::PipkinRogersMembrane { p };
    let prog = programs::ramp_hold(Quantity::Dimensionless, 0.53, 1.0, 1.0).unwrap();
    let times: Vec<f64> = (0..=30).map(|k| 1.53 * k as f64 / 30.0).collect();
    let l = Loading::new(ControlKind::Displacement, prog, times).unwrap();
    let ours = simulate(
        &p,
        &Geometry {
            rs: 1.03,
            nodes: 48,
        },
        &l,
    )
    .unwrap();
    let theirs = simulate_with(
        m,
        1.0,
        &Geometry {
            rs: 1.03,
            nodes: 48,
        },
        &l,
    )
    .unwrap();
    for (a, b) in ours.history.iter().zip(&theirs.history) {
        approx::assert_relative_eq!(a.force, b.force, max_relative = 1e-8, epsilon = 1e-12);
        approx::assert_relative_eq!(a.psi_c, b.psi_c, max_relative = 1e-8);
    }
}
