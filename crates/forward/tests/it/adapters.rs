//! Each adapter's run equals a direct call of the underlying solver set up
//! independently here; bad studies give errors naming file, line and key.

#![allow(clippy::unwrap_used)]

use nlvid_fem::afm::{AfmSetup, Cantilever, Engagement, MeshLayout, MeshSpec};
use nlvid_fem::{FemError, NonConvergence};
use nlvid_forward::{ForwardSettings, ForwardSpec, HertzProny, fem_failure, from_study};
use nlvid_membrane::{ControlKind, Geometry, Loading, PipkinRogersParams, simulate};
use nlvid_model::{FailureKind, ForwardModel};
use nlvid_protocol::{Quantity, programs};
use nlvid_study::Study;

fn study(text: &str) -> Study {
    Study::parse("s.toml", text).unwrap()
}

const HERTZ: &str = r#"
[forward]
model = "hertz-prony"
probe_radius = "2.5 um"
rate = "2 um/s"
ramp = "0.5 s"
hold = "4.5 s"
points = 40
"#;

#[test]
fn hertz_prony_from_study_equals_the_directly_built_model() {
    let mut s = study(HERTZ);
    let model = from_study(&mut s).unwrap();
    s.finish().unwrap();
    let direct = HertzProny::new(2.5e-6, 2e-6, 0.5, 5.0, 40).unwrap();
    let p = [1200.0, 0.3, 0.25, 0.08, 6.0];
    assert_eq!(model.run(&p).unwrap(), direct.run(&p).unwrap());
    assert_eq!(model.time_grid(), direct.time_grid());
    assert_eq!(model.parameter_names(), ["G0", "g1", "g2", "tau1", "tau2"]);
    assert_eq!(model.parameter_units(), ["Pa", "1", "1", "s", "s"]);
    // Every setting is in the identity: change one, the identity changes.
    let mut s2 = study(&HERTZ.replace("4.5 s", "4.6 s"));
    assert_ne!(from_study(&mut s2).unwrap().identity(), model.identity());
}

#[test]
fn test_delay_changes_the_identity_but_not_the_response() {
    let mut s = study(&format!("{HERTZ}test_delay = \"1 ms\"\n"));
    let settings = ForwardSettings::from_study(&mut s).unwrap();
    assert_eq!(settings.test_delay, Some(1e-3));
    let delayed = settings.build().unwrap();
    let plain = from_study(&mut study(HERTZ)).unwrap();
    let p = [1200.0, 0.3, 0.25, 0.08, 6.0];
    assert_eq!(delayed.run(&p).unwrap(), plain.run(&p).unwrap());
    assert_ne!(delayed.identity(), plain.identity());
}

const MEMBRANE: &str = r#"
[forward]
model = "membrane"
radius = "1.5 mm"
wall_thickness = "40 um"
nodes = 48
points = 12

[protocol]
kind = "ramp-hold"
displacement = "0.75 mm"
speed = "1.5 mm/s"
hold = "1 s"
"#;

#[test]
fn membrane_adapter_equals_a_dimensionless_simulation_scaled_by_hand() {
    let mut s = study(MEMBRANE);
    let model = from_study(&mut s).unwrap();
    s.finish().unwrap();
    assert_eq!(
        model.parameter_names(),
        [
            "G10",
            "gamma0",
            "g1_long_term",
            "g2_long_term",
            "tau1",
            "tau2"
        ]
    );
    let (g10, gamma0, g1, g2, tau1, tau2) = (3000.0, 0.1, 0.3, 0.3, 0.5, 0.25);
    let f = model.run(&[g10, gamma0, g1, g2, tau1, tau2]).unwrap();
    let t = model.time_grid().to_vec();
    // 12 points on [0, 1.5] s; the ramp end (0.5 s) is not on it and is added.
    assert_eq!(t.len(), 13);
    assert!(t.iter().any(|&x| (x - 0.5).abs() < 1e-12));

    // Independent path: eq. 2.47 units (G10 = 1, τ1 = 1), D/r0 = 0.5 reached
    // at t0 = 0.5 s / τ1 = 1, hold to t0 = 3; F = F̄ G10 h0 r0.
    let p = PipkinRogersParams {
        g10: 1.0,
        gamma0,
        g1,
        g2,
        c: tau1 / tau2,
        tau1: 1.0,
        a: 0.0,
    };
    let prog = programs::ramp_hold(Quantity::Dimensionless, 0.5, 0.5, 2.0).unwrap();
    let t0: Vec<f64> = t.iter().map(|x| x / tau1).collect();
    let loading = Loading::new(ControlKind::Displacement, prog, t0.clone()).unwrap();
    assert_eq!(loading.times.len(), t0.len());
    let run = simulate(
        &p,
        &Geometry {
            rs: 1.03,
            nodes: 48,
        },
        &loading,
    )
    .unwrap();
    let scale = g10 * 40e-6 * 1.5e-3;
    let peak = f.iter().copied().fold(0.0, f64::max);
    assert!(peak > 0.0);
    for (a, b) in f.iter().zip(run.force()) {
        assert!((a - b * scale).abs() <= 1e-9 * peak, "{a} vs {}", b * scale);
    }
    assert_eq!(f[0], 0.0);
    // Relaxation during the hold.
    assert!(f[f.len() - 1] < f.iter().copied().fold(0.0, f64::max));
}

#[test]
fn membrane_bad_parameters_are_a_typed_failure() {
    let model = from_study(&mut study(MEMBRANE)).unwrap();
    let e = model.run(&[3000.0, 0.1, 0.0, 0.7, 0.5, 2.0]).unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters);
    assert!(e.message.contains("g1"), "{e}");
}

const AFM: &str = r#"
[forward]
model = "afm-fe"
height = "6 um"
diameter = "14 um"
probe_radius = "2.5 um"
spring_constant = "0.12 N/m"
mesh = "coons"
elements_per_side = 6
hold_step_max = "0.5 s"
points = 12

[protocol]
kind = "afm"
engage_force = "0.2 nN"
engage_time = "1 s"
cycle_rates = ["10 um/s"]
depth = "0.5 um"
retract = "0.25 um"
final_rate = "10 um/s"
hold = "1 s"
"#;

fn afm_setup_by_hand() -> AfmSetup {
    let mut s = AfmSetup::thesis_setup1();
    s.height = 6e-6;
    s.diameter = 14e-6;
    s.probe_radius = 2.5e-6;
    s.cantilever = Cantilever::Spring { stiffness: 0.12 };
    s.engagement = Engagement {
        force: 0.2e-9,
        ramp: 1.0,
        hold: 0.0,
    };
    // 0 → 0.5 µm at 10 µm/s, back to 0.25 µm, up to 0.5 µm, hold 1 s.
    s.piezo = vec![
        (0.0, 0.0),
        (0.05, 0.5e-6),
        (0.075, 0.25e-6),
        (0.1, 0.5e-6),
        (1.1, 0.5e-6),
    ];
    s.mesh_layout = MeshLayout::Coons;
    s.mesh = MeshSpec {
        elements_per_side: 6,
        bias: 4.0,
    };
    // bulk_ratio: not in the study, so the fem default (κ/G0 = 200) of
    // thesis_setup1 — the one `nlvid simulate` and `nlvid build` both use.
    s.output_times = (0..12).map(|i| 1.1 * i as f64 / 11.0).collect();
    s.ramp_step_fraction = 0.1;
    s.hold_step_max = 0.5;
    s
}

#[test]
fn afm_fe_setup_from_study_matches_the_setup_written_by_hand() {
    let mut s = study(AFM);
    let settings = ForwardSettings::from_study(&mut s).unwrap();
    s.finish().unwrap();
    let ForwardSpec::AfmFe(spec) = &settings.spec else {
        panic!("not afm-fe")
    };
    let got = spec.setup().unwrap();
    let want = afm_setup_by_hand();
    assert_eq!(got.piezo.len(), want.piezo.len());
    for (a, b) in got.piezo.iter().zip(&want.piezo) {
        assert!(
            (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-18,
            "{a:?} {b:?}"
        );
    }
    for (a, b) in got.output_times.iter().zip(&want.output_times) {
        assert!((a - b).abs() < 1e-12);
    }
    assert_eq!(got.engagement, want.engagement);
    assert_eq!(got.cantilever, want.cantilever);
    assert_eq!(got.mesh, want.mesh);
    assert_eq!(
        (
            got.height,
            got.diameter,
            got.probe_radius,
            got.hold_step_max,
            got.bulk_ratio
        ),
        (
            want.height,
            want.diameter,
            want.probe_radius,
            want.hold_step_max,
            200.0
        )
    );
}

#[test]
fn afm_fe_run_equals_a_direct_fem_call() {
    let model = from_study(&mut study(AFM)).unwrap();
    let (g0, g1, g2, tau1, tau2) = (1000.0, 0.3, 0.2, 0.1, 5.0);
    let f = model.run(&[g0, g1, g2, tau1, tau2]).unwrap();
    let shear = nlvid_model::Relaxation::new(
        "G0",
        g0,
        nlvid_model::Prony::new("G", &[(g1, tau1), (g2, tau2)]).unwrap(),
    )
    .unwrap();
    let direct = nlvid_fem::afm::run(&shear, &afm_setup_by_hand()).unwrap();
    assert_eq!(f.len(), 12);
    let peak = direct.peak_force;
    assert!(peak > 0.2e-9, "peak {peak}");
    for (a, b) in f.iter().zip(&direct.force) {
        assert!((a - b).abs() <= 1e-9 * peak, "{a} vs {b}");
    }
    // Parameters outside the material's domain: a typed failure.
    let e = model.run(&[1000.0, 0.7, 0.6, 0.1, 5.0]).unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters, "{e}");
}

#[test]
fn fem_non_convergence_becomes_not_converged_with_its_time() {
    let e = FemError::NonConvergence(Box::new(NonConvergence {
        time: 0.25,
        dt: 1e-6,
        residual: 1e-3,
        tolerance: 1e-9,
        iterations: 25,
        cause: "iteration limit".into(),
    }));
    let f = fem_failure(&e);
    assert_eq!(f.kind, FailureKind::NotConverged);
    assert_eq!(f.time, Some(0.25));
    assert!(
        f.message.contains("no convergence after t = 2.5"),
        "{}",
        f.message
    );
}

fn err(text: &str) -> String {
    match from_study(&mut study(text)) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_studies_name_file_line_and_key() {
    // Missing key: names the table.
    let e = err(&HERTZ.replace("rate = \"2 um/s\"\n", ""));
    assert!(e.contains("s.toml:2") && e.contains("forward.rate"), "{e}");
    // Wrong unit: line of the key.
    let e = err(&HERTZ.replace("\"2.5 um\"", "\"2.5 s\""));
    assert!(
        e.contains("s.toml:4") && e.contains("forward.probe_radius"),
        "{e}"
    );
    // Unknown model.
    let e = err(&HERTZ.replace("hertz-prony", "abaqus"));
    assert!(e.contains("s.toml:3") && e.contains("forward.model"), "{e}");
    // Unknown key (a typo) in [forward].
    let e = err(&format!("{HERTZ}pionts = 3\n"));
    assert!(
        e.contains("s.toml:9") && e.contains("forward.pionts"),
        "{e}"
    );
    // afm-fe with a plate program instead of the AFM script.
    let e = err(&AFM.replace("kind = \"afm\"", "kind = \"ramp-hold\""));
    assert!(
        e.contains("protocol.kind") || e.contains("protocol."),
        "{e}"
    );
    // afm-fe without a spring constant and without `cantilever = "rigid"`.
    let e = err(&AFM.replace("spring_constant = \"0.12 N/m\"\n", ""));
    assert!(e.contains("forward.spring_constant"), "{e}");
    // membrane: output grid given twice.
    let e = err(&MEMBRANE.replace("hold = \"1 s\"", "hold = \"1 s\"\noutput_points = 5"));
    assert!(e.contains("s.toml:") && e.contains("forward.points"), "{e}");
    // membrane under force control.
    let e = err(&MEMBRANE.replace(
        "displacement = \"0.75 mm\"\nspeed = \"1.5 mm/s\"",
        "control = \"force\"\ntarget = \"1 mN\"\nrate = \"1 mN/s\"",
    ));
    assert!(e.contains("protocol.control"), "{e}");
}

/// `elements_per_side` and `mesh_bias` size the Coons mesh only: without
/// `mesh = "coons"` they are an error naming the graded default, and
/// `mesh_refinement` refines the graded mesh.
#[test]
fn coons_mesh_keys_need_mesh_coons_and_the_graded_mesh_refines() {
    let graded = AFM.replace("mesh = \"coons\"\n", "");
    let mut s = study(&graded);
    let e = ForwardSettings::from_study(&mut s).unwrap_err().to_string();
    assert!(
        e.contains("elements_per_side") && e.contains("mesh = \"coons\""),
        "{e}"
    );

    let refined = graded.replace("elements_per_side = 6\n", "mesh_refinement = 2\n");
    let mut s = study(&refined);
    let settings = ForwardSettings::from_study(&mut s).unwrap();
    let ForwardSpec::AfmFe(spec) = &settings.spec else {
        panic!("not afm-fe")
    };
    let MeshLayout::ContactGraded(got) = spec.setup().unwrap().mesh_layout else {
        panic!("not the graded mesh")
    };
    let MeshLayout::ContactGraded(default) = AfmSetup::thesis_setup1().mesh_layout else {
        panic!("the default mesh is graded")
    };
    assert_eq!(got.core, 2 * default.core);
    assert_eq!(got.spacing, default.spacing / 2.0);
}

/// `geometry = "inputs"`: H and D are parameters 6 and 7 (m); a run at
/// (x, H, D) equals a direct fem call on the setup with that height and
/// diameter written in (and differs from the study's fixed shape).
#[test]
fn afm_fe_geometry_inputs_run_each_shape_and_name_h_and_d() {
    let inputs = AFM
        .replace("height = \"6 um\"\n", "")
        .replace("diameter = \"14 um\"\n", "")
        .replace(
            "model = \"afm-fe\"\n",
            "model = \"afm-fe\"\ngeometry = \"inputs\"\n",
        );
    assert_ne!(inputs, AFM);
    let model = from_study(&mut study(&inputs)).unwrap();
    assert_eq!(
        model.parameter_names(),
        ["G0", "g1", "g2", "tau1", "tau2", "H", "D"]
    );
    assert_eq!(
        model.parameter_units(),
        ["Pa", "1", "1", "s", "s", "m", "m"]
    );
    let c = model.conditions().unwrap();
    assert_eq!((c.cell_height_m, c.cell_diameter_m), (None, None));
    let (g0, g1, g2, tau1, tau2) = (1000.0, 0.3, 0.2, 0.1, 5.0);
    let shear = nlvid_model::Relaxation::new(
        "G0",
        g0,
        nlvid_model::Prony::new("G", &[(g1, tau1), (g2, tau2)]).unwrap(),
    )
    .unwrap();
    let mut setup = afm_setup_by_hand();
    (setup.height, setup.diameter) = (5e-6, 16e-6);
    let direct = nlvid_fem::afm::run(&shear, &setup).unwrap();
    let f = model.run(&[g0, g1, g2, tau1, tau2, 5e-6, 16e-6]).unwrap();
    let peak = direct.peak_force;
    for (a, b) in f.iter().zip(&direct.force) {
        assert!((a - b).abs() <= 1e-9 * peak, "{a} vs {b}");
    }
    let fixed = from_study(&mut study(AFM)).unwrap();
    let f6 = fixed.run(&[g0, g1, g2, tau1, tau2]).unwrap();
    let diff = f
        .iter()
        .zip(&f6)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff > 1e-3 * peak, "another shape, another curve: {diff}");
    assert_ne!(model.identity(), fixed.identity());
    // five parameters, or a bad shape: typed failures
    let e = model.run(&[g0, g1, g2, tau1, tau2]).unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters, "{e}");
    let e = model
        .run(&[g0, g1, g2, tau1, tau2, -5e-6, 16e-6])
        .unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters, "{e}");
    // a fixed height beside geometry = "inputs" is refused, naming the key
    let both = AFM.replace(
        "model = \"afm-fe\"\n",
        "model = \"afm-fe\"\ngeometry = \"inputs\"\n",
    );
    let e = err(&both);
    assert!(
        e.contains("forward.height") && e.contains("design.parameters"),
        "{e}"
    );
}
