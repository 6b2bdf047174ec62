//! 3D hexahedral models (`Model<M, Solid>`): patch test, volumetric locking
//! (thick cylinder vs Lamé), thin-wall bending (pinched ring vs curved-beam
//! theory), symmetry rollers and frictionless rigid planes that allow
//! separation.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::reference::NeoHookean;
use nlvid_fem::{
    Component, Control, Mesh3, Model, Parts, RigidPlane, Settings, Solid, SphereProbe, Stage,
    Support,
};
use nlvid_material::{Mat3, Material3, PointState};
use std::f64::consts::PI;

fn run<M: Material3>(
    model: &mut Model<M, Solid>,
    end: f64,
    dt: f64,
    control: &dyn Fn(f64) -> Control,
) {
    model
        .run_stage(&Stage {
            name: "load",
            end,
            dt_initial: dt,
            dt_max: dt,
            control,
        })
        .unwrap();
}

fn scaled(t: f64) -> Control {
    Control {
        support_scale: t,
        ..Control::default()
    }
}

/// Every node of `nodes` in its own set `n{a}` with prescribed u = field(X).
fn pin_nodes(
    mesh: &mut Mesh3,
    nodes: &[usize],
    field: impl Fn([f64; 3]) -> [f64; 3],
    out: &mut Vec<Support>,
) {
    for &a in nodes {
        let name = format!("n{a}");
        mesh.set_nodes(&name, vec![a]);
        let u = field(mesh.nodes[a]);
        for (c, v) in [Component::X, Component::Y, Component::Z]
            .into_iter()
            .zip(u)
        {
            out.push(Support {
                set: name.clone(),
                component: c,
                value: v,
            });
        }
    }
}

#[test]
fn hexahedral_patch_reproduces_uniform_finite_deformation_exactly() {
    // 2×2×2 distorted patch; boundary nodes follow u = (F0 − I) X, the
    // interior node is free and must land on it, and every boundary
    // reaction is the consistent nodal share of the uniform traction P N —
    // with the capsule's viscoelastic material, so the history is uniform too.
    let mut mesh = Mesh3::structured([2, 2, 2], |i, j, k| {
        let w = [0.0, 1.0, 2.0];
        if (i, j, k) == (1, 1, 1) {
            [0.91, 1.08, 1.13]
        } else {
            [
                w[i] + 0.02 * w[j] * w[k],
                w[j] - 0.03 * w[i],
                w[k] + 0.05 * w[i] * w[j],
            ]
        }
    })
    .unwrap();
    let f0 = [[1.25, 0.08, -0.04], [0.06, 0.88, 0.1], [-0.07, 0.03, 1.12]];
    let interior = 13; // (1, 1, 1)
    let boundary: Vec<usize> = (0..27).filter(|&a| a != interior).collect();
    let field = |x: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|j| f0[i][j] * x[j]).sum::<f64>() - x[i])
    };
    let mut supports = Vec::new();
    pin_nodes(&mut mesh, &boundary, field, &mut supports);
    let x_int = mesh.nodes[interior];
    let material =
        nlvid_material::PronyViscoelastic::capsule(1e6, 0.3, (0.5, 0.1), (0.2, 2.0), 1e9).unwrap();
    let parts = Parts {
        supports,
        ..Parts::default()
    };
    let mut model =
        Model::<_, Solid>::build(mesh, material.clone(), &parts, Settings::default()).unwrap();
    run(&mut model, 1.0, 0.25, &scaled);
    let u: Vec<[f64; 3]> = model.displacements().collect();
    let exact = field(x_int);
    for i in 0..3 {
        assert!(
            (u[interior][i] - exact[i]).abs() < 1e-12,
            "u[{i}] off by {:e}",
            u[interior][i] - exact[i]
        );
    }
    // Each boundary node's reaction is its consistent share of the uniform
    // traction, Σ_faces ∫ N_a P n dA over the six sides (bilinear faces,
    // n dA = x_s × x_t ds dt, exact by 2×2 Gauss).
    // The viscoelastic point history, replayed at one point through the
    // same four steps F(t) = I + t (F0 − I), dt = 0.25.
    let mut state = material.initial_state();
    let mut tr = state.clone();
    let mut p = Mat3::zeros();
    for k in 1..=4 {
        let t = 0.25 * k as f64;
        let fm = Mat3::from_fn(|i, j| {
            f64::from(u8::from(i == j)) + t * (f0[i][j] - f64::from(u8::from(i == j)))
        });
        p = material
            .update(&state, &fm, 0.25, &mut tr)
            .unwrap()
            .first_piola;
        state = tr.clone();
    }
    // The initial state (stage 0, dense output's start point) and 4 steps.
    assert_eq!(model.records().len(), 5);
    let mesh = model.mesh();
    let mut expected = vec![[0.0; 3]; 27];
    let g = 1.0 / 3f64.sqrt();
    for side in ["x0", "x1", "y0", "y1", "z0", "z1"] {
        for f in mesh.faces_in(side).unwrap() {
            let x = f.map(|a| mesh.nodes[a]);
            for (s, t) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
                let n = [
                    (1.0 - s) * (1.0 - t),
                    (1.0 + s) * (1.0 - t),
                    (1.0 + s) * (1.0 + t),
                    (1.0 - s) * (1.0 + t),
                ]
                .map(|v| 0.25 * v);
                let ns = [-(1.0 - t), 1.0 - t, 1.0 + t, -(1.0 + t)].map(|v| 0.25 * v);
                let nt = [-(1.0 - s), -(1.0 + s), 1.0 + s, 1.0 - s].map(|v| 0.25 * v);
                let xs: [f64; 3] = std::array::from_fn(|i| (0..4).map(|k| ns[k] * x[k][i]).sum());
                let xt: [f64; 3] = std::array::from_fn(|i| (0..4).map(|k| nt[k] * x[k][i]).sum());
                let nda = [
                    xs[1] * xt[2] - xs[2] * xt[1],
                    xs[2] * xt[0] - xs[0] * xt[2],
                    xs[0] * xt[1] - xs[1] * xt[0],
                ];
                for k in 0..4 {
                    for i in 0..3 {
                        expected[f[k]][i] += n[k] * (0..3).map(|j| p[(i, j)] * nda[j]).sum::<f64>();
                    }
                }
            }
        }
    }
    for &a in &boundary {
        for (i, c) in [Component::X, Component::Y, Component::Z]
            .into_iter()
            .enumerate()
        {
            let r = model.reaction(&format!("n{a}"), c).unwrap();
            assert!(
                (r - expected[a][i]).abs() < 1e-9 * p.norm(),
                "node {a} component {i}: {r} vs {}",
                expected[a][i]
            );
        }
    }
}

/// Quarter of a thick-walled cylinder a ≤ r ≤ b (plane strain: one element
/// layer, u_z = 0 on both ends), symmetry rollers on x = 0 and y = 0, inner
/// wall pushed out radially by u0 (small): FE and Lamé inner pressures.
fn thick_cylinder_pressure(fbar: bool, kappa_over_mu: f64) -> (f64, f64) {
    let (a, b, h) = (1e-3, 3e-3, 0.25e-3);
    let (nr, nt) = (10, 8);
    let mut mesh = Mesh3::structured([nr, nt, 1], |i, j, k| {
        let r = a + (b - a) * i as f64 / nr as f64;
        let t = 0.5 * PI * j as f64 / nt as f64;
        [r * t.cos(), r * t.sin(), h * k as f64]
    })
    .unwrap();
    let mu = 1e3;
    let kappa = kappa_over_mu * mu;
    let u0 = 1e-5 * a;
    let inner = mesh.nodes_in("x0").unwrap().to_vec();
    let mut supports = vec![
        Support::fixed("z0", Component::Z),
        Support::fixed("z1", Component::Z),
        Support::fixed("y0", Component::Y), // θ = 0: the plane y = 0
        Support::fixed("y1", Component::X), // θ = π/2: the plane x = 0
    ];
    pin_nodes(
        &mut mesh,
        &inner,
        |x| {
            let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
            [u0 * x[0] / r, u0 * x[1] / r, 0.0]
        },
        &mut supports,
    );
    let parts = Parts {
        supports,
        ..Parts::default()
    };
    let settings = Settings {
        fbar,
        ..Settings::default()
    };
    let mut model =
        Model::<_, Solid>::build(mesh, NeoHookean { mu, kappa }, &parts, settings).unwrap();
    run(&mut model, 1.0, 1.0, &scaled);
    // The radial components of the reactions on the inner wall (the corner
    // nodes also carry the symmetry planes' reactions, in the hoop
    // direction, which this projection leaves out). A uniform pressure p on
    // the polygonal wall of nt chords gives Σ radial = p a h nt sin(π/2nt).
    let radial: f64 = inner
        .iter()
        .map(|&n| {
            let x = model.mesh().nodes[n];
            let r = (x[0] * x[0] + x[1] * x[1]).sqrt();
            let name = format!("n{n}");
            (model.reaction(&name, Component::X).unwrap() * x[0]
                + model.reaction(&name, Component::Y).unwrap() * x[1])
                / r
        })
        .sum();
    let fe = radial / (a * h * nt as f64 * (0.5 * PI / nt as f64).sin());
    // Lamé, plane strain: u = A r + B/r, σ_rr(b) = 0, u(a) = u0.
    let lambda = kappa - 2.0 * mu / 3.0;
    let c = mu / ((lambda + mu) * b * b);
    let bb = u0 / (c * a + 1.0 / a);
    let exact = 2.0 * mu * bb * (1.0 / (a * a) - 1.0 / (b * b));
    (fe, exact)
}

#[test]
fn hexahedral_fbar_does_not_lock_in_near_incompressible_thick_cylinder() {
    // κ/μ = 10⁴ (ν = 0.49995): F-bar within 2 % of Lamé, the plain
    // displacement hexahedron on the same mesh far too stiff.
    let (fe, exact) = thick_cylinder_pressure(true, 1e4);
    let err_fbar = (fe / exact - 1.0).abs();
    let (fe_plain, _) = thick_cylinder_pressure(false, 1e4);
    let err_plain = (fe_plain / exact - 1.0).abs();
    eprintln!("3D thick cylinder κ/μ = 1e4: F-bar error {err_fbar:.5}, plain error {err_plain:.4}");
    assert!(err_fbar < 0.02, "F-bar error {err_fbar}");
    assert!(
        err_plain > 10.0 * err_fbar,
        "plain {err_plain} vs F-bar {err_fbar}"
    );
}

#[test]
fn both_hexahedra_agree_with_lame_when_compressible() {
    // ν = 0.3: nothing to lock, both converge to Lamé.
    let kappa_over_mu = 2.0 * 1.3 / (3.0 * 0.4);
    for fbar in [true, false] {
        let (fe, exact) = thick_cylinder_pressure(fbar, kappa_over_mu);
        assert!(
            (fe / exact - 1.0).abs() < 0.02,
            "fbar={fbar}: {fe} vs {exact}"
        );
    }
}

/// A pinched thin ring (mean radius R, wall t, plane strain), quarter model
/// with rollers on x = 0 and y = 0; the section at the top (x = 0) is
/// pushed down by δ/2 (a rigid load across the section). Returns the FE
/// diametral stiffness P/δ over the thin-ring value E'I/((π/4 − 2/π) R³).
fn pinched_ring_ratio(fbar: bool, through: usize, n_around: usize, kappa_over_mu: f64) -> f64 {
    let (r, t, h) = (10e-3, 0.5e-3, 0.25e-3);
    let mesh = Mesh3::structured([through, n_around, 1], |i, j, k| {
        let rr = r - 0.5 * t + t * i as f64 / through as f64;
        let th = 0.5 * PI * j as f64 / n_around as f64;
        [rr * th.cos(), rr * th.sin(), h * k as f64]
    })
    .unwrap();
    let mu = 1e6;
    let kappa = kappa_over_mu * mu;
    let delta = 1e-4 * r;
    let supports = vec![
        Support::fixed("z0", Component::Z),
        Support::fixed("z1", Component::Z),
        Support::fixed("y0", Component::Y),
        Support::fixed("y1", Component::X),
        Support {
            set: "y1".into(),
            component: Component::Y,
            value: -0.5 * delta,
        },
    ];
    let parts = Parts {
        supports,
        ..Parts::default()
    };
    let settings = Settings {
        fbar,
        ..Settings::default()
    };
    let mut model =
        Model::<_, Solid>::build(mesh, NeoHookean { mu, kappa }, &parts, settings).unwrap();
    run(&mut model, 1.0, 1.0, &scaled);
    // The top section of the quarter carries half the diametral load P.
    let p = -2.0 * model.reaction("y1", Component::Y).unwrap();
    let e = 9.0 * kappa * mu / (3.0 * kappa + mu);
    let nu = (3.0 * kappa - 2.0 * mu) / (2.0 * (3.0 * kappa + mu));
    let e_plane = e / (1.0 - nu * nu);
    let inertia = h * t.powi(3) / 12.0;
    let thin_ring = e_plane * inertia / ((PI / 4.0 - 2.0 / PI) * r.powi(3));
    p / delta / thin_ring
}

#[test]
fn thin_ring_bends_without_locking_and_converges_to_ring_theory() {
    // R/t = 20, κ/μ = 10⁴; thin-ring theory is exact to O((t/R)²) ≈ 0.3 %.
    // The F-bar hexahedron has two O(h²) errors in bending, both
    // independent of ν (no locking): parasitic shear, stiff, ∝ (length/t)²,
    // and the loss of the dilatation's variation inside an element (mean
    // dilatation), soft by 2/(3N²) for N elements through the wall
    // (docs/theory/fem.md). Refining both together (N = 2, 4, 8 layers,
    // length ≈ t/2, t/4, t/8) the error falls ≈ 4× per level to < 1 %;
    // the plain hexahedron is locked (≫ 1).
    let ratios: Vec<f64> = [(2, 64), (4, 128), (8, 256)]
        .iter()
        .map(|&(layers, n)| pinched_ring_ratio(true, layers, n, 1e4))
        .collect();
    let fixed_layers = pinched_ring_ratio(true, 4, 64, 1e4);
    let plain = pinched_ring_ratio(false, 4, 64, 1e4);
    eprintln!(
        "pinched ring P/δ over thin-ring theory: F-bar (N, n) = (2, 64), (4, 128), (8, 256): {ratios:?}; \
         (4, 64): {fixed_layers}; plain (4, 64): {plain}"
    );
    let err: Vec<f64> = ratios.iter().map(|r| (r - 1.0).abs()).collect();
    assert!(err[2] < 0.01, "{ratios:?}");
    assert!(
        err[0] > 3.0 * err[1] && err[1] > 3.0 * err[2],
        "second order {ratios:?}"
    );
    assert!(
        plain > 10.0,
        "plain displacement hexahedra should lock: {plain}"
    );
}

#[test]
fn plate_compression_of_a_block_matches_homogeneous_neo_hookean_and_separates() {
    // Quarter of a square prism on rollers (x = 0, y = 0, base z = 0),
    // squeezed by a frictionless rigid plate: homogeneous uniaxial stress,
    // |F| = μ (λ⁻² − λ) A (incompressible). Then the plate lifts off past
    // the free height: contact separates and the force vanishes.
    let (a, h, mu) = (1e-3, 0.8e-3, 1e6);
    let mesh = Mesh3::structured([3, 3, 3], |i, j, k| {
        [a * i as f64 / 3.0, a * j as f64 / 3.0, h * k as f64 / 3.0]
    })
    .unwrap();
    let parts = Parts {
        supports: vec![
            Support::fixed("x0", Component::X),
            Support::fixed("y0", Component::Y),
            Support::fixed("z0", Component::Z),
        ],
        planes: vec![RigidPlane::above("z1")],
        ..Parts::default()
    };
    // Separation: a Newton step from a state just off the plate may land
    // inside it with a large penalty force; accept such a full step (the
    // next one has the right contact set) instead of halving it forever.
    // At the instant of separation the force passes through zero: an
    // absolute tolerance (1e-9 of the peak) replaces rtol × vanishing force.
    let settings = Settings {
        penalty: 1e4,
        residual_growth: 1e6,
        atol: 1e-9 * mu * 0.3 * a * a,
        ..Settings::default()
    };
    let mut model = Model::<_, Solid>::build(
        mesh,
        NeoHookean {
            mu,
            kappa: 1e5 * mu,
        },
        &parts,
        settings,
    )
    .unwrap();
    let squeeze = 0.2 * h;
    // Down by 20 % over t ∈ [0, 1], back up to 5 % above the top by t = 2.
    let plane = move |t: f64| {
        let z = if t <= 1.0 {
            h - squeeze * t
        } else {
            h - squeeze + (squeeze + 0.05 * h) * (t - 1.0)
        };
        Control {
            plane_z: z,
            ..Control::default()
        }
    };
    run(&mut model, 1.0, 0.1, &plane);
    let top = top_height(&model);
    let lambda = top / h;
    let exact = mu * (1.0 / (lambda * lambda) - lambda) * a * a;
    let rec = *model.records().last().unwrap();
    assert!(
        (rec.plane_force / exact - 1.0).abs() < 2e-3,
        "FE {} vs {exact} at λ = {lambda}",
        rec.plane_force
    );
    assert!(lambda < 0.81);
    // The base rollers carry the plate force.
    let base = model.reaction("z0", Component::Z).unwrap();
    assert!(
        (base - rec.plane_force).abs() < 1e-6 * rec.plane_force,
        "{base}"
    );
    run(&mut model, 2.0, 0.1, &plane);
    let rec = *model.records().last().unwrap();
    assert_eq!(rec.plane_force, 0.0);
    assert!(
        (top_height(&model) / h - 1.0).abs() < 1e-9,
        "unloaded block returns to its height"
    );
}

/// Mean current height of the z1 side.
fn top_height<M: Material3>(model: &Model<M, Solid>) -> f64 {
    let top = model.mesh().nodes_in("z1").unwrap().to_vec();
    let u: Vec<[f64; 3]> = model.displacements().collect();
    top.iter()
        .map(|&a| model.mesh().nodes[a][2] + u[a][2])
        .sum::<f64>()
        / top.len() as f64
}

#[test]
fn block_between_two_plates_matches_block_on_rollers() {
    // The base roller replaced by a fixed frictionless plane below: same
    // force, and the two planes carry equal and opposite loads.
    let (a, h, mu) = (1e-3, 0.8e-3, 1e6);
    let make = |base_plane: bool| {
        let mesh = Mesh3::structured([2, 2, 3], |i, j, k| {
            [a * i as f64 / 2.0, a * j as f64 / 2.0, h * k as f64 / 3.0]
        })
        .unwrap();
        let mut supports = vec![
            Support::fixed("x0", Component::X),
            Support::fixed("y0", Component::Y),
        ];
        let mut planes = vec![RigidPlane::above("z1")];
        if base_plane {
            planes.push(RigidPlane::below("z0", 0.0));
        } else {
            supports.push(Support::fixed("z0", Component::Z));
        }
        let parts = Parts {
            supports,
            planes,
            ..Parts::default()
        };
        let mut model = Model::<_, Solid>::build(
            mesh,
            NeoHookean {
                mu,
                kappa: 1e4 * mu,
            },
            &parts,
            Settings {
                penalty: 1e5,
                ..Settings::default()
            },
        )
        .unwrap();
        let ctl = |t: f64| Control {
            plane_z: h - 0.1 * h * t,
            ..Control::default()
        };
        run(&mut model, 1.0, 0.25, &ctl);
        *model.records().last().unwrap()
    };
    let rollers = make(false);
    let plates = make(true);
    assert!((plates.plane_force - plates.base_force).abs() < 1e-6 * plates.plane_force);
    // Penetration into the base plate (≈ p h/(penalty G)) shortens the
    // squeeze slightly: agreement to the penalty's order, 1e-4.
    assert!(
        (plates.plane_force / rollers.plane_force - 1.0).abs() < 1e-3,
        "{} vs {}",
        plates.plane_force,
        rollers.plane_force
    );
}

#[test]
fn unsupported_parts_are_rejected_with_clear_errors() {
    let mesh = || Mesh3::structured([1, 1, 1], |i, j, k| [i as f64, j as f64, k as f64]).unwrap();
    let mat = NeoHookean {
        mu: 1.0,
        kappa: 10.0,
    };
    let parts = Parts {
        supports: vec![Support::fixed("x0", Component::R)],
        ..Parts::default()
    };
    let e = Model::<_, Solid>::build(mesh(), mat, &parts, Settings::default()).unwrap_err();
    assert!(e.to_string().contains("support component"), "{e}");
    let parts = Parts {
        probe: Some(SphereProbe {
            radius: 1.0,
            centre_z: 2.0,
            surface: "z1".into(),
        }),
        ..Parts::default()
    };
    let e = Model::<_, Solid>::build(mesh(), mat, &parts, Settings::default()).unwrap_err();
    assert!(e.to_string().contains("probe"), "{e}");
    let parts = Parts {
        planes: vec![RigidPlane::above("top")],
        ..Parts::default()
    };
    let e = Model::<_, Solid>::build(mesh(), mat, &parts, Settings::default()).unwrap_err();
    assert!(e.to_string().contains("no face set named `top`"), "{e}");
}

#[test]
fn parallel_hexahedron_loop_is_bitwise_serial() {
    let run_with = |threads: usize| {
        let mesh = Mesh3::structured([3, 3, 3], |i, j, k| {
            [
                1e-3 * i as f64 / 3.0,
                1e-3 * j as f64 / 3.0,
                0.8e-3 * k as f64 / 3.0,
            ]
        })
        .unwrap();
        let parts = Parts {
            supports: vec![
                Support::fixed("x0", Component::X),
                Support::fixed("y0", Component::Y),
                Support::fixed("z0", Component::Z),
            ],
            planes: vec![RigidPlane::above("z1")],
            ..Parts::default()
        };
        let material =
            nlvid_material::PronyViscoelastic::capsule(1e6, 0.3, (0.5, 0.1), (0.2, 2.0), 1e9)
                .unwrap();
        let settings = Settings {
            threads,
            ..Settings::default()
        };
        let mut model = Model::<_, Solid>::build(mesh, material, &parts, settings).unwrap();
        let ctl = |t: f64| Control {
            plane_z: 0.8e-3 * (1.0 - 0.1 * t),
            ..Control::default()
        };
        run(&mut model, 1.0, 0.25, &ctl);
        model
            .records()
            .iter()
            .map(|r| (r.plane_force, r.iterations))
            .collect::<Vec<_>>()
    };
    assert_eq!(run_with(1), run_with(2));
}
