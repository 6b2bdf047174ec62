//! Cost of one elastic plate-compression run of the thesis capsule (§4.3):
//! one eighth of the fluid-filled ellipsoidal shell (2a = 9.96 mm,
//! 2b = 2c = 6.51 mm, wall 0.62 → 0.4 mm, four elements through the wall),
//! incompressible fluid, rigid frictionless plate, squeezed by d = 1.5 mm
//! (d/2 on the eighth), instantaneous Mooney–Rivlin wall of §4.4.3's set
//! (C1 = 21.25 MPa, α = 0.372).
//!
//! ```text
//! cargo run -p nlvid-fem --release --example capsule_plates              # default mesh (0.3 mm), median of 5
//! cargo run -p nlvid-fem --release --example capsule_plates -- 0.2 1     # element size 0.2 mm, one run
//! cargo run -p nlvid-fem --release --example capsule_plates -- 0.3 1 8   # eight elements through the wall
//! ```

#![allow(clippy::unwrap_used)]

use nlvid_fem::shell::{ShellSpec, ellipsoidal_shell};
use nlvid_fem::{Control, Fluid, Model, Parts, Settings, Solid, Stage};
use nlvid_material::MooneyRivlin;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    faer::set_global_parallelism(faer::Par::Seq);
    let args: Vec<String> = std::env::args().collect();
    let size_mm: f64 = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(0.3);
    let repeats: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(5);
    let layers: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(4);
    let (c1, alpha) = (21.2546e6, 0.3720);
    let g0 = 2.0 * c1 * (1.0 + alpha);
    let d = 1.5e-3;
    let mut cpu = Vec::new();
    for _ in 0..repeats {
        let spec = ShellSpec {
            layers,
            ..ShellSpec::thesis_capsule(size_mm * 1e-3)
        };
        let c = spec.semi_axes[2];
        let mesh = ellipsoidal_shell(&spec)?;
        let (elements, nodes) = (mesh.elements.len(), mesh.nodes.len());
        let parts = Parts::eighth_capsule(Fluid::Incompressible);
        let settings = Settings {
            residual_growth: 1e6,
            atol: 1e-9,
            ..Settings::default()
        };
        let material = MooneyRivlin::with_ratio(c1, alpha, 1e3 * g0)?;
        let start = std::time::Instant::now();
        let clock = cpu_time::ThreadTime::now();
        let mut model = Model::<_, Solid>::build(mesh, material, &parts, settings)?;
        let setup = clock.elapsed().as_secs_f64();
        let control = |t: f64| Control {
            plane_z: c - 0.5 * d * t,
            ..Control::default()
        };
        model.run_stage(&Stage {
            name: "squeeze",
            end: 1.0,
            dt_initial: 0.05,
            dt_max: 0.05,
            control: &control,
        })?;
        let total = clock.elapsed().as_secs_f64();
        let wall = start.elapsed().as_secs_f64();
        let k = model.counters();
        let last = *model.records().last().unwrap();
        let v0 = model.cavity_reference_volume().unwrap();
        let contact = model
            .plane_contact_forces(0)
            .iter()
            .filter(|f| f.1 > 0.0)
            .count();
        println!(
            "size {size_mm} mm, {layers} layers: {elements} elements, {nodes} nodes, {} equations; force (whole capsule) {:.4} N, \
             p = {:.4} MPa, V/V0 − 1 = {:.1e}, {contact} nodes in contact; {} steps, {} cut-backs, {} iterations, \
             {} assemblies; CPU {total:.2} s (setup {setup:.2}, assembly {:.2} of which elements {:.2}, solve {:.2}), wall {wall:.2} s",
            model.equations(),
            4.0 * last.plane_force,
            last.cavity_pressure * 1e-6,
            last.cavity_volume / v0 - 1.0,
            k.steps,
            k.cutbacks,
            k.iterations,
            k.assemblies,
            k.assembly_seconds,
            k.element_seconds,
            k.solve_seconds,
        );
        cpu.push(total);
    }
    cpu.sort_by(f64::total_cmp);
    println!("median CPU of {}: {:.2} s", cpu.len(), cpu[cpu.len() / 2]);
    Ok(())
}
