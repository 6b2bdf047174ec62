//! `nlvid surrogate fit --proportional-to`: the output scale is recorded in
//! the model file and applied by `check`, and an unknown column is a
//! located error. Data: y = G0 · (1 − g1 + g1 e^{−t/τ}) (exactly ∝ G0).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::PathBuf;

use crate::common;
use common::{nlvid, text};

fn dir() -> PathBuf {
    common::temp_dir("surrogate-scale")
}

/// Deterministic scattered points (G0 log-uniform in [100, 5000]).
fn tables(n: usize, offset: usize) -> (String, String) {
    let ts = [0.1, 0.5, 1.0, 2.0, 5.0];
    let mut x = String::from("G0,g1,lntau\n");
    let mut y = String::from("t0,t1,t2,t3,t4\n");
    for i in 0..n {
        let k = i + offset;
        let u = |a: usize, b: usize| ((k * a + b) % 97) as f64 / 97.0 + 0.5 / 97.0;
        let g0 = (100f64.ln() + u(37, 11) * 50f64.ln()).exp();
        let g1 = 0.9 * u(59, 3);
        let lntau: f64 = 0.1f64.ln() + u(71, 29) * 50f64.ln();
        x.push_str(&format!("{g0},{g1},{lntau}\n"));
        let row: Vec<String> = ts
            .iter()
            .map(|t: &f64| (g0 * (1.0 - g1 + g1 * (-t / lntau.exp()).exp())).to_string())
            .collect();
        y.push_str(&(row.join(",") + "\n"));
    }
    (x, y)
}

fn max_error(model: &str, xc: &str, yc: &str) -> f64 {
    let out = nlvid(&["--json", "surrogate", "check", model, "--x", xc, "--y", yc]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["max"].as_f64().unwrap()
}

#[test]
fn proportional_to_is_recorded_and_improves_the_checking_error() {
    let d = dir();
    let (x, y) = tables(60, 0);
    let (xc, yc) = tables(20, 500);
    let p = |n: &str| d.join(n).to_string_lossy().into_owned();
    for (name, body) in [
        ("X.csv", &x),
        ("Y.csv", &y),
        ("Xc.csv", &xc),
        ("Yc.csv", &yc),
    ] {
        std::fs::write(d.join(name), body).unwrap();
    }
    let fit = |extra: &[&str], out: &str| {
        let (xs, ys) = (p("X.csv"), p("Y.csv"));
        let mut args = vec!["surrogate", "fit", "--x", &xs, "--y", &ys];
        args.extend_from_slice(extra);
        let o = p(out);
        args.extend_from_slice(&["--out", &o]);
        let r = nlvid(&args);
        assert!(r.status.success(), "{}", text(&r.stderr));
    };
    fit(&[], "plain.json");
    fit(&["--proportional-to", "G0"], "scaled.json");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("scaled.json")).unwrap()).unwrap();
    assert_eq!(
        model["output_scale"]["Linear"]["input"], 0,
        "{}",
        model["output_scale"]
    );
    let (plain, scaled) = (
        max_error(&p("plain.json"), &p("Xc.csv"), &p("Yc.csv")),
        max_error(&p("scaled.json"), &p("Xc.csv"), &p("Yc.csv")),
    );
    assert!(scaled < 0.2 * plain, "scaled {scaled} vs plain {plain}");

    // --log-inputs: recorded, and check takes the original values.
    fit(
        &["--proportional-to", "G0", "--log-inputs", "G0"],
        "login.json",
    );
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("login.json")).unwrap()).unwrap();
    assert_eq!(model["log_inputs"], serde_json::json!([true, false, false]));
    let login = max_error(&p("login.json"), &p("Xc.csv"), &p("Yc.csv"));
    assert!(login < 0.2 * plain, "log inputs {login} vs plain {plain}");

    let bad = nlvid(&[
        "surrogate",
        "fit",
        "--x",
        &p("X.csv"),
        "--y",
        &p("Y.csv"),
        "--proportional-to",
        "E",
        "--out",
        &p("bad.json"),
    ]);
    assert!(!bad.status.success());
    let e = text(&bad.stderr);
    assert!(
        e.contains("--proportional-to E") && e.contains("X.csv"),
        "{e}"
    );
}
