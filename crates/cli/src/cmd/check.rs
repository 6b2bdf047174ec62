//! `nlvid check <study.toml>`: validate a study file and print every value
//! as the program reads it, in SI.
//!
//! Checks TOML syntax, every quantity string (unit known, finite), bare
//! non-finite numbers, and — for sections whose stage has registered a
//! reader in [`STAGE_READERS`] — the full schema (required keys, dimensions,
//! ranges, unknown keys).

use std::path::PathBuf;
use std::process::ExitCode;

use nlvid_study::{LeafValue, Section, Study, StudyError};
use serde_json::json;

use super::{Context, Run};
use crate::output::{print_json, print_text};

/// A stage's schema check for one top-level section: reads it fully (the
/// caller then reports unknown keys).
type SectionReader = fn(&mut Section) -> Result<(), StudyError>;

/// Stages register `(section name, reader)` here so that `nlvid check`
/// validates their sections' schema; other sections get syntax, units and
/// numbers checked, not their keys.
const STAGE_READERS: &[(&str, SectionReader)] = &[("protocol", |s| {
    <nlvid_protocol::ProtocolSettings as nlvid_study::FromSection>::from_section(s).map(|_| ())
})];

/// Raw arguments of `nlvid check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML).
    pub study: PathBuf,
    /// Treat warnings (strings that look like quantities but cannot be read) as errors.
    #[arg(long)]
    pub strict: bool,
}

/// What `check` found: the study's values and any warnings.
#[derive(Debug)]
pub struct Config {
    path: PathBuf,
    hash: String,
    leaves: Vec<nlvid_study::Leaf>,
    table: String,
    schema_checked: Vec<&'static str>,
    warnings: Vec<String>,
    strict: bool,
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let mut study = Study::load(&self.study)?;
        let mut schema_checked = Vec::new();
        for (name, reader) in STAGE_READERS {
            if let Some(mut s) = study.opt_section(name)? {
                reader(&mut s)?;
                s.finish()?;
                schema_checked.push(*name);
            }
        }
        let lint = study.lint();
        if let Some(e) = lint.errors.first() {
            anyhow::bail!("{e}");
        }
        let (leaves, warnings) = (study.leaves(), lint.warnings);
        Ok(Config {
            path: self.study,
            hash: study.hash().to_string(),
            leaves,
            table: study.values_table(),
            schema_checked,
            warnings,
            strict: self.strict,
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        if ctx.json {
            let values: Vec<_> = c.leaves.iter().map(leaf_json).collect();
            print_json(&json!({
                "study": c.path.display().to_string(),
                "sha256": c.hash,
                "schema_checked_sections": c.schema_checked,
                "values": values,
                "warnings": c.warnings,
            }))?;
        } else {
            let checked = if c.schema_checked.is_empty() {
                "none registered yet".to_string()
            } else {
                c.schema_checked.join(", ")
            };
            print_text(&format!(
                "{}ok: syntax, units and numbers valid; section schemas checked: {checked}\n",
                c.table
            ))?;
            for w in &c.warnings {
                eprintln!("warning: {w}");
            }
        }
        if c.strict && !c.warnings.is_empty() {
            eprintln!("error: {} warning(s) with --strict", c.warnings.len());
            return Ok(ExitCode::FAILURE);
        }
        Ok(ExitCode::SUCCESS)
    }
}

fn leaf_json(l: &nlvid_study::Leaf) -> serde_json::Value {
    let mut v = json!({ "key": l.key, "line": l.line });
    let (value, unit, written) = match &l.value {
        LeafValue::Quantity { text, si } => (json!(si.value), si.dim.si_unit(), json!(text)),
        LeafValue::Number(x) => (json!(x), String::new(), json!(null)),
        LeafValue::Integer(i) => (json!(i), String::new(), json!(null)),
        LeafValue::Bool(b) => (json!(b), String::new(), json!(null)),
        LeafValue::Text(t) | LeafValue::Datetime(t) => (json!(t), String::new(), json!(null)),
    };
    v["value"] = value;
    v["unit"] = json!(unit);
    v["written"] = written;
    v
}
