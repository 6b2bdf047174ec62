//! Element verification: patch test (uniform stretch reproduced exactly on
//! a distorted mesh) and volumetric locking (thick-walled cylinder, Lamé).

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::reference::NeoHookean;
use nlvid_fem::{Component, Control, Mesh, Model, Settings, Stage, Support};
use nlvid_material::{Mat3, Material3};

/// A 3×3-node patch on [r0, r0+w] × [0, h] with a displaced interior node.
fn distorted_patch(r0: f64, w: f64, h: f64) -> Mesh {
    let mut nodes = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            nodes.push([r0 + 0.5 * w * i as f64, 0.5 * h * j as f64]);
        }
    }
    nodes[4] = [r0 + 0.37 * w, 0.61 * h];
    let id = |i: usize, j: usize| 3 * j + i;
    let mut elements = Vec::new();
    for j in 0..2 {
        for i in 0..2 {
            elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mut mesh = Mesh::new(nodes, elements).unwrap();
    for a in 0..9 {
        mesh.set_nodes(&format!("n{a}"), vec![a]);
    }
    mesh.set_nodes("top", vec![6, 7, 8]);
    mesh
}

fn uniform_stretch_is_exact(fbar: bool) {
    let (r0, w, h) = (1e-6, 2e-6, 1.5e-6);
    let mesh = distorted_patch(r0, w, h);
    let (a, b) = (0.3, -0.2); // u_r = a R, u_z = b Z: F = diag(1+a, 1+b, 1+a)
    let mut supports = Vec::new();
    for n in [0usize, 1, 2, 3, 5, 6, 7, 8] {
        let x = mesh.nodes[n];
        supports.push(Support {
            set: format!("n{n}"),
            component: Component::R,
            value: a * x[0],
        });
        supports.push(Support {
            set: format!("n{n}"),
            component: Component::Z,
            value: b * x[1],
        });
    }
    let interior = mesh.nodes[4];
    let material = NeoHookean {
        mu: 1e3,
        kappa: 5e4,
    };
    let settings = Settings {
        fbar,
        ..Settings::default()
    };
    let mut model = Model::new(mesh, material, &supports, None, None, settings).unwrap();
    let control = |t: f64| Control {
        support_scale: t,
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "stretch",
            end: 1.0,
            dt_initial: 0.25,
            dt_max: 0.25,
            control: &control,
        })
        .unwrap();
    let u: Vec<[f64; 2]> = model.displacements().collect();
    assert!(
        (u[4][0] - a * interior[0]).abs() < 1e-12 * r0,
        "u_r {:e}",
        u[4][0] - a * interior[0]
    );
    assert!(
        (u[4][1] - b * interior[1]).abs() < 1e-12 * r0,
        "u_z {:e}",
        u[4][1] - b * interior[1]
    );
    // Axial force on the top face = P_zZ × π((r0+w)² − r0²), P from the
    // material evaluated directly at the uniform F.
    let f = Mat3::new(1.0 + a, 0.0, 0.0, 0.0, 1.0 + b, 0.0, 0.0, 0.0, 1.0 + a);
    let p = material.update(&(), &f, 0.0, &mut ()).unwrap().first_piola;
    let area = std::f64::consts::PI * ((r0 + w).powi(2) - r0 * r0);
    let top = model.reaction("top", Component::Z).unwrap();
    assert!(
        (top - p[(1, 1)] * area).abs() < 1e-9 * (p[(1, 1)] * area).abs(),
        "{top} vs {}",
        p[(1, 1)] * area
    );
}

#[test]
fn fbar_patch_reproduces_uniform_finite_stretch_exactly() {
    uniform_stretch_is_exact(true);
}

#[test]
fn displacement_patch_reproduces_uniform_finite_stretch_exactly() {
    uniform_stretch_is_exact(false);
}

/// Thick-walled cylinder a ≤ r ≤ b in plane strain, inner radius pushed out
/// by u0 (small): returns the FE and Lamé pressures on the inner wall.
fn thick_cylinder_pressure(fbar: bool, kappa_over_mu: f64) -> (f64, f64) {
    let (a, b, h) = (1e-6, 3e-6, 0.5e-6);
    let (nr, nz) = (10, 2);
    let mut nodes = Vec::new();
    for j in 0..=nz {
        for i in 0..=nr {
            nodes.push([a + (b - a) * i as f64 / nr as f64, h * j as f64 / nz as f64]);
        }
    }
    let id = |i: usize, j: usize| j * (nr + 1) + i;
    let mut elements = Vec::new();
    for j in 0..nz {
        for i in 0..nr {
            elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mut mesh = Mesh::new(nodes, elements).unwrap();
    mesh.set_nodes("inner", (0..=nz).map(|j| id(0, j)).collect());
    mesh.set_nodes(
        "ends",
        (0..=nr).flat_map(|i| [id(i, 0), id(i, nz)]).collect(),
    );
    let mu = 1e3;
    let kappa = kappa_over_mu * mu;
    let u0 = 1e-5 * a;
    let supports = [
        Support::fixed("ends", Component::Z),
        Support {
            set: "inner".into(),
            component: Component::R,
            value: u0,
        },
    ];
    let settings = Settings {
        fbar,
        ..Settings::default()
    };
    let mut model = Model::new(
        mesh,
        NeoHookean { mu, kappa },
        &supports,
        None,
        None,
        settings,
    )
    .unwrap();
    let control = |t: f64| Control {
        support_scale: t,
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "push",
            end: 1.0,
            dt_initial: 1.0,
            dt_max: 1.0,
            control: &control,
        })
        .unwrap();
    let fe = model.reaction("inner", Component::R).unwrap() / (2.0 * std::f64::consts::PI * a * h);
    // Lamé, plane strain: u = A r + B/r, σ_rr(b) = 0, u(a) = u0.
    let lambda = kappa - 2.0 * mu / 3.0;
    let c = mu / ((lambda + mu) * b * b);
    let bb = u0 / (c * a + 1.0 / a);
    let exact = 2.0 * mu * bb * (1.0 / (a * a) - 1.0 / (b * b));
    (fe, exact)
}

#[test]
fn fbar_does_not_lock_in_near_incompressible_thick_cylinder() {
    // κ/μ = 10⁴ (ν = 0.49995). F-bar stays within 2 % of Lamé; the plain
    // displacement element on the same mesh is far too stiff.
    let (fe, exact) = thick_cylinder_pressure(true, 1e4);
    let err_fbar = (fe / exact - 1.0).abs();
    let (fe_plain, _) = thick_cylinder_pressure(false, 1e4);
    let err_plain = (fe_plain / exact - 1.0).abs();
    eprintln!("thick cylinder κ/μ = 1e4: F-bar error {err_fbar:.4}, plain error {err_plain:.4}");
    assert!(err_fbar < 0.02, "F-bar error {err_fbar}");
    assert!(
        err_plain > 10.0 * err_fbar,
        "plain {err_plain} vs F-bar {err_fbar}"
    );
}

#[test]
fn both_elements_agree_with_lame_when_compressible() {
    // ν = 0.3: no locking to remove, both elements converge to Lamé.
    let kappa_over_mu = 2.0 * 1.3 / (3.0 * 0.4);
    for fbar in [true, false] {
        let (fe, exact) = thick_cylinder_pressure(fbar, kappa_over_mu);
        assert!(
            (fe / exact - 1.0).abs() < 0.02,
            "fbar={fbar}: {fe} vs {exact}"
        );
    }
}
