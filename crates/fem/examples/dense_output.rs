//! Accuracy of the written curves on the thesis run (issue 15): the force
//! at the 5095 samples of the default run, with the dense-output tolerances
//! given as arguments, against a reference run with tolerance 2e-6, 5×
//! smaller step limits and Newton's rtol 1e-9; prints steps, CPU and the worst relative difference.
//!
//! ```text
//! cargo run -p nlvid-fem --release --example dense_output -- 2e-4 1e-3 0
//! ```
//!
//! `SHOW=1` lists the samples near the worst one; `RTOL`, `EASY`, `LAZY`,
//! `RSF` (ramp step fraction), `HOLD` (largest hold step, s) change the
//! compared run's settings.

#![allow(clippy::unwrap_used)]
use nlvid_fem::afm::{self, AfmSetup};
use nlvid_model::{Relaxation, names};
fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let p = Relaxation::from_named(&names::PRONY2, &[1e3, 0.3, 0.3, 0.5, 10.0]).unwrap();
    let mut reference = AfmSetup::thesis_setup1();
    reference.settings.output_tolerance = 2e-6;
    reference.ramp_step_fraction = 0.02;
    reference.hold_step_max = 0.1;
    // Newton to the general default (1e-9), so that the reference does not
    // share the compared runs' tolerance.
    reference.settings.rtol = nlvid_fem::Settings::default().rtol;
    let r = afm::run(&p, &reference).unwrap();
    eprintln!("reference: {} steps, cpu {:.2}", r.steps, r.cpu_seconds);
    for tol in std::env::args().skip(1).map(|a| a.parse::<f64>().unwrap()) {
        let mut s = AfmSetup::thesis_setup1();
        s.settings.output_tolerance = tol;
        if let Ok(v) = std::env::var("RTOL") {
            s.settings.rtol = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("EASY") {
            s.settings.easy_iterations = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("LAZY") {
            s.settings.lazy_tangent = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("RSF") {
            s.ramp_step_fraction = v.parse().unwrap();
        }
        if let Ok(v) = std::env::var("HOLD") {
            s.hold_step_max = v.parse().unwrap();
        }
        let a = afm::run(&p, &s).unwrap();
        let mut worst = (0.0f64, 0.0);
        for i in 0..a.force.len() {
            let e = (a.force[i] / r.force[i] - 1.0).abs();
            if e > worst.0 {
                worst = (e, a.time[i]);
            }
        }
        if std::env::var_os("SHOW").is_some() {
            for i in 0..a.force.len() {
                if (a.time[i] - worst.1).abs() < 0.03 {
                    println!(
                        "  t {:.4} a {:.6e} ref {:.6e} rel {:+.2e}",
                        a.time[i],
                        a.force[i],
                        r.force[i],
                        a.force[i] / r.force[i] - 1.0
                    );
                }
            }
        }
        println!(
            "tol {tol:e}: steps {} its {} cpu {:.3} worst {:.2e} at t = {:.4}",
            a.steps, a.iterations, a.cpu_seconds, worst.0, worst.1
        );
    }
}
