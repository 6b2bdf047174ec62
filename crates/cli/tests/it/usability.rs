//! What a new user runs into (issue 13), one test each: JSON outputs that
//! name their quantities and carry units, outputs next to the study, the
//! old study keys, and a closed stdout (`nlvid … | head`).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::io::Read as _;
use std::path::Path;
use std::process::{Command, Stdio};

use crate::common;
use common::{nlvid, scratch, text};

const FD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../afm/tests/data/fmt-jpk-fd_spot3-0192.jpk-force"
);
const RESULTS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../stats/tests/data/results_example.csv"
);

fn json(args: &[&str]) -> serde_json::Value {
    let out = nlvid(args);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn write(dir: &Path, name: &str, body: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p.to_str().unwrap().to_string()
}

/// Sites of a 2-input table and responses `f` at them, as CSV bodies.
fn xy(f: impl Fn(f64, f64) -> [f64; 2]) -> (String, String) {
    let (mut x, mut y) = (String::from("a,b\n"), String::from("early_N,late_N\n"));
    for i in 0..12 {
        let (a, b) = (i as f64 / 11.0, ((i * 7) % 12) as f64 / 11.0);
        let v = f(a, b);
        x.push_str(&format!("{a},{b}\n"));
        y.push_str(&format!("{},{}\n", v[0], v[1]));
    }
    (x, y)
}

fn fit(dir: &Path, tag: &str, f: impl Fn(f64, f64) -> [f64; 2]) -> serde_json::Value {
    let (x, y) = xy(f);
    let (xp, yp) = (
        write(dir, "x.csv", &x),
        write(dir, &format!("y{tag}.csv"), &y),
    );
    let model = dir.join(format!("m{tag}.json"));
    json(&[
        "--json",
        "surrogate",
        "fit",
        "--x",
        &xp,
        "--y",
        &yp,
        "--theta",
        "1,1",
        "--out",
        model.to_str().unwrap(),
    ])
}

/// `surrogate predict --json` names the outputs by the Y header the model
/// was fitted on (the CSV too), not `y_0 …`; Kriging interpolates, so at a
/// site the prediction is the data.
#[test]
fn predict_json_names_the_outputs() {
    let dir = scratch("predict-names");
    fit(&dir, "", |a, b| [a + b * b, (3.0 * a).sin()]);
    let x = write(&dir, "p.csv", "a,b\n0,0\n");
    let model = dir.join("m.json");
    let v = json(&[
        "--json",
        "surrogate",
        "predict",
        model.to_str().unwrap(),
        "--x",
        &x,
    ]);
    assert_eq!(v["outputs"], serde_json::json!(["early_N", "late_N"]));
    let y = &v["points"][0]["y"];
    assert!(y["early_N"].as_f64().unwrap().abs() < 1e-6, "{y}");
    let out = nlvid(&[
        "surrogate",
        "predict",
        model.to_str().unwrap(),
        "--x",
        &x,
        "--mse",
    ]);
    assert!(text(&out.stdout).starts_with("early_N,late_N,mse_early_N,mse_late_N\n"));
}

/// `surrogate fit` reports the trend β and the process variance σ² in the
/// outputs' units: exactly linear data give back their own coefficients
/// (GLS reproduces a linear function), and scaling Y by c scales β by c and
/// σ² by c² (the file's standardised σ² does not change).
#[test]
fn fit_reports_beta_and_sigma2_in_output_units() {
    let dir = scratch("fit-units");
    let v = fit(&dir, "lin", |a, b| [3.0 + 2.0 * a - 0.5 * b, 1.0 + a]);
    let beta = v["beta"].as_array().unwrap();
    let terms: Vec<&str> = beta.iter().map(|t| t["term"].as_str().unwrap()).collect();
    assert_eq!(terms, ["1", "a", "b"]);
    for (t, want) in beta.iter().zip([3.0, 2.0, -0.5]) {
        let got = t["coefficients"][0].as_f64().unwrap();
        assert!((got - want).abs() < 1e-9, "{}: {got} vs {want}", t["term"]);
    }
    let f = |a: f64, b: f64| [(3.0 * a).sin() + b, a * b];
    let (v1, v2) = (
        fit(&dir, "1", f),
        fit(&dir, "2", |a, b| f(a, b).map(|y| 1e3 * y)),
    );
    for j in 0..2 {
        let (s1, s2) = (
            v1["sigma2"][j].as_f64().unwrap(),
            v2["sigma2"][j].as_f64().unwrap(),
        );
        assert!(
            s1 > 0.0 && ((s2 / s1) / 1e6 - 1.0).abs() < 1e-9,
            "{s1} {s2}"
        );
        let (b1, b2) = (
            v1["beta"][1]["coefficients"][j].as_f64().unwrap(),
            v2["beta"][1]["coefficients"][j].as_f64().unwrap(),
        );
        assert!((b2 / b1 / 1e3 - 1.0).abs() < 1e-9, "{b1} {b2}");
    }
}

/// `inspect --json --samples` carries every sample; without it, only ranges.
#[test]
fn inspect_json_can_include_the_samples() {
    let v = json(&["--json", "inspect", FD, "--samples"]);
    let seg = &v["segments"][0];
    assert_eq!(seg["points"], 2000);
    assert_eq!(seg["time_s"].as_array().unwrap().len(), 2000);
    let ch = &seg["channels"][0];
    let values = ch["values"].as_array().unwrap();
    assert_eq!(values.len(), 2000);
    let min = values
        .iter()
        .map(|x| x.as_f64().unwrap())
        .fold(f64::INFINITY, f64::min);
    assert_eq!(min, ch["min"].as_f64().unwrap());
    let v = json(&["--json", "inspect", FD]);
    assert!(v["segments"][0]["time_s"].is_null());
    assert!(v["segments"][0]["channels"][0]["values"].is_null());
}

const HERTZ: &str = r#"
[forward]
model = "hertz-prony"
probe_radius = "5 um"
rate = "1 um/s"
ramp = "1 s"
hold = "1 s"
points = 20
"#;

/// `simulate --json` has provenance, parameters with units and the curve,
/// like `material --json`; an elastic cell (g1 = g2 = 0) on the ramp is
/// Hertz, F = (16/3) G0 √R δ^{3/2} with δ = rate·t (eq. 1.1, E = 3G0).
#[test]
fn simulate_json_has_the_curve_and_provenance() {
    let dir = scratch("simulate-json");
    let study = write(
        &dir,
        "cell.toml",
        &format!(
            "{HERTZ}[parameters]\nG0 = \"2 kPa\"\ng1 = 0\ng2 = 0\ntau1 = \"1 s\"\ntau2 = \"5 s\"\n"
        ),
    );
    let v = json(&["--json", "simulate", &study]);
    assert_eq!(v["provenance"]["study"], study);
    assert_eq!(v["provenance"]["study_sha256"].as_str().unwrap().len(), 64);
    assert_eq!(v["parameters"]["G0_Pa"], 2000.0);
    assert_eq!(v["parameters"]["tau2_s"], 5.0);
    let t = v["curve"]["time_s"].as_array().unwrap();
    let f = v["curve"]["force_N"].as_array().unwrap();
    assert_eq!((t.len(), f.len()), (20, 20));
    for (t, f) in t.iter().zip(f) {
        let (t, f) = (t.as_f64().unwrap(), f.as_f64().unwrap());
        if t <= 1.0 {
            let hertz = 16.0 / 3.0 * 2000.0 * 5e-6f64.sqrt() * (1e-6 * t).powf(1.5);
            assert!((f - hertz).abs() <= 1e-6 * hertz, "t = {t}: {f} vs {hertz}");
        }
    }
    // Default output next to the study.
    assert!(dir.join("cell.simulate.csv").is_file());
}

/// The former simulate keys are errors naming the key to use.
#[test]
fn old_simulate_keys_name_the_new_ones() {
    let dir = scratch("simulate-old");
    let study = write(
        &dir,
        "old.toml",
        &format!("{HERTZ}[cantilever]\nk = \"0.1 N/m\"\n"),
    );
    let out = nlvid(&["simulate", &study]);
    assert_eq!(out.status.code(), Some(1));
    let e = text(&out.stderr);
    assert!(
        e.contains("old.toml") && e.contains("`spring_constant`"),
        "{e}"
    );
}

/// `membrane` writes next to the study (`<stem>.membrane/`), never into
/// the current directory, and its JSON keys carry units.
#[test]
fn membrane_writes_next_to_the_study_with_unit_keys() {
    let dir = scratch("membrane-out");
    let cwd = dir.join("cwd");
    std::fs::create_dir_all(&cwd).unwrap();
    let study = write(
        &dir,
        "capsule.toml",
        r#"
[forward]
model = "membrane"
radius = "1.5 mm"
wall_thickness = "40 um"
nodes = 48
points = 6

[protocol]
kind = "ramp-hold"
displacement = "0.3 mm"
speed = "5 mm/s"
hold = "0.5 s"

[parameters]
G10 = "3 kPa"
gamma0 = 0.1
g1_long_term = 0.5
g2_long_term = 0.5
tau1 = "0.1 s"
tau2 = "2 s"
"#,
    );
    let out = Command::new(env!("CARGO_BIN_EXE_nlvid"))
        .args(["--json", "membrane", &study])
        .current_dir(&cwd)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let out_dir = dir.join("capsule.membrane");
    assert!(out_dir.join("history.csv").is_file());
    assert_eq!(std::fs::read_dir(&cwd).unwrap().count(), 0);
    assert_eq!(v["parameters"]["G10_Pa"], 3000.0);
    let fin = &v["final"];
    for key in [
        "time_s",
        "displacement_m",
        "force_N",
        "pressure_Pa",
        "contact_angle_rad",
    ] {
        assert!(fin[key].is_number(), "{key}: {fin}");
    }
    // End of the hold, plate at 0.3 mm, compressive force.
    assert!((fin["time_s"].as_f64().unwrap() - 0.56).abs() < 1e-12);
    assert!((fin["displacement_m"].as_f64().unwrap() - 3e-4).abs() < 1e-12);
    assert!(fin["force_N"].as_f64().unwrap() > 0.0);
}

/// A command whose stdout is closed early (`nlvid … | head`) ends quietly:
/// exit status 0, no panic, no "Broken pipe" on stderr.
#[test]
fn a_closed_stdout_ends_quietly() {
    let runs: [&[&str]; 3] = [
        &["--json", "inspect", FD, "--samples"],
        &["inspect", FD],
        &[
            "compare",
            RESULTS,
            "--out-dir",
            "cli-broken-pipe",
            "--points",
            "400",
        ],
    ];
    let dir = scratch("broken-pipe");
    for args in runs {
        let mut child = Command::new(env!("CARGO_BIN_EXE_nlvid"))
            .args(args)
            .current_dir(&dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let mut err = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        let status = child.wait().unwrap();
        assert!(status.success(), "{args:?}: {status}: {err}");
        assert!(
            !err.contains("Broken pipe") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}
