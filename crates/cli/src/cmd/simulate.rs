//! `nlvid simulate <study.toml>`: one run of the study's forward model
//! (`[forward]` + `[protocol]`, the sections `nlvid build` reads) at the
//! parameter values of `[parameters]` ([`nlvid_forward::SimulateStudy`]);
//! writes the time history as CSV. See docs/cli/simulate.md.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nlvid_forward::{SimulateStudy, Simulation};
use nlvid_study::Study;
use serde_json::json;

use super::{Context, Run};
use crate::output::{curve_json, next_to, parameters_json, print_json, provenance, write_atomic};
use crate::say;

/// Raw arguments of `nlvid simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML) with [forward], [protocol] and [parameters].
    pub study: PathBuf,
    /// Output CSV (default: `<study stem>.simulate.csv` next to the study).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// afm-fe: also write the deformed mesh at the end of the run (node, r_m, z_m; elements as comment lines) to this CSV.
    #[arg(long)]
    pub mesh_output: Option<PathBuf>,
}

/// A validated simulation.
#[derive(Debug)]
pub struct Config {
    name: String,
    provenance: serde_json::Value,
    sim: SimulateStudy,
    output: PathBuf,
    mesh_output: Option<PathBuf>,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let study = Study::load(&self.study)?;
        let (name, provenance) = (study.name().to_string(), provenance(&study));
        let sim = SimulateStudy::from_study(study)?;
        if self.mesh_output.is_some() && sim.model() != "afm-fe" {
            anyhow::bail!("--mesh-output: only the afm-fe model has a mesh");
        }
        Ok(Config {
            output: self
                .output
                .unwrap_or_else(|| next_to(&self.study, "simulate.csv")),
            name,
            provenance,
            sim,
            mesh_output: self.mesh_output,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let run = c
            .sim
            .run(&[])
            .with_context(|| format!("{}: simulation failed", c.name))?;
        let curve = run.curve()?;
        write_atomic(&c.output, curve.to_csv().as_bytes())?;
        let fe = match &run {
            Simulation::AfmFe(r) => Some(r),
            _ => None,
        };
        if let (Some(path), Some(csv)) = (&c.mesh_output, run.mesh_csv()) {
            write_atomic(path, csv.as_bytes())?;
        }
        let force = curve.values("force").unwrap_or_default();
        // afm-fe: the peak over every solver step (the output grid may miss it).
        let peak = fe.map_or_else(
            || force.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            |r| r.peak_force,
        );
        let last = force.last().copied().unwrap_or(f64::NAN);
        let min = force.iter().copied().fold(f64::INFINITY, f64::min);
        if ctx.json {
            let mut doc = json!({
                "provenance": c.provenance,
                "model": c.sim.model(),
                "parameters": parameters_json(&c.sim.parameters()),
                "csv": c.output,
                "peak_force_N": peak, "final_force_N": last, "min_force_N": min,
                "curve": curve_json(&curve),
            });
            if let Some(r) = fe {
                doc["solver"] = json!({
                    "elements": r.elements, "steps": r.steps, "cutbacks": r.cutbacks,
                    "newton_iterations": r.iterations, "wall_time_s": r.wall_seconds,
                });
            }
            print_json(&doc)?;
            return Ok(ExitCode::SUCCESS);
        }
        if let Some(r) = fe {
            say!(
                "{}: {} elements, {} steps ({} cut-backs, {} Newton iterations) in {:.2} s",
                c.name,
                r.elements,
                r.steps,
                r.cutbacks,
                r.iterations,
                r.wall_seconds
            )?;
        }
        say!(
            "{}: peak force {peak:.4e} N, final force {last:.4e} N, min force {min:.4e} N → {}",
            c.sim.model(),
            c.output.display()
        )?;
        Ok(ExitCode::SUCCESS)
    }
}
