//! The enclosed fluid cavity (thesis §4.3): a thick sphere inflated by
//! volume against the exact incompressible finite-strain solution, volume
//! conservation under plate compression, and the energy balance
//! plate work = stored energy + pressure–volume work.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::shell::{ShellPart, ShellSpec, ellipsoidal_shell};
use nlvid_fem::{
    Cavity, Component, Control, Fluid, Model, Parts, RigidPlane, Settings, Solid, Stage, Support,
};
use nlvid_material::{Mat3, MooneyRivlin};
use std::f64::consts::PI;

fn rollers() -> Vec<Support> {
    vec![
        Support::fixed("x0", Component::X),
        Support::fixed("y0", Component::Y),
        Support::fixed("z0", Component::Z),
    ]
}

/// Mooney–Rivlin strain energy density with the volumetric penalty of
/// `nlvid_material::MooneyRivlin`: C1(Ī1 − 3) + C2(Ī2 − 3) + K/2 (J − 1)².
fn mooney_rivlin_energy(m: &MooneyRivlin) -> impl Fn(&Mat3) -> f64 {
    let (c1, c2, k) = (m.c1(), m.c2(), m.bulk());
    move |f: &Mat3| {
        let j = f.determinant();
        let c = f.transpose() * f;
        let i1 = c.trace();
        let i2 = 0.5 * (i1 * i1 - (c * c).trace());
        c1 * (j.powf(-2.0 / 3.0) * i1 - 3.0)
            + c2 * (j.powf(-4.0 / 3.0) * i2 - 3.0)
            + 0.5 * k * (j - 1.0).powi(2)
    }
}

/// Inner pressure of an incompressible Mooney–Rivlin thick sphere
/// (radii ri < ro) whose cavity grew by `dv` (whole sphere):
/// p = ∫ 2(σ_θθ − σ_rr)/r dr, σ_θθ − σ_rr = 2(λ² − λ⁻⁴)(C1 + C2 λ²),
/// λ = r/R, r³ = R³ + 3 dv/(4π); Simpson in R with 4000 intervals.
fn thick_sphere_pressure(c1: f64, c2: f64, ri: f64, ro: f64, dv: f64) -> f64 {
    let shift = 3.0 * dv / (4.0 * PI);
    let integrand = |rr: f64| {
        let r = (rr.powi(3) + shift).cbrt();
        let l = r / rr;
        let diff = 2.0 * (l * l - l.powi(-4)) * (c1 + c2 * l * l);
        // dr/r = R² dR / r³.
        2.0 * diff * rr * rr / r.powi(3)
    };
    let n = 4000;
    let h = (ro - ri) / n as f64;
    let mut s = integrand(ri) + integrand(ro);
    for i in 1..n {
        s += integrand(ri + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

fn inflate(fbar: bool, layers: usize, size: f64) -> Vec<(f64, f64, f64)> {
    let (ro, t) = (1e-3, 0.4e-3);
    let mesh =
        ellipsoidal_shell(&ShellSpec::sphere(ro, t, layers, size, ShellPart::Eighth)).unwrap();
    let material = MooneyRivlin::new(1e5, 0.3e5, 1e4 * 2.6e5).unwrap();
    let parts = Parts {
        supports: rollers(),
        cavity: Some(Cavity {
            boundary: "inner".into(),
            fluid: Fluid::Incompressible,
        }),
        ..Parts::default()
    };
    let settings = Settings {
        fbar,
        ..Settings::default()
    };
    let mut model = Model::<_, Solid>::build(mesh, material, &parts, settings).unwrap();
    let v0 = model.cavity_reference_volume().unwrap();
    // Inject 1.5 V₀: the inner radius grows by 36 %.
    let control = move |t: f64| Control {
        fluid_injected: 1.5 * v0 * t,
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "inflate",
            end: 1.0,
            dt_initial: 0.1,
            dt_max: 0.1,
            control: &control,
        })
        .unwrap();
    model
        .records()
        .iter()
        .map(|r| {
            let dv = 1.5 * v0 * r.time;
            (
                dv / v0,
                r.cavity_volume / (v0 + dv) - 1.0,
                r.cavity_pressure,
            )
        })
        .collect()
}

#[test]
fn volume_controlled_inflation_of_a_thick_sphere_matches_the_exact_pressure() {
    // Eighth of a sphere with ro/ri = 1/0.6, near-incompressible wall
    // (κ/μ = 10⁴), inflated by fluid volume to 2.5 V₀. The cavity's volume
    // is the one injected to 1e-9; the pressure (the Lagrange multiplier)
    // follows the exact incompressible solution within 1 % at every step;
    // the plain hexahedron, locked, is far stiffer.
    let (ri, ro): (f64, f64) = (0.6e-3, 1e-3);
    let fe = inflate(true, 4, 0.15e-3);
    let plain = inflate(false, 4, 0.15e-3);
    let mut worst: f64 = 0.0;
    for (k, &(ratio, dv_err, p)) in fe.iter().enumerate() {
        // The discrete cavity's V₀ differs from (4/3)πri³ by the faceting;
        // the exact solution is taken at the same relative growth.
        let dv = ratio * 4.0 / 3.0 * PI * ri.powi(3);
        let exact = thick_sphere_pressure(1e5, 0.3e5, ri, ro, dv);
        assert!(dv_err.abs() < 1e-9, "volume error {dv_err:e} at step {k}");
        worst = worst.max((p / exact - 1.0).abs());
        if k + 1 == fe.len() {
            eprintln!(
                "thick sphere at V = {:.2} V0: FE {p:.6e} Pa, exact {exact:.6e} Pa, plain hexahedra {:.6e} Pa",
                1.0 + ratio,
                plain[k].2
            );
            assert!(
                plain[k].2 > 1.5 * exact,
                "plain {} vs exact {exact}",
                plain[k].2
            );
        }
    }
    eprintln!("thick sphere: worst pressure error {worst:.4}");
    assert!(worst < 0.01, "worst pressure error {worst}");
}

/// (plate z, plate force, p, V) of one step.
type Squeezed = (f64, f64, f64, f64);

/// The eighth sphere capsule (ro = 1 mm, wall 0.1 mm) squeezed by a plate
/// from z = ro to ro − squeeze in `steps` equal steps; returns per step
/// (plate z, plate force, p, V), with the model.
fn squeeze(
    fluid: Fluid,
    squeeze: f64,
    steps: usize,
) -> (Vec<Squeezed>, Model<MooneyRivlin, Solid>) {
    let ro = 1e-3;
    let mesh = ellipsoidal_shell(&ShellSpec::sphere(
        ro,
        0.1e-3,
        2,
        0.25e-3,
        ShellPart::Eighth,
    ))
    .unwrap();
    let material = MooneyRivlin::new(1e6, 0.2e6, 1e3 * 2.4e6).unwrap();
    let parts = Parts {
        supports: rollers(),
        planes: vec![RigidPlane::above("outer")],
        cavity: Some(Cavity {
            boundary: "inner".into(),
            fluid,
        }),
        ..Parts::default()
    };
    let settings = Settings {
        residual_growth: 1e6,
        ..Settings::default()
    };
    let mut model = Model::<_, Solid>::build(mesh, material, &parts, settings).unwrap();
    let control = move |t: f64| Control {
        plane_z: ro - squeeze * t,
        ..Control::default()
    };
    let dt = 1.0 / steps as f64;
    model
        .run_stage(&Stage {
            name: "squeeze",
            end: 1.0,
            dt_initial: dt,
            dt_max: dt,
            control: &control,
        })
        .unwrap();
    let recs = model
        .records()
        .iter()
        .map(|r| {
            (
                ro - squeeze * r.time,
                r.plane_force,
                r.cavity_pressure,
                r.cavity_volume,
            )
        })
        .collect();
    (recs, model)
}

#[test]
fn incompressible_cavity_conserves_volume_under_plate_compression() {
    let (recs, model) = squeeze(Fluid::Incompressible, 0.25e-3, 20);
    let v0 = model.cavity_reference_volume().unwrap();
    for &(z, f, p, v) in &recs {
        assert!(
            (v / v0 - 1.0).abs() < 1e-9,
            "V/V0 − 1 = {:e} at plate z = {z}",
            v / v0 - 1.0
        );
        assert!(f >= 0.0 && p >= 0.0);
    }
    let last = recs.last().unwrap();
    assert!(
        last.1 > 0.0 && last.2 > 0.0,
        "squeezed: force {} N, pressure {} Pa",
        last.1,
        last.2
    );
    // Vertical equilibrium of the eighth: the plate force is carried by the
    // wall's cut at z = 0 (the roller reactions) and by the fluid's
    // pressure on its own cut, p × the cavity's deformed cross-section (the
    // polygon of the inner wall's nodes on z = 0, closed at the origin).
    let base = model.reaction("z0", Component::Z).unwrap();
    let mesh = model.mesh();
    let u: Vec<[f64; 3]> = model.displacements().collect();
    let mut ring: Vec<[f64; 2]> = mesh
        .nodes_in("inner")
        .unwrap()
        .iter()
        .filter(|&&a| mesh.nodes[a][2] == 0.0)
        .map(|&a| [mesh.nodes[a][0] + u[a][0], mesh.nodes[a][1] + u[a][1]])
        .collect();
    ring.sort_by(|p, q| p[1].atan2(p[0]).total_cmp(&q[1].atan2(q[0])));
    let area: f64 = ring
        .windows(2)
        .map(|w| 0.5 * (w[0][0] * w[1][1] - w[1][0] * w[0][1]))
        .sum();
    assert!(ring.len() > 3 && area > 0.0);
    assert!(
        (base + last.2 * area - last.1).abs() < 1e-6 * last.1,
        "wall cut {base} + fluid cut {} vs plate {}",
        last.2 * area,
        last.1
    );
}

/// Plate work (composite trapezoid over the steps), stored energy (wall +
/// contact penalty), pressure–volume work done on the fluid, −∫ p dV
/// (trapezoid: exact for a linear fluid).
fn energy_balance(fluid: Fluid, steps: usize) -> (f64, f64, f64, f64) {
    let (recs, model) = squeeze(fluid, 0.2e-3, steps);
    let v0 = model.cavity_reference_volume().unwrap();
    let mut plate = 0.0;
    let mut pv = 0.0;
    let (mut z_prev, mut f_prev, mut p_prev, mut v_prev) = (1e-3, 0.0, 0.0, v0);
    for &(z, f, p, v) in &recs {
        plate += 0.5 * (f + f_prev) * (z_prev - z);
        pv -= 0.5 * (p + p_prev) * (v - v_prev);
        (z_prev, f_prev, p_prev, v_prev) = (z, f, p, v);
    }
    let material = MooneyRivlin::new(1e6, 0.2e6, 1e3 * 2.4e6).unwrap();
    let stored =
        model.strain_energy(&mooney_rivlin_energy(&material)) + model.plane_contact_energy();
    let p_end = recs.last().map(|r| r.2).unwrap_or(0.0);
    (plate, stored, pv, v0 * p_end * p_end)
}

#[test]
fn pressure_volume_work_is_plate_work_minus_stored_energy() {
    // Elastic wall, compressible fluid (K_f = 0.2 MPa, of the order of the
    // shell's own volumetric stiffness: the fluid takes ≈ 2 % of the work,
    // the rest goes into flattening the cap) and incompressible fluid (no
    // pV work: the plate work is all stored). The plate work is the
    // composite trapezoid over 800 equal steps; its error, estimated from
    // the 400-step value as (W₄₀₀ − W₈₀₀)/3 (O(Δz²)), is itself below 1e-6.
    for fluid in [
        Fluid::Compressible { bulk_modulus: 2e5 },
        Fluid::Incompressible,
    ] {
        let (w1, s1, _, _) = energy_balance(fluid, 400);
        let (plate, stored, pv, v0_p2) = energy_balance(fluid, 800);
        assert!(
            (s1 / stored - 1.0).abs() < 1e-9,
            "the end state does not depend on the steps"
        );
        let quadrature = (w1 - plate) / 3.0;
        let residual = pv - (plate - stored);
        eprintln!(
            "{fluid:?}: plate work {plate:.9e} J (400 steps: {w1:.9e}; quadrature error ≈ {:.1e}), stored {stored:.9e} J, pV work {pv:.9e} J, balance {:.2e}",
            quadrature / plate,
            residual / plate
        );
        assert!(quadrature.abs() < 1e-6 * plate);
        assert!(
            residual.abs() < 1e-6 * plate,
            "pV − (plate − stored) = {:e} of the plate work",
            residual / plate
        );
        if let Fluid::Compressible { bulk_modulus } = fluid {
            // A linear fluid stores V₀ p²/(2K_f): the pV work in closed form.
            assert!((pv / (0.5 * v0_p2 / bulk_modulus) - 1.0).abs() < 1e-9);
            assert!(pv > 0.01 * plate, "the fluid's share {pv} of {plate}");
        } else {
            assert!(pv.abs() < 1e-9 * plate);
        }
    }
}
