//! The AFM cell model end to end on a coarse mesh and a short protocol.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::afm::{self, AfmParams, AfmSetup, Cantilever};
use nlvid_fem::{FemError, Settings};

fn params() -> AfmParams {
    AfmParams {
        g0: 1e3,
        g1: 0.3,
        tau1: 0.5,
        g2: 0.3,
        tau2: 10.0,
    }
}

fn short_setup(cantilever: Cantilever) -> AfmSetup {
    let mut setup = AfmSetup::thesis_setup1();
    setup.cantilever = cantilever;
    setup.mesh.elements_per_side = 14;
    // 0 → 1 µm at 10 µm/s, back 0.5 µm, to 1 µm, hold 5 s.
    setup.piezo = vec![
        (0.0, 0.0),
        (0.1, 1e-6),
        (0.15, 0.5e-6),
        (0.2, 1e-6),
        (5.2, 1e-6),
    ];
    setup.output_times = (0..=104).map(|i| 0.05 * i as f64).collect();
    setup
}

#[test]
fn coarse_afm_run_finishes_repulsive_and_relaxes() {
    let setup = short_setup(Cantilever::Spring { stiffness: 0.12 });
    let run = afm::run(&params(), &setup).unwrap();
    assert_eq!(run.force.len(), setup.output_times.len());
    // Engaged at 0.48 nN, then repulsive throughout.
    assert!(
        (run.force[0] - 0.48e-9).abs() < 1e-6 * 0.48e-9,
        "F(0) = {}",
        run.force[0]
    );
    assert!(run.force.iter().all(|&f| f > 0.0));
    // δ = Z − d and F = k d on every output point.
    for i in 0..run.time.len() {
        assert!((run.indentation[i] - (run.piezo[i] - run.deflection[i])).abs() < 1e-15);
        assert!((run.force[i] - 0.12 * run.deflection[i]).abs() < 1e-12 * run.peak_force);
    }
    // The hold relaxes: force at the end of the hold below the force at its start.
    let start_hold = run.time.iter().position(|&t| t >= 0.2).unwrap();
    assert!(run.final_force < 0.8 * run.force[start_hold]);
    assert!(run.peak_force >= run.force[start_hold]);
}

#[test]
fn rigid_cantilever_indentation_equals_piezo_travel() {
    let setup = short_setup(Cantilever::Rigid);
    let run = afm::run(&params(), &setup).unwrap();
    let z0 = run.piezo[0];
    for i in 0..run.time.len() {
        assert_eq!(run.deflection[i], 0.0);
        assert!((run.indentation[i] - run.piezo[i]).abs() < 1e-15);
        let program = afm::interpolate(
            &[0.0, 0.1, 0.15, 0.2, 5.2],
            &[0.0, 1e-6, 0.5e-6, 1e-6, 1e-6],
            run.time[i],
        );
        assert!((run.piezo[i] - z0 - program).abs() < 1e-12);
    }
}

#[test]
fn impossible_step_budget_is_a_typed_non_convergence_not_a_panic() {
    let mut setup = short_setup(Cantilever::Spring { stiffness: 0.12 });
    setup.settings = Settings {
        max_iterations: 1,
        min_step_fraction: 0.2,
        ..Settings::default()
    };
    match afm::run(&params(), &setup) {
        Err(FemError::NonConvergence(nc)) => {
            assert!(nc.dt > 0.0 && nc.residual.is_finite() && nc.residual > nc.tolerance);
            assert!(nc.cause.contains("iteration limit"), "{}", nc.cause);
        }
        other => panic!("expected non-convergence, got {other:?}"),
    }
}

#[test]
fn material_crate_cell_model_agrees_with_reference_prony_solid() {
    // Two independent finite-strain Prony implementations (ABAQUS form in
    // the material crate, Simo form here) coincide in the small-strain
    // limit and stay close at the moderate strains of this run.
    let setup = short_setup(Cantilever::Spring { stiffness: 0.12 });
    let a = afm::run(&params(), &setup).unwrap();
    let b = afm::run_reference(&params(), &setup).unwrap();
    let rel = (a.peak_force / b.peak_force - 1.0).abs();
    eprintln!(
        "peak: material crate {:.4e} N, reference {:.4e} N ({rel:.4})",
        a.peak_force, b.peak_force
    );
    assert!(rel < 0.01, "peak forces differ by {rel}");
    let relf = (a.final_force / b.final_force - 1.0).abs();
    assert!(relf < 0.01, "final forces differ by {relf}");
}
