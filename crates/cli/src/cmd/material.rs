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
use crate::output::{Column, Table, print_json, provenance};
use crate::say;

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
        let material: MaterialSpec = study.read("material")?;
        let loading: LoadingSpec = study.read("loading")?;
        let output = self.output.unwrap_or_else(|| {
            let stem = self
                .study
                .file_stem()
                .map_or_else(|| "study".into(), |s| s.to_string_lossy().into_owned());
            self.study.with_file_name(format!("{stem}.material.csv"))
        });
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
        let mut cols = vec![
            Column::new("time", "s"),
            Column::new(if shear { "shear" } else { "stretch" }, ""),
            Column::new("sigma_1", "Pa"),
            Column::new("sigma_2", "Pa"),
            Column::new("sigma_3", "Pa"),
        ];
        if shear {
            cols.extend([
                Column::new("sigma_11", "Pa"),
                Column::new("sigma_22", "Pa"),
                Column::new("sigma_12", "Pa"),
                Column::new("N_1", "Pa"),
                Column::new("N_2", "Pa"),
            ]);
        }
        let mut table = Table::new(cols);
        for s in &samples {
            let mut row = vec![
                s.time,
                s.value,
                s.principal[0],
                s.principal[1],
                s.principal[2],
            ];
            if shear {
                let m = &s.cauchy;
                row.extend([
                    m[(0, 0)],
                    m[(1, 1)],
                    m[(0, 1)],
                    m[(0, 0)] - m[(1, 1)],
                    m[(1, 1)] - m[(2, 2)],
                ]);
            }
            table.push_row(&row)?;
        }
        table.write_csv(&c.output)?;
        let (model, params) = c.material.parameters();
        if ctx.json {
            let p: serde_json::Map<String, serde_json::Value> = params
                .iter()
                .map(|(n, v, u)| {
                    let key = if u.is_empty() {
                        n.clone()
                    } else {
                        format!("{n}_{u}")
                    };
                    (key, json!(v))
                })
                .collect();
            print_json(&json!({
                "provenance": provenance(&c.study),
                "model": model,
                "parameters": p,
                "mode": c.loading.mode.name(),
                "max_dt_s": c.loading.max_dt,
                "csv": c.output.display().to_string(),
                "curve": table.to_json(),
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
