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
    parse_properties(&read_entry(zip, name)?, name)
}

/// Parse Java `.properties` text (ISO-8859-1), as `java.util.Properties.load` does:
/// natural lines end at `\n`, `\r` or `\r\n`; a line ending in an odd number of
/// backslashes continues on the next (whose leading blanks are dropped); blank lines
/// and lines whose first non-blank character is `#` or `!` are comments; the key ends
/// at the first unescaped `=`, `:` or blank, then blanks and one `=`/`:` separate it
/// from the value; `\t \n \r \f \uXXXX` are escapes and `\x` stands for `x`.
/// Blanks are space, tab and form feed. (Replaces the java-properties crate, whose
/// regex-based parser was a sixth of the cost of a batch.)
///
/// # Errors
/// [`AfmError::Properties`] for a malformed `\uXXXX` escape, with its line.
pub(super) fn parse_properties(bytes: &[u8], entry: &str) -> Result<Props> {
    let blank = |c: u8| c == b' ' || c == b'\t' || c == 0x0c;
    let mut props = Props::new();
    let mut i = 0;
    let mut line_no = 0usize;
    let n = bytes.len();
    // One natural line: [start, end) and the index after its terminator.
    let natural = |from: usize| -> (usize, usize) {
        let mut e = from;
        while e < n && bytes[e] != b'\n' && bytes[e] != b'\r' {
            e += 1;
        }
        let next = if e < n && bytes[e] == b'\r' && e + 1 < n && bytes[e + 1] == b'\n' {
            e + 2
        } else {
            e + 1
        };
        (e, next)
    };
    while i < n {
        // Skip leading blanks of the natural line.
        let (mut end, mut next) = natural(i);
        line_no += 1;
        let first_line = line_no;
        let mut start = i;
        while start < end && blank(bytes[start]) {
            start += 1;
        }
        if start == end || bytes[start] == b'#' || bytes[start] == b'!' {
            i = next;
            continue;
        }
        // Gather the logical line (continuations), raw, without the joining backslashes.
        let mut logical: Vec<u8> = Vec::new();
        loop {
            let seg = &bytes[start..end];
            let trailing = seg.iter().rev().take_while(|&&c| c == b'\\').count();
            if trailing % 2 == 1 && next <= n && end < n {
                logical.extend_from_slice(&seg[..seg.len() - 1]);
                let (e2, n2) = natural(next);
                line_no += 1;
                start = next;
                while start < e2 && blank(bytes[start]) {
                    start += 1;
                }
                end = e2;
                next = n2;
            } else {
                if trailing % 2 == 1 {
                    // a final backslash at the end of the input is dropped
                    logical.extend_from_slice(&seg[..seg.len() - 1]);
                } else {
                    logical.extend_from_slice(seg);
                }
                break;
            }
        }
        i = next;
        // Split key and value at the first unescaped separator.
        let mut k = 0;
        let mut escaped = false;
        while k < logical.len() {
            let c = logical[k];
            if escaped {
                escaped = false;
            } else if c == b'\\' {
                escaped = true;
            } else if c == b'=' || c == b':' || blank(c) {
                break;
            }
            k += 1;
        }
        let key_raw = &logical[..k];
        let mut v = k;
        while v < logical.len() && blank(logical[v]) {
            v += 1;
        }
        if v < logical.len() && (logical[v] == b'=' || logical[v] == b':') {
            v += 1;
            while v < logical.len() && blank(logical[v]) {
                v += 1;
            }
        }
        let bad = |detail: String| AfmError::Properties {
            entry: entry.into(),
            line: first_line,
            detail,
        };
        let key = unescape(key_raw).map_err(&bad)?;
        let value = unescape(&logical[v..]).map_err(&bad)?;
        props.insert(key, value);
    }
    Ok(props)
}

/// Resolve `.properties` escapes in ISO-8859-1 bytes.
fn unescape(raw: &[u8]) -> std::result::Result<String, String> {
    let mut out = String::with_capacity(raw.len());
    let mut j = 0;
    while j < raw.len() {
        let c = raw[j];
        j += 1;
        if c != b'\\' {
            out.push(char::from(c));
            continue;
        }
        let Some(&e) = raw.get(j) else {
            break;
        };
        j += 1;
        match e {
            b't' => out.push('\t'),
            b'n' => out.push('\n'),
            b'r' => out.push('\r'),
            b'f' => out.push('\u{c}'),
            b'u' => {
                let hex = raw
                    .get(j..j + 4)
                    .and_then(|h| std::str::from_utf8(h).ok())
                    .and_then(|h| u32::from_str_radix(h, 16).ok())
                    .ok_or_else(|| "malformed \\uXXXX escape".to_string())?;
                j += 4;
                // A lone surrogate half cannot be a char; keep U+FFFD in its place.
                out.push(char::from_u32(hex).unwrap_or('\u{fffd}'));
            }
            other => out.push(char::from(other)),
        }
    }
    Ok(out)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &[u8]) -> Props {
        parse_properties(text, "t").expect("parses")
    }

    #[test]
    fn properties_follow_the_java_rules() {
        // Separators, blanks around them, comments, blank lines, line endings.
        let p = parse(b"# comment\r\n! also\n\n  a=1\rb : 2\r\nc 3\nd\te=\nf\n  g = x = y\n");
        assert_eq!(p["a"], "1");
        assert_eq!(p["b"], "2");
        assert_eq!(p["c"], "3");
        assert_eq!(p["d"], "e=");
        assert_eq!(p["f"], "");
        assert_eq!(p["g"], "x = y");
        assert_eq!(p.len(), 6);
        // Escapes in keys and values; JPK writes `\:` in time stamps.
        let p = parse(b"k\\=ey=2021-06-30 12\\:37\\:07\\t\\u00b5\\\\z\n");
        assert_eq!(p["k=ey"], "2021-06-30 12:37:07\t\u{b5}\\z");
        // Continuation: odd trailing backslashes join lines, leading blanks dropped;
        // an even count is a literal backslash.
        let p = parse(b"list=a \\\n    b \\\r\n\tc\neven=x\\\\\nnext=1\n");
        assert_eq!(p["list"], "a b c");
        assert_eq!(p["even"], "x\\");
        assert_eq!(p["next"], "1");
        // Latin-1 bytes decode one to one.
        assert_eq!(parse(b"u=\xb5m\n")["u"], "\u{b5}m");
        // A malformed unicode escape names its line.
        let err = parse_properties(b"a=1\nb=\\u12x4\n", "hdr").expect_err("bad escape");
        assert!(
            matches!(&err, AfmError::Properties { entry, line: 2, .. } if entry == "hdr"),
            "{err}"
        );
        // Last line without terminator, and a lone trailing backslash.
        assert_eq!(parse(b"a=1")["a"], "1");
        assert_eq!(parse(b"a=1\\")["a"], "1");
    }
}
