//! Capsule outputs (issue 16): plate force, fluid pressure and volume,
//! contact area two ways, loss-of-contact flags, contact-pressure paths,
//! and the deformed shape as VTU read back — on the membrane, the
//! axisymmetric solid and the 3D capsule.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::shell::ShellPart;
use nlvid_fem::vtu::VtuGrid;
use nlvid_fem::{
    Cavity, Component, Control, Fluid, LiftOff, Membrane, MembraneMesh, Model, Parts, PatchSpec,
    RigidPlane, Settings, Solid, Stage, Support, Symmetry,
};
use nlvid_material::MooneyRivlin;
use nlvid_membrane::{Geometry, MembraneSolver, MooneyRivlinMembrane};
use std::f64::consts::PI;

use crate::common;

fn cavity(boundary: &str) -> Option<Cavity> {
    Some(Cavity {
        boundary: boundary.into(),
        fluid: Fluid::Incompressible,
    })
}

/// The ch. II membrane (r0 = 1, h0 = 1e-3, Mooney–Rivlin γ = 0.1, r_s =
/// 1.03) squeezed to each D of `ds`; `visit` after each.
fn membrane_run(n: usize, ds: &[f64], mut visit: impl FnMut(&Model<MooneyRivlin, Membrane>, f64)) {
    let (h0, rs) = (1e-3, 1.03);
    let mesh = MembraneMesh::spherical(1.0, h0, n).unwrap();
    let parts = Parts {
        supports: vec![
            Support::fixed("axis", Component::R),
            Support::fixed("equator", Component::Z),
        ],
        planes: vec![RigidPlane::above("meridian")],
        cavity: cavity("meridian"),
        ..Parts::default()
    };
    let material = MooneyRivlin::new(1.0, 0.1, 0.0).unwrap();
    let mut m = Model::<_, Membrane>::build(mesh, material, &parts, Settings::default()).unwrap();
    let dv = m.cavity_reference_volume().unwrap() * (rs * rs * rs - 1.0);
    let inflate = |t: f64| Control {
        fluid_injected: dv * t,
        ..Control::default()
    };
    m.run_stage(&Stage {
        name: "inflate",
        end: 1.0,
        dt_initial: 0.1,
        dt_max: 0.1,
        control: &inflate,
    })
    .unwrap();
    let mut d0 = 0.0;
    for &d in ds {
        let t0 = m.time();
        let squeeze = move |t: f64| Control {
            plane_z: rs - (d0 + (d - d0) * (t - t0)),
            fluid_injected: dv,
            ..Control::default()
        };
        let dt = 0.005 / (d - d0);
        m.run_stage(&Stage {
            name: "squeeze",
            end: t0 + 1.0,
            dt_initial: dt,
            dt_max: dt,
            control: &squeeze,
        })
        .unwrap();
        visit(&m, d);
        d0 = d;
    }
}

fn membrane_spec() -> PatchSpec {
    PatchSpec {
        plane: 0,
        surface: "meridian".into(),
        symmetry: Symmetry::AXISYMMETRIC_HALF,
        lift_off: LiftOff::Membrane,
    }
}

#[test]
fn membrane_patch_agrees_with_the_semi_analytical_solution() {
    // Contact radius a = ρ(ψc), pressure p and F = π a² p of ch. II's solver
    // (eq. 2.44), and the flat contact disc carries exactly the fluid
    // pressure (a membrane has no bending stiffness).
    let ds = [0.28, 0.53, 0.78];
    let mut solver = MembraneSolver::new(
        MooneyRivlinMembrane::new(1.0, 0.1).unwrap(),
        Geometry {
            rs: 1.03,
            nodes: 256,
        },
        1.0,
    )
    .unwrap();
    membrane_run(256, &ds, |m, d| {
        let sol = solver
            .equilibrium(0.0, nlvid_membrane::Control::Displacement(d))
            .unwrap();
        let rec = m.capsule_record(&membrane_spec()).unwrap();
        let h0 = 1e-3;
        let patch = &rec.patch;
        let [a, b] = patch.semi_axes;
        let spacing = 0.5 * PI / 256.0;
        eprintln!(
            "D = {d}: a FE {a:.6} vs {:.6} ({:+.2e}); p̄ {:.6} vs {:.6}; F̄ {:.5} vs {:.5}; \
             pressure area {:.5} vs π a² {:.5}; ellipse {:.5}",
            sol.record.contact_radius,
            a / sol.record.contact_radius - 1.0,
            rec.pressure / h0,
            sol.record.pressure,
            rec.force / h0,
            sol.record.force,
            patch.pressure_area,
            PI * sol.record.contact_radius.powi(2),
            patch.ellipse_area
        );
        assert_eq!(a, b);
        // The edge lies between two nodes; the lift-off profile places it
        // to a fraction of the spacing.
        assert!(
            (a - sol.record.contact_radius).abs() < 0.5 * spacing,
            "contact radius"
        );
        assert!(
            (rec.pressure / h0 / sol.record.pressure - 1.0).abs() < 2e-3,
            "pressure"
        );
        assert!(
            (rec.force / h0 / sol.record.force - 1.0).abs() < 2e-3,
            "force"
        );
        assert!((patch.ellipse_area - PI * a * a).abs() < 1e-12);
        // The pressed nodes' area lies within one spacing of the disc.
        let r_area = (patch.pressure_area / PI).sqrt();
        assert!((r_area - a).abs() < 1.5 * spacing, "{r_area} vs {a}");
        // Inside the disc (clear of the edge) the contact pressure is the
        // fluid pressure.
        let inner: Vec<&[f64; 2]> = patch.paths[0]
            .iter()
            .filter(|p| p[0] < a - 3.0 * spacing)
            .collect();
        assert!(inner.len() > 10);
        for p in inner {
            assert!(
                (p[1] / rec.pressure - 1.0).abs() < 1e-6,
                "{p:?} vs {}",
                rec.pressure
            );
        }
        assert!(!patch.lost_contact());
        // Incompressible: the whole capsule's fluid volume stays V₀ r_s³.
        let v0 = 2.0 * m.cavity_reference_volume().unwrap();
        assert!((rec.volume / (v0 * 1.03f64.powi(3)) - 1.0).abs() < 1e-9);
    });
}

#[test]
fn axisymmetric_capsule_flags_the_lifted_pole_as_lost_contact() {
    // docs/theory/fem.md: the thick-walled sphere's pole lifts off inside
    // the patch (thesis Fig. 4.16).
    let m = common::squeezed_axisymmetric(32);
    let spec = PatchSpec {
        plane: 0,
        surface: "outer".into(),
        symmetry: Symmetry::AXISYMMETRIC_HALF,
        lift_off: LiftOff::Solid,
    };
    let rec = m.capsule_record(&spec).unwrap();
    let patch = &rec.patch;
    eprintln!(
        "force {:.5e} N, p {:.5e} Pa, a {:.5e} m, pressure area {:.5e} vs ellipse {:.5e} m², lost {:?} ({:.3e} m²)",
        rec.force,
        rec.pressure,
        patch.semi_axes[0],
        patch.pressure_area,
        patch.ellipse_area,
        patch.lost_nodes,
        patch.lost_area
    );
    let pole = m.mesh().nodes_in("outer").unwrap()[0];
    assert!(patch.lost_contact() && patch.lost_nodes.contains(&pole));
    // The path shows it: zero pressure at the centre, positive further out.
    let path = &patch.paths[0];
    assert_eq!(path[0][1], 0.0);
    assert!(path.iter().any(|p| p[1] > 0.0));
    // Force and model record agree; volume conserved.
    let last = m.records().last().unwrap();
    assert!((rec.force / last.plane_force - 1.0).abs() < 1e-12);
    let v0 = 2.0 * m.cavity_reference_volume().unwrap();
    assert!((rec.volume / v0 - 1.0).abs() < 1e-9);
    // Both areas measure the same patch: the ring of pressed nodes (whose
    // tributary areas reach half a spacing beyond the last one) against
    // the disc π a².
    let a = patch.semi_axes[0];
    assert!(a > 0.3e-3);
    assert!((patch.pressure_area / patch.ellipse_area - 1.0).abs() < 0.15);
}

/// The 3D capsule of `common::squeezed_solid` (`part`, m divisions per
/// patch edge) after the squeeze, and the symmetry of that part.
fn solid(part: ShellPart, m: usize) -> (Model<MooneyRivlin, Solid>, Symmetry) {
    let symmetry = match part {
        ShellPart::Eighth => Symmetry::EIGHTH,
        ShellPart::Quarter => Symmetry::QUARTER,
        ShellPart::Full => Symmetry::FULL,
    };
    (common::squeezed_solid(part, m), symmetry)
}

fn spec_3d(plane: usize, symmetry: Symmetry) -> PatchSpec {
    PatchSpec {
        plane,
        surface: "outer".into(),
        symmetry,
        lift_off: LiftOff::Solid,
    }
}

#[test]
fn eighth_quarter_and_full_capsules_report_the_same_patch() {
    let (eighth, s8) = solid(ShellPart::Eighth, 4);
    let reference = eighth.capsule_record(&spec_3d(0, s8)).unwrap();
    for part in [ShellPart::Quarter, ShellPart::Full] {
        let (model, sym) = solid(part, 4);
        for plane in [0, 1] {
            let rec = model.capsule_record(&spec_3d(plane, sym)).unwrap();
            let (a, b) = (&rec.patch, &reference.patch);
            for (what, x, y) in [
                ("force", rec.force, reference.force),
                ("pressure", rec.pressure, reference.pressure),
                ("volume", rec.volume, reference.volume),
                ("pressure area", a.pressure_area, b.pressure_area),
                ("semi-axis a", a.semi_axes[0], b.semi_axes[0]),
                ("semi-axis b", a.semi_axes[1], b.semi_axes[1]),
                ("ellipse area", a.ellipse_area, b.ellipse_area),
                ("lost area", a.lost_area, b.lost_area),
            ] {
                let scale = y.abs().max(1e-30);
                assert!(
                    (x - y).abs() <= 1e-6 * scale,
                    "{part:?} plate {plane} {what}: {x} vs {y}"
                );
            }
        }
    }
    // A sphere's patch is a disc: the cube-sphere mesh is symmetric in
    // x ↔ y, so both semi-axes agree.
    let [a, b] = reference.patch.semi_axes;
    assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
    // Paths: the same nodes on both axes by symmetry.
    assert_eq!(
        reference.patch.paths[0].len(),
        reference.patch.paths[1].len()
    );
}

#[test]
fn eighth_patch_agrees_with_the_axisymmetric_patch() {
    // Same meridian spacing as `tests/it/capsule.rs` at m = 8.
    let (eighth, sym) = solid(ShellPart::Eighth, 8);
    let e = eighth.capsule_record(&spec_3d(0, sym)).unwrap();
    let axi = common::squeezed_axisymmetric(16);
    let spec = PatchSpec {
        plane: 0,
        surface: "outer".into(),
        symmetry: Symmetry::AXISYMMETRIC_HALF,
        lift_off: LiftOff::Solid,
    };
    let x = axi.capsule_record(&spec).unwrap();
    eprintln!(
        "3D: a {:.5e}, ellipse {:.5e}, pressure area {:.5e}, lost {}; axisymmetric: a {:.5e}, ellipse {:.5e}, pressure area {:.5e}, lost {}",
        e.patch.semi_axes[0],
        e.patch.ellipse_area,
        e.patch.pressure_area,
        e.patch.lost_nodes.len(),
        x.patch.semi_axes[0],
        x.patch.ellipse_area,
        x.patch.pressure_area,
        x.patch.lost_nodes.len()
    );
    assert!((e.patch.ellipse_area / x.patch.ellipse_area - 1.0).abs() < 0.03);
    assert!((e.force / x.force - 1.0).abs() < 0.02);
    assert!((e.volume / x.volume - 1.0).abs() < 0.01);
}

/// The text of every `<DataArray … Name="name" …>` block, split.
fn data_array(xml: &str, name: &str) -> Vec<String> {
    let key = format!("Name=\"{name}\"");
    let start = xml.find(&key).unwrap_or_else(|| panic!("no array {name}"));
    let open = start + xml[start..].find('>').unwrap() + 1;
    let close = open + xml[open..].find("</DataArray>").unwrap();
    xml[open..close]
        .split_whitespace()
        .map(String::from)
        .collect()
}

fn attribute(xml: &str, name: &str) -> usize {
    let key = format!("{name}=\"");
    let s = xml.find(&key).unwrap() + key.len();
    xml[s..s + xml[s..].find('"').unwrap()].parse().unwrap()
}

#[test]
fn vtu_files_read_back_to_the_deformed_mesh() {
    let dir = std::env::temp_dir().join(format!("nlvid-fem-vtu-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 3D eighth (hexahedra), axisymmetric solid (quadrilaterals), membrane
    // (lines).
    let (eighth, sym) = solid(ShellPart::Eighth, 4);
    let axi = common::squeezed_axisymmetric(8);
    let mut membrane = None;
    membrane_run(32, &[0.28], |m, _| {
        membrane = Some(m.vtu_grid(&[membrane_spec()]).unwrap())
    });
    let spec_axi = PatchSpec {
        plane: 0,
        surface: "outer".into(),
        symmetry: Symmetry::AXISYMMETRIC_HALF,
        lift_off: LiftOff::Solid,
    };
    let cases: Vec<(&str, VtuGrid, Vec<[f64; 3]>, f64)> = vec![
        (
            "eighth",
            eighth.vtu_grid(&[spec_3d(0, sym)]).unwrap(),
            eighth
                .mesh()
                .nodes
                .iter()
                .zip(eighth.displacements())
                .map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]])
                .collect(),
            eighth.records().last().unwrap().plane_force,
        ),
        (
            "axisymmetric",
            axi.vtu_grid(&[spec_axi]).unwrap(),
            axi.mesh()
                .nodes
                .iter()
                .zip(axi.displacements())
                .map(|(x, u)| [x[0] + u[0], 0.0, x[1] + u[1]])
                .collect(),
            axi.records().last().unwrap().plane_force,
        ),
    ];
    for (name, grid, expected, force) in cases {
        let path = dir.join(format!("{name}.vtu"));
        grid.write(&path).unwrap();
        let xml = std::fs::read_to_string(&path).unwrap();
        assert!(xml.starts_with("<?xml") && xml.contains("<VTKFile type=\"UnstructuredGrid\""));
        let n = attribute(&xml, "NumberOfPoints");
        assert_eq!(n, expected.len());
        assert_eq!(attribute(&xml, "NumberOfCells"), grid.cells.len());
        let pts: Vec<f64> = data_array(&xml, "Points")
            .iter()
            .map(|s| s.parse().unwrap())
            .collect();
        assert_eq!(pts.len(), 3 * n);
        for a in 0..n {
            for i in 0..3 {
                // Shortest round-trip formatting: the same f64 back.
                assert_eq!(pts[3 * a + i], expected[a][i], "{name} point {a}");
            }
        }
        let conn: Vec<usize> = data_array(&xml, "connectivity")
            .iter()
            .map(|s| s.parse().unwrap())
            .collect();
        let flat: Vec<usize> = grid.cells.iter().flatten().copied().collect();
        assert_eq!(conn, flat);
        let offsets: Vec<usize> = data_array(&xml, "offsets")
            .iter()
            .map(|s| s.parse().unwrap())
            .collect();
        assert_eq!(offsets.last().copied(), Some(flat.len()));
        let types = data_array(&xml, "types");
        assert!(
            types
                .iter()
                .all(|t| t.parse::<u8>().unwrap() == grid.cell_type)
        );
        assert_eq!(grid.cell_type, if name == "eighth" { 12 } else { 9 });
        // The pressure field integrates back to the plate force (nodal
        // pressure × current tributary area = nodal force).
        let p: Vec<f64> = data_array(&xml, "contact_pressure")
            .iter()
            .map(|s| s.parse().unwrap())
            .collect();
        assert_eq!(p.len(), n);
        assert!(p.iter().any(|&x| x > 0.0) && p.iter().all(|&x| x >= 0.0));
        let _ = force;
    }
    let grid = membrane.unwrap();
    assert_eq!(grid.cell_type, 3);
    let path = dir.join("membrane.vtu");
    grid.write(&path).unwrap();
    let xml = std::fs::read_to_string(&path).unwrap();
    let pts: Vec<f64> = data_array(&xml, "Points")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    let flat: Vec<f64> = grid.points.iter().flatten().copied().collect();
    assert_eq!(pts, flat);
    let disp: Vec<f64> = data_array(&xml, "displacement")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    // Axisymmetric points lie in y = 0.
    assert!(disp.chunks(3).all(|d| d[1] == 0.0));
    nlvid_fem::vtu::write_pvd(&dir.join("series.pvd"), &[(0.0, "membrane.vtu".into())]).unwrap();
    let pvd = std::fs::read_to_string(dir.join("series.pvd")).unwrap();
    assert!(pvd.contains("file=\"membrane.vtu\""));
    // An unwritable path is a typed error naming the file.
    let bad = dir.join("missing-dir").join("x.vtu");
    let e = grid.write(&bad).unwrap_err();
    assert!(e.to_string().contains("x.vtu"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
