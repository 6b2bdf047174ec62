//! `nlvid material <study.toml>`: drive one material through a homogeneous
//! deformation (uniaxial, equibiaxial, simple shear) under a stretch or
//! shear history and write the stress history as CSV (and JSON with
//! `--json`). See docs/cli/material.md.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use nlvid_material::homogeneous::Mode;
use nlvid_material::{LoadingSpec, MaterialSpec};
use nlvid_study::Study;
use serde_json::json;

use super::{Context, Run};
use crate::output::{print_json, write_atomic};

/// Raw arguments of `nlvid material`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file with `[material]` and `[loading]` sections.
    pub study: PathBuf,
    /// CSV output (default: `<study stem>.material.csv` next to the study).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Validated configuration.
#[derive(Debug)]
pub struct Config {
    study: Study,
    material: MaterialSpec,
    loading: LoadingSpec,
    output: PathBuf,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let mut study = Study::load(&self.study)?;
        super::check::section_typos(&mut study)?;
        let material: MaterialSpec = study.read("material")?;
        let loading: LoadingSpec = study.read("loading")?;
        let output = self
            .output
            .unwrap_or_else(|| nlvid_study::next_to(&self.study, "material.csv"));
        nlvid_study::check_output_file(&output)?;
        Ok(Config {
            study,
            material,
            loading,
            output,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let samples = c
            .material
            .drive(c.loading.mode, &c.loading.history, c.loading.max_dt)
            .with_context(|| format!("{}: driving the material", c.study.name()))?;
        let shear = c.loading.mode == Mode::SimpleShear;
        let curve = nlvid_material::samples_curve(&samples, c.loading.mode)?;
        write_atomic(&c.output, curve.to_csv().as_bytes())?;
        let (model, params) = c.material.parameters();
        if ctx.json {
            let p: Vec<(String, f64, String)> = params
                .iter()
                .map(|(n, v, u)| (n.to_string(), *v, u.to_string()))
                .collect();
            print_json(&json!({
                "provenance": c.study.provenance(),
                "model": model,
                "parameters": nlvid_model::parameters_json(&p),
                "mode": c.loading.mode.name(),
                "max_dt_s": c.loading.max_dt,
                "csv": c.output.display().to_string(),
                "curve": curve.to_json(),
            }))?;
        } else {
            let last = samples.last().context("no samples")?;
            say!(
                "{model}, {}: {} points to t = {} s; final {} = {}, sigma_1 = {} Pa",
                c.loading.mode.name(),
                samples.len(),
                last.time,
                if shear { "shear" } else { "stretch" },
                last.value,
                last.principal[0]
            )?;
            say!("wrote {}", c.output.display())?;
        }
        Ok(ExitCode::SUCCESS)
    }
}
