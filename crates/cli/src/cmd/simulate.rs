//! `nlvid simulate <study.toml>`: one finite-element run of the AFM cell
//! indentation model (thesis §5.3) for the material in the study; writes
//! `time_s, piezo_m, deflection_m, force_N, indentation_m` on the study's
//! output grid. Sections and keys: docs/cli/simulate.md.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nlvid_fem::afm::{self, AfmSetup, Cantilever, Engagement, MeshSpec};
use nlvid_model::{Prony, Relaxation, names};
use nlvid_protocol::{Loading, ProtocolSettings};
use nlvid_study::{Bounds, Dimension, Study};
use serde_json::json;

use super::{Context, Run};
use crate::output::{Column, Table, print_json, write_atomic};

/// Raw arguments of `nlvid simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML) with [geometry], [cantilever], [protocol], [material] and optional [fem].
    pub study: PathBuf,
    /// Output CSV (default: `<study stem>.simulate.csv` next to the study).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the deformed mesh at the end of the run (node, r_m, z_m; elements as comment lines) to this CSV.
    #[arg(long)]
    pub mesh_output: Option<PathBuf>,
}

/// A validated simulation.
#[derive(Debug)]
pub struct Config {
    study: PathBuf,
    output: PathBuf,
    mesh_output: Option<PathBuf>,
    params: Relaxation,
    setup: AfmSetup,
}

fn read(study_path: &PathBuf) -> anyhow::Result<(Relaxation, AfmSetup)> {
    let mut study = Study::load(study_path)?;
    let pos = Bounds::positive();
    let mut setup = AfmSetup::thesis_setup1();

    let mut g = study.section("geometry")?;
    setup.height = g.req_quantity("height", Dimension::LENGTH, pos)?;
    setup.diameter = g.req_quantity("diameter", Dimension::LENGTH, pos)?;
    setup.probe_radius = g.quantity_or("probe_radius", Dimension::LENGTH, pos, 2.5e-6)?;
    g.finish()?;

    let mut c = study.section("cantilever")?;
    let rigid = c.opt_bool("rigid")?.unwrap_or(false);
    setup.cantilever = if rigid {
        Cantilever::Rigid
    } else {
        Cantilever::Spring {
            stiffness: c.req_quantity("k", Dimension::STIFFNESS, pos)?,
        }
    };
    c.finish()?;

    let protocol: ProtocolSettings = study.read("protocol")?;
    let program = protocol.program()?;
    match &protocol.loading {
        Loading::Afm(script) => {
            setup.engagement = Engagement {
                force: script.engage.setpoint_force,
                ramp: script.engage.ramp_time,
                hold: script.engage.hold,
            };
        }
        Loading::Program(_) => {
            setup.engagement = Engagement {
                force: 0.0,
                ramp: 1.0,
                hold: 0.0,
            };
        }
    }
    let mut piezo = vec![(program.start(), program.value(program.start()))];
    for s in program.segments() {
        if s.is_jump() {
            anyhow::bail!(
                "{}: [protocol]: the piezo program jumps at t = {} s; the FE model needs a continuous Z(t)",
                study.name(),
                s.t0
            );
        }
        piezo.push((s.t1, s.v1));
    }
    if piezo[0].0 != 0.0 {
        let t0 = piezo[0].0;
        for p in &mut piezo {
            p.0 -= t0;
        }
    }
    setup.piezo = piezo;
    let end = setup.piezo.last().map_or(0.0, |p| p.0);
    setup.output_times = match protocol.output_grid()? {
        Some(grid) => grid,
        None => (0..5095).map(|i| end * i as f64 / 5094.0).collect(),
    };

    let mut m = study.section("material")?;
    let g0 = m.req_quantity("G0", Dimension::PRESSURE, pos)?;
    let mut prony = m.subsection("prony")?;
    let gs = prony.req_f64s("g", Bounds::open(0.0, 1.0))?;
    let taus = prony.req_quantities("tau", Dimension::TIME, pos)?;
    prony.finish()?;
    m.finish()?;
    if gs.len() != 2 || taus.len() != 2 {
        anyhow::bail!(
            "{}: [material.prony]: the cell model of eq. 5.1 has exactly two terms (g = [g1, g2], tau = [tau1, tau2]); got {} and {}",
            study.name(),
            gs.len(),
            taus.len()
        );
    }
    // G0 is the shear modulus of eq. 5.1 (docs/theory/model.md).
    let params = Prony::new("G", &[(gs[0], taus[0]), (gs[1], taus[1])])
        .and_then(|p| Relaxation::new(names::G0, g0, p))
        .with_context(|| format!("{}: [material.prony]", study.name()))?;

    if let Some(mut f) = study.opt_section("fem")? {
        setup.mesh = MeshSpec {
            elements_per_side: f
                .opt_usize("elements_per_side", Bounds::at_least(2.0))?
                .unwrap_or(setup.mesh.elements_per_side),
            bias: f.f64_or("bias", Bounds::at_least(1.0), setup.mesh.bias)?,
        };
        setup.bulk_ratio = f.f64_or("bulk_ratio", Bounds::at_least(1.0), setup.bulk_ratio)?;
        f.finish()?;
    }
    Ok((params, setup))
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let (params, setup) = read(&self.study)?;
        let output = self.output.unwrap_or_else(|| {
            let stem = self
                .study
                .file_stem()
                .map_or("study".into(), |s| s.to_string_lossy().to_string());
            self.study.with_file_name(format!("{stem}.simulate.csv"))
        });
        Ok(Config {
            study: self.study,
            output,
            mesh_output: self.mesh_output,
            params,
            setup,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let run = afm::run(&c.params, &c.setup)
            .with_context(|| format!("{}: simulation failed", c.study.display()))?;
        let mut table = Table::new(vec![
            Column::new("time", "s"),
            Column::new("piezo", "m"),
            Column::new("deflection", "m"),
            Column::new("force", "N"),
            Column::new("indentation", "m"),
        ]);
        for i in 0..run.time.len() {
            table.push_row(&[
                run.time[i],
                run.piezo[i],
                run.deflection[i],
                run.force[i],
                run.indentation[i],
            ])?;
        }
        table.write_csv(&c.output)?;
        if let Some(path) = &c.mesh_output {
            let mut csv = String::from("node,r_m,z_m\n");
            for (i, p) in run.deformed_nodes.iter().enumerate() {
                csv.push_str(&format!("{i},{:e},{:e}\n", p[0], p[1]));
            }
            csv.push_str("# elements: node indices, counter-clockwise\n");
            for e in &run.elements_connectivity {
                csv.push_str(&format!("# {},{},{},{}\n", e[0], e[1], e[2], e[3]));
            }
            write_atomic(path, csv.as_bytes())?;
        }
        let min_force = run.force.iter().cloned().fold(f64::INFINITY, f64::min);
        if ctx.json {
            print_json(&json!({
                "study": c.study.display().to_string(),
                "output": c.output.display().to_string(),
                "elements": run.elements,
                "peak_force_N": run.peak_force,
                "final_force_N": run.final_force,
                "min_force_N": min_force,
                "steps": run.steps,
                "cutbacks": run.cutbacks,
                "newton_iterations": run.iterations,
                "wall_time_s": run.wall_seconds,
            }))?;
        } else {
            println!(
                "{}: {} elements, {} steps ({} cut-backs, {} Newton iterations) in {:.2} s",
                c.study.display(),
                run.elements,
                run.steps,
                run.cutbacks,
                run.iterations,
                run.wall_seconds
            );
            println!(
                "peak force {:.4e} N, final force {:.4e} N, min force {:.4e} N → {}",
                run.peak_force,
                run.final_force,
                min_force,
                c.output.display()
            );
        }
        Ok(ExitCode::SUCCESS)
    }
}
