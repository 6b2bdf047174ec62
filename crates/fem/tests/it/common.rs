//! Helpers shared by the capsule tests (`capsule`, `outputs`): the
//! fluid-filled spherical capsule of issue 16 (outer radius 1 mm, wall
//! 0.1 mm in 4 layers, Mooney–Rivlin wall, incompressible fluid) squeezed
//! between rigid plates, as an axisymmetric model and as a 3D eighth,
//! quarter or full model.
#![allow(clippy::unwrap_used)]

use nlvid_fem::shell::{ShellPart, ShellSpec, ellipsoidal_shell};
use nlvid_fem::{
    Axisymmetric, Cavity, Component, Control, Fluid, Mesh, Model, Parts, RigidPlane, Settings,
    Solid, Stage, Support,
};
use nlvid_material::MooneyRivlin;
use std::f64::consts::PI;

/// Outer radius, wall, squeeze per plate (m).
pub const R: f64 = 1e-3;
const WALL: f64 = 0.1e-3;
const SQUEEZE: f64 = 0.15e-3;

/// The wall: Mooney–Rivlin with C1 = 1 MPa, C2 = 0.2 C1 and a bulk
/// modulus of 1000 × 2.4 MPa.
fn material() -> MooneyRivlin {
    MooneyRivlin::with_ratio(1e6, 0.2, 1e3 * 2.4e6).unwrap()
}

fn settings() -> Settings {
    Settings {
        residual_growth: 1e6,
        atol: 1e-12,
        ..Settings::default()
    }
}

/// The incompressible fluid filling the cavity inside the `inner` surface.
fn cavity() -> Option<Cavity> {
    Some(Cavity {
        boundary: "inner".into(),
        fluid: Fluid::Incompressible,
    })
}

/// The squeeze: one stage from t = 0 to 1 in steps of 0.05.
fn stage(control: &dyn Fn(f64) -> Control) -> Stage<'_> {
    Stage {
        name: "squeeze",
        end: 1.0,
        dt_initial: 0.05,
        dt_max: 0.05,
        control,
    }
}

/// The axisymmetric capsule (upper half, `n_arc` elements along the
/// meridian) after the top plate has moved down by the squeeze.
pub fn squeezed_axisymmetric(n_arc: usize) -> Model<MooneyRivlin, Axisymmetric> {
    let mesh = Mesh::spherical_shell(R, WALL, 4, n_arc).unwrap();
    let parts = Parts {
        supports: vec![
            Support::fixed("axis", Component::R),
            Support::fixed("equator", Component::Z),
        ],
        planes: vec![RigidPlane::above("outer")],
        cavity: cavity(),
        ..Parts::default()
    };
    let mut model = Model::<_, Axisymmetric>::build(mesh, material(), &parts, settings()).unwrap();
    let control = |t: f64| Control {
        plane_z: R - SQUEEZE * t,
        ..Control::default()
    };
    model.run_stage(&stage(&control)).unwrap();
    model
}

/// A 3D model of `part` with m divisions per cube-sphere patch edge (2m
/// elements along a quarter meridian, as the axisymmetric `n_arc` = 2m),
/// after the squeeze.
pub fn squeezed_solid(part: ShellPart, m: usize) -> Model<MooneyRivlin, Solid> {
    let size = 0.25 * PI * R / (m as f64 - 0.5);
    let mesh = ellipsoidal_shell(&ShellSpec::sphere(R, WALL, 4, size, part)).unwrap();
    // The symmetric eighth sees a plate moving by SQUEEZE; the others a
    // fixed base plate and a top plate moving by 2 SQUEEZE (the same
    // deformation, translated by SQUEEZE).
    let (supports, planes, travel) = match part {
        ShellPart::Eighth => (
            vec![
                Support::fixed("x0", Component::X),
                Support::fixed("y0", Component::Y),
                Support::fixed("z0", Component::Z),
            ],
            vec![RigidPlane::above("outer")],
            SQUEEZE,
        ),
        ShellPart::Quarter => (
            vec![
                Support::fixed("x0", Component::X),
                Support::fixed("y0", Component::Y),
            ],
            vec![RigidPlane::above("outer"), RigidPlane::below("outer", -R)],
            2.0 * SQUEEZE,
        ),
        ShellPart::Full => (
            // Rigid-body motions in x, y and about every axis, removed
            // where the symmetric solution has these components zero.
            vec![
                Support::fixed("top", Component::X),
                Support::fixed("top", Component::Y),
                Support::fixed("bottom", Component::X),
                Support::fixed("bottom", Component::Y),
                Support::fixed("side_y", Component::X),
            ],
            vec![RigidPlane::above("outer"), RigidPlane::below("outer", -R)],
            2.0 * SQUEEZE,
        ),
    };
    let parts = Parts {
        supports,
        planes,
        cavity: cavity(),
        ..Parts::default()
    };
    let mut model = Model::<_, Solid>::build(mesh, material(), &parts, settings()).unwrap();
    let control = |t: f64| Control {
        plane_z: R - travel * t,
        ..Control::default()
    };
    model.run_stage(&stage(&control)).unwrap();
    model
}
