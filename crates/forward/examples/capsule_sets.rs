//! The thesis's optimised capsule sets (§4.4.2, §4.4.3) re-run through the
//! `capsule-fe` forward model at d = 1.5 mm, RH (5 mm/s, 10 s hold) and RR
//! (0.2 mm/s down and up), thesis capsule on the default force mesh,
//! 1200 output times:
//!
//! * Material Sets 1 and 2 (§4.4.2; g1 + g2 = 0.9835 vs 0.85): the largest
//!   force difference over time, relative to the larger peak, for RR and
//!   for RH (Fig. 4.13: RR nearly the same, RH different);
//! * equal C1 + C2 with different α (§4.4.2: "several different
//!   combinations … with the same (C1 + C2) … give very close force-time
//!   results"): §4.4.3's RH set (α = 0.372) against α = 0 and α = 0.5 with
//!   the same C1 + C2 and Prony series.
//!
//! Writes one CSV per run and SVG figures of force and contact area
//! against time (crate `nlvid-figure`) into the output directory, and
//! prints the differences.
//!
//! ```text
//! cargo run -p nlvid-forward --release --example capsule_sets [-- OUT_DIR [ELEMENT_SIZE_MM]]
//! ```

#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use nlvid_figure::{Chart, Mark, Series, palette};
use nlvid_forward::CapsuleFeSpec;
use nlvid_model::Curve;
use nlvid_protocol::{Program, Quantity, programs};

/// (label, [C1, α, g1, g2, τ1, τ2]) in nlvid's order.
type Set = (&'static str, [f64; 6]);

const SET1: Set = (
    "Set 1 (g1+g2 = 0.9835)",
    [28.8179e6, 0.0, 0.7652, 0.2183, 0.1608, 5.0],
);
const SET2: Set = (
    "Set 2 (g1+g2 = 0.85)",
    [21.9096e6, 0.0, 0.5036, 0.3464, 0.2018, 1.1285],
);
/// §4.4.3's RH set (C1 = 21.2546 MPa, α = 0.372; C1 + C2 = 29.1613 MPa).
const RH_SET: [f64; 6] = [21.2546e6, 0.3720, 0.7674, 0.1546, 0.0623, 1.3936];

/// `RH_SET` with α replaced and C1 chosen so that C1 + C2 is unchanged.
fn same_sum(alpha: f64) -> [f64; 6] {
    let sum = RH_SET[0] * (1.0 + RH_SET[1]);
    let mut p = RH_SET;
    p[0] = sum / (1.0 + alpha);
    p[1] = alpha;
    p
}

fn run(program: &Program, size: f64, p: &[f64; 6]) -> (Curve, Vec<String>, f64) {
    let mut spec = CapsuleFeSpec::thesis(program.clone(), 1200);
    spec.shell.element_size = size;
    let model = spec.build().unwrap();
    let clock = std::time::Instant::now();
    let (curve, notes) = model.run_curve(p).unwrap();
    (curve, notes, clock.elapsed().as_secs_f64())
}

fn force(c: &Curve) -> &[f64] {
    c.values("force").unwrap()
}

fn peak(c: &Curve) -> f64 {
    force(c).iter().copied().fold(0.0, f64::max)
}

/// Largest |F_a − F_b| over the output times, relative to the larger peak,
/// and the time where it occurs.
fn largest_difference(a: &Curve, b: &Curve) -> (f64, f64) {
    let scale = peak(a).max(peak(b));
    force(a)
        .iter()
        .zip(force(b))
        .zip(a.time())
        .map(|((x, y), &t)| ((x - y).abs() / scale, t))
        .fold((0.0, 0.0), |m, d| if d.0 > m.0 { d } else { m })
}

/// Every `step`-th sample (the SVG holds every point).
fn thin(x: &[f64], step: usize) -> Vec<f64> {
    x.iter().step_by(step).copied().collect()
}

fn chart(title: &str, y: &str, channel: &str, scale: f64, runs: &[(&str, &Curve)]) -> Chart {
    let mut c = Chart::new(title, "t (s)", y);
    for (i, (label, curve)) in runs.iter().enumerate() {
        let v: Vec<f64> = curve
            .values(channel)
            .unwrap()
            .iter()
            .map(|v| v * scale)
            .collect();
        let mark = if i % 2 == 0 { Mark::Line } else { Mark::Dashed };
        c.push(
            Series::from_xy(mark, palette(i), &thin(curve.time(), 3), &thin(&v, 3))
                .labelled(*label),
        );
    }
    c
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = PathBuf::from(args.get(1).map_or("capsule-sets.out", String::as_str));
    let size = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(0.3) * 1e-3;
    std::fs::create_dir_all(&out)?;
    let d = 1.5e-3;
    let rh = programs::ramp_hold(Quantity::Displacement, d, 5e-3, 10.0)?;
    let rr = programs::ramp_reverse(Quantity::Displacement, d, 0.2e-3, 0.0)?;
    let mut results = Vec::new();
    for (test, program) in [("rh", &rh), ("rr", &rr)] {
        for (k, (label, p)) in [SET1, SET2].iter().enumerate() {
            let (curve, notes, wall) = run(program, size, p);
            println!(
                "{test} set {}: peak {:.4} N at t = {:.3} s, final {:.4} N, peak ellipse area {:.3} mm², {wall:.1} s",
                k + 1,
                peak(&curve),
                curve.time()[force(&curve)
                    .iter()
                    .position(|&f| f == peak(&curve))
                    .unwrap()],
                force(&curve).last().unwrap(),
                curve
                    .values("ellipse_area")
                    .unwrap()
                    .iter()
                    .copied()
                    .fold(0.0, f64::max)
                    * 1e6
            );
            for n in &notes {
                println!("  note: {n}");
            }
            std::fs::write(out.join(format!("{test}-set{}.csv", k + 1)), curve.to_csv())?;
            results.push((test, *label, curve));
        }
    }
    let find = |test: &str, set: &str| {
        &results
            .iter()
            .find(|r| r.0 == test && r.1 == set)
            .unwrap()
            .2
    };
    let (drr, trr) = largest_difference(find("rr", SET1.0), find("rr", SET2.0));
    let (drh, trh) = largest_difference(find("rh", SET1.0), find("rh", SET2.0));
    println!(
        "Material Sets 1 vs 2, largest |ΔF| / peak: RR {:.3} % (t = {trr:.3} s), RH {:.3} % (t = {trh:.3} s), ratio RH/RR {:.1}",
        100.0 * drr,
        100.0 * drh,
        drh / drr
    );
    for test in ["rh", "rr"] {
        let sets: Vec<(&str, &Curve)> = [SET1.0, SET2.0]
            .iter()
            .map(|s| (*s, find(test, s)))
            .collect();
        let name = test.to_uppercase();
        chart(
            &format!("{name}, d = 1.5 mm: Material Sets 1 and 2 (§4.4.2, Fig. 4.13)"),
            "F (N)",
            "force",
            1.0,
            &sets,
        )
        .write(&out.join(format!("{test}-sets-force.svg")))?;
        chart(
            &format!("{name}, d = 1.5 mm: contact area (ellipse, §4.4.3)"),
            "A (mm²)",
            "ellipse_area",
            1e6,
            &sets,
        )
        .write(&out.join(format!("{test}-sets-area.svg")))?;
    }
    // Equal C1 + C2, different α (RH).
    let mut alpha_runs = Vec::new();
    for alpha in [0.372, 0.0, 0.5] {
        let p = same_sum(alpha);
        let (curve, _, _) = run(&rh, size, &p);
        println!(
            "rh alpha = {alpha}: C1 = {:.4} MPa, C1 + C2 = {:.4} MPa, peak {:.4} N, final {:.4} N",
            p[0] * 1e-6,
            p[0] * (1.0 + alpha) * 1e-6,
            peak(&curve),
            force(&curve).last().unwrap()
        );
        std::fs::write(out.join(format!("rh-alpha{alpha}.csv")), curve.to_csv())?;
        alpha_runs.push((alpha, curve));
    }
    for (alpha, curve) in &alpha_runs[1..] {
        let (dmax, t) = largest_difference(&alpha_runs[0].1, curve);
        println!(
            "equal C1 + C2: alpha = 0.372 vs {alpha}: largest |ΔF| / peak {:.3} % (t = {t:.3} s), peak {:+.3} %",
            100.0 * dmax,
            100.0 * (peak(curve) / peak(&alpha_runs[0].1) - 1.0)
        );
    }
    let labels: Vec<String> = alpha_runs
        .iter()
        .map(|(a, _)| format!("α = {a}, C1 + C2 = 29.16 MPa"))
        .collect();
    let runs: Vec<(&str, &Curve)> = labels
        .iter()
        .zip(&alpha_runs)
        .map(|(l, (_, c))| (l.as_str(), c))
        .collect();
    chart(
        "RH, d = 1.5 mm: equal C1 + C2, different α (§4.4.2)",
        "F (N)",
        "force",
        1.0,
        &runs,
    )
    .write(&out.join("rh-alpha-force.svg"))?;
    println!("wrote CSV and SVG files to {}", out.display());
    Ok(())
}
