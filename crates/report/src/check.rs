//! `nlvid check`: a study file validated as every stage that reads it
//! would validate it, and its values in SI. Checks TOML syntax, every
//! quantity string (unit known, finite), bare non-finite numbers, the
//! dimension of every key named after a parameter of the vocabulary
//! (`C1`, `G0`, `tau1`, … in any section), and runs the validation of every
//! stage whose sections the study has ([`STAGES`]): a study a stage would
//! refuse is refused here with the stage's message. The command line and
//! the Python package both call [`check_study`].

use std::path::{Path, PathBuf};

use nlvid_study::{Dimension, LeafValue, Section, Study, StudyError};
use serde_json::json;

/// Any stage's error (study, forward model, build, fit settings).
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

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
type StageValidation = fn(&Path) -> Result<(), BoxError>;

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
        crate::settings::FitSettings::load(p)?;
        Ok(())
    }),
    ("cohort", &["fit", "probe"], |p| {
        crate::settings::CohortSettings::load(p)?;
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
pub fn section_typos(study: &mut Study) -> Result<(), StudyError> {
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

/// What a check found.
#[derive(Debug, Clone)]
pub struct StudyCheck {
    /// The study file.
    pub path: PathBuf,
    /// Its provenance hash (SHA-256).
    pub hash: String,
    /// Every value, in SI.
    pub leaves: Vec<nlvid_study::Leaf>,
    /// The values as a text table.
    pub table: String,
    /// Sections and stages whose schema was checked.
    pub schema_checked: Vec<&'static str>,
    /// Strings that look like quantities but cannot be read.
    pub warnings: Vec<String>,
}

/// Validates the study at `path` (see the module documentation).
///
/// # Errors
/// The first problem, with the message the stage that reads the key gives
/// (file, line, key).
pub fn check_study(path: &Path) -> Result<StudyCheck, BoxError> {
    let mut study = Study::load(path)?;
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
        return Err(format!("{}: the study is empty (no values)", path.display()).into());
    }
    section_typos(&mut study)?;
    check_vocabulary_units(&mut Study::load(path)?)?;
    let mut ran = std::collections::BTreeSet::new();
    for (stage, sections, validate) in STAGES {
        if sections.iter().all(|s| study.has(s)) && ran.insert(*stage) {
            // The plain forward check only when no fuller stage ran.
            if *stage == "forward" && (ran.contains("simulate") || ran.contains("build")) {
                continue;
            }
            validate(path)?;
            schema_checked.push(*stage);
        }
    }
    let lint = study.lint();
    if let Some(e) = lint.errors.first() {
        return Err(e.clone().into());
    }
    Ok(StudyCheck {
        path: path.to_path_buf(),
        hash: study.hash().to_string(),
        leaves: study.leaves(),
        table: study.values_table(),
        schema_checked,
        warnings: lint.warnings,
    })
}

impl StudyCheck {
    /// The `--json` document of `nlvid check`.
    pub fn to_json(&self) -> serde_json::Value {
        let values: Vec<_> = self.leaves.iter().map(leaf_json).collect();
        json!({
            "study": self.path.display().to_string(),
            "sha256": self.hash,
            "schema_checked_sections": self.schema_checked,
            "values": values,
            "warnings": self.warnings,
        })
    }

    /// The text report of `nlvid check` (values table and verdict).
    pub fn text(&self) -> String {
        let checked = if self.schema_checked.is_empty() {
            "none registered yet".to_string()
        } else {
            self.schema_checked.join(", ")
        };
        format!(
            "{}ok: syntax, units and numbers valid; section schemas checked: {checked}\n",
            self.table
        )
    }
}

/// One value as JSON: key, line, SI value, SI unit, the string as written.
pub fn leaf_json(l: &nlvid_study::Leaf) -> serde_json::Value {
    let (value, unit, written) = match &l.value {
        LeafValue::Quantity { text, si } => (json!(si.value), si.dim.si_unit(), json!(text)),
        LeafValue::Number(x) => (json!(x), String::new(), json!(null)),
        LeafValue::Integer(i) => (json!(i), String::new(), json!(null)),
        LeafValue::Bool(b) => (json!(b), String::new(), json!(null)),
        LeafValue::Text(t) | LeafValue::Datetime(t) => (json!(t), String::new(), json!(null)),
    };
    json!({ "key": l.key, "line": l.line, "value": value, "unit": unit, "written": written })
}
