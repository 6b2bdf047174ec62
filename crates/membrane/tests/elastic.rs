//! Elastic (Mooney–Rivlin / neo-Hookean) limits of the squeezed membrane.

use std::f64::consts::PI;

use nlvid_membrane::{Control, Geometry, MembraneError, MembraneSolver, MooneyRivlinMembrane};

fn solver(gamma: f64, rs: f64, nodes: usize) -> MembraneSolver<MooneyRivlinMembrane> {
    let m = MooneyRivlinMembrane::new(1.0, gamma).unwrap();
    MembraneSolver::new(m, Geometry { rs, nodes }, 1.0).unwrap()
}

#[test]
fn free_inflation_satisfies_rivlin_identity() {
    for gamma in [0.0, 0.1, 0.3] {
        for rs in [1.03, 1.2, 1.5] {
            let mut s = solver(gamma, rs, 64);
            let sol = s.equilibrium(0.0, Control::Displacement(0.0)).unwrap();
            let l = rs;
            let rivlin = 4.0 * (1.0 / l - l.powi(-7)) * (1.0 + gamma * l * l);
            approx::assert_relative_eq!(sol.pressure, rivlin, max_relative = 1e-8);
            approx::assert_relative_eq!(sol.lambda0, rs, max_relative = 1e-8);
            approx::assert_relative_eq!(sol.h1, rs, max_relative = 1e-8);
            assert_eq!(sol.force, 0.0);
        }
    }
}

#[test]
fn explore() {
    let mut s = solver(0.1, 1.03, 96);
    for d in [0.1, 0.28, 0.53, 0.78] {
        let sol = s.equilibrium(0.0, Control::Displacement(d)).unwrap();
        eprintln!(
            "D={d} F={:.5} p={:.5} psic={:.5} ({:.2} deg) a={:.4} l0={:.5} req={:.4} it={} ang={:.2}",
            sol.force, sol.pressure, sol.psi_c, sol.psi_c.to_degrees(), sol.contact_radius, sol.lambda0,
            sol.equator_radius, sol.iterations, sol.current_contact_angle_deg()
        );
        let cap = sol.pressure * PI * (sol.equator_radius.powi(2) - sol.contact_radius.powi(2));
        eprintln!("  cap {cap:.6} vs {:.6}", 2.0 * PI * sol.equator_radius * sol.t1_equator);
    }
    let _ = MembraneError::Input { name: "x", value: 0.0, reason: String::new() };
}
