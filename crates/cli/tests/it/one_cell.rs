//! One physical cell through every path of the pipeline (issue 13): the
//! same study values — G0 = 1 kPa (the shear modulus G(0)), g = (0.4, 0.3),
//! τ = (0.5 s, 10 s) — given to `nlvid material`, `nlvid simulate`,
//! `nlvid build` + `nlvid fit`, and `nlvid cohort`, must come back as the
//! same relaxation modulus G(t) of eq. 5.1 from each.
//!
//! The references are written here, independently of the code under test:
//! eq. 5.1 in closed form, its average over a ramp, and the Lee–Radok
//! (Hertz) ramp-hold force by quadrature. A path that read G0 as the
//! Mooney–Rivlin C1 (the factor-2 error this issue removed) is off by 100 %
//! and fails every check below.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use crate::common;

use common::{nlvid, scratch, text};
use std::path::Path;

/// Shear modulus G(0) (Pa), Prony weights g_k and times τ_k (s).
const G0: f64 = 1000.0;
const G: [f64; 2] = [0.4, 0.3];
const TAU: [f64; 2] = [0.5, 10.0];

/// Probe radius (m), indentation rate (m/s), ramp duration (s), and the
/// cantilever spring (N/m) of the AFM-style paths (the demo's protocol).
const RADIUS: f64 = 2.5e-6;
const RATE: f64 = 2e-6;
const RAMP: f64 = 1.0;
const SPRING: f64 = 0.12;

/// The times at which the fits report G(t) (s).
const MODULUS_TIMES: [f64; 6] = [0.5, 1.0, 2.0, 5.0, 10.0, 52.0];

/// Eq. 5.1: G(t) = G0 [1 − Σ g_k (1 − e^{−t/τ_k})].
fn relaxation(t: f64) -> f64 {
    G0 * (1.0
        - G.iter()
            .zip(TAU)
            .map(|(g, tau)| g * (1.0 - (-t / tau).exp()))
            .sum::<f64>())
}

/// ∫₀ᵗ G(s) ds in closed form.
fn relaxation_integral(t: f64) -> f64 {
    G0 * (t - G
        .iter()
        .zip(TAU)
        .map(|(g, tau)| g * (t - tau * (1.0 - (-t / tau).exp())))
        .sum::<f64>())
}

/// σ12/γ after a linear shear ramp of duration `ramp` (small strain):
/// (1/t_r) ∫_{t−t_r}^{t} G(s) ds for t ≥ t_r.
fn ramp_averaged_relaxation(t: f64, ramp: f64) -> f64 {
    (relaxation_integral(t) - relaxation_integral(t - ramp)) / ramp
}

/// Indentation δ(t) of the ramp-hold (m).
fn indentation(t: f64) -> f64 {
    RATE * t.clamp(0.0, RAMP)
}

/// Lee–Radok force of a rigid sphere on an incompressible linear
/// viscoelastic half space (eq. 5.2 with ν = 1/2):
/// F(t) = (16 √R / 3) ∫₀ᵗ G(t − s) d[δ(s)^{3/2}]. With s = u² on the ramp,
/// d(δ^{3/2}) = 3 v^{3/2} u² du: composite Simpson on a smooth integrand.
fn lee_radok_force(t: f64) -> f64 {
    let upper = t.min(RAMP).sqrt();
    let n = 4000;
    let h = upper / n as f64;
    let f = |u: f64| relaxation(t - u * u) * u * u;
    let mut sum = f(0.0) + f(upper);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(i as f64 * h);
    }
    16.0 * RADIUS.sqrt() / 3.0 * 3.0 * RATE.powf(1.5) * sum * h / 3.0
}

fn ok(out: &std::process::Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed:\nstdout: {}\nstderr: {}",
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

fn run_in(dir: &Path, args: &[&str]) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nlvid"))
        .args(args)
        .current_dir(dir)
        .env_remove("NLVID_LOG")
        .output()
        .expect("run nlvid");
    ok(&out, &args.join(" "))
}

fn relative(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The `[forward]` section every AFM-style path shares (the demo's).
const FORWARD: &str = r#"
[forward]
model = "hertz-prony"
probe_radius = "2.5 um"
rate = "2 um/s"
ramp = "1 s"
hold = "51 s"
points = 520
"#;

/// The cell's values as `[parameters]`.
const PARAMETERS: &str = r#"
[parameters]
G0 = "1 kPa"
g1 = 0.4
g2 = 0.3
tau1 = "0.5 s"
tau2 = "10 s"
"#;

/// `nlvid material`: the cell model (`neo-hookean-prony`) in simple shear,
/// γ = 1e-3 ramped in 10 ms and held: σ12/γ is the ramp-averaged G(t).
#[test]
fn material_reports_the_cells_relaxation_modulus() {
    let dir = scratch("one-cell-material");
    std::fs::write(
        dir.join("cell.toml"),
        r#"title = "one cell: material"

[material]
model = "neo-hookean-prony"
G0 = "1 kPa"

[material.prony]
g = [0.4, 0.3]
tau = ["0.5 s", "10 s"]

[loading]
mode = "simple-shear"
history = "ramp-hold"
shear = 1e-3
ramp = "10 ms"
hold = "20 s"
max_dt = "1 ms"
"#,
    )
    .unwrap();
    let out = nlvid(&[
        "material",
        dir.join("cell.toml").to_str().unwrap(),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&ok(&out, "material")).unwrap();
    let times = v["curve"]["time_s"].as_array().unwrap();
    let stress = v["curve"]["sigma_12_Pa"].as_array().unwrap();
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for (t, s) in times.iter().zip(stress) {
        let (t, s) = (t.as_f64().unwrap(), s.as_f64().unwrap());
        if t < 0.01 {
            continue;
        }
        worst = worst.max(relative(s / 1e-3, ramp_averaged_relaxation(t, 0.01)));
        checked += 1;
    }
    eprintln!("material: σ12/γ vs eq. 5.1 over {checked} times, worst {worst:.2e}");
    assert!(checked > 100, "only {checked} hold samples");
    assert!(worst < 1e-4, "σ12/γ differs from G(t) by {worst:.2e}");
}

/// `nlvid simulate` of the analytic model: its force is the Lee–Radok
/// force of G(t), to quadrature accuracy.
#[test]
fn simulate_reports_the_lee_radok_force_of_the_cells_relaxation_modulus() {
    let dir = scratch("one-cell-simulate");
    std::fs::write(
        dir.join("cell.toml"),
        format!("title = \"one cell: simulate\"\n{FORWARD}{PARAMETERS}"),
    )
    .unwrap();
    let study = dir.join("cell.toml");
    let csv = dir.join("force.csv");
    ok(
        &nlvid(&[
            "simulate",
            study.to_str().unwrap(),
            "--output",
            csv.to_str().unwrap(),
        ]),
        "simulate",
    );
    let table = std::fs::read_to_string(&csv).unwrap();
    let mut lines = table.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.starts_with(name))
            .unwrap_or_else(|| panic!("no {name} column in {header:?}"))
    };
    let (it, iforce) = (col("time"), col("force"));
    let peak = lee_radok_force(RAMP);
    let mut worst: f64 = 0.0;
    let mut rows = 0;
    for line in lines {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        worst = worst.max((f[iforce] - lee_radok_force(f[it])).abs() / peak);
        rows += 1;
    }
    eprintln!(
        "simulate: force vs Lee–Radok quadrature over {rows} rows, worst {worst:.2e} of peak"
    );
    assert_eq!(rows, 520);
    assert!(
        worst < 1e-6,
        "simulate force differs by {worst:.2e} of peak"
    );
}

/// The cell's measured curve in the AFM columns the fits read: time,
/// piezo = δ + F/k, deflection = F/k (noise-free Lee–Radok force).
fn afm_csv() -> String {
    let mut csv = String::from("time [s],piezo [um],deflection [nm]\n");
    for i in 0..=5200 {
        let t = i as f64 * 0.01;
        let f = lee_radok_force(t);
        let d = f / SPRING;
        csv.push_str(&format!(
            "{t:.4},{:.9},{:.9}\n",
            (indentation(t) + d) * 1e6,
            d * 1e9
        ));
    }
    csv
}

/// `nlvid build` (a meta-model of the same forward model over a domain
/// around the cell) + `nlvid surrogate fit` + `nlvid fit`, then
/// `nlvid cohort` on the same curve: both report G(t) of the cell.
#[test]
fn build_fit_and_cohort_report_the_cells_relaxation_modulus() {
    let dir = scratch("one-cell-fit");
    std::fs::write(
        dir.join("build.toml"),
        format!(
            r#"title = "one cell: meta-model"
{FORWARD}
[design]
n_train = 80
n_check = 20
seed = 7
ese = true

[design.parameters]
G0 = {{ range = ["500 Pa", "2 kPa"], log = true }}
g1 = {{ range = [0.25, 0.55] }}
g2 = {{ range = [0.15, 0.45] }}
tau1 = {{ range = ["0.25 s", "1 s"], log = true }}
tau2 = {{ range = ["5 s", "20 s"], log = true }}

[[design.constraint]]
coefficients = {{ g1 = 1, g2 = 1 }}
at_most = 0.99

[build]
store = "store"
export = "export"
"#
        ),
    )
    .unwrap();
    run_in(&dir, &["build", "build.toml", "--quiet"]);
    run_in(
        &dir,
        &[
            "surrogate",
            "fit",
            "--x",
            "export/train/X.csv",
            "--y",
            "export/train/Y.csv",
            "--regression",
            "poly1",
            "--correlation",
            "gauss",
            "--proportional-to",
            "G0",
            "--log-inputs",
            "G0,tau1,tau2",
            "-o",
            "model.json",
        ],
    );
    run_in(
        &dir,
        &[
            "surrogate",
            "check",
            "model.json",
            "--x",
            "export/check/X.csv",
            "--y",
            "export/check/Y.csv",
        ],
    );
    std::fs::create_dir_all(dir.join("cells/one")).unwrap();
    std::fs::write(dir.join("cells/one/cell.csv"), afm_csv()).unwrap();
    // One study file for both commands: the same [fit], and both check the
    // cell against the nominal ramp-hold of [fit.protocol] (the piezo's
    // travel is δ + F/k: 2 µm + 0.16 µm at the end of the ramp).
    let study = r#"title = "one cell: fit"

[probe]
radius = "2.5 um"
poisson = 0.5

[fit]
model = "surrogate"
surrogate = "model.json"
meta = "export/train/meta.json"
ramp = "1 s"
hold_end = "52 s"
starts = 8
seed = 1
modulus_times = ["0.5 s", "1 s", "2 s", "5 s", "10 s", "52 s"]

[fit.columns]
time = "time"
piezo = "piezo"
deflection = "deflection"

[fit.calibration]
spring_constant = "0.12 N/m"

[fit.protocol]
rate = "2.16 um/s"
amplitude = "2.16 um"
"#;
    std::fs::write(dir.join("fit.toml"), study).unwrap();

    let fitted: serde_json::Value = serde_json::from_str(&run_in(
        &dir,
        &["--json", "fit", "fit.toml", "cells/one/cell.csv"],
    ))
    .unwrap();
    let fit_modulus = modulus_of_fit(&fitted);
    run_in(&dir, &["cohort", "fit.toml", "cells", "--out", "cohort"]);
    let cohort_modulus = modulus_of_cohort(&dir.join("cohort/results.csv"));

    for (k, t) in MODULUS_TIMES.iter().enumerate() {
        let truth = relaxation(*t);
        eprintln!(
            "G({t} s): truth {truth:.3} Pa, fit {:.3} Pa ({:+.3} %), cohort {:.3} Pa",
            fit_modulus[k],
            100.0 * (fit_modulus[k] / truth - 1.0),
            cohort_modulus[k],
        );
    }
    for (k, t) in MODULUS_TIMES.iter().enumerate() {
        let truth = relaxation(*t);
        assert!(
            relative(fit_modulus[k], truth) < 1e-3,
            "fit: G({t} s) = {} Pa, truth {truth} Pa",
            fit_modulus[k]
        );
        assert!(
            relative(cohort_modulus[k], fit_modulus[k]) < 1e-6,
            "cohort: G({t} s) = {} Pa, fit {} Pa",
            cohort_modulus[k],
            fit_modulus[k]
        );
    }
}

/// G(t) at [`MODULUS_TIMES`] from `nlvid --json fit`.
fn modulus_of_fit(v: &serde_json::Value) -> Vec<f64> {
    let table = v["modulus"]
        .as_array()
        .unwrap_or_else(|| panic!("no `modulus` array in {v}"));
    MODULUS_TIMES
        .iter()
        .map(|t| {
            table
                .iter()
                .find(|row| (row["time"].as_f64().unwrap() - t).abs() < 1e-9)
                .and_then(|row| row["shear"].as_f64())
                .unwrap_or_else(|| panic!("no G({t} s) in {table:?}"))
        })
        .collect()
}

/// G(t) at [`MODULUS_TIMES`] of the cohort's one cell: eq. 5.1 (written
/// here) of the parameters in its row of the results table.
fn modulus_of_cohort(csv: &Path) -> Vec<f64> {
    let table = std::fs::read_to_string(csv).unwrap();
    let mut lines = table.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let row: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let value = |name: &str| -> f64 {
        let i = header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no {name} column in {header:?}"));
        row[i]
            .parse()
            .unwrap_or_else(|_| panic!("{name} = {:?} in {csv:?}", row[i]))
    };
    let (g0, g, tau) = (
        value("G0_Pa"),
        [value("g1"), value("g2")],
        [value("tau1_s"), value("tau2_s")],
    );
    MODULUS_TIMES
        .iter()
        .map(|t| {
            g0 * (1.0
                - g.iter()
                    .zip(tau)
                    .map(|(g, tau)| g * (1.0 - (-t / tau).exp()))
                    .sum::<f64>())
        })
        .collect()
}

/// `nlvid simulate --parameters` (the curve writer) writes the cell as a
/// measured AFM curve: without noise, deflection × k is the Lee–Radok
/// force of G(t) and piezo − deflection the indentation, to the digits
/// the CSV keeps.
#[test]
fn curve_writer_writes_the_cells_lee_radok_curve() {
    let dir = scratch("one-cell-curves");
    std::fs::write(
        dir.join("cell.toml"),
        format!("title = \"one cell: curves\"\n{FORWARD}"),
    )
    .unwrap();
    std::fs::write(
        dir.join("sets.csv"),
        "name,G0,g1,g2,tau1,tau2\ncell,1000,0.4,0.3,0.5,10\n",
    )
    .unwrap();
    run_in(
        &dir,
        &[
            "simulate",
            "cell.toml",
            "--parameters",
            "sets.csv",
            "--out-dir",
            "curves",
            "--noise",
            "0",
            "--spring-constant",
            "0.12",
        ],
    );
    let table = std::fs::read_to_string(dir.join("curves/cell.csv")).unwrap();
    let peak = lee_radok_force(RAMP);
    let (mut worst_force, mut worst_depth, mut rows): (f64, f64, usize) = (0.0, 0.0, 0);
    for line in table.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let (t, piezo, deflection) = (v[0], v[1] * 1e-6, v[2] * 1e-9);
        worst_force = worst_force.max((deflection * SPRING - lee_radok_force(t)).abs() / peak);
        worst_depth = worst_depth.max((piezo - deflection - indentation(t)).abs());
        rows += 1;
    }
    eprintln!(
        "curve writer: {rows} rows, force worst {worst_force:.1e} of peak, depth worst {worst_depth:.1e} m"
    );
    assert_eq!(rows, 520);
    assert!(worst_force < 1e-5, "force off by {worst_force:.2e} of peak");
    assert!(
        worst_depth < 1e-11,
        "indentation off by {worst_depth:.2e} m"
    );
}
