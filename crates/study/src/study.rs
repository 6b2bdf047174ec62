//! [`Study`]: a whole study file, handed out section by section.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use sha2::{Digest, Sha256};

use crate::error::{Result, StudyError};
use crate::section::{FromSection, Section};
use crate::source::Source;
use crate::tree::{self, Entry, Value};
use crate::units::{Dimension, Quantity, UnitError};

/// A parsed study file. Stages take their sections with [`Study::section`]
/// or [`Study::read`]; [`Study::finish`] then reports unknown top-level keys.
#[derive(Debug)]
#[must_use = "call finish() to report unknown sections"]
pub struct Study {
    root: Section,
    hash: StudyHash,
}

impl Study {
    /// Reads and parses a study file. Relative paths inside it resolve
    /// against its directory.
    ///
    /// # Errors
    /// [`StudyError::Io`] if unreadable, [`StudyError::Syntax`] for bad TOML.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| StudyError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Self::parse_in(path.display().to_string(), text, dir)
    }

    /// Parses study text held in memory; `name` appears in error messages and
    /// relative paths resolve against the current directory.
    ///
    /// # Errors
    /// [`StudyError::Syntax`] for bad TOML.
    pub fn parse(name: &str, text: &str) -> Result<Self> {
        Self::parse_in(name.to_string(), text.to_string(), PathBuf::new())
    }

    /// Parses study text; relative paths resolve against `base_dir`.
    ///
    /// # Errors
    /// [`StudyError::Syntax`] for bad TOML.
    pub fn parse_in(name: String, text: String, base_dir: PathBuf) -> Result<Self> {
        let src = Arc::new(Source::new(name, text, base_dir));
        let entries = {
            let parsed = toml::de::DeTable::parse(&src.text).map_err(|e| StudyError::Syntax {
                at: src.locate(e.span().map_or(0, |s| s.start)),
                message: e.message().to_string(),
            })?;
            tree::convert_table(parsed.get_ref()).map_err(|(at, message)| StudyError::Syntax {
                at: src.locate(at),
                message,
            })?
        };
        let hash = StudyHash::of(&entries);
        let root = Section::new(src, String::new(), 0, entries);
        Ok(Self { root, hash })
    }

    /// The provenance hash of this study (see [`StudyHash`]).
    pub fn hash(&self) -> &StudyHash {
        &self.hash
    }

    /// Provenance embedded in every JSON result: the study file, its
    /// SHA-256 hash ([`StudyHash`]) and the program version.
    pub fn provenance(&self) -> serde_json::Value {
        serde_json::json!({
            "study": self.name(),
            "study_sha256": self.hash().to_string(),
            "nlvid_version": env!("CARGO_PKG_VERSION"),
        })
    }

    /// The file name used in messages.
    pub fn name(&self) -> &str {
        &self.root.source().name
    }

    /// The directory relative paths resolve against.
    pub fn base_dir(&self) -> &Path {
        &self.root.source().base_dir
    }

    /// The top-level table, for top-level keys such as `title`.
    pub fn root(&mut self) -> &mut Section {
        &mut self.root
    }

    /// Whether a top-level section or key is present.
    pub fn has(&self, name: &str) -> bool {
        self.root.has(name)
    }

    /// A required section `[name]`; the caller must `finish()` it.
    ///
    /// # Errors
    /// Missing or not a table.
    pub fn section(&mut self, name: &str) -> Result<Section> {
        self.root.subsection(name)
    }

    /// An optional section.
    ///
    /// # Errors
    /// Not a table.
    pub fn opt_section(&mut self, name: &str) -> Result<Option<Section>> {
        self.root.opt_subsection(name)
    }

    /// Reads required section `[name]` into a stage's settings struct.
    ///
    /// # Errors
    /// As [`Section::read`].
    pub fn read<T: FromSection>(&mut self, name: &str) -> Result<T> {
        self.root.read(name)
    }

    /// Reads an optional section into a stage's settings struct.
    ///
    /// # Errors
    /// As [`Section::opt_read`].
    pub fn opt_read<T: FromSection>(&mut self, name: &str) -> Result<Option<T>> {
        self.root.opt_read(name)
    }

    /// Reports the first top-level key or section that nothing read.
    ///
    /// # Errors
    /// [`crate::ErrorKind::UnknownKey`] with its line.
    pub fn finish(self) -> Result<()> {
        self.root.finish()
    }

    /// Every leaf value of the file with its dotted key and line, strings
    /// that read as quantities converted to SI. Used by `nlvid check` to show
    /// what the program will see, without knowing any stage's schema.
    pub fn leaves(&self) -> Vec<Leaf> {
        let mut out = Vec::new();
        walk(self.root.source(), "", self.root.entries(), &mut out);
        out
    }
}

/// What [`Study::lint`] finds in the values of a study, schema aside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lint {
    /// Non-finite numbers (`nan`, `inf`, `"inf s"`), as `file:line:col: key …`.
    pub errors: Vec<String>,
    /// Strings that look like quantities but cannot be read (unknown unit,
    /// bad exponent, syntax), as `file:line:col: key …`.
    pub warnings: Vec<String>,
}

impl Study {
    /// Checks every leaf value without knowing any stage's schema: bare
    /// non-finite numbers and non-finite quantities are errors, strings
    /// that look like quantities but cannot be read are warnings.
    pub fn lint(&self) -> Lint {
        let mut out = Lint::default();
        for leaf in self.leaves() {
            let at = format!(
                "{}:{}:{}: key `{}`",
                self.name(),
                leaf.line,
                leaf.column,
                leaf.key
            );
            match &leaf.value {
                LeafValue::Number(x) if !x.is_finite() => {
                    out.errors
                        .push(format!("{at}: `{x}` is not a finite number"));
                }
                LeafValue::Text(t) => match Quantity::parse(t) {
                    Err(UnitError::NotFinite) => {
                        out.errors
                            .push(format!("{at}: `{t}` is not a finite number"));
                    }
                    Err(
                        e @ (UnitError::UnknownUnit(_)
                        | UnitError::BadExponent(_)
                        | UnitError::Syntax(..)),
                    ) => out.warnings.push(format!(
                        "{at}: `{t}` looks like a quantity but cannot be read: {e}"
                    )),
                    _ => {}
                },
                _ => {}
            }
        }
        out
    }
}

impl Study {
    /// Every value as the program reads it, for people: a header with the
    /// file and its hash, then `line  key  value (SI)  as written`, one
    /// leaf per row.
    pub fn values_table(&self) -> String {
        use std::fmt::Write as _;
        let leaves = self.leaves();
        let mut out = format!("{}  sha256 {}\n", self.name(), self.hash());
        let kw = leaves.iter().map(|l| l.key.len()).max().unwrap_or(3).max(3);
        let _ = writeln!(
            out,
            "{:>4}  {:kw$}  {:20}  as written",
            "line", "key", "value (SI)"
        );
        for l in &leaves {
            let (si, written) = match &l.value {
                LeafValue::Quantity { text, si } => (si.to_string(), text.clone()),
                LeafValue::Number(x) => (crate::units::fmt_number(*x), String::new()),
                LeafValue::Integer(i) => (i.to_string(), String::new()),
                LeafValue::Bool(b) => (b.to_string(), String::new()),
                LeafValue::Text(t) | LeafValue::Datetime(t) => (t.clone(), String::new()),
            };
            let _ = writeln!(out, "{:>4}  {:kw$}  {:20}  {written}", l.line, l.key, si);
        }
        out
    }
}

/// One leaf of a study file as the program reads it (see [`Study::leaves`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    /// Dotted key path (`geometry.radius`, `material.tau[1]`).
    pub key: String,
    /// 1-based line of the value.
    pub line: usize,
    /// 1-based column of the value.
    pub column: usize,
    /// The value.
    pub value: LeafValue,
}

/// The value of a [`Leaf`].
#[derive(Clone, Debug, PartialEq)]
pub enum LeafValue {
    /// A string that reads as a number with a unit, converted to SI.
    Quantity {
        /// As written.
        text: String,
        /// In SI.
        si: Quantity,
    },
    /// A bare number.
    Number(f64),
    /// An integer.
    Integer(i64),
    /// A boolean.
    Bool(bool),
    /// Any other string (names, file paths, choices).
    Text(String),
    /// A TOML date-time, as written.
    Datetime(String),
}

fn walk(src: &Source, prefix: &str, entries: &[Entry], out: &mut Vec<Leaf>) {
    for e in entries {
        let key = if prefix.is_empty() {
            e.key.clone()
        } else {
            format!("{prefix}.{}", e.key)
        };
        walk_value(src, key, &e.node, out);
    }
}

fn walk_value(src: &Source, key: String, node: &tree::Node, out: &mut Vec<Leaf>) {
    let at = src.locate(node.span.start);
    let (line, column) = (at.line, at.column);
    let value = match &node.value {
        Value::Table(t) => return walk(src, &key, t, out),
        Value::Array(a) => {
            for (j, n) in a.iter().enumerate() {
                walk_value(src, format!("{key}[{j}]"), n, out);
            }
            return;
        }
        Value::Str(s) => match Quantity::parse(s) {
            Ok(si) if si.dim != Dimension::NONE || s.trim().ends_with('%') => LeafValue::Quantity {
                text: s.clone(),
                si,
            },
            _ => LeafValue::Text(s.clone()),
        },
        Value::Int(i) => LeafValue::Integer(*i),
        Value::Float(x) => LeafValue::Number(*x),
        Value::Bool(b) => LeafValue::Bool(*b),
        Value::Datetime(d) => LeafValue::Datetime(d.clone()),
    };
    out.push(Leaf {
        key,
        line,
        column,
        value,
    });
}

/// SHA-256 of a study's canonical content, for provenance in outputs.
///
/// The canonical content is the parsed TOML tree with keys sorted, floats
/// by bit pattern and strings verbatim, prefixed by a format tag. Comments,
/// whitespace, key order and TOML spelling do not change the hash; any change
/// of a value does. Units are *not* normalised: `"5 mm/s"` and `"0.005 m/s"`
/// hash differently (the file states the same study in different words).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct StudyHash(pub [u8; 32]);

impl StudyHash {
    fn of(entries: &[Entry]) -> Self {
        let mut text = String::from("nlvid-study-v1\n");
        tree::canonical(entries, &mut text);
        let digest = Sha256::digest(text.as_bytes());
        let mut out = [0u8; 32];
        out.copy_from_slice(&digest);
        Self(out)
    }

    /// The first 12 hex digits, for file names and log lines.
    pub fn short(&self) -> String {
        self.to_string()[..12].to_string()
    }
}

impl fmt::Display for StudyHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for b in self.0 {
            write!(f, "{b:02x}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for StudyHash {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "StudyHash({self})")
    }
}
