//! Errors of study reading: every one names the file, line, column and key.

use std::fmt;
use std::path::PathBuf;

use crate::units::{Dimension, UnitError};

/// Result alias of this crate.
pub type Result<T, E = StudyError> = std::result::Result<T, E>;

/// A place in a study file: file name, 1-based line and column.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file as given by the user (or a name such as `<stdin>`).
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, counted in characters.
    pub column: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

/// Everything that can go wrong when reading a study file.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The file could not be read.
    #[error("{}: cannot read study file: {source}", path.display())]
    Io {
        /// The path that failed.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not valid TOML.
    #[error("{at}: TOML syntax error: {message}")]
    Syntax {
        /// Where the parser stopped.
        at: Location,
        /// The parser's message.
        message: String,
    },
    /// A key's value is wrong, missing or unknown.
    #[error("{at}: key `{key}`: {kind}")]
    Key {
        /// Where: the value, or the key, or the table header for missing keys.
        at: Location,
        /// Full dotted key path, e.g. `geometry.radius` or `experiment[1].speed`.
        key: String,
        /// What is wrong (boxed to keep `Result`s small).
        kind: Box<ErrorKind>,
    },
}

impl StudyError {
    /// The kind of a key error (`None` for I/O and syntax errors).
    pub fn kind(&self) -> Option<&ErrorKind> {
        match self {
            StudyError::Key { kind, .. } => Some(kind),
            _ => None,
        }
    }

    /// The location, if the error has one.
    pub fn location(&self) -> Option<&Location> {
        match self {
            StudyError::Key { at, .. } | StudyError::Syntax { at, .. } => Some(at),
            StudyError::Io { .. } => None,
        }
    }

    /// The dotted key path, if the error concerns a key.
    pub fn key(&self) -> Option<&str> {
        match self {
            StudyError::Key { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// What is wrong with a key.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ErrorKind {
    /// The key is not read by any stage: a typo or a misplaced key.
    #[error("unknown key{}", unknown_hint(.key, .expected))]
    UnknownKey {
        /// The unknown key as written.
        key: String,
        /// Keys the reader asked for in this table (may be empty).
        expected: Vec<String>,
    },
    /// A required key is absent.
    #[error("missing required key ({expected}){}", near_hint(.near))]
    MissingKey {
        /// What the key should hold.
        expected: String,
        /// An unread key of the same table that looks like a typo of this
        /// one (`n_trian` for `n_train`).
        near: Option<String>,
    },
    /// A value of the wrong TOML type.
    #[error("expected {expected}, found {found}")]
    WrongType {
        /// The expected TOML type.
        expected: String,
        /// The TOML type found.
        found: String,
    },
    /// A number without a unit where a dimensioned quantity is required.
    #[error("`{text}` has no unit; expected a {expected}, e.g. \"{text} {}\"", expected.example_unit())]
    MissingUnit {
        /// The text found.
        text: String,
        /// The dimension required.
        expected: Dimension,
    },
    /// A quantity of the wrong dimension.
    #[error("`{text}` is a {found}, expected a {expected}")]
    WrongDimension {
        /// The text found.
        text: String,
        /// The dimension of the text.
        found: Dimension,
        /// The dimension required.
        expected: Dimension,
    },
    /// The quantity could not be read.
    #[error("cannot read `{text}`: {reason}")]
    BadQuantity {
        /// The text found.
        text: String,
        /// Why.
        reason: UnitError,
    },
    /// NaN or infinity (also after conversion to SI).
    #[error("`{text}` is not a finite number")]
    NotFinite {
        /// The text found.
        text: String,
    },
    /// The value lies outside its allowed range.
    #[error("{value} is out of range: must be {bounds}")]
    OutOfRange {
        /// The value, in SI, with its unit.
        value: String,
        /// The allowed range, in SI, with units.
        bounds: String,
    },
    /// A string that is none of the allowed choices.
    #[error("`{value}` is not one of: {}", .allowed.join(", "))]
    BadChoice {
        /// The text found.
        value: String,
        /// The allowed choices.
        allowed: Vec<String>,
    },
    /// A check made by the stage that reads the section (cross-key rules).
    #[error("{0}")]
    Invalid(String),
}

fn near_hint(near: &Option<String>) -> String {
    near.as_ref().map_or_else(String::new, |k| {
        format!("; the table has the unknown key `{k}`: a typo?")
    })
}

fn unknown_hint(key: &str, expected: &[String]) -> String {
    match closest(key, expected) {
        Some(k) => format!(": did you mean `{k}`?{}", expected_hint(expected)),
        None => expected_hint(expected),
    }
}

/// The candidate closest to `key` when it is a likely typo of it: at most
/// two edits (insertions, deletions, substitutions, adjacent swaps) for
/// keys of five or more characters, one for shorter ones; ties go to the
/// first candidate.
pub fn closest<'a>(key: &str, candidates: &'a [String]) -> Option<&'a str> {
    let limit = if key.chars().count() >= 5 { 2 } else { 1 };
    candidates
        .iter()
        .map(|c| (edit_distance(&key.to_lowercase(), &c.to_lowercase()), c))
        .filter(|(d, c)| *d <= limit && c.as_str() != key)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c.as_str())
}

/// Optimal string alignment distance (Damerau–Levenshtein without
/// repeated edits of one substring).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    for i in 0..=a.len() {
        for j in 0..=b.len() {
            d[i * w + j] = if i == 0 || j == 0 {
                i + j
            } else {
                let cost = usize::from(a[i - 1] != b[j - 1]);
                let mut v = (d[(i - 1) * w + j] + 1)
                    .min(d[i * w + j - 1] + 1)
                    .min(d[(i - 1) * w + j - 1] + cost);
                if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                    v = v.min(d[(i - 2) * w + j - 2] + 1);
                }
                v
            };
        }
    }
    d[a.len() * w + b.len()]
}

fn expected_hint(expected: &[String]) -> String {
    if expected.is_empty() {
        String::new()
    } else {
        format!(" (expected one of: {})", expected.join(", "))
    }
}

/// The message nlvid prints for `err` (after `error: ` on the command line,
/// as the exception text in Python): the error and each of its causes,
/// `: `-joined, a cause whose text is already in the message left out (an
/// I/O error wrapped with its own text is printed once).
pub fn error_message(err: &(dyn std::error::Error + 'static)) -> String {
    let mut msg = String::new();
    let mut next = Some(err);
    while let Some(e) = next {
        let t = e.to_string();
        if !t.is_empty() && !msg.contains(&t) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(&t);
        }
        next = e.source();
    }
    msg
}

#[cfg(test)]
mod typo_tests {
    use super::*;

    #[test]
    fn typos_are_matched_unrelated_keys_are_not() {
        let keys: Vec<String> = ["n_train", "n_check", "seed"].map(String::from).to_vec();
        assert_eq!(closest("n_trian", &keys), Some("n_train"));
        assert_eq!(closest("n_chek", &keys), Some("n_check"));
        assert_eq!(closest("sede", &keys), Some("seed"));
        assert_eq!(closest("points", &keys), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("ab", "ba"), 1);
    }
}
