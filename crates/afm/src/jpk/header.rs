//! JPK `.properties` headers: reading them out of the archive, and the per-segment view
//! that resolves references into `shared-data/header.properties`.
//!
//! Format 2.0 files keep what is common to many segments once, in the shared header,
//! and refer to it from each segment header with keys ending in `.*`:
//!
//! ```text
//! segment header:  channel.vDeflection.lcd-info.*=1
//!                  force-segment-header.force-segment-header-info.*=0
//! shared header:   lcd-info.1.encoder.scaling.multiplier=…
//!                  force-segment-header-info.0.settings.style=extend
//! ```
//!
//! A reference `<head>.<section>.*=<n>` stands for every shared key `<section>.<n>.<rest>`
//! under the name `<head>.<rest>` (the rule the Python reader afmformats applies). Single
//! curves of format 2.0 refer to shared channel descriptions (`lcd-info`);
//! force and QI maps also refer to shared segment settings (`force-segment-header-info`).

use std::collections::HashMap;
use std::io::Read;

use super::Zip;
use crate::error::{AfmError, Result};

/// Largest archive entry the reader will decompress (guards against zip bombs).
const MAX_ENTRY_BYTES: u64 = 1 << 30;

/// The shared header's file name.
pub(super) const SHARED: &str = "shared-data/header.properties";

/// Keys and values of one `.properties` file.
pub(super) type Props = HashMap<String, String>;

/// Decompress one archive entry.
pub(super) fn read_entry(zip: &mut Zip<'_>, name: &str) -> Result<Vec<u8>> {
    let mut file = zip.by_name(name).map_err(|e| AfmError::Corrupt {
        entry: name.into(),
        detail: e.to_string(),
    })?;
    if file.size() > MAX_ENTRY_BYTES {
        return Err(AfmError::Corrupt {
            entry: name.into(),
            detail: format!(
                "entry claims {} bytes (limit {MAX_ENTRY_BYTES})",
                file.size()
            ),
        });
    }
    let mut buf = Vec::new();
    file.by_ref()
        .take(MAX_ENTRY_BYTES + 1)
        .read_to_end(&mut buf)
        .map_err(|e| AfmError::Corrupt {
            entry: name.into(),
            detail: e.to_string(),
        })?;
    Ok(buf)
}

/// Read and parse a `.properties` entry.
pub(super) fn read_props(zip: &mut Zip<'_>, name: &str) -> Result<Props> {
    let bytes = read_entry(zip, name)?;
    // Decode ISO-8859-1 (the .properties encoding) here and hand java-properties valid
    // UTF-8: its own decoder sniffs byte-order marks and panics on a UTF-16 BOM followed
    // by an odd byte count (found by fuzzing, java-properties 2.0.0 / encoding_rs 0.8).
    // Latin-1 text re-encoded as UTF-8 can hold neither a BOM nor an incomplete sequence.
    let text: String = bytes.iter().map(|&b| char::from(b)).collect();
    let mut props = Props::new();
    java_properties::PropertiesIter::new_with_encoding(text.as_bytes(), encoding_rs::UTF_8)
        .read_into(|k, v| {
            props.insert(k, v);
        })
        .map_err(|e| AfmError::Properties {
            entry: name.into(),
            line: e.line_number().unwrap_or(0),
            detail: e.to_string(),
        })?;
    Ok(props)
}

/// The shared header grouped by `<section>.<n>.` (e.g. `lcd-info.1.`), built once per file.
#[derive(Debug, Default)]
pub(super) struct Shared {
    groups: HashMap<String, Vec<(String, String)>>,
}

impl Shared {
    pub(super) fn new(props: &Props) -> Self {
        let mut groups: HashMap<String, Vec<(String, String)>> = HashMap::new();
        for (k, v) in props {
            let mut it = k.splitn(3, '.');
            if let (Some(section), Some(n), Some(rest)) = (it.next(), it.next(), it.next()) {
                groups
                    .entry(format!("{section}.{n}."))
                    .or_default()
                    .push((rest.to_string(), v.clone()));
            }
        }
        Shared { groups }
    }
}

/// One reference `<head>.<section>.*=<n>` of a segment header into the shared header.
#[derive(Debug, Clone)]
struct SharedRef {
    /// The reference as written, e.g. `channel.vDeflection.lcd-info.*=1`.
    written: String,
    /// `<head>.` as seen in the merged view, e.g. `channel.vDeflection.`.
    head: String,
    /// `<section>.<n>.` in the shared header, e.g. `lcd-info.1.`.
    shared: String,
}

/// A segment header with its shared references resolved: what the reader looks keys up in.
#[derive(Debug, Clone)]
pub(super) struct Merged {
    /// Archive entry of the segment header.
    entry: String,
    /// Segment keys and resolved shared keys (shared values win, as in afmformats).
    props: Props,
    /// Keys the segment header itself sets.
    own: std::collections::HashSet<String>,
    refs: Vec<SharedRef>,
}

impl Merged {
    /// Resolve the `.*` references of `segment` (read from `entry`) against `shared`.
    ///
    /// # Errors
    /// [`AfmError::MissingKey`] if the segment refers to shared data the archive lacks,
    /// or to a shared section that is absent.
    pub(super) fn new(entry: &str, segment: Props, shared: Option<&Shared>) -> Result<Self> {
        let mut refs = Vec::new();
        let mut keys: Vec<&String> = segment.keys().filter(|k| k.ends_with(".*")).collect();
        keys.sort();
        for key in keys {
            let n = segment[key].trim();
            let stem = &key[..key.len() - 2];
            let Some((head, section)) = stem.rsplit_once('.') else {
                continue;
            };
            refs.push(SharedRef {
                written: format!("{key}={n}"),
                head: format!("{head}."),
                shared: format!("{section}.{n}."),
            });
        }
        let own = segment.keys().cloned().collect();
        let mut props = segment;
        for r in &refs {
            let group = shared
                .ok_or_else(|| AfmError::MissingKey {
                    entry: SHARED.into(),
                    key: format!(
                        "{}* (referred to by {entry}; the archive has no shared header)",
                        r.shared
                    ),
                })?
                .groups
                .get(&r.shared)
                .ok_or_else(|| AfmError::MissingKey {
                    entry: SHARED.into(),
                    key: format!("{}* (referred to by {entry})", r.shared),
                })?;
            for (rest, v) in group {
                props.insert(format!("{}{rest}", r.head), v.clone());
            }
        }
        Ok(Merged {
            entry: entry.to_string(),
            props,
            own,
            refs,
        })
    }

    /// Accessor naming this header in errors.
    pub(super) fn hdr(&self) -> Hdr<'_> {
        Hdr { merged: self }
    }
}

/// Key look-ups on a [`Merged`] header whose errors name the file and key at fault.
#[derive(Clone, Copy)]
pub(super) struct Hdr<'a> {
    merged: &'a Merged,
}

impl<'a> Hdr<'a> {
    /// Where `key` lives, as (entry, key there): a key resolved through a shared
    /// reference is named by its place in the shared header; a key the segment sets
    /// itself, or one missing from both, by the segment header.
    pub(super) fn locate(&self, key: &str) -> (String, String) {
        let m = self.merged;
        if !m.own.contains(key) {
            for r in &m.refs {
                if let Some(rest) = key.strip_prefix(&r.head) {
                    let shared_key = format!("{}{rest}", r.shared);
                    return if m.props.contains_key(key) {
                        (
                            format!("{SHARED} (via {} in {})", r.written, m.entry),
                            shared_key,
                        )
                    } else {
                        (
                            format!("{} (nor {shared_key} in {SHARED})", m.entry),
                            key.to_string(),
                        )
                    };
                }
            }
        }
        (m.entry.clone(), key.to_string())
    }

    /// Entry name of the segment header itself.
    pub(super) fn entry(&self) -> &'a str {
        &self.merged.entry
    }

    pub(super) fn opt(&self, key: &str) -> Option<&'a str> {
        self.merged.props.get(key).map(String::as_str)
    }

    pub(super) fn missing(&self, key: &str) -> AfmError {
        let (entry, key) = self.locate(key);
        AfmError::MissingKey { entry, key }
    }

    pub(super) fn get(&self, key: &str) -> Result<&'a str> {
        self.opt(key).ok_or_else(|| self.missing(key))
    }

    pub(super) fn bad(&self, key: &str, value: &str, expected: &str) -> AfmError {
        let (entry, key) = self.locate(key);
        AfmError::BadValue {
            entry,
            key,
            value: value.into(),
            expected: expected.into(),
        }
    }

    pub(super) fn unsupported(&self, key: &str, what: String) -> AfmError {
        let (entry, key) = self.locate(key);
        AfmError::Unsupported {
            entry,
            what: format!("{what} (key {key})"),
        }
    }

    pub(super) fn f64(&self, key: &str) -> Result<f64> {
        let v = self.get(key)?;
        v.trim()
            .parse::<f64>()
            .map_err(|_| self.bad(key, v, "a number"))
    }

    pub(super) fn finite(&self, key: &str) -> Result<f64> {
        let x = self.f64(key)?;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.bad(key, self.opt(key).unwrap_or(""), "a finite number"))
        }
    }

    pub(super) fn usize(&self, key: &str) -> Result<usize> {
        let v = self.get(key)?;
        v.trim()
            .parse::<usize>()
            .map_err(|_| self.bad(key, v, "a non-negative integer"))
    }
}
