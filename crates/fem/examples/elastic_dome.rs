//! The elastic dome of issue 15 (benchmark, [`AfmSetup::elastic_dome`]):
//! the setup-1 half spheroid (H = 12.22 µm, D = 28.88 µm), neo-Hookean
//! G = 1 kPa, K = 1000 G, pushed 2 µm by a rigid 2.5 µm sphere, forces
//! written at 201 depths. Prints the forces at a few depths and the CPU
//! time (median of 5).
//!
//! ```text
//! cargo run -p nlvid-fem --release --example elastic_dome              # default mesh (0.5 % from 0.05 µm)
//! cargo run -p nlvid-fem --release --example elastic_dome -- benchmark # the benchmark's run (0.5 % from 0.1 µm)
//! ```

#![allow(clippy::unwrap_used)]

use nlvid_fem::afm::{self, AfmSetup};
use nlvid_model::{Prony, Relaxation, names};

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    let mut setup = if std::env::args().nth(1).as_deref() == Some("benchmark") {
        AfmSetup::elastic_dome_benchmark()
    } else {
        AfmSetup::elastic_dome()
    };
    // Experiment knobs: NLVID_FEM_OUTPUT_TOL, NLVID_FEM_REFINE (the default
    // mesh refined that many times), NLVID_FEM_DUMP (write "δ F" lines).
    if let Ok(v) = std::env::var("NLVID_FEM_OUTPUT_TOL") {
        setup.settings.output_tolerance = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_RAMP_STEPS") {
        setup.ramp_step_fraction = 1.0 / v.parse::<f64>().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_EASY") {
        setup.settings.easy_iterations = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_GROWTH") {
        setup.settings.growth = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_RTOL") {
        setup.settings.rtol = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_LAZY") {
        setup.settings.lazy_tangent = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_CHORD") {
        setup.settings.chord_contraction = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_TANGENT_PREDICTOR") {
        setup.settings.tangent_predictor = v != "0";
    }
    if let Ok(v) = std::env::var("NLVID_FEM_THREADS") {
        setup.settings.threads = v.parse().unwrap();
    }
    // NLVID_FEM_MESH = "h0,k_r,k_z,q": the graded mesh's element size at
    // the pole (m), core elements along the surface and in depth, ring
    // ratio (the accuracy budget of the dome, docs/theory/fem.md).
    if let Ok(v) = std::env::var("NLVID_FEM_MESH") {
        let p: Vec<&str> = v.split(',').collect();
        setup.mesh_layout = afm::MeshLayout::ContactGraded(nlvid_fem::ContactMesh {
            spacing: p[0].parse().unwrap(),
            core: p[1].parse().unwrap(),
            core_depth: p[2].parse().unwrap(),
            growth: p[3].parse().unwrap(),
        });
    }
    if let Ok(v) = std::env::var("NLVID_FEM_REFINE")
        && let afm::MeshLayout::ContactGraded(spec) = setup.mesh_layout
    {
        setup.mesh_layout = afm::MeshLayout::ContactGraded(spec.refined(v.parse().unwrap()));
    }
    let repeats = if std::env::var_os("NLVID_FEM_DUMP").is_some() {
        1
    } else {
        5
    };
    let params = Relaxation::new(names::G0, 1e3, Prony::elastic()).unwrap();
    let mut cpu = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let run = afm::run(&params, &setup).unwrap();
        cpu.push(run.cpu_seconds);
        last = Some(run);
    }
    cpu.sort_by(f64::total_cmp);
    let run = last.unwrap();
    if let Some(path) = std::env::var_os("NLVID_FEM_DUMP") {
        let text: String = run
            .indentation
            .iter()
            .zip(&run.force)
            .map(|(d, f)| format!("{d:.6e} {f:.9e}\n"))
            .collect();
        std::fs::write(path, text).unwrap();
    }
    // NLVID_FEM_COMPARE: a file of "δ F" lines (NLVID_FEM_DUMP of a reference
    // run on the same output grid): the largest relative force difference
    // from δ = 0.1 µm on.
    if let Some(path) = std::env::var_os("NLVID_FEM_COMPARE") {
        let text = std::fs::read_to_string(path).unwrap();
        let reference: Vec<f64> = text
            .lines()
            .map(|l| l.split_whitespace().nth(1).unwrap().parse().unwrap())
            .collect();
        let worst = run
            .indentation
            .iter()
            .zip(&run.force)
            .zip(&reference)
            .filter(|((d, _), _)| **d >= 0.1e-6 - 1e-12)
            .map(|((_, f), r)| (f / r - 1.0).abs())
            .fold(0.0, f64::max);
        println!(
            "largest difference from the reference curve (δ ≥ 0.1 µm): {:.3e}",
            worst
        );
    }
    for depth in [0.1e-6, 0.25e-6, 0.5e-6, 1e-6, 2e-6] {
        let i = run
            .time
            .iter()
            .position(|&t| (t * 2e-6 - depth).abs() < 1e-12)
            .unwrap();
        println!("δ = {:.2} µm: F = {:.6e} N", depth * 1e6, run.force[i]);
    }
    println!(
        "{} elements, {} steps ({} cut-backs), {} Newton iterations, {} assemblies ({} residual-only), {} factorisations; CPU median = {:.3} s (all {:.3?})",
        run.elements,
        run.steps,
        run.cutbacks,
        run.iterations,
        run.assemblies,
        run.residual_only_assemblies,
        run.factorisations,
        cpu[cpu.len() / 2],
        cpu
    );
    // Load-free speed figure (docs/theory/fem.md, "Speed"): assemblies are
    // deterministic and track the CPU time.
    println!(
        "bench: assemblies {} / 1070 (session-5 default) = {:.3}",
        run.assemblies,
        run.assemblies as f64 / 1070.0
    );
}
