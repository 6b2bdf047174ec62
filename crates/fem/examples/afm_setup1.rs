//! Thesis-scale AFM run (setup 1 of ch. V) and the mesh-convergence study of
//! Fig. 5.11.
//!
//! ```text
//! cargo run -p nlvid-fem --release --example afm_setup1            # default mesh, timing (median of 5)
//! cargo run -p nlvid-fem --release --example afm_setup1 -- once    # one run
//! cargo run -p nlvid-fem --release --example afm_setup1 -- study   # n = 35, 65, 129 (≈1200/4200/16600 elements)
//! ```

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::afm::{self, AfmSetup};
use nlvid_model::{Relaxation, names};

fn params() -> Relaxation {
    // G0 = 1 kPa (shear modulus), g1 = g2 = 0.3, tau1 = 0.5 s, tau2 = 10 s.
    Relaxation::from_named(&names::PRONY2, &[1e3, 0.3, 0.3, 0.5, 10.0]).unwrap()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mode = std::env::args().nth(1).unwrap_or_default();
    if std::env::var_os("NLVID_FEM_PAR").is_none() {
        faer::set_global_parallelism(faer::Par::Seq);
    }
    if mode == "study" {
        let mut results = Vec::new();
        let sizes: Vec<usize> = match std::env::var("NLVID_FEM_STUDY_N") {
            Ok(v) => v
                .split(',')
                .map(|x| x.trim().parse())
                .collect::<Result<_, _>>()?,
            Err(_) => vec![35, 65, 129],
        };
        for &n in &sizes {
            let mut setup = AfmSetup::thesis_setup1();
            setup.mesh.elements_per_side = n;
            let run = afm::run(&params(), &setup)?;
            let min_force = run.force.iter().cloned().fold(f64::INFINITY, f64::min);
            println!(
                "n = {n:4} elements = {:6}  peak = {:.6e} N  final = {:.6e} N  min = {:.3e} N  steps = {} cutbacks = {} iterations = {}  CPU = {:.2} s",
                run.elements,
                run.peak_force,
                run.final_force,
                min_force,
                run.steps,
                run.cutbacks,
                run.iterations,
                run.cpu_seconds
            );
            results.push(run);
        }
        let Some(finest) = results.last() else {
            return Ok(());
        };
        for r in &results[..results.len() - 1] {
            println!(
                "elements {:6}: peak-force error {:+.3} %, final-force error {:+.3} % (vs {} elements)",
                r.elements,
                100.0 * (r.peak_force / finest.peak_force - 1.0),
                100.0 * (r.final_force / finest.final_force - 1.0),
                finest.elements
            );
        }
        return Ok(());
    }
    let mut setup = AfmSetup::thesis_setup1();
    if let Ok(n) = std::env::var("NLVID_FEM_N") {
        // The sessions-1–3 Coons patch with n × n elements.
        setup.mesh_layout = afm::MeshLayout::Coons;
        setup.mesh.elements_per_side = n.parse()?;
    }
    // Experiment knobs (solver settings of the run).
    if let Ok(v) = std::env::var("NLVID_FEM_RTOL") {
        setup.settings.rtol = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_GROWTH") {
        setup.settings.growth = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_CUTBACK") {
        setup.settings.cutback = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_EASY") {
        setup.settings.easy_iterations = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_PENALTY") {
        setup.settings.penalty = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_RAMP_STEPS") {
        setup.ramp_step_fraction = 1.0 / v.parse::<f64>()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_CHORD") {
        setup.settings.chord_contraction = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_TANGENT_PREDICTOR") {
        setup.settings.tangent_predictor = v != "0";
    }
    if let Ok(v) = std::env::var("NLVID_FEM_THREADS") {
        setup.settings.threads = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_BULK") {
        setup.bulk_ratio = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_LAZY") {
        setup.settings.lazy_tangent = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_OUTPUT_TOL") {
        setup.settings.output_tolerance = v.parse()?;
    }
    if let Ok(v) = std::env::var("NLVID_FEM_LS") {
        setup.settings.residual_growth = v.parse()?;
    }
    if mode == "info" {
        let model = afm::build(afm::cell_material(&params(), setup.bulk_ratio)?, &setup)?;
        println!("{model:?}");
        return Ok(());
    }
    let mut walls = Vec::new();
    let mut last = None;
    let repeats = if mode == "once" { 1 } else { 5 };
    for _ in 0..repeats {
        let run = if std::env::var_os("NLVID_FEM_REFERENCE").is_some() {
            afm::run_reference(&params(), &setup)?
        } else {
            afm::run(&params(), &setup)?
        };
        walls.push(run.cpu_seconds);
        last = Some(run);
    }
    walls.sort_by(f64::total_cmp);
    // NLVID_FEM_DUMP=FILE: the written curve, "t F" per sample (to compare
    // runs with different solver settings sample by sample).
    if let (Some(path), Some(run)) = (std::env::var_os("NLVID_FEM_DUMP"), &last) {
        let text: String = run
            .time
            .iter()
            .zip(&run.force)
            .map(|(t, f)| format!("{t:.9e} {f:.9e}\n"))
            .collect();
        std::fs::write(path, text)?;
    }
    // NLVID_FEM_DUMP_BITS=FILE: every written sample (t, Z, d, F, δ) as the
    // hexadecimal bits of the f64s, to check two builds for bitwise equality.
    if let (Some(path), Some(run)) = (std::env::var_os("NLVID_FEM_DUMP_BITS"), &last) {
        let mut text = String::new();
        for i in 0..run.time.len() {
            let row = [
                run.time[i],
                run.piezo[i],
                run.deflection[i],
                run.force[i],
                run.indentation[i],
            ];
            let row: Vec<String> = row
                .iter()
                .map(|x| format!("{:016x}", x.to_bits()))
                .collect();
            text.push_str(&row.join(" "));
            text.push('\n');
        }
        std::fs::write(path, text)?;
    }
    if let Some(run) = last {
        let min_force = run.force.iter().cloned().fold(f64::INFINITY, f64::min);
        println!(
            "setup 1, {} elements: peak {:.6e} N, final {:.6e} N, min {:.3e} N, steps {}, cutbacks {}, iterations {}",
            run.elements,
            run.peak_force,
            run.final_force,
            min_force,
            run.steps,
            run.cutbacks,
            run.iterations
        );
        println!(
            "last run: CPU {:.3} s (wall {:.3} s) = assembly {:.3} s (elements {:.3} s, contact+loads {:.3} s) + factorise/solve {:.3} s + other {:.3} s; {} assemblies ({} residual-only), {} factorisations, {} LU fallbacks",
            run.cpu_seconds,
            run.wall_seconds,
            run.assembly_seconds,
            run.element_seconds,
            run.assembly_seconds - run.element_seconds,
            run.solve_seconds,
            run.cpu_seconds - run.assembly_seconds - run.solve_seconds,
            run.assemblies,
            run.residual_only_assemblies,
            run.factorisations,
            run.lu_fallbacks
        );
        // The bench ratios (docs/theory/fem.md, "Speed"): assemblies are
        // deterministic and track the CPU time (≈ 1.5 ms each), so their
        // ratio to the session-5 default run is a load-free speed figure.
        println!(
            "bench: assemblies {} / 1132 (session-5 default) = {:.3}; peak {:+.1e}, final {:+.1e} relative to 2.137008e-8 / 9.750558e-9 N",
            run.assemblies,
            run.assemblies as f64 / 1132.0,
            run.peak_force / 2.137008e-8 - 1.0,
            run.final_force / 9.750558e-9 - 1.0
        );
    }
    println!(
        "CPU time (thread): median of {repeats} = {:.3} s (all: {walls:.3?})",
        walls[repeats / 2]
    );
    Ok(())
}
