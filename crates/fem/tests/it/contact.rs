//! Contact verification against closed forms: Hertz (eq. 1.1, E = 3G,
//! ν = ½), Lee–Radok for a Prony solid, frictionless plate compression of
//! a cylinder, and the cantilever spring (δ = Z − d, F = k d).

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::reference::{NeoHookean, PronyNeoHookean};
use nlvid_fem::{
    Component, Control, Mesh, Model, ProbeDrive, RigidPlane, Settings, SphereProbe, Stage, Support,
};
use nlvid_material::Material3;
use nlvid_model::{Prony, Relaxation};

const R: f64 = 2.5e-6;

/// Half-space stand-in: a block of side `size_over_r · R`, graded toward
/// the contact, indented by a rigid sphere of radius R.
fn block<M: Material3>(material: M, n: usize, size_over_r: f64, bias: f64) -> Model<M> {
    let l = size_over_r * R;
    let mesh = Mesh::graded_block(l, l, n, n, bias).unwrap();
    let probe = SphereProbe {
        radius: R,
        centre_z: l + R,
        surface: "top".into(),
    };
    let supports = [
        Support::fixed("axis", Component::R),
        Support::fixed("base", Component::Z),
    ];
    Model::new(
        mesh,
        material,
        &supports,
        Some(probe),
        None,
        Settings::default(),
    )
    .unwrap()
}

fn hertz(g: f64, delta: f64) -> f64 {
    16.0 / 3.0 * g * R.sqrt() * delta.powf(1.5)
}

fn hertz_errors(n: usize, size_over_r: f64, bias: f64) -> Vec<(f64, f64)> {
    let g = 1e3;
    let mut model = block(
        NeoHookean {
            mu: g,
            kappa: 1e4 * g,
        },
        n,
        size_over_r,
        bias,
    );
    let depth = 0.05 * R;
    let control = |t: f64| Control {
        probe: ProbeDrive::Displacement(-depth * t),
        ..Control::default()
    };
    let mut errors = Vec::new();
    for k in 1..=5 {
        let t = k as f64 / 5.0;
        model
            .run_stage(&Stage {
                name: "indent",
                end: t,
                dt_initial: 0.1,
                dt_max: 0.1,
                control: &control,
            })
            .unwrap();
        let rec = model.records().last().copied().unwrap();
        let delta = -rec.probe_w;
        errors.push((delta / R, rec.contact_force / hertz(g, delta) - 1.0));
        // Global equilibrium: the base carries the probe force.
        let base = model.reaction("base", Component::Z).unwrap();
        assert!(
            (base - rec.contact_force).abs() < 1e-6 * rec.contact_force,
            "{base} vs {}",
            rec.contact_force
        );
        // The penalty lets the probe sink in only a little.
        assert!(
            rec.penetration < 0.01 * delta,
            "penetration {} of δ {}",
            rec.penetration,
            delta
        );
    }
    errors
}

/// Sneddon's exact small-strain force of a rigid sphere (not Hertz's
/// paraboloid) on an elastic half space with plane-strain modulus `e_star`:
/// δ = (a/2) ln((R + a)/(R − a)), F = (E*/2)[(a² + R²) ln((R + a)/(R − a))
/// − 2aR]; a from δ by bisection. Below Hertz by ≈ 0.1 δ/R.
fn sneddon_sphere(e_star: f64, delta: f64) -> f64 {
    let depth = |a: f64| 0.5 * a * ((R + a) / (R - a)).ln();
    let (mut lo, mut hi) = (0.0, 0.999 * R);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if depth(mid) < delta {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let a = 0.5 * (lo + hi);
    0.5 * e_star * ((a * a + R * R) * ((R + a) / (R - a)).ln() - 2.0 * a * R)
}

/// Elastic half space (issue 15): the neo-Hookean quarter disc of radius
/// 200 R around the contact, meshed by `Mesh::contact_graded_half_space`
/// with the default cell mesh parameters, far boundary fixed, κ = 200 G
/// (the cell model's default): the force is within 1 % of the exact
/// small-strain sphere solution for δ/R ≤ 0.05. (Against Hertz's
/// paraboloid, eq. 1.1, the same run is 0.5–1.3 % low: the sphere's own
/// −0.1 δ/R plus finite strain.)
#[test]
fn graded_half_space_matches_the_sphere_solution_within_1_percent() {
    let g = 1e3;
    let ratio = 200.0;
    let l = 200.0 * R;
    let spec = nlvid_fem::ContactMesh::cell_default(R);
    let mesh = Mesh::contact_graded_half_space(l, &spec).unwrap();
    let probe = SphereProbe {
        radius: R,
        centre_z: l + R,
        surface: "surface".into(),
    };
    let supports = [
        Support::fixed("axis", Component::R),
        Support::fixed("outer", Component::R),
        Support::fixed("outer", Component::Z),
    ];
    let material = NeoHookean {
        mu: g,
        kappa: ratio * g,
    };
    let mut model = Model::new(
        mesh,
        material,
        &supports,
        Some(probe),
        None,
        Settings::default(),
    )
    .unwrap();
    let nu = (3.0 * ratio - 2.0) / (2.0 * (3.0 * ratio + 1.0));
    let e_star = 2.0 * g / (1.0 - nu);
    let depth = 0.05 * R;
    let control = |t: f64| Control {
        probe: ProbeDrive::Displacement(-depth * t),
        ..Control::default()
    };
    let mut worst: f64 = 0.0;
    for k in 1..=10 {
        let t = k as f64 / 10.0;
        model
            .run_stage(&Stage {
                name: "indent",
                end: t,
                dt_initial: 0.1,
                dt_max: 0.1,
                control: &control,
            })
            .unwrap();
        let rec = model.records().last().copied().unwrap();
        let delta = -rec.probe_w;
        let e = rec.contact_force / sneddon_sphere(e_star, delta) - 1.0;
        let hertz = 4.0 / 3.0 * e_star * R.sqrt() * delta.powf(1.5);
        eprintln!(
            "δ/R = {:.4}: vs sphere {:+.3} %, vs Hertz {:+.3} %",
            delta / R,
            100.0 * e,
            100.0 * (rec.contact_force / hertz - 1.0)
        );
        worst = worst.max(e.abs());
    }
    assert!(worst < 0.01, "worst {worst}");
}

/// The finer Hertz check that session 1 had to drop: its first Newton
/// iteration started at a round-off-level residual and the line search
/// rejected every step (fixed: the round-off acceptance now applies at the
/// first iteration). 6400 elements: run it in release,
/// `cargo test -p nlvid-fem --release --test it contact::hertz_fine -- --ignored`.
#[test]
#[ignore = "6400 elements, ≈ 2.5 min in release on the loaded machine"]
fn hertz_fine_mesh_within_3_percent() {
    let errors = hertz_errors(80, 60.0, 1500.0);
    eprintln!("Hertz, 80×80 (δ/R, relative error): {errors:.4?}");
    for &(d, e) in &errors {
        assert!(e.abs() < 0.03, "δ/R = {d}: error {e:+.4}");
    }
}

#[test]
fn lee_radok_ramp_hold_within_3_percent() {
    // G(t) = G0 (0.4 + 0.3 e^{−t/0.5} + 0.3 e^{−t/10}); ramp to δ0 = 0.05 R
    // in 1 s, hold to 12 s. Lee–Radok: F = 16/3 √R ∫ G(t−s) d(δ^{3/2})/ds ds.
    let g0 = 1e3;
    let relax = Relaxation::new(
        "G0",
        g0,
        Prony::new("G", &[(0.3, 0.5), (0.3, 10.0)]).unwrap(),
    )
    .unwrap();
    let material = PronyNeoHookean::new(relax.clone(), 1e4 * g0).unwrap();
    let mut model = block(material, 40, 40.0, 250.0);
    let (t_ramp, t_end, d0) = (1.0, 12.0, 0.05 * R);
    let delta = move |t: f64| d0 * (t / t_ramp).min(1.0);
    let control = |t: f64| Control {
        probe: ProbeDrive::Displacement(-delta(t)),
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "ramp",
            end: t_ramp,
            dt_initial: 0.05,
            dt_max: 0.05,
            control: &control,
        })
        .unwrap();
    model
        .run_stage(&Stage {
            name: "hold",
            end: t_end,
            dt_initial: 0.02,
            dt_max: 0.5,
            control: &control,
        })
        .unwrap();
    // Reference by an independent quadrature (midpoint, 20000 intervals).
    let lee_radok = |t: f64| {
        let n = 20000;
        let s_end = t.min(t_ramp);
        let h = s_end / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            let s = (i as f64 + 0.5) * h;
            let rate = 1.5 * d0.powf(1.5) * s.sqrt() / t_ramp.powf(1.5);
            sum += relax.value(t - s) * rate * h;
        }
        16.0 / 3.0 * R.sqrt() * sum
    };
    let mut worst: f64 = 0.0;
    for rec in model.records().iter().filter(|r| r.time >= t_ramp - 1e-12) {
        let e = rec.contact_force / lee_radok(rec.time) - 1.0;
        worst = worst.max(e.abs());
    }
    assert!(worst < 0.03, "worst relative error over the hold {worst}");
}

#[test]
fn frictionless_plate_compression_matches_homogeneous_neo_hookean() {
    // A short cylinder on a frictionless base, squeezed by a rigid plate:
    // homogeneous uniaxial stress, |F| = μ (λ⁻² − λ) π a² (incompressible).
    let (a, h, mu) = (5e-6, 4e-6, 1e3);
    let mesh = Mesh::graded_block(a, h, 4, 4, 1.0).unwrap();
    let supports = [
        Support::fixed("axis", Component::R),
        Support::fixed("base", Component::Z),
    ];
    let plane = RigidPlane::above("top");
    let mut model = Model::new(
        mesh,
        NeoHookean {
            mu,
            kappa: 1e5 * mu,
        },
        &supports,
        None,
        Some(plane),
        Settings {
            penalty: 1e4,
            ..Settings::default()
        },
    )
    .unwrap();
    let squeeze = 0.2 * h;
    let control = |t: f64| Control {
        plane_z: h - squeeze * t,
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "squeeze",
            end: 1.0,
            dt_initial: 0.1,
            dt_max: 0.1,
            control: &control,
        })
        .unwrap();
    let top_z = h + model.displacements().last().map(|u| u[1]).unwrap();
    let lambda = top_z / h;
    let exact = mu * (1.0 / (lambda * lambda) - lambda) * std::f64::consts::PI * a * a;
    let fe = model.records().last().unwrap().plane_force;
    assert!(
        (fe / exact - 1.0).abs() < 2e-3,
        "FE {fe} vs {exact} at λ = {lambda}"
    );
    assert!(
        lambda < 0.81,
        "plate should have compressed the cylinder by ≈ 20 %: λ = {lambda}"
    );
}

/// Runs the block under a piezo ramp with a spring, or with the probe
/// displacement prescribed; returns (time, w, free end, force) per step.
fn ramp_run(spring: Option<f64>, depth: f64, dt: f64) -> (Vec<(f64, f64, f64, f64)>, f64) {
    let g = 1e3;
    let mut model = block(
        NeoHookean {
            mu: g,
            kappa: 1e3 * g,
        },
        16,
        20.0,
        60.0,
    );
    let control = |t: f64| Control {
        probe: match spring {
            Some(k) => ProbeDrive::Spring {
                stiffness: k,
                free_end: -depth * t,
            },
            None => ProbeDrive::Displacement(-depth * t),
        },
        ..Control::default()
    };
    model
        .run_stage(&Stage {
            name: "ramp",
            end: 1.0,
            dt_initial: dt,
            dt_max: dt,
            control: &control,
        })
        .unwrap();
    let base = model.reaction("base", Component::Z).unwrap();
    let recs = model
        .records()
        .iter()
        .map(|r| (r.time, r.probe_w, r.free_end, r.contact_force))
        .collect();
    (recs, base)
}

#[test]
fn soft_cantilever_force_follows_rigid_curve_at_delta_z_minus_d() {
    // Soft spring: k comparable to the contact stiffness 2aE* ≈ 5e-3 N/m.
    let k = 2e-3;
    let depth = 0.12 * R;
    let (spring, base) = ramp_run(Some(k), depth, 0.05);
    // The rigid curve F(δ) finely sampled (kinks where nodes engage).
    let (rigid, _) = ramp_run(None, depth, 0.005);
    let last = *spring.last().unwrap();
    // Equilibrium of the probe: spring force = contact reaction, and the
    // base carries it (global equilibrium), to 1e-6.
    let f_spring = k * (last.1 - last.2);
    assert!(
        (f_spring - last.3).abs() < 1e-6 * last.3,
        "{f_spring} vs {}",
        last.3
    );
    assert!(
        (base - last.3).abs() < 1e-6 * last.3,
        "{base} vs {}",
        last.3
    );
    // The spring run indents less than the piezo travel by d = F/k …
    let d = f_spring / k;
    let z = -last.2;
    assert!(
        d > 0.2 * z,
        "the spring should take a sizeable share: d = {d}, Z = {z}"
    );
    // … and its force at δ = Z − d equals the rigid run's force at that δ.
    let rigid_delta: Vec<f64> = rigid.iter().map(|r| -r.1).collect();
    let rigid_force: Vec<f64> = rigid.iter().map(|r| r.3).collect();
    for s in spring.iter().skip(5) {
        let delta = -s.2 - k.recip() * s.3;
        let f_rigid = nlvid_fem::afm::interpolate(&rigid_delta, &rigid_force, delta);
        assert!(
            (s.3 / f_rigid - 1.0).abs() < 0.01,
            "δ = {delta}: spring {} vs rigid {f_rigid}",
            s.3
        );
        assert!(
            (delta + s.1).abs() < 1e-6 * delta,
            "δ = Z − d = {delta} must equal the probe travel {}",
            -s.1
        );
    }
}

/// Residual tolerances at near-zero forces (issue 15): a 1e-15…1e-8 m
/// indentation loads the body by forces of 1e-33…1e-11 N, where a
/// tolerance relative to the force itself asks for a residual below the
/// round-off of the near-incompressible pressure (≈ ε K per unit area).
/// With the floor 32 ε K L² on stagnation every bulk ratio converges (the
/// old rule failed at κ/G = 100, δ = 1e-15 m, "tolerance 8.9e-27 N"), the
/// force grows with the depth, and above the floor it barely depends on κ
/// (near incompressible).
#[test]
fn tiny_indentations_converge_at_any_bulk_ratio() {
    let g = 1e3;
    let l = 20.0 * R;
    let mut slopes = Vec::new();
    for ratio in [1e2, 1e4, 1e6] {
        let mut model = block(
            NeoHookean {
                mu: g,
                kappa: ratio * g,
            },
            8,
            20.0,
            20.0,
        );
        let floor = 32.0 * f64::EPSILON * (ratio + 4.0 / 3.0) * g * l * l;
        let depths = [1e-15, 1e-13, 1e-11, 1e-9, 1e-8];
        let mut forces = Vec::new();
        let mut previous = 0.0;
        for (k, depth) in depths.into_iter().enumerate() {
            // From the previous depth to this one over the stage.
            let control = move |t: f64| Control {
                probe: ProbeDrive::Displacement(
                    -(previous + (depth - previous) * (t - k as f64).clamp(0.0, 1.0)),
                ),
                ..Control::default()
            };
            previous = depth;
            model
                .run_stage(&Stage {
                    name: "tiny",
                    end: (k + 1) as f64,
                    dt_initial: 1.0,
                    dt_max: 1.0,
                    control: &control,
                })
                .unwrap_or_else(|e| panic!("κ/G = {ratio:e}, δ = {depth:e}: {e}"));
            forces.push(model.records().last().unwrap().contact_force);
        }
        eprintln!("κ/G = {ratio:e}: forces {forces:?}, floor {floor:.2e} N");
        assert!(forces.windows(2).all(|w| w[1] > w[0]), "{forces:?}");
        assert!(forces[4] > 100.0 * floor);
        slopes.push(forces[4] / depths[4]);
    }
    // Near-incompressible: the contact stiffness barely depends on κ.
    assert!((slopes[2] / slopes[1] - 1.0).abs() < 0.01, "{slopes:?}");
    assert!((slopes[1] / slopes[0] - 1.0).abs() < 0.02, "{slopes:?}");
}
