//! `nlvid simulate <study.toml>`: one run of the study's forward model
//! (`[forward]` + `[protocol]`, the sections `nlvid build` reads) at the
//! parameter values of `[parameters]` ([`nlvid_forward::SimulateStudy`]);
//! writes the time history as CSV. See docs/cli/simulate.md.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nlvid_forward::{CurveJob, Noise, SimulateStudy};
use nlvid_study::Study;
use serde_json::json;

use super::{Context, Run};
use crate::output::{emit, print_text, write_atomic};

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
    /// Curve writer: a CSV of parameter sets (header: the model's parameter
    /// names, SI values; optional `name` column). Writes one synthetic AFM
    /// curve per row (`time [s]`, `piezo [um]`, `deflection [nm]`) on the
    /// model's output grid into --out-dir; the study needs no [parameters].
    #[arg(long, requires = "out_dir")]
    pub parameters: Option<PathBuf>,
    /// Curve writer: the output folder (`<name>.csv` per set).
    #[arg(long, requires = "parameters")]
    pub out_dir: Option<PathBuf>,
    /// Curve writer: Gaussian force noise, sd as a fraction of each curve's
    /// peak force, written on the deflection.
    #[arg(long, default_value_t = 0.0, requires = "parameters")]
    pub noise: f64,
    /// Curve writer: seed of the noise (one stream per row).
    #[arg(long, default_value_t = 1, requires = "parameters")]
    pub seed: u64,
    /// Curve writer, hertz-prony only: the cantilever's spring constant
    /// [N/m] for the deflection column (afm-fe uses its own).
    #[arg(long, requires = "parameters")]
    pub spring_constant: Option<f64>,
}

/// A validated simulation.
#[derive(Debug)]
pub enum Config {
    /// One run at the study's `[parameters]`.
    Run(Box<OneRun>),
    /// The curve writer (`--parameters`): the job and where its curves go.
    Curves(Box<(CurveJob, PathBuf)>),
}

/// One run: the study, its name and provenance, and where the files go.
#[derive(Debug)]
pub struct OneRun {
    name: String,
    provenance: serde_json::Value,
    sim: SimulateStudy,
    output: PathBuf,
    mesh_output: Option<PathBuf>,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        if let (Some(table), Some(out_dir)) = (&self.parameters, self.out_dir) {
            let noise = Noise {
                relative: self.noise,
                seed: self.seed,
            };
            let job = CurveJob::load(&self.study, table, self.spring_constant, noise)?;
            return Ok(Config::Curves(Box::new((job, out_dir))));
        }
        let study = Study::load(&self.study)?;
        let (name, provenance) = (study.name().to_string(), study.provenance());
        let sim = SimulateStudy::from_study(study)?;
        if self.mesh_output.is_some() && sim.model() != "afm-fe" {
            anyhow::bail!("--mesh-output: only the afm-fe model has a mesh");
        }
        let output = self
            .output
            .unwrap_or_else(|| nlvid_study::next_to(&self.study, "simulate.csv"));
        nlvid_study::check_output_file(&output)?;
        if let Some(m) = &self.mesh_output {
            nlvid_study::check_output_file(m)?;
        }
        Ok(Config::Run(Box::new(OneRun {
            output,
            name,
            provenance,
            sim,
            mesh_output: self.mesh_output,
        })))
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let c = match c {
            Config::Curves(curves) => {
                let (job, out_dir) = *curves;
                let (files, samples) = job.write(&out_dir)?;
                let text = job.summary(files.len(), samples, &out_dir);
                emit(ctx.json, &json!({ "curves": files }), &text)?;
                return Ok(ExitCode::SUCCESS);
            }
            Config::Run(run) => *run,
        };
        let run = c
            .sim
            .run(&[])
            .with_context(|| format!("{}: simulation failed", c.name))?;
        let curve = run.curve()?;
        write_atomic(&c.output, curve.to_csv().as_bytes())?;
        if let (Some(path), Some(csv)) = (&c.mesh_output, run.mesh_csv()) {
            write_atomic(path, csv.as_bytes())?;
        }
        let files = (json!({ "csv": c.output }), &*c.output.display().to_string());
        let text = run.report(ctx.json, &c.sim, (&c.name, &c.provenance), files)?;
        print_text(&text)?;
        Ok(ExitCode::SUCCESS)
    }
}
