//! [`Section`]: a reader for one TOML table that converts units, checks
//! ranges, and remembers which keys were read so that the rest can be
//! reported as unknown.

use std::path::PathBuf;
use std::sync::Arc;

use crate::bounds::Bounds;
use crate::error::{ErrorKind, Location, Result, StudyError};
use crate::source::Source;
use crate::tree::{Entry, Node, Value};
use crate::units::{Dimension, Quantity, UnitError, fmt_number};

/// A stage's settings struct that reads itself from one study section.
///
/// Implement this in the stage's own crate; [`Section::read`] and
/// [`crate::Study::read`] call it and then report unknown keys.
///
/// ```
/// use nlvid_study::{Bounds, Dimension, FromSection, Section, Study, StudyError};
///
/// struct Geometry { radius: f64, thickness: f64 }
///
/// impl FromSection for Geometry {
///     fn from_section(s: &mut Section) -> Result<Self, StudyError> {
///         let radius = s.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?;
///         let thickness = s.req_quantity("thickness", Dimension::LENGTH, Bounds::positive())?;
///         if thickness >= radius {
///             return Err(s.invalid("thickness", "wall must be thinner than the radius"));
///         }
///         Ok(Geometry { radius, thickness })
///     }
/// }
///
/// let mut study = Study::parse("demo.toml", "[geometry]\nradius = \"12.22 um\"\nthickness = \"50 nm\"\n")?;
/// let g: Geometry = study.read("geometry")?;
/// study.finish()?;
/// assert!((g.radius - 12.22e-6).abs() < 1e-18);
/// # Ok::<(), StudyError>(())
/// ```
pub trait FromSection: Sized {
    /// Reads every key this struct needs; unread keys are reported afterwards.
    ///
    /// # Errors
    /// Any [`StudyError`] from the section's readers, or one built with
    /// [`Section::invalid`] for cross-key checks.
    fn from_section(section: &mut Section) -> Result<Self>;
}

/// One table of a study file, being read by a pipeline stage.
///
/// Every `req_*`/`opt_*` call marks its key as read; [`Section::finish`]
/// then fails on the first key nobody read (in file order), naming it, its
/// line and the keys that were expected. All quantities come back in SI.
#[derive(Debug)]
#[must_use = "call finish() to report unknown keys"]
pub struct Section {
    src: Arc<Source>,
    path: String,
    at: usize,
    entries: Vec<Entry>,
    used: Vec<bool>,
    asked: Vec<String>,
}

impl Section {
    pub(crate) fn new(src: Arc<Source>, path: String, at: usize, entries: Vec<Entry>) -> Self {
        let used = vec![false; entries.len()];
        Self {
            src,
            path,
            at,
            entries,
            used,
            asked: Vec::new(),
        }
    }

    /// Dotted path of this table in the file (`""` for the top level).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Where this table starts (its header, or the key that holds it).
    pub fn location(&self) -> Location {
        self.src.locate(self.at)
    }

    /// Where `key`'s value is written, if present (does not mark it read).
    pub fn location_of(&self, key: &str) -> Option<Location> {
        self.index(key)
            .map(|i| self.src.locate(self.entries[i].node.span.start))
    }

    /// Whether `key` is present (does not mark it read).
    pub fn has(&self, key: &str) -> bool {
        self.index(key).is_some()
    }

    /// All keys present, in file order (does not mark them read).
    pub fn keys(&self) -> Vec<&str> {
        self.entries.iter().map(|e| e.key.as_str()).collect()
    }

    /// The full dotted name of `key` in this table, for messages.
    pub fn key_path(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// An error about `key` for checks the stage makes itself (e.g. "inner
    /// radius must be below outer radius"), located at the key's value, or
    /// at the table if the key is absent.
    pub fn invalid(&self, key: &str, message: impl Into<String>) -> StudyError {
        let mut message = message.into();
        let at = match self.index(key) {
            Some(i) => self.entries[i].node.span.start,
            None => match self.near_typo(key) {
                Some(k) => {
                    message.push_str(&format!("; the table has the unknown key `{k}`: a typo?"));
                    self.index(&k)
                        .map_or(self.at, |i| self.entries[i].key_span.start)
                }
                None => self.at,
            },
        };
        self.err(at, key, ErrorKind::Invalid(message))
    }

    /// An unread key of this table that looks like a typo of `key`.
    fn near_typo(&self, key: &str) -> Option<String> {
        let wanted = [key.to_string()];
        self.entries
            .iter()
            .zip(&self.used)
            .filter(|(e, u)| !**u && crate::error::closest(&e.key, &wanted).is_some())
            .map(|(e, _)| e.key.clone())
            .next()
    }

    /// Refuses a key whose meaning moved to another key (an old study file):
    /// if `old` is present, an error at it that names `new` and says why
    /// (`reason`), so no file silently keeps a reading that changed.
    ///
    /// # Errors
    /// [`ErrorKind::Invalid`] at `old` when it is present.
    pub fn renamed(&self, old: &str, new: &str, reason: &str) -> Result<()> {
        if self.has(old) {
            return Err(self.invalid(
                old,
                format!("`{old}` is no longer read here; write `{new}` instead ({reason})"),
            ));
        }
        Ok(())
    }

    /// Marks `key` as read without interpreting it (e.g. a key a stage
    /// deliberately ignores). Returns whether it was present.
    pub fn skip(&mut self, key: &str) -> bool {
        self.take(key).is_some()
    }

    // ---- quantities -------------------------------------------------------

    /// A required quantity of dimension `dim` within `bounds`, in SI.
    ///
    /// Dimensioned values must be strings with a unit (`"12.22 um"`); for
    /// [`Dimension::NONE`] a bare TOML number is also accepted.
    ///
    /// # Errors
    /// Missing key, wrong TOML type, missing unit, wrong dimension, unreadable
    /// unit, NaN/inf, or a value outside `bounds` — each naming file, line and key.
    pub fn req_quantity(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<f64> {
        let i = self.require(key, &format!("a {dim}, e.g. \"{}\"", example(dim)))?;
        self.quantity_of(
            &self.entries[i].node,
            &self.key_path(key),
            dim,
            bounds.into(),
        )
    }

    /// An optional quantity: `Ok(None)` when absent, errors as [`Self::req_quantity`].
    ///
    /// # Errors
    /// As [`Self::req_quantity`], except for a missing key.
    pub fn opt_quantity(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<Option<f64>> {
        self.take(key)
            .map(|i| {
                self.quantity_of(
                    &self.entries[i].node,
                    &self.key_path(key),
                    dim,
                    bounds.into(),
                )
            })
            .transpose()
    }

    /// An optional quantity with a default (in SI) used when absent.
    ///
    /// # Errors
    /// As [`Self::opt_quantity`].
    pub fn quantity_or(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
        default: f64,
    ) -> Result<f64> {
        Ok(self.opt_quantity(key, dim, bounds)?.unwrap_or(default))
    }

    /// A required array of quantities (`["1 s", "10 s"]`), each checked.
    ///
    /// # Errors
    /// As [`Self::req_quantity`] for each element (the key names the index,
    /// e.g. `material.tau[1]`), or wrong type if not an array.
    pub fn req_quantities(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<Vec<f64>> {
        let i = self.require(key, &format!("an array of {dim}"))?;
        self.quantities_of(i, key, dim, bounds.into())
    }

    /// An optional array of quantities.
    ///
    /// # Errors
    /// As [`Self::req_quantities`], except for a missing key.
    pub fn opt_quantities(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<Option<Vec<f64>>> {
        self.take(key)
            .map(|i| self.quantities_of(i, key, dim, bounds.into()))
            .transpose()
    }

    // ---- plain values -----------------------------------------------------

    /// A required dimensionless number (`0.3`, `1`, `"0.3"`, `"30 %"`).
    ///
    /// # Errors
    /// As [`Self::req_quantity`] with [`Dimension::NONE`].
    pub fn req_f64(&mut self, key: &str, bounds: impl Into<Bounds>) -> Result<f64> {
        self.req_quantity(key, Dimension::NONE, bounds)
    }

    /// An optional dimensionless number.
    ///
    /// # Errors
    /// As [`Self::opt_quantity`] with [`Dimension::NONE`].
    pub fn opt_f64(&mut self, key: &str, bounds: impl Into<Bounds>) -> Result<Option<f64>> {
        self.opt_quantity(key, Dimension::NONE, bounds)
    }

    /// A dimensionless number with a default.
    ///
    /// # Errors
    /// As [`Self::opt_f64`].
    pub fn f64_or(&mut self, key: &str, bounds: impl Into<Bounds>, default: f64) -> Result<f64> {
        Ok(self.opt_f64(key, bounds)?.unwrap_or(default))
    }

    /// A required array of dimensionless numbers.
    ///
    /// # Errors
    /// As [`Self::req_quantities`] with [`Dimension::NONE`].
    pub fn req_f64s(&mut self, key: &str, bounds: impl Into<Bounds>) -> Result<Vec<f64>> {
        self.req_quantities(key, Dimension::NONE, bounds)
    }

    /// A required non-negative integer (counts, seeds, numbers of terms).
    ///
    /// # Errors
    /// Missing key, not an integer, negative, or outside `bounds`.
    pub fn req_usize(&mut self, key: &str, bounds: impl Into<Bounds>) -> Result<usize> {
        let i = self.require(key, "a non-negative integer")?;
        self.usize_of(i, key, bounds.into())
    }

    /// An optional non-negative integer.
    ///
    /// # Errors
    /// As [`Self::req_usize`], except for a missing key.
    pub fn opt_usize(&mut self, key: &str, bounds: impl Into<Bounds>) -> Result<Option<usize>> {
        self.take(key)
            .map(|i| self.usize_of(i, key, bounds.into()))
            .transpose()
    }

    /// A non-negative integer with a default.
    ///
    /// # Errors
    /// As [`Self::opt_usize`].
    pub fn usize_or(
        &mut self,
        key: &str,
        bounds: impl Into<Bounds>,
        default: usize,
    ) -> Result<usize> {
        Ok(self.opt_usize(key, bounds)?.unwrap_or(default))
    }

    /// A required `u64` (e.g. a random seed).
    ///
    /// # Errors
    /// Missing key, not an integer, or negative.
    pub fn req_u64(&mut self, key: &str) -> Result<u64> {
        let i = self.require(key, "a non-negative integer")?;
        self.u64_of(i, key)
    }

    /// An optional `u64`.
    ///
    /// # Errors
    /// As [`Self::req_u64`], except for a missing key.
    pub fn opt_u64(&mut self, key: &str) -> Result<Option<u64>> {
        self.take(key).map(|i| self.u64_of(i, key)).transpose()
    }

    /// A required boolean.
    ///
    /// # Errors
    /// Missing key or not a boolean.
    pub fn req_bool(&mut self, key: &str) -> Result<bool> {
        let i = self.require(key, "true or false")?;
        self.bool_of(i, key)
    }

    /// An optional boolean.
    ///
    /// # Errors
    /// Not a boolean.
    pub fn opt_bool(&mut self, key: &str) -> Result<Option<bool>> {
        self.take(key).map(|i| self.bool_of(i, key)).transpose()
    }

    /// A required string.
    ///
    /// # Errors
    /// Missing key or not a string.
    pub fn req_str(&mut self, key: &str) -> Result<String> {
        let i = self.require(key, "a string")?;
        self.str_of(i, key)
    }

    /// An optional string.
    ///
    /// # Errors
    /// Not a string.
    pub fn opt_str(&mut self, key: &str) -> Result<Option<String>> {
        self.take(key).map(|i| self.str_of(i, key)).transpose()
    }

    /// A required choice among named values, e.g.
    /// `s.req_enum("model", &[("pipkin-rogers", Model::Pr), ("qlv", Model::Qlv)])`.
    ///
    /// # Errors
    /// Missing key, not a string, or not one of the names (all are listed).
    pub fn req_enum<T: Copy>(&mut self, key: &str, choices: &[(&str, T)]) -> Result<T> {
        let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
        let i = self.require(key, &format!("one of: {}", names.join(", ")))?;
        self.enum_of(i, key, choices)
    }

    /// An optional choice among named values.
    ///
    /// # Errors
    /// As [`Self::req_enum`], except for a missing key.
    pub fn opt_enum<T: Copy>(&mut self, key: &str, choices: &[(&str, T)]) -> Result<Option<T>> {
        self.take(key)
            .map(|i| self.enum_of(i, key, choices))
            .transpose()
    }

    /// An optional choice with a default used when absent.
    ///
    /// # Errors
    /// As [`Self::opt_enum`].
    pub fn enum_or<T: Copy>(&mut self, key: &str, choices: &[(&str, T)], default: T) -> Result<T> {
        Ok(self.opt_enum(key, choices)?.unwrap_or(default))
    }

    /// A required interval `[lo, hi]` written as a two-element array of
    /// quantities, e.g. a parameter's search domain `C1 = ["1 kPa", "10 kPa"]`.
    /// Both ends must lie in `bounds` and `lo < hi`.
    ///
    /// # Errors
    /// As [`Self::req_quantities`], or not exactly two elements, or `lo >= hi`.
    pub fn req_range(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<(f64, f64)> {
        let i = self.require(key, &format!("[lower, upper] as two values of {dim}"))?;
        self.range_of(i, key, dim, bounds.into())
    }

    /// An optional interval, as [`Self::req_range`].
    ///
    /// # Errors
    /// As [`Self::req_range`], except for a missing key.
    pub fn opt_range(
        &mut self,
        key: &str,
        dim: Dimension,
        bounds: impl Into<Bounds>,
    ) -> Result<Option<(f64, f64)>> {
        self.take(key)
            .map(|i| self.range_of(i, key, dim, bounds.into()))
            .transpose()
    }

    /// A required path, resolved against the study file's directory.
    /// Existence is not checked (outputs need not exist); see [`Self::req_input_file`].
    ///
    /// # Errors
    /// Missing key or not a string.
    pub fn req_path(&mut self, key: &str) -> Result<PathBuf> {
        let s = self.req_str(key)?;
        Ok(self.src.base_dir.join(s))
    }

    /// An optional path, resolved against the study file's directory.
    ///
    /// # Errors
    /// Not a string.
    pub fn opt_path(&mut self, key: &str) -> Result<Option<PathBuf>> {
        Ok(self.opt_str(key)?.map(|s| self.src.base_dir.join(s)))
    }

    /// A required input file that must exist, resolved against the study
    /// file's directory.
    ///
    /// # Errors
    /// Missing key, not a string, or no such file (the resolved path is shown).
    pub fn req_input_file(&mut self, key: &str) -> Result<PathBuf> {
        let p = self.req_path(key)?;
        if p.is_file() {
            Ok(p)
        } else {
            Err(self.invalid(key, format!("no such file: {}", p.display())))
        }
    }

    // ---- tables -----------------------------------------------------------

    /// A required sub-table. The returned section must be `finish()`ed (or
    /// use [`Self::read`], which does it).
    ///
    /// # Errors
    /// Missing key or not a table.
    pub fn subsection(&mut self, key: &str) -> Result<Section> {
        let i = self.require(key, "a table")?;
        self.table_of(i, key)
    }

    /// An optional sub-table.
    ///
    /// # Errors
    /// Not a table.
    pub fn opt_subsection(&mut self, key: &str) -> Result<Option<Section>> {
        self.take(key).map(|i| self.table_of(i, key)).transpose()
    }

    /// Reads a required sub-table into `T` and reports its unknown keys.
    ///
    /// # Errors
    /// As [`Self::subsection`], `T::from_section`, and [`Self::finish`].
    pub fn read<T: FromSection>(&mut self, key: &str) -> Result<T> {
        let mut s = self.subsection(key)?;
        let t = T::from_section(&mut s)?;
        s.finish()?;
        Ok(t)
    }

    /// Reads an optional sub-table into `T`.
    ///
    /// # Errors
    /// As [`Self::read`], except for a missing key.
    pub fn opt_read<T: FromSection>(&mut self, key: &str) -> Result<Option<T>> {
        match self.opt_subsection(key)? {
            None => Ok(None),
            Some(mut s) => {
                let t = T::from_section(&mut s)?;
                s.finish()?;
                Ok(Some(t))
            }
        }
    }

    /// An array of tables (`[[experiment]]`), one section per element,
    /// named `key[0]`, `key[1]`, …; an absent key gives an empty list.
    ///
    /// # Errors
    /// Not an array of tables.
    pub fn tables(&mut self, key: &str) -> Result<Vec<Section>> {
        let Some(i) = self.take(key) else {
            return Ok(Vec::new());
        };
        let node = &self.entries[i].node;
        let Value::Array(items) = &node.value else {
            return Err(self.wrong_type(node, key, "an array of tables ([[...]])"));
        };
        let mut out = Vec::with_capacity(items.len());
        for (j, n) in items.iter().enumerate() {
            let name = format!("{key}[{j}]");
            match &n.value {
                Value::Table(t) => out.push(Section::new(
                    self.src.clone(),
                    self.key_path(&name),
                    n.span.start,
                    t.clone(),
                )),
                _ => return Err(self.wrong_type(n, &name, "a table")),
            }
        }
        Ok(out)
    }

    /// Reads every element of an array of tables into `T`.
    ///
    /// # Errors
    /// As [`Self::tables`], `T::from_section` and [`Self::finish`].
    pub fn read_tables<T: FromSection>(&mut self, key: &str) -> Result<Vec<T>> {
        let mut out = Vec::new();
        for mut s in self.tables(key)? {
            out.push(T::from_section(&mut s)?);
            s.finish()?;
        }
        Ok(out)
    }

    /// Ends reading: fails on the first key (in file order) that nothing read.
    ///
    /// # Errors
    /// [`ErrorKind::UnknownKey`] at the key's line, listing the keys read here.
    pub fn finish(self) -> Result<()> {
        match self.used.iter().position(|u| !u) {
            None => Ok(()),
            Some(i) => {
                let e = &self.entries[i];
                Err(self.err(
                    e.key_span.start,
                    &e.key,
                    ErrorKind::UnknownKey {
                        key: e.key.clone(),
                        expected: self.asked.clone(),
                    },
                ))
            }
        }
    }

    // ---- internals --------------------------------------------------------

    fn index(&self, key: &str) -> Option<usize> {
        self.entries.iter().position(|e| e.key == key)
    }

    fn take(&mut self, key: &str) -> Option<usize> {
        if !self.asked.iter().any(|k| k == key) {
            self.asked.push(key.to_string());
        }
        let i = self.index(key)?;
        self.used[i] = true;
        Some(i)
    }

    fn require(&mut self, key: &str, expected: &str) -> Result<usize> {
        self.take(key).ok_or_else(|| {
            // An unread key that looks like a typo of this one: point at it.
            let near = self.near_typo(key);
            let at = near
                .as_ref()
                .and_then(|k| self.index(k))
                .map_or(self.at, |i| self.entries[i].key_span.start);
            self.err(
                at,
                key,
                ErrorKind::MissingKey {
                    expected: expected.to_string(),
                    near,
                },
            )
        })
    }

    fn err(&self, at: usize, key: &str, kind: ErrorKind) -> StudyError {
        StudyError::Key {
            at: self.src.locate(at),
            key: self.key_path(key),
            kind: Box::new(kind),
        }
    }

    fn err_full(&self, at: usize, full_key: &str, kind: ErrorKind) -> StudyError {
        StudyError::Key {
            at: self.src.locate(at),
            key: full_key.to_string(),
            kind: Box::new(kind),
        }
    }

    fn wrong_type(&self, node: &Node, key: &str, expected: &str) -> StudyError {
        self.err(
            node.span.start,
            key,
            ErrorKind::WrongType {
                expected: expected.to_string(),
                found: node.value.type_name().to_string(),
            },
        )
    }

    fn quantity_of(
        &self,
        node: &Node,
        full_key: &str,
        dim: Dimension,
        bounds: Bounds,
    ) -> Result<f64> {
        let at = node.span.start;
        let fail = |kind| self.err_full(at, full_key, kind);
        let (value, text) = match &node.value {
            Value::Str(s) => {
                let q = Quantity::parse(s).map_err(|reason| match reason {
                    UnitError::NotFinite => fail(ErrorKind::NotFinite { text: s.clone() }),
                    reason => fail(ErrorKind::BadQuantity {
                        text: s.clone(),
                        reason,
                    }),
                })?;
                if q.dim != dim {
                    return Err(fail(if q.dim == Dimension::NONE {
                        ErrorKind::MissingUnit {
                            text: s.trim().to_string(),
                            expected: dim,
                        }
                    } else {
                        ErrorKind::WrongDimension {
                            text: s.clone(),
                            found: q.dim,
                            expected: dim,
                        }
                    }));
                }
                (q.value, s.clone())
            }
            Value::Float(x) if !x.is_finite() => {
                return Err(fail(ErrorKind::NotFinite {
                    text: format!("{x}"),
                }));
            }
            Value::Int(_) | Value::Float(_) if dim != Dimension::NONE => {
                let text = match &node.value {
                    Value::Int(i) => i.to_string(),
                    Value::Float(x) => fmt_number(*x),
                    _ => String::new(),
                };
                return Err(fail(ErrorKind::MissingUnit {
                    text,
                    expected: dim,
                }));
            }
            Value::Int(i) => (*i as f64, i.to_string()),
            Value::Float(x) => (*x, fmt_number(*x)),
            other => {
                let expected = if dim == Dimension::NONE {
                    "a number".to_string()
                } else {
                    format!("a quantity string such as \"{}\"", example(dim))
                };
                return Err(fail(ErrorKind::WrongType {
                    expected,
                    found: other.type_name().to_string(),
                }));
            }
        };
        if !bounds.contains(value) {
            let q = Quantity { value, dim };
            let shown = if text.trim() == fmt_number(value) {
                q.to_string()
            } else {
                format!("{q} (from `{}`)", text.trim())
            };
            return Err(fail(ErrorKind::OutOfRange {
                value: shown,
                bounds: bounds.describe(dim),
            }));
        }
        Ok(value)
    }

    fn quantities_of(
        &self,
        i: usize,
        key: &str,
        dim: Dimension,
        bounds: Bounds,
    ) -> Result<Vec<f64>> {
        let node = &self.entries[i].node;
        let Value::Array(items) = &node.value else {
            return Err(self.wrong_type(node, key, &format!("an array of {dim}")));
        };
        items
            .iter()
            .enumerate()
            .map(|(j, n)| self.quantity_of(n, &self.key_path(&format!("{key}[{j}]")), dim, bounds))
            .collect()
    }

    fn range_of(&self, i: usize, key: &str, dim: Dimension, bounds: Bounds) -> Result<(f64, f64)> {
        let v = self.quantities_of(i, key, dim, bounds)?;
        let at = self.entries[i].node.span.start;
        match v[..] {
            [lo, hi] if lo < hi => Ok((lo, hi)),
            [_, _] => Err(self.err(
                at,
                key,
                ErrorKind::Invalid("lower end must be below upper end".into()),
            )),
            _ => Err(self.err(
                at,
                key,
                ErrorKind::Invalid(format!(
                    "expected [lower, upper] (2 values), found {} value(s)",
                    v.len()
                )),
            )),
        }
    }

    fn u64_of(&self, i: usize, key: &str) -> Result<u64> {
        let node = &self.entries[i].node;
        match node.value {
            Value::Int(x) if x >= 0 => Ok(x as u64),
            Value::Int(x) => Err(self.err(
                node.span.start,
                key,
                ErrorKind::OutOfRange {
                    value: x.to_string(),
                    bounds: ">= 0".into(),
                },
            )),
            _ => Err(self.wrong_type(node, key, "a non-negative integer")),
        }
    }

    fn usize_of(&self, i: usize, key: &str, bounds: Bounds) -> Result<usize> {
        let x = self.u64_of(i, key)?;
        let node = &self.entries[i].node;
        let out_of_range = |b: String| {
            self.err(
                node.span.start,
                key,
                ErrorKind::OutOfRange {
                    value: x.to_string(),
                    bounds: b,
                },
            )
        };
        let n = usize::try_from(x).map_err(|_| out_of_range(format!("<= {}", usize::MAX)))?;
        if bounds.contains(n as f64) {
            Ok(n)
        } else {
            Err(out_of_range(bounds.describe(Dimension::NONE)))
        }
    }

    fn bool_of(&self, i: usize, key: &str) -> Result<bool> {
        let node = &self.entries[i].node;
        match node.value {
            Value::Bool(b) => Ok(b),
            _ => Err(self.wrong_type(node, key, "true or false")),
        }
    }

    fn str_of(&self, i: usize, key: &str) -> Result<String> {
        let node = &self.entries[i].node;
        match &node.value {
            Value::Str(s) => Ok(s.clone()),
            _ => Err(self.wrong_type(node, key, "a string")),
        }
    }

    fn enum_of<T: Copy>(&self, i: usize, key: &str, choices: &[(&str, T)]) -> Result<T> {
        let s = self.str_of(i, key)?;
        choices
            .iter()
            .find(|c| c.0 == s)
            .map(|c| c.1)
            .ok_or_else(|| {
                self.err(
                    self.entries[i].node.span.start,
                    key,
                    ErrorKind::BadChoice {
                        value: s,
                        allowed: choices.iter().map(|c| c.0.to_string()).collect(),
                    },
                )
            })
    }

    fn table_of(&self, i: usize, key: &str) -> Result<Section> {
        let e = &self.entries[i];
        match &e.node.value {
            Value::Table(t) => Ok(Section::new(
                self.src.clone(),
                self.key_path(key),
                e.key_span.start,
                t.clone(),
            )),
            _ => Err(self.wrong_type(&e.node, key, "a table")),
        }
    }

    pub(crate) fn entries(&self) -> &[Entry] {
        &self.entries
    }

    pub(crate) fn source(&self) -> &Arc<Source> {
        &self.src
    }
}

fn example(dim: Dimension) -> String {
    if dim == Dimension::NONE {
        "0.3".to_string()
    } else {
        format!("1 {}", dim.example_unit())
    }
}
