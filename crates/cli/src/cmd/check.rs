//! `nlvid check <study.toml>`: validate a study file and print every value
//! as the program reads it, in SI.
//!
//! Checks TOML syntax, every quantity string (unit known, finite), bare
//! non-finite numbers, the dimension of every key named after a parameter
//! of the vocabulary (`C1`, `G0`, `tau1`, … in any section), and runs the
//! validation of every stage whose sections the study has ([`STAGES`]): a
//! study a stage would refuse is refused here with the stage's message.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use nlvid_study::{Dimension, LeafValue, Section, Study, StudyError};
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

/// A stage's validation of a whole study file: exactly what the stage's
/// command runs before it computes anything.
type StageValidation = fn(&Path) -> anyhow::Result<()>;

/// `(stage, sections that select it, validation)`: a stage is checked when
/// the study has all of its sections.
const STAGES: &[(&str, &[&str], StageValidation)] = &[
    ("material", &["material", "loading"], |p| {
        let mut s = Study::load(p)?;
        s.read::<nlvid_material::MaterialSpec>("material")?;
        s.read::<nlvid_material::LoadingSpec>("loading")?;
        Ok(())
    }),
    ("simulate", &["forward", "parameters"], |p| {
        nlvid_forward::SimulateStudy::from_study(Study::load(p)?)?;
        Ok(())
    }),
    ("build", &["forward", "design"], |p| {
        nlvid_surrogate::BuildStudy::load(p)?;
        Ok(())
    }),
    ("build", &["forward", "build"], |p| {
        nlvid_surrogate::BuildStudy::load(p)?;
        Ok(())
    }),
    ("forward", &["forward"], |p| {
        nlvid_forward::ForwardSettings::from_study(&mut Study::load(p)?)?.build()?;
        Ok(())
    }),
    ("fit", &["fit"], |p| {
        nlvid_report::settings::FitSettings::load(p)?;
        Ok(())
    }),
    ("cohort", &["fit", "probe"], |p| {
        nlvid_report::settings::CohortSettings::load(p)?;
        Ok(())
    }),
];

/// The top-level sections the stages read (docs/study-format.md).
const KNOWN_SECTIONS: [&str; 12] = [
    "geometry",
    "protocol",
    "material",
    "loading",
    "forward",
    "parameters",
    "design",
    "build",
    "fit",
    "probe",
    "experiment",
    "slurm",
];

/// A top-level key that is a likely typo of a section name
/// (`[lodaing]`) is an error naming both: no stage would read it.
///
/// # Errors
/// The first such key, at its line.
pub(crate) fn section_typos(study: &mut Study) -> Result<(), StudyError> {
    let known: Vec<String> = KNOWN_SECTIONS.iter().map(|s| s.to_string()).collect();
    let keys: Vec<String> = study.root().keys().iter().map(|k| k.to_string()).collect();
    for k in keys {
        if known.contains(&k) {
            continue;
        }
        if let Some(near) = nlvid_study::closest(&k, &known) {
            return Err(study
                .root()
                .invalid(&k, format!("unknown section: did you mean [{near}]?")));
        }
    }
    Ok(())
}

/// Every key named after a vocabulary parameter (`nlvid_model::names`)
/// carries that parameter's dimension, whichever section holds it; the
/// message is the one a stage's reader gives.
fn check_vocabulary_units(study: &mut Study) -> Result<(), StudyError> {
    for leaf in study.leaves() {
        let LeafValue::Quantity { .. } = leaf.value else {
            continue;
        };
        let mut parts: Vec<&str> = leaf.key.split('.').collect();
        let Some(key) = parts.pop() else { continue };
        let dim = match nlvid_model::names::unit(key) {
            Some("Pa") => Dimension::PRESSURE,
            Some("s") => Dimension::TIME,
            Some("1") => Dimension::NONE,
            _ => continue,
        };
        let Some((first, rest)) = parts.split_first() else {
            study
                .root()
                .opt_quantity(key, dim, nlvid_study::Bounds::ANY)?;
            continue;
        };
        // Keys inside arrays of tables are not reachable by name: skip.
        let Ok(Some(mut s)) = study.opt_section(first) else {
            continue;
        };
        let mut reachable = true;
        for part in rest {
            match s.opt_subsection(part) {
                Ok(Some(sub)) => s = sub,
                _ => {
                    reachable = false;
                    break;
                }
            }
        }
        if reachable {
            s.opt_quantity(key, dim, nlvid_study::Bounds::ANY)?;
        }
    }
    Ok(())
}

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
        let has_forward = study.has("forward");
        for (name, reader) in STAGE_READERS {
            // With [forward], [protocol] is the forward model's (checked below).
            if has_forward && *name == "protocol" {
                continue;
            }
            if let Some(mut s) = study.opt_section(name)? {
                reader(&mut s)?;
                s.finish()?;
                schema_checked.push(*name);
            }
        }
        if study.leaves().is_empty() {
            anyhow::bail!("{}: the study is empty (no values)", self.study.display());
        }
        section_typos(&mut study)?;
        check_vocabulary_units(&mut Study::load(&self.study)?)?;
        let mut ran = std::collections::BTreeSet::new();
        for (stage, sections, validate) in STAGES {
            if sections.iter().all(|s| study.has(s)) && ran.insert(*stage) {
                // The plain forward check only when no fuller stage ran.
                if *stage == "forward" && (ran.contains("simulate") || ran.contains("build")) {
                    continue;
                }
                validate(&self.study)?;
                schema_checked.push(*stage);
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
    let (value, unit, written) = match &l.value {
        LeafValue::Quantity { text, si } => (json!(si.value), si.dim.si_unit(), json!(text)),
        LeafValue::Number(x) => (json!(x), String::new(), json!(null)),
        LeafValue::Integer(i) => (json!(i), String::new(), json!(null)),
        LeafValue::Bool(b) => (json!(b), String::new(), json!(null)),
        LeafValue::Text(t) | LeafValue::Datetime(t) => (json!(t), String::new(), json!(null)),
    };
    json!({ "key": l.key, "line": l.line, "value": value, "unit": unit, "written": written })
}
