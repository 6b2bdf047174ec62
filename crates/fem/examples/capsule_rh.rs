//! RH and RR plate tests (thesis §4.2) on the viscoelastic thesis capsule
//! (§4.3; one eighth, incompressible fluid, Mooney–Rivlin + 2-term Prony
//! wall with §4.4.3's RH set C1 = 21.2546 MPa, α = 0.3720, g1 = 0.7674,
//! τ1 = 0.0623 s, g2 = 0.1546, τ2 = 1.3936 s), outputs on 1200 times.
//!
//! ```text
//! cargo run -p nlvid-fem --release --example capsule_rh                      # RH, d = 1.5 mm, 0.3 mm mesh, median of 5
//! cargo run -p nlvid-fem --release --example capsule_rh -- rr 1.5 0.3 4 1    # RR, one run
//! cargo run -p nlvid-fem --release --example capsule_rh -- rh 1.5 0.15 4 1 20 out.csv
//! ```
//! Arguments: test (rh|rr), d (mm), element size (mm), layers, repeats,
//! steps per stage, CSV file of the samples.

#![allow(clippy::unwrap_used)]

use nlvid_fem::shell::{ShellSpec, ellipsoidal_shell};
use nlvid_fem::{
    Fluid, LiftOff, Model, Parts, PatchSpec, PlateProgram, Settings, Solid, Symmetry,
    run_plate_program,
};
use nlvid_material::PronyViscoelastic;
use nlvid_protocol::{Quantity, grid, programs};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    faer::set_global_parallelism(faer::Par::Seq);
    let args: Vec<String> = std::env::args().collect();
    let test = args.get(1).cloned().unwrap_or_else(|| "rh".into());
    let d = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1.5) * 1e-3;
    let size = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(0.3) * 1e-3;
    let layers: usize = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(4);
    let repeats: usize = args.get(5).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let min_steps: usize = args.get(6).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let csv = args.get(7).cloned();
    let (c1, alpha) = (21.2546e6, 0.3720);
    let g0 = 2.0 * c1 * (1.0 + alpha);
    let program = match test.as_str() {
        "rh" => programs::ramp_hold(Quantity::Displacement, d, 5e-3, 10.0)?,
        "rr" => programs::ramp_reverse(Quantity::Displacement, d, 0.2e-3, 0.0)?,
        other => return Err(format!("test `{other}`: use rh or rr").into()),
    };
    let times = grid::uniform(program.start(), program.end(), 1200)?;
    let mut cpu = Vec::new();
    for _ in 0..repeats {
        let spec = ShellSpec {
            layers,
            ..ShellSpec::thesis_capsule(size)
        };
        let mesh = ellipsoidal_shell(&spec)?;
        let elements = mesh.elements.len();
        let parts = Parts::eighth_capsule(Fluid::Incompressible);
        let settings = Settings {
            residual_growth: 1e6,
            atol: 1e-9,
            ..Settings::default()
        };
        let material =
            PronyViscoelastic::capsule(c1, alpha, (0.7674, 0.0623), (0.1546, 1.3936), 1e3 * g0)?;
        let clock = cpu_time::ThreadTime::now();
        let start = std::time::Instant::now();
        let mut model = Model::<_, Solid>::build(mesh, material, &parts, settings)?;
        let mut plate = PlateProgram::new(
            program.clone(),
            times.clone(),
            PatchSpec {
                plane: 0,
                surface: "outer".into(),
                symmetry: Symmetry::EIGHTH,
                lift_off: LiftOff::Solid,
            },
            "inner",
        );
        plate.min_steps = min_steps;
        let run = run_plate_program(&mut model, &plate)?;
        let total = clock.elapsed().as_secs_f64();
        let k = run.counters;
        let last = run.samples.last().unwrap();
        let peak = run.samples.iter().map(|s| s.force).fold(0.0, f64::max);
        println!(
            "{test} d = {:.2} mm, size {:.3} mm, {layers} layers ({elements} hexahedra): peak {:.5} N (steps {:.5} N), \
             final {:.5} N at t = {:.2} s, contact area {:.4} mm² (ellipse {:.4} mm²) at the peak; {} steps, {} cut-backs, \
             {} iterations, {} assemblies; CPU {total:.2} s (assembly {:.2}, elements {:.2}, solve {:.2}), wall {:.2} s",
            d * 1e3,
            size * 1e3,
            peak,
            run.peak_force(),
            last.force,
            last.time,
            run.samples
                .iter()
                .max_by(|a, b| a.force.total_cmp(&b.force))
                .unwrap()
                .pressure_area
                * 1e6,
            run.samples
                .iter()
                .max_by(|a, b| a.force.total_cmp(&b.force))
                .unwrap()
                .ellipse_area
                * 1e6,
            k.steps,
            k.cutbacks,
            k.iterations,
            k.assemblies,
            k.assembly_seconds,
            k.element_seconds,
            k.solve_seconds,
            start.elapsed().as_secs_f64()
        );
        for n in &run.notes {
            println!("  note: {n}");
        }
        if let Some(path) = &csv {
            run.write_csv(std::path::Path::new(path))?;
        }
        cpu.push(total);
    }
    cpu.sort_by(f64::total_cmp);
    println!("median CPU of {}: {:.2} s", cpu.len(), cpu[cpu.len() / 2]);
    Ok(())
}
