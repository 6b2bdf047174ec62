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
        let output = self
            .output
            .unwrap_or_else(|| next_to(&self.study, "simulate.csv"));
        crate::output::check_output_file(&output)?;
        if let Some(m) = &self.mesh_output {
            crate::output::check_output_file(m)?;
        }
        Ok(Config {
            output,
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
        if let (Some(path), Some(csv)) = (&c.mesh_output, run.mesh_csv()) {
            write_atomic(path, csv.as_bytes())?;
        }
        let files = json!({ "csv": c.output });
        let wrote = c.output.display().to_string();
        report(
            ctx.json,
            &c.name,
            &c.provenance,
            &c.sim,
            &run,
            files,
            &wrote,
        )?;
        Ok(ExitCode::SUCCESS)
    }
}

/// Prints one run: with `json`, provenance, model, parameters (unit
/// suffixed), the curve, the summary and `files`; else the summary and
/// `wrote` (where the files went).
///
/// # Errors
/// A non-finite value in the run; stdout cannot be written.
pub fn report(
    json: bool,
    name: &str,
    provenance: &serde_json::Value,
    sim: &SimulateStudy,
    run: &Simulation,
    files: serde_json::Value,
    wrote: &str,
) -> anyhow::Result<()> {
    if json {
        let mut doc = json!({
            "provenance": provenance,
            "model": sim.model(),
            "parameters": parameters_json(&sim.parameters()),
            "curve": curve_json(&run.curve()?),
        });
        for extra in [run.summary_json()?, files] {
            for (k, v) in extra.as_object().into_iter().flatten() {
                doc[k] = v.clone();
            }
        }
        return print_json(&doc);
    }
    say!("{} → {wrote}", run.summary_text(name)?)?;
    Ok(())
}
