//! Axisymmetric membrane elements against the semi-analytical solver of
//! ch. II (`nlvid-membrane`): the thesis's §2.5.2 check (Fig. 2.16) and the
//! elastic force–displacement curve (Fig. 2.4), issue 16.
//!
//! Dimensionless as ch. II (eq. 2.47): r0 = 1, C1 = 1, τ1 = 1; the FE
//! membrane has thickness h0 = 1e-3 (it only scales forces and pressures:
//! F̄ = F/(C1 h0 r0)); the sphere is inflated to r_s = 1.03 by injecting
//! fluid, then squeezed by the plate, both at t ≈ 0 (within 2e-9 τ1), then
//! held.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::{
    Cavity, Component, Control, Fluid, Membrane, MembraneMesh, MembranePoint, Model, Parts,
    RigidPlane, Settings, Stage, Support,
};
use nlvid_material::{Material3, MembraneMaterial, MooneyRivlin};
use nlvid_membrane::{
    ControlKind, Geometry, Loading, MembraneSolver, MooneyRivlinMembrane, PipkinRogersParams,
    simulate,
};
use nlvid_protocol::{Quantity, programs};
use std::f64::consts::FRAC_PI_2;

const H0: f64 = 1e-3;
const RS: f64 = 1.03;
/// Duration of the (nearly instantaneous) inflation and squeeze (τ1 = 1).
const EPS: f64 = 1e-9;

fn model<M>(material: M, n: usize) -> Model<M, Membrane>
where
    M: Material3 + MembraneMaterial,
{
    let mesh = MembraneMesh::spherical(1.0, H0, n).unwrap();
    let parts = Parts {
        supports: vec![
            Support::fixed("axis", Component::R),
            Support::fixed("equator", Component::Z),
        ],
        planes: vec![RigidPlane::above("meridian")],
        cavity: Some(Cavity {
            boundary: "meridian".into(),
            fluid: Fluid::Incompressible,
        }),
        ..Parts::default()
    };
    Model::<_, Membrane>::build(mesh, material, &parts, Settings::default()).unwrap()
}

/// Inflates to r_s (volume V₀ r_s³ of the polygon's own V₀) over
/// [−2ε, −ε], then moves the plate from z = r_s to each height
/// r_s − D in `ds` (increasing), calling `visit` after each.
fn inflate_and_squeeze<M>(
    model: &mut Model<M, Membrane>,
    ds: &[f64],
    mut visit: impl FnMut(&Model<M, Membrane>, f64),
) where
    M: Material3 + MembraneMaterial,
{
    let dv = model.cavity_reference_volume().unwrap() * (RS.powi(3) - 1.0);
    model.set_time(-2.0 * EPS);
    let inflate = |t: f64| Control {
        fluid_injected: dv * ((t + 2.0 * EPS) / EPS).min(1.0),
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "inflate",
            end: -EPS,
            dt_initial: EPS / 10.0,
            dt_max: EPS / 10.0,
            control: &inflate,
        })
        .unwrap();
    let mut d_prev = 0.0;
    let t_prev = -EPS;
    for (k, &d) in ds.iter().enumerate() {
        let (t0, t1) = (
            t_prev + EPS * k as f64 / ds.len() as f64,
            t_prev + EPS * (k + 1) as f64 / ds.len() as f64,
        );
        let (da, db) = (d_prev, d);
        let squeeze = move |t: f64| Control {
            plane_z: RS - (da + (db - da) * (t - t0) / (t1 - t0)),
            fluid_injected: dv,
            ..Control::default()
        };
        let steps = ((d - d_prev) / 0.005).ceil().max(1.0);
        model
            .run_stage(&Stage {
                name: "squeeze",
                end: if k + 1 == ds.len() { 0.0 } else { t1 },
                dt_initial: (t1 - t0) / steps,
                dt_max: (t1 - t0) / steps,
                control: &squeeze,
            })
            .unwrap();
        visit(model, d);
        d_prev = d;
    }
}

/// σ2 at the crown (ψ = 0) and the equator (ψ = π/2), extrapolated from the
/// first and last element's two Gauss points: σ2 is even in ψ about both
/// (symmetry), so σ2 = σ + a ψ² there and two points give σ to O(ψ⁴).
fn crown_and_equator(points: &[MembranePoint]) -> [f64; 2] {
    let even = |p: &MembranePoint, q: &MembranePoint, s: &dyn Fn(&MembranePoint) -> f64| {
        let (a, b) = (s(p).powi(2), s(q).powi(2));
        (p.stress[1] * b - q.stress[1] * a) / (b - a)
    };
    let psi = |p: &MembranePoint| p.reference[0].atan2(p.reference[1]);
    let n = points.len();
    [
        even(&points[0], &points[1], &psi),
        even(&points[n - 1], &points[n - 2], &|p| FRAC_PI_2 - psi(p)),
    ]
}

/// The FE membrane of the Fig. 2.16 case (n elements) stepped to D/r0 = 0.28
/// at t ≈ 0 and held; σ2 at (crown, equator) at each of `times` (the first
/// is 0; hold steps exactly the gaps between them).
fn fig_2_16_fe(n: usize, times: &[f64]) -> Vec<[f64; 2]> {
    let params = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    let d = 0.28;
    // The same point update as the semi-analytical solver (trapezoidal
    // hereditary sums, eq. 2.48).
    let material = params.check().unwrap().material().clone();
    let mut fe = model(material, n);
    let mut sigma = Vec::new();
    inflate_and_squeeze(&mut fe, &[d], |m, _| {
        sigma.push(crown_and_equator(&m.membrane_points().unwrap()))
    });
    let dv = fe.cavity_reference_volume().unwrap() * (RS.powi(3) - 1.0);
    for w in times.windows(2) {
        let hold = |_: f64| Control {
            plane_z: RS - d,
            fluid_injected: dv,
            ..Control::default()
        };
        let dt = w[1] - w[0];
        let stage = Stage {
            name: "hold",
            end: w[1],
            dt_initial: dt,
            dt_max: dt,
            control: &hold,
        };
        fe.run_stage(&stage).unwrap();
        assert_eq!(
            fe.counters().cutbacks,
            0,
            "the hold must step exactly on the grid"
        );
        sigma.push(crown_and_equator(&fe.membrane_points().unwrap()));
    }
    sigma
}

/// The thesis's measure |σ_FE − σ_A| / ((σ_FE + σ_A)/2), largest over the
/// times, for (crown, equator).
fn largest_difference(fe: &[[f64; 2]], analytic: &[[f64; 2]], times: &[f64]) -> [f64; 2] {
    let mut worst = [0.0f64; 2];
    for (k, (a, b)) in fe.iter().zip(analytic).enumerate() {
        for i in 0..2 {
            worst[i] = worst[i].max((a[i] - b[i]).abs() / (0.5 * (a[i] + b[i])));
        }
        if k % 20 == 0 {
            eprintln!(
                "t = {:4.1}: σ2 crown FE {:.7} vs {:.7}, equator FE {:.7} vs {:.7}",
                times[k], a[0], b[0], a[1], b[1]
            );
        }
    }
    eprintln!(
        "largest relative difference: crown {:.3e}, equator {:.3e}",
        worst[0], worst[1]
    );
    worst
}

#[test]
fn fig_2_16_case_hoop_stress_at_crown_and_equator_within_0_2_percent_at_every_time() {
    // §2.5.2: D/r0 = 0.28, g1 = g2 = 0.2, c = 1, γ0 = γ∞ = 0.1, step at
    // t = 0 then hold to t0 = 10 (the thesis's ABAQUS membrane model agreed
    // with the analytical σ2 to < 0.2 % at each time; "edge" = the equator,
    // "the biggest horizontal circumference").
    //
    // The case is QLV (G2 = γ0 G1): the deformed shape does not change in
    // the hold and every stress is its t = 0 value times the discrete
    // relaxation function of the trapezoidal rule, f_n = 1 − g h_n with
    // h_{n+1} = e^{−x} h_n + (x/2)(e^{−x} + 1), h_0 = 0, x = Δt/τ, g = 0.8
    // (written here from eq. 2.48). The reference at time t_n is the
    // semi-analytical solver's t = 0 solution of the same Pipkin–Rogers
    // membrane times f_n. (The solver's own time marching drifts at the
    // crown by O(Δψ²) — 0.15 % at N = 128, 0.04 % at 256 by t0 = 10 — so the
    // direct comparison with it is the ignored test below, at N = 512.)
    let params = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    let times: Vec<f64> = (0..=100).map(|k| 0.1 * k as f64).collect();
    let loading = Loading::new(
        ControlKind::Displacement,
        programs::step(Quantity::Dimensionless, 0.28, 10.0).unwrap(),
        vec![0.0],
    )
    .unwrap()
    .with_profiles(&[0.0]);
    let start = simulate(&params, &Geometry { rs: RS, nodes: 256 }, &loading).unwrap();
    let p0 = &start.profiles[0].profile;
    let s0 = [p0[0].sigma2, p0[p0.len() - 1].sigma2];
    let (x, g): (f64, f64) = (0.1, 0.8);
    let mut h = 0.0;
    let mut analytic = Vec::new();
    for k in 0..times.len() {
        if k > 0 {
            h = (-x).exp() * h + 0.5 * x * ((-x).exp() + 1.0);
        }
        let f = 1.0 - g * h;
        analytic.push([s0[0] * f, s0[1] * f]);
    }
    let fe = fig_2_16_fe(256, &times);
    let worst = largest_difference(&fe, &analytic, &times);
    assert!(worst[0] < 2e-3 && worst[1] < 2e-3, "{worst:?}");
    // The stresses relax to ≈ 0.2 of their t = 0 value: not a frozen
    // comparison.
    assert!(fe[100][0] < 0.21 * fe[0][0] && fe[100][1] < 0.21 * fe[0][1]);
}

#[test]
#[ignore = "≈ 75 s in release: the semi-analytical time marching at N = 512"]
fn fig_2_16_case_against_the_semi_analytical_time_marching() {
    // The direct comparison of the thesis: both models step the same times
    // with the same trapezoidal hereditary sums.
    // `cargo test -p nlvid-fem --release --test it membrane:: -- --ignored --nocapture`
    let params = PipkinRogersParams::chapter2(0.2, 0.2, 1.0);
    let times: Vec<f64> = (0..=100).map(|k| 0.1 * k as f64).collect();
    let loading = Loading::new(
        ControlKind::Displacement,
        programs::step(Quantity::Dimensionless, 0.28, 10.0).unwrap(),
        times.clone(),
    )
    .unwrap()
    .with_profiles(&times);
    let reference = simulate(&params, &Geometry { rs: RS, nodes: 512 }, &loading).unwrap();
    let analytic: Vec<[f64; 2]> = reference
        .profiles
        .iter()
        .map(|s| [s.profile[0].sigma2, s.profile[s.profile.len() - 1].sigma2])
        .collect();
    assert_eq!(analytic.len(), times.len());
    let fe = fig_2_16_fe(256, &times);
    let worst = largest_difference(&fe, &analytic, &times);
    assert!(worst[0] < 2e-3 && worst[1] < 2e-3, "{worst:?}");
}

#[test]
fn elastic_force_displacement_within_0_2_percent_of_the_semi_analytical_curve() {
    // Fig. 2.4's Mooney–Rivlin membrane, γ = 0.1, D/r0 = 0.1 … 0.78.
    let ds: Vec<f64> = (5..=39).map(|k| 0.02 * k as f64).collect();
    let mut solver = MembraneSolver::new(
        MooneyRivlinMembrane::new(1.0, 0.1).unwrap(),
        Geometry { rs: RS, nodes: 256 },
        1.0,
    )
    .unwrap();
    let analytic: Vec<f64> = ds
        .iter()
        .map(|&d| {
            solver
                .equilibrium(0.0, nlvid_membrane::Control::Displacement(d))
                .unwrap()
                .record
                .force
        })
        .collect();
    let mut fe = model(MooneyRivlin::new(1.0, 0.1, 0.0).unwrap(), 256);
    let mut forces = Vec::new();
    inflate_and_squeeze(&mut fe, &ds, |m, _| {
        forces.push(m.records().last().unwrap().plane_force / H0)
    });
    let mut worst = 0.0f64;
    for k in 0..ds.len() {
        let e = forces[k] / analytic[k] - 1.0;
        worst = worst.max(e.abs());
        eprintln!(
            "D = {:.2}: F̄ FE {:.6} vs {:.6} ({e:+.2e})",
            ds[k], forces[k], analytic[k]
        );
    }
    assert!(
        worst < 2e-3,
        "largest relative force difference {worst:.3e}"
    );
}
