//! A fluid-filled spherical capsule of uniform wall squeezed between rigid
//! plates (the verification case of issue 16): the 3D eighth model against
//! the axisymmetric model of the same engine, and eighth, quarter and full
//! 3D models against each other.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::shell::{ShellPart, ShellSpec, ellipsoidal_shell};
use nlvid_fem::{
    Axisymmetric, Cavity, Component, Control, Fluid, Mesh, Model, Parts, RigidPlane, Settings,
    Solid, Stage, Support,
};
use nlvid_material::MooneyRivlin;
use std::f64::consts::PI;

/// Outer radius, wall, squeeze per plate (m).
const R: f64 = 1e-3;
const WALL: f64 = 0.1e-3;
const SQUEEZE: f64 = 0.15e-3;

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

fn cavity() -> Option<Cavity> {
    Some(Cavity {
        boundary: "inner".into(),
        fluid: Fluid::Incompressible,
    })
}

fn stage(control: &dyn Fn(f64) -> Control) -> Stage<'_> {
    Stage {
        name: "squeeze",
        end: 1.0,
        dt_initial: 0.05,
        dt_max: 0.05,
        control,
    }
}

#[derive(Debug, Clone, Copy)]
struct Outcome {
    /// Force on the top plate, whole capsule (N).
    force: f64,
    /// Cavity pressure (Pa).
    pressure: f64,
    /// Cavity reference volume, whole capsule (m³).
    volume: f64,
    /// Contact radius (m): where the gap along the outer meridian, linearly
    /// interpolated between its last closed and first open node, vanishes.
    radius: f64,
}

/// Contact radius from a meridian's current (radial, vertical) positions,
/// ordered from the pole, under a plate at height `plane_z`.
///
/// Which node is the last one closed is decided at the penalty's
/// penetration scale (nm), so the last closed node jumps by a whole
/// spacing between models that agree to 1e-3 elsewhere. The boundary is
/// therefore taken from the lift-off profile just outside: near the edge
/// of a frictionless contact whose pressure vanishes continuously the gap
/// grows as (r − a)^{3/2} (Hertz), so g^{2/3} is linear in r and its zero,
/// through the first two open nodes clear of the penetration scale (gap
/// above 10 × the deepest penetration), is a.
fn contact_radius(meridian: &[[f64; 2]], plane_z: f64) -> f64 {
    let gap = |p: &[f64; 2]| plane_z - p[1];
    let penetration = meridian.iter().map(|p| -gap(p)).fold(0.0f64, f64::max);
    assert!(penetration > 0.0, "no contact");
    // The outermost closed node (the pole may have lifted off: loss of
    // contact inside the patch, thesis Fig. 4.16).
    let last = meridian.iter().rposition(|p| gap(p) <= 0.0).unwrap();
    let open: Vec<[f64; 2]> = meridian[last + 1..]
        .iter()
        .filter(|p| gap(p) > 10.0 * penetration)
        .take(2)
        .copied()
        .collect();
    assert!(open.len() == 2 && last > 0, "contact edge not resolved");
    let (s1, s2) = (gap(&open[0]).powf(2.0 / 3.0), gap(&open[1]).powf(2.0 / 3.0));
    open[0][0] - s1 * (open[1][0] - open[0][0]) / (s2 - s1)
}

/// The axisymmetric model with `n_arc` elements along the meridian.
fn axisymmetric(n_arc: usize) -> Outcome {
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
    let last = *model.records().last().unwrap();
    let u: Vec<[f64; 2]> = model.displacements().collect();
    let mesh = model.mesh();
    let meridian: Vec<[f64; 2]> = mesh
        .nodes_in("outer")
        .unwrap()
        .iter()
        .map(|&a| [mesh.nodes[a][0] + u[a][0], mesh.nodes[a][1] + u[a][1]])
        .collect();
    Outcome {
        force: last.plane_force,
        pressure: last.cavity_pressure,
        // The model is the upper half (symmetry plane z = 0).
        volume: 2.0 * model.cavity_reference_volume().unwrap(),
        radius: contact_radius(&meridian, R - SQUEEZE),
    }
}

/// A 3D model of `part` with m divisions per cube-sphere patch edge (2m
/// elements along a quarter meridian, as the axisymmetric `n_arc` = 2m).
fn solid(part: ShellPart, m: usize) -> Outcome {
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
    let last = *model.records().last().unwrap();
    if part != ShellPart::Eighth {
        assert!(
            (last.base_force / last.plane_force - 1.0).abs() < 1e-6,
            "{last:?}"
        );
    }
    let u: Vec<[f64; 3]> = model.displacements().collect();
    let mesh = model.mesh();
    // The outer meridian in the plane y = 0, x ≥ 0, from the top pole.
    let mut meridian: Vec<(f64, [f64; 2])> = mesh
        .nodes_in("outer")
        .unwrap()
        .iter()
        .filter(|&&a| mesh.nodes[a][1] == 0.0 && mesh.nodes[a][0] >= 0.0 && mesh.nodes[a][2] >= 0.0)
        .map(|&a| {
            let x = mesh.nodes[a];
            (x[0].atan2(x[2]), [x[0] + u[a][0], x[2] + u[a][2]])
        })
        .collect();
    meridian.sort_by(|p, q| p.0.total_cmp(&q.0));
    let meridian: Vec<[f64; 2]> = meridian.into_iter().map(|p| p.1).collect();
    // Plate height relative to the capsule's centre (which the unsymmetric
    // parts translate down by SQUEEZE): shift the meridian instead.
    let shift = if part == ShellPart::Eighth {
        0.0
    } else {
        SQUEEZE
    };
    let meridian: Vec<[f64; 2]> = meridian.iter().map(|p| [p[0], p[1] + shift]).collect();
    let (copies_force, copies_volume) = match part {
        ShellPart::Eighth => (4.0, 8.0),
        ShellPart::Quarter => (4.0, 4.0),
        ShellPart::Full => (1.0, 1.0),
    };
    Outcome {
        force: copies_force * last.plane_force,
        pressure: last.cavity_pressure,
        volume: copies_volume * model.cavity_reference_volume().unwrap(),
        radius: contact_radius(&meridian, R - SQUEEZE),
    }
}

#[test]
fn eighth_model_agrees_with_the_axisymmetric_model() {
    // Same meridian spacing (π/4m), same four layers, same material and
    // penalty; the 3D model adds the circumferential discretisation.
    // Refining m = 8 → 16 the differences fall at second order, to below
    // 0.5 % in force and 1 % in contact radius.
    let mut rows = Vec::new();
    for m in [8, 16] {
        let axi = axisymmetric(2 * m);
        let eighth = solid(ShellPart::Eighth, m);
        let df = eighth.force / axi.force - 1.0;
        let dp = eighth.pressure / axi.pressure - 1.0;
        let da = eighth.radius / axi.radius - 1.0;
        let dv = eighth.volume / axi.volume - 1.0;
        eprintln!(
            "m = {m}: force 3D {:.6e} N vs axisymmetric {:.6e} N ({df:+.2e}); pressure {dp:+.2e}; \
             contact radius {:.5e} vs {:.5e} m ({da:+.2e}); V₀ {dv:+.2e}",
            eighth.force, axi.force, eighth.radius, axi.radius
        );
        rows.push((df, da));
    }
    let (df, da) = rows[1];
    assert!(df.abs() < 5e-3, "force differs by {df:e}");
    assert!(da.abs() < 1e-2, "contact radius differs by {da:e}");
    assert!(
        rows[0].0.abs() > 2.0 * df.abs(),
        "force difference should shrink with the mesh: {rows:?}"
    );
}

#[test]
fn eighth_quarter_and_full_models_agree() {
    let m = 4;
    let eighth = solid(ShellPart::Eighth, m);
    let quarter = solid(ShellPart::Quarter, m);
    let full = solid(ShellPart::Full, m);
    for (name, other) in [("quarter", quarter), ("full", full)] {
        eprintln!("{name}: {other:?} vs eighth {eighth:?}");
        for (what, a, b) in [
            ("force", other.force, eighth.force),
            ("pressure", other.pressure, eighth.pressure),
            ("volume", other.volume, eighth.volume),
            ("contact radius", other.radius, eighth.radius),
        ] {
            assert!((a / b - 1.0).abs() < 1e-6, "{name} {what}: {a} vs {b}");
        }
    }
    // Sanity: a squeezed capsule, pressurised.
    assert!(eighth.force > 0.0 && eighth.pressure > 0.0 && eighth.radius > 0.2 * R);
}
