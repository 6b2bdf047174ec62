//! The `capsule-fe` forward model (thesis ch. IV, §4.2–4.3): read from the
//! one study schema, the force is exactly proportional to C1 (displacement
//! control; bulk modulus and contact penalty scale with the modulus), the
//! fluid volume is conserved, and bad input is a clear error or a flagged
//! output. Coarse meshes (0.6 mm, 2 layers) keep every run well under a
//! second in release; the default mesh is measured in docs/theory/fem.md.

#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use nlvid_forward::{CapsuleFeSpec, ForwardSettings, ForwardSpec, from_study};
use nlvid_model::{Domain, FailureKind, ForwardModel, names};
use nlvid_protocol::{Quantity, programs};
use nlvid_study::Study;

fn study(text: &str) -> Study {
    Study::parse("s.toml", text).unwrap()
}

/// The thesis's RH test at d = 1.5 mm (§4.2) on the capsule of §4.3.
const RH: &str = r#"
[forward]
model = "capsule-fe"
axes = ["9.96 mm", "6.51 mm", "6.51 mm"]
wall_thickness = ["0.62 mm", "0.4 mm", "0.4 mm"]
points = 1200

[protocol]
kind = "ramp-hold"
target = "1.5 mm"
rate = "5 mm/s"
hold = "10 s"
"#;

/// A coarse capsule and a short RH test (1 mm at 5 mm/s, 0.4 s hold).
fn coarse(protocol: &str) -> String {
    format!(
        r#"
[forward]
model = "capsule-fe"
axes = ["9.96 mm", "6.51 mm", "6.51 mm"]
wall_thickness = ["0.62 mm", "0.4 mm", "0.4 mm"]
element_size = "0.6 mm"
layers = 2
min_steps = 8
points = 25

[protocol]
{protocol}
"#
    )
}

const SHORT_RH: &str = r#"kind = "ramp-hold"
target = "1 mm"
rate = "5 mm/s"
hold = "0.4 s""#;

/// §4.4.3's RH set in nlvid's order (C1, α, g1, g2, τ1, τ2).
const SET: [f64; 6] = [21.2546e6, 0.3720, 0.7674, 0.1546, 0.0623, 1.3936];

#[test]
fn capsule_fe_from_study_is_the_thesis_capsule_and_the_rh_program() {
    let mut s = study(RH);
    let settings = ForwardSettings::from_study(&mut s).unwrap();
    s.finish().unwrap();
    let program = programs::ramp_hold(Quantity::Displacement, 1.5e-3, 5e-3, 10.0).unwrap();
    assert_eq!(
        settings.spec,
        ForwardSpec::CapsuleFe(CapsuleFeSpec::thesis(program, 1200))
    );
    let model = settings.build().unwrap();
    assert_eq!(model.parameter_names(), names::CAPSULE);
    assert_eq!(model.parameter_units(), ["Pa", "1", "1", "1", "s", "s"]);
    // Table 4.1's domain speaks the model's names, in its order.
    Domain::table_4_1(0.01)
        .unwrap()
        .check_names(&model.parameter_names())
        .unwrap();
    let t = model.time_grid();
    assert_eq!(t.len(), 1200);
    assert_eq!((t[0], t[1199]), (0.0, 0.3 + 10.0));
    // Every setting enters the identity (and so the study hash).
    let mut s2 = study(&RH.replace("points = 1200", "points = 1200\nelement_size = \"0.4 mm\""));
    assert_ne!(from_study(&mut s2).unwrap().identity(), model.identity());
}

#[test]
fn force_is_proportional_to_c1_and_the_fluid_volume_is_conserved() {
    let model = match ForwardSettings::from_study(&mut study(&coarse(SHORT_RH)))
        .unwrap()
        .spec
    {
        ForwardSpec::CapsuleFe(spec) => spec.build().unwrap(),
        other => panic!("{other:?}"),
    };
    let (curve, notes) = model.run_curve(&SET).unwrap();
    let f = curve.values("force").unwrap();
    let peak = f.iter().copied().fold(0.0, f64::max);
    assert_eq!(f[0], 0.0, "undeformed at t = 0");
    assert!(peak > 1.0 && peak < 20.0, "peak {peak} N");
    // The hold relaxes: the last force is below the peak by more than g∞.
    assert!(f[f.len() - 1] < 0.5 * peak);
    // Incompressible oil: the whole capsule's fluid volume never changes.
    let v = curve.values("volume").unwrap();
    assert!(v.iter().all(|x| (x / v[0] - 1.0).abs() < 1e-9), "{v:?}");
    // At the peak the plate presses a patch; both areas see it.
    let k = f.iter().position(|&x| x == peak).unwrap();
    let (ellipse, pressed) = (
        curve.values("ellipse_area").unwrap()[k],
        curve.values("pressure_area").unwrap()[k],
    );
    assert!(ellipse > 1e-6 && pressed > 1e-6, "{ellipse} {pressed}");
    assert_eq!(curve.values("contact_area").unwrap()[k], ellipse);
    assert_eq!(curve.values("in_contact").unwrap()[k], 1.0);
    assert!(
        notes.iter().all(|n| !n.contains("lost the capsule")),
        "{notes:?}"
    );
    // Displacement control with the wall's bulk modulus and the contact
    // penalty ∝ G0: doubling C1 doubles every force, to round-off.
    let mut twice = SET;
    twice[0] *= 2.0;
    let f2 = model.run(&twice).unwrap();
    let worst = f
        .iter()
        .zip(&f2)
        .map(|(a, b)| (b - 2.0 * a).abs() / (2.0 * peak))
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "F(2 C1) − 2 F(C1): {worst:e} of the peak");
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nlvid-capsule-fe-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn bad_plate_input_is_a_clear_error_or_a_flagged_output() {
    let dir = temp_dir("bad");
    let table = |rows: &str| -> Result<Box<dyn ForwardModel>, String> {
        std::fs::write(
            dir.join("plate.csv"),
            format!("time_s,displacement_mm\n{rows}"),
        )
        .unwrap();
        let path = dir.join("s.toml");
        let text = coarse("kind = \"table\"\nfile = \"plate.csv\"");
        std::fs::write(&path, &text).unwrap();
        let mut s = Study::load(&path).unwrap();
        from_study(&mut s).map_err(|e| e.to_string())
    };
    // A measured table whose time goes back: the file and its line.
    let e = table("0,0\n0.1,0.5\n0.05,0.6\n0.5,0.6\n").err().unwrap();
    assert!(e.contains("plate.csv") && e.contains("line 4"), "{e}");
    // A plate that crushes the capsule past its walls (height 6.51 mm,
    // two walls of 0.4 mm at the poles): refused when the model is built,
    // before any run.
    let crush =
        coarse("kind = \"ramp-hold\"\ntarget = \"6 mm\"\nrate = \"5 mm/s\"\nhold = \"1 s\"");
    let e = from_study(&mut study(&crush)).err().unwrap().to_string();
    assert!(e.contains("crush") && e.contains("6.0000 mm"), "{e}");
    // A plate that starts pressed.
    let e = table("0,0.2\n0.5,0.2\n").err().unwrap();
    assert!(e.contains("starts pressed"), "{e}");
    // A plate that loses the capsule: squeeze 1 mm, then retract 0.3 mm
    // past the undeformed top — flagged in the curve and the notes.
    let model = table("0,0\n0.2,1\n0.4,-0.3\n0.6,-0.3\n").unwrap();
    let f = model.run(&SET).unwrap();
    assert!(f.iter().copied().fold(0.0, f64::max) > 1.0);
    assert_eq!(f[f.len() - 1], 0.0);
    let spec = match ForwardSettings::from_study(&mut Study::load(dir.join("s.toml")).unwrap())
        .unwrap()
        .spec
    {
        ForwardSpec::CapsuleFe(spec) => spec,
        other => panic!("{other:?}"),
    };
    let (curve, notes) = spec.build().unwrap().run_curve(&SET).unwrap();
    let contact = curve.values("in_contact").unwrap();
    assert_eq!(contact[contact.len() - 1], 0.0);
    assert!(
        notes.iter().any(|n| n.contains("lost the capsule")),
        "{notes:?}"
    );
    // A wall too thick for the curvature would fold the mesh inside out
    // (inverted elements): refused, naming the rule.
    let folded = coarse(SHORT_RH).replace("\"0.62 mm\", \"0.4 mm\"", "\"0.62 mm\", \"2.5 mm\"");
    let e = from_study(&mut study(&folded)).err().unwrap().to_string();
    assert!(e.contains("radius of curvature"), "{e}");
    // Parameters the material refuses: named, typed.
    let model = from_study(&mut study(&coarse(SHORT_RH))).unwrap();
    let e = model.run(&SET[..5]).unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters);
    assert!(e.message.contains("6 parameters"), "{e}");
    let e = model.run(&[20e6, 0.1, 0.8, 0.3, 0.1, 2.0]).unwrap_err();
    assert_eq!(e.kind, FailureKind::InvalidParameters, "{e}");
    // Wrong shapes in the study: three lengths, with units.
    let e = from_study(&mut study(&RH.replace(
        "[\"0.62 mm\", \"0.4 mm\", \"0.4 mm\"]",
        "[\"0.62 mm\", \"0.4 mm\"]",
    )))
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("forward.wall_thickness") && e.contains("three lengths"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
