//! Mesh convergence of the AFM cell model (issue 15, docs/theory/fem.md
//! "Mesh graded to the contact"): the elastic dome (setup-1 half spheroid,
//! neo-Hookean G = 1 kPa, K = 1000 G, rigid 2.5 µm sphere) pushed to 2 µm on
//! the default mesh and on the same mesh refined `NLVID_FEM_REFINE` (4)
//! times; forces at 65 depths from 0.05 µm to 2 µm (each a step end of its
//! own piezo segment, so no interpolation enters) and the largest relative
//! difference.
//!
//! ```text
//! cargo run -p nlvid-fem --release --example mesh_study     # ≈ 3 min of CPU
//! ```
//!
//! `NLVID_FEM_CORE=kr,kz`, `NLVID_FEM_GROWTH`, `NLVID_FEM_SPACING` (m) and
//! `NLVID_FEM_BULK` change the mesh and the bulk ratio; `NLVID_FEM_COONS=n`
//! runs the sessions-1–3 Coons patch with n × n elements instead of the
//! coarse mesh.

#![allow(clippy::unwrap_used)]

use nlvid_fem::afm::{self, AfmSetup, MeshLayout};
use nlvid_model::{Prony, Relaxation, names};

fn forces(setup: &AfmSetup) -> (Vec<f64>, Vec<f64>, usize, f64) {
    let elastic = Relaxation::new(names::G0, 1e3, Prony::elastic()).unwrap();
    let run = afm::run(&elastic, setup).unwrap();
    (run.indentation, run.force, run.elements, run.cpu_seconds)
}

fn main() {
    faer::set_global_parallelism(faer::Par::Seq);
    // The elastic dome, pushed through one piezo segment per depth.
    let mut setup = AfmSetup::elastic_dome();
    setup.bulk_ratio = std::env::var("NLVID_FEM_BULK").map_or(1000.0, |v| v.parse().unwrap());
    let depths: Vec<f64> = (0..=64)
        .map(|i| 0.05e-6 * 40f64.powf(i as f64 / 64.0))
        .collect();
    // One piezo segment per depth (time in µm), outputs at the segment ends.
    setup.piezo = std::iter::once((0.0, 0.0))
        .chain(depths.iter().map(|&d| (d * 1e6, d)))
        .collect();
    setup.output_times = depths.iter().map(|&d| d * 1e6).collect();
    let MeshLayout::ContactGraded(mut spec) = setup.mesh_layout else {
        unreachable!("the default is graded")
    };
    if let Ok(v) = std::env::var("NLVID_FEM_CORE") {
        let k: Vec<usize> = v.split(',').map(|x| x.trim().parse().unwrap()).collect();
        spec.core = k[0];
        spec.core_depth = k[1];
    }
    if let Ok(v) = std::env::var("NLVID_FEM_GROWTH") {
        spec.growth = v.parse().unwrap();
    }
    if let Ok(v) = std::env::var("NLVID_FEM_SPACING") {
        spec.spacing = v.parse().unwrap();
    }
    let factor = std::env::var("NLVID_FEM_REFINE").map_or(4, |v| v.parse().unwrap());
    let mut coarse = setup.clone();
    coarse.mesh_layout = MeshLayout::ContactGraded(spec);
    if let Ok(v) = std::env::var("NLVID_FEM_COONS") {
        coarse.mesh_layout = MeshLayout::Coons;
        coarse.mesh.elements_per_side = v.parse().unwrap();
    }
    let mut fine = setup;
    fine.mesh_layout = MeshLayout::ContactGraded(spec.refined(factor));
    let (d, f, n, cpu) = forces(&coarse);
    let (_, f_ref, n_ref, cpu_ref) = forces(&fine);
    let mut worst = (0.0f64, 0.0);
    for i in 0..d.len() {
        let e = f[i] / f_ref[i] - 1.0;
        println!(
            "δ = {:.4e} m: F = {:.6e} N, refined {:.6e} N, {:+.3} %",
            d[i],
            f[i],
            f_ref[i],
            100.0 * e
        );
        if e.abs() > worst.0.abs() {
            worst = (e, d[i]);
        }
    }
    println!(
        "mesh {:?}: {n} elements ({cpu:.1} s CPU) vs refined {factor}×: {n_ref} elements ({cpu_ref:.1} s); largest difference {:+.3} % at δ = {:.3e} m",
        coarse.mesh_layout,
        100.0 * worst.0,
        worst.1
    );
}
