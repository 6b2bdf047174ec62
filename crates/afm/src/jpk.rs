//! JPK `.jpk-force` / `.jpk-force-map` reader.
//!
//! A JPK force file is a ZIP archive of Java `.properties` headers and raw big-endian
//! channel files:
//!
//! ```text
//! header.properties                      jpk-data-file, file-format-version, ...
//! shared-data/header.properties          (format ≥ 2.0) lcd-info.N.*: encoder + conversions
//! segments/<m>/segment-header.properties duration, num-points, style, channels.list,
//!                                        channel.<ch>.* (0.12: encoder/conversions inline,
//!                                        2.0: channel.<ch>.lcd-info.*=N → shared lcd-info.N)
//! segments/<m>/channels/<ch>.dat         raw samples
//! ```
//!
//! A force map holds the same tree once per curve under `index/<n>/`.
//!
//! Decoding a channel: raw integer (or float) → volts with the *encoder* scaling
//! `v = offset + multiplier·raw`; then along the channel's conversion set from the
//! base slot (`volts`) to the default slot, each step `y = offset + multiplier·x`
//! (`vDeflection`: volts → distance [m] → force [N]).

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::io::{Cursor, Read};
use std::path::Path;

use zip::ZipArchive;

use crate::curve::{Calibration, CalibrationSource, Channel, ForceCurve, Segment, SegmentKind};
use crate::error::{AfmError, Result};

/// Largest archive entry the reader will decompress (guards against zip bombs).
const MAX_ENTRY_BYTES: u64 = 1 << 30;
/// Longest conversion chain followed (guards against cycles).
const MAX_CHAIN: usize = 16;

/// Options that change how a file is read.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReadOptions {
    /// Spring constant k, N/m, replacing the file's (needed if the file has none).
    pub spring_constant: Option<f64>,
    /// Deflection sensitivity, m/V, replacing the file's (needed if the file has none).
    pub sensitivity: Option<f64>,
}

/// Read a single-curve `.jpk-force` file with the file's own calibration.
///
/// # Errors
/// Any [`AfmError`] reader variant: I/O, not a ZIP/JPK file, corrupt or truncated entries,
/// missing keys, missing calibration ([`AfmError::NoCalibration`]); a force map holding
/// more than one curve is rejected with [`AfmError::InvalidInput`] (use [`read_force_map`]).
pub fn read_force_curve(path: impl AsRef<Path>) -> Result<ForceCurve> {
    read_force_curve_with(path, &ReadOptions::default())
}

/// Read a single-curve `.jpk-force` file, with calibration overrides.
///
/// # Errors
/// As [`read_force_curve`].
pub fn read_force_curve_with(path: impl AsRef<Path>, options: &ReadOptions) -> Result<ForceCurve> {
    let mut curves = read_force_map(path, options)?;
    if curves.len() != 1 {
        return Err(AfmError::InvalidInput(format!(
            "{} holds {} curves; read it with read_force_map",
            curves.first().map_or("file", |c| c.source.as_str()),
            curves.len()
        )));
    }
    curves.pop().ok_or_else(|| AfmError::NotJpk {
        detail: "no curve".into(),
    })
}

/// Read every curve of a `.jpk-force-map` (or the single curve of a `.jpk-force`).
///
/// # Errors
/// As [`read_force_curve`].
pub fn read_force_map(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Vec<ForceCurve>> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| AfmError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_jpk_bytes(&bytes, &path.display().to_string(), options)
}

/// Decode a JPK force file or force map held in memory. `source` names it in errors
/// and in [`ForceCurve::source`].
///
/// # Errors
/// As [`read_force_curve`]; never panics on any input bytes.
pub fn read_jpk_bytes(
    bytes: &[u8],
    source: &str,
    options: &ReadOptions,
) -> Result<Vec<ForceCurve>> {
    check_override(options)?;
    let mut zip = ZipArchive::new(Cursor::new(bytes)).map_err(|e| AfmError::NotZip {
        detail: e.to_string(),
    })?;
    let names: HashSet<String> = zip.file_names().map(str::to_owned).collect();
    if !names.contains("header.properties") {
        return Err(AfmError::NotJpk {
            detail: "ZIP archive without header.properties".into(),
        });
    }
    let header = read_props(&mut zip, "header.properties")?;
    if !header.contains_key("jpk-data-file") && !header.contains_key("file-format-version") {
        return Err(AfmError::NotJpk {
            detail: "header.properties has neither 'jpk-data-file' nor 'file-format-version'"
                .into(),
        });
    }
    let format_version = header
        .get("file-format-version")
        .cloned()
        .unwrap_or_else(|| "unknown".into());
    let shared = if names.contains("shared-data/header.properties") {
        Some(read_props(&mut zip, "shared-data/header.properties")?)
    } else {
        None
    };
    // Shortest non-empty `...description.instrument` key (HashMap order is not stable).
    let instrument = header
        .iter()
        .filter(|(k, v)| k.ends_with("description.instrument") && !v.trim().is_empty())
        .min_by_key(|(k, _)| (k.len(), k.as_str()))
        .map(|(_, v)| v.clone());

    // One pass over the entry names: segment ids per curve (None = single curve,
    // Some(n) = curve n of a map under index/<n>/).
    let mut layout: BTreeMap<Option<usize>, BTreeSet<usize>> = BTreeMap::new();
    for n in &names {
        let (curve, rest) = match n.strip_prefix("index/") {
            Some(r) => match r.split_once('/') {
                Some((i, rest)) => match i.parse::<usize>() {
                    Ok(i) => (Some(i), rest),
                    Err(_) => continue,
                },
                None => continue,
            },
            None => (None, n.as_str()),
        };
        if let Some(seg) = rest
            .strip_prefix("segments/")
            .and_then(|r| r.strip_suffix("/segment-header.properties"))
            .and_then(|id| id.parse::<usize>().ok())
        {
            layout.entry(curve).or_default().insert(seg);
        }
    }
    if layout.contains_key(&None) && layout.len() > 1 {
        return Err(AfmError::NotJpk {
            detail: "archive mixes a single-curve segments/ tree with force-map index/<n>/ curves"
                .into(),
        });
    }
    if layout.is_empty() {
        return Err(AfmError::NotJpk {
            detail: "no segments/<n>/segment-header.properties in the archive".into(),
        });
    }

    let ctx = Ctx {
        shared: shared.as_ref(),
        options,
    };
    let mut curves = Vec::with_capacity(layout.len());
    for (index, seg_ids) in layout {
        let (prefix, name) = match index {
            None => (String::new(), source.to_string()),
            Some(i) => (format!("index/{i}/"), format!("{source}#{i}")),
        };
        let curve_header = if prefix.is_empty() {
            None
        } else {
            let entry = format!("{prefix}header.properties");
            if names.contains(&entry) {
                Some(read_props(&mut zip, &entry)?)
            } else {
                None
            }
        };
        let position = curve_header
            .as_ref()
            .and_then(position_of)
            .or_else(|| position_of(&header));
        let mut curve = read_curve(&mut zip, &names, &prefix, &seg_ids, &ctx)?;
        curve.source = name;
        curve.format_version = format_version.clone();
        curve.instrument = instrument.clone();
        curve.position = position;
        curves.push(curve);
    }
    Ok(curves)
}

fn check_override(options: &ReadOptions) -> Result<()> {
    for (name, v) in [
        ("spring constant", options.spring_constant),
        ("sensitivity", options.sensitivity),
    ] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err(AfmError::InvalidInput(format!(
                "{name} override must be finite and positive, got {v}"
            )));
        }
    }
    Ok(())
}

type Props = HashMap<String, String>;
type Zip<'a> = ZipArchive<Cursor<&'a [u8]>>;

struct Ctx<'a> {
    shared: Option<&'a Props>,
    options: &'a ReadOptions,
}

fn position_of(p: &Props) -> Option<(f64, f64)> {
    let get = |suffix: &str| {
        p.iter()
            .filter(|(k, _)| k.ends_with(suffix) && !k.contains("scanner"))
            .min_by_key(|(k, _)| (k.len(), k.as_str()))
            .and_then(|(_, v)| v.parse::<f64>().ok())
    };
    Some((get("position.x")?, get("position.y")?))
}

fn read_entry(zip: &mut Zip<'_>, name: &str) -> Result<Vec<u8>> {
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

fn read_props(zip: &mut Zip<'_>, name: &str) -> Result<Props> {
    let bytes = read_entry(zip, name)?;
    java_properties::read(bytes.as_slice()).map_err(|e| AfmError::Properties {
        entry: name.into(),
        line: e.line_number().unwrap_or(0),
        detail: e.to_string(),
    })
}

/// A header file together with its name, for error messages.
#[derive(Clone, Copy)]
struct Hdr<'a> {
    entry: &'a str,
    props: &'a Props,
}

impl<'a> Hdr<'a> {
    fn opt(&self, key: &str) -> Option<&'a str> {
        self.props.get(key).map(String::as_str)
    }
    fn get(&self, key: &str) -> Result<&'a str> {
        self.opt(key).ok_or_else(|| AfmError::MissingKey {
            entry: self.entry.into(),
            key: key.into(),
        })
    }
    fn bad(&self, key: &str, value: &str, expected: &str) -> AfmError {
        AfmError::BadValue {
            entry: self.entry.into(),
            key: key.into(),
            value: value.into(),
            expected: expected.into(),
        }
    }
    fn f64(&self, key: &str) -> Result<f64> {
        let v = self.get(key)?;
        v.trim()
            .parse::<f64>()
            .map_err(|_| self.bad(key, v, "a number"))
    }
    fn finite(&self, key: &str) -> Result<f64> {
        let x = self.f64(key)?;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.bad(key, self.opt(key).unwrap_or(""), "a finite number"))
        }
    }
    fn usize(&self, key: &str) -> Result<usize> {
        let v = self.get(key)?;
        v.trim()
            .parse::<usize>()
            .map_err(|_| self.bad(key, v, "a non-negative integer"))
    }
}

fn read_curve(
    zip: &mut Zip<'_>,
    names: &HashSet<String>,
    prefix: &str,
    seg_ids: &BTreeSet<usize>,
    ctx: &Ctx<'_>,
) -> Result<ForceCurve> {
    let seg_prefix = format!("{prefix}segments/");
    let mut segments = Vec::with_capacity(seg_ids.len());
    let mut calibration: Option<Calibration> = None;
    let mut t0 = 0.0;
    for (index, id) in seg_ids.iter().enumerate() {
        let dir = format!("{seg_prefix}{id}/");
        let entry = format!("{dir}segment-header.properties");
        let props = read_props(zip, &entry)?;
        let hdr = Hdr {
            entry: &entry,
            props: &props,
        };
        let (segment, cal) = read_segment(zip, names, &dir, hdr, index, t0, ctx)?;
        t0 += segment.duration;
        if calibration.is_none() {
            calibration = cal;
        }
        segments.push(segment);
    }
    let calibration = calibration.ok_or_else(|| AfmError::MissingChannel {
        segment: 0,
        channel: "vDeflection".into(),
        available: segments
            .first()
            .map(|s| {
                s.channels
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default(),
    })?;
    Ok(ForceCurve {
        source: String::new(),
        format_version: String::new(),
        instrument: None,
        position: None,
        calibration,
        segments,
    })
}

fn segment_kind(hdr: Hdr<'_>) -> Result<SegmentKind> {
    let style_key = "force-segment-header.settings.style";
    let style = hdr
        .opt(style_key)
        .or_else(|| hdr.opt("force-segment-header.settings.segment-settings.style"))
        .ok_or_else(|| AfmError::MissingKey {
            entry: hdr.entry.into(),
            key: style_key.into(),
        })?;
    let seg_type = hdr
        .opt("force-segment-header.settings.segment-settings.type")
        .unwrap_or("");
    let pause_option = hdr
        .opt("force-segment-header.settings.segment-settings.pause-option.type")
        .unwrap_or("");
    match style {
        "extend" => Ok(SegmentKind::Extend),
        "retract" => Ok(SegmentKind::Retract),
        "pause" => {
            if seg_type.contains("constant-force") || pause_option == "constant-force" {
                Ok(SegmentKind::Creep)
            } else {
                Ok(SegmentKind::Hold)
            }
        }
        other => Err(hdr.bad(style_key, other, "extend, retract or pause")),
    }
}

fn read_segment(
    zip: &mut Zip<'_>,
    names: &HashSet<String>,
    dir: &str,
    hdr: Hdr<'_>,
    index: usize,
    t0: f64,
    ctx: &Ctx<'_>,
) -> Result<(Segment, Option<Calibration>)> {
    let kind = segment_kind(hdr)?;
    let name = hdr
        .opt("force-segment-header.name.name")
        .unwrap_or("")
        .to_string();
    let n = hdr.usize("force-segment-header.num-points")?;
    let duration = hdr.finite("force-segment-header.duration")?;
    if duration < 0.0 {
        return Err(hdr.bad(
            "force-segment-header.duration",
            hdr.opt("force-segment-header.duration").unwrap_or(""),
            "a non-negative duration in s",
        ));
    }
    let list = hdr.get("channels.list")?;
    let mut channels = Vec::new();
    let mut calibration = None;
    for ch in list.split_whitespace() {
        let spec = ChannelSpec::resolve(hdr, ch, ctx.shared)?;
        let file_key = format!("channel.{ch}.data.file.name");
        let file = hdr.get(&file_key)?;
        let format_key = format!("channel.{ch}.data.file.format");
        if let Some(fmt) = hdr.opt(&format_key)
            && fmt != "raw"
        {
            return Err(AfmError::Unsupported {
                entry: hdr.entry.into(),
                what: format!("channel file format '{fmt}' (key {format_key}; only 'raw')"),
            });
        }
        let points = match hdr.opt(&format!("channel.{ch}.data.num-points")) {
            Some(_) => hdr.usize(&format!("channel.{ch}.data.num-points"))?,
            None => n,
        };
        let entry = format!("{dir}{file}");
        if !names.contains(&entry) {
            return Err(AfmError::Corrupt {
                entry,
                detail: format!("channel file named by {file_key} is missing from the archive"),
            });
        }
        let bytes = read_entry(zip, &entry)?;
        let volts = spec.decode(&bytes, points, &entry)?;
        let (values, unit, conversion) = if ch == "vDeflection" {
            let (cal, force) = deflection_to_force(&spec, volts, ctx.options)?;
            calibration = Some(cal);
            (force, "N".to_string(), "force".to_string())
        } else {
            spec.convert_default(volts)?
        };
        channels.push(Channel {
            name: ch.to_string(),
            unit,
            conversion,
            values,
        });
    }
    let len = channels.iter().map(|c| c.values.len()).min().unwrap_or(n);
    if let Some(bad) = channels.iter().find(|c| c.values.len() != len) {
        return Err(AfmError::Corrupt {
            entry: hdr.entry.into(),
            detail: format!(
                "channel '{}' has {} points but another channel has {len}",
                bad.name,
                bad.values.len()
            ),
        });
    }
    let dt = if n > 0 { duration / n as f64 } else { 0.0 };
    let time = (0..len).map(|i| t0 + i as f64 * dt).collect();
    Ok((
        Segment {
            index,
            kind,
            name,
            duration,
            time,
            channels,
        },
        calibration,
    ))
}

/// Raw sample storage of a channel file.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Storage {
    I16,
    U16,
    I32,
    U32,
    I64,
    F32,
    F64,
}

impl Storage {
    fn width(self) -> usize {
        match self {
            Storage::I16 | Storage::U16 => 2,
            Storage::I32 | Storage::U32 | Storage::F32 => 4,
            Storage::I64 | Storage::F64 => 8,
        }
    }
}

/// Where a channel's description lives and how to decode it.
struct ChannelSpec<'a> {
    name: String,
    /// Header holding the encoder and conversion-set keys.
    hdr: Hdr<'a>,
    /// Key prefix, e.g. `channel.height.` (0.12) or `lcd-info.0.` (2.0).
    prefix: String,
    storage: Storage,
    /// Encoder scaling (offset, multiplier) raw → volts; None for float data.
    encoder: Option<(f64, f64)>,
}

impl<'a> ChannelSpec<'a> {
    fn resolve(seg: Hdr<'a>, ch: &str, shared: Option<&'a Props>) -> Result<Self> {
        let lcd_key = format!("channel.{ch}.lcd-info.*");
        let (hdr, prefix, type_key, enc_prefix) = if let Some(idx) = seg.opt(&lcd_key) {
            let props = shared.ok_or_else(|| AfmError::MissingKey {
                entry: "shared-data/header.properties".into(),
                key: format!("lcd-info.{idx}.* (the file refers to shared data it lacks)"),
            })?;
            let hdr = Hdr {
                entry: "shared-data/header.properties",
                props,
            };
            let p = format!("lcd-info.{}.", idx.trim());
            (hdr, p.clone(), format!("{p}type"), format!("{p}encoder."))
        } else {
            let p = format!("channel.{ch}.");
            (
                seg,
                p.clone(),
                format!("{p}data.type"),
                format!("{p}data.encoder."),
            )
        };
        let dtype = hdr.get(&type_key)?;
        let enc_type = hdr.opt(&format!("{enc_prefix}type")).unwrap_or("");
        let unsigned = enc_type.starts_with("unsigned");
        let storage = match dtype {
            "short" | "short-data" | "shortdata" | "memory-short-data" => {
                if unsigned {
                    Storage::U16
                } else {
                    Storage::I16
                }
            }
            "integer" | "integer-data" | "memory-integer-data" => {
                if unsigned {
                    Storage::U32
                } else {
                    Storage::I32
                }
            }
            "long" | "long-data" | "memory-long-data" => Storage::I64,
            "float" | "float-data" | "memory-float-data" => Storage::F32,
            "double" | "double-data" | "memory-double-data" => Storage::F64,
            other => {
                return Err(AfmError::Unsupported {
                    entry: hdr.entry.into(),
                    what: format!("channel data type '{other}' (key {type_key})"),
                });
            }
        };
        let encoder = if hdr
            .opt(&format!("{enc_prefix}scaling.multiplier"))
            .is_some()
        {
            Some(scaling(hdr, &format!("{enc_prefix}scaling."))?)
        } else if matches!(storage, Storage::F32 | Storage::F64) {
            None
        } else {
            return Err(AfmError::MissingKey {
                entry: hdr.entry.into(),
                key: format!("{enc_prefix}scaling.multiplier"),
            });
        };
        Ok(ChannelSpec {
            name: ch.to_string(),
            hdr,
            prefix,
            storage,
            encoder,
        })
    }

    /// Raw big-endian samples → volts (encoder scaling).
    fn decode(&self, bytes: &[u8], points: usize, entry: &str) -> Result<Vec<f64>> {
        let w = self.storage.width();
        let expected_bytes = points.checked_mul(w).ok_or_else(|| AfmError::Corrupt {
            entry: entry.into(),
            detail: format!("absurd point count {points}"),
        })?;
        if bytes.len() < expected_bytes {
            return Err(AfmError::Truncated {
                entry: entry.into(),
                expected: points,
                expected_bytes,
                found_bytes: bytes.len(),
            });
        }
        let raw = bytes[..expected_bytes].chunks_exact(w);
        let mut out = Vec::with_capacity(points);
        let s = self.storage;
        for c in raw {
            let x = match s {
                Storage::I16 => f64::from(i16::from_be_bytes([c[0], c[1]])),
                Storage::U16 => f64::from(u16::from_be_bytes([c[0], c[1]])),
                Storage::I32 => f64::from(i32::from_be_bytes([c[0], c[1], c[2], c[3]])),
                Storage::U32 => f64::from(u32::from_be_bytes([c[0], c[1], c[2], c[3]])),
                Storage::F32 => f64::from(f32::from_be_bytes([c[0], c[1], c[2], c[3]])),
                Storage::I64 => {
                    i64::from_be_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f64
                }
                Storage::F64 => {
                    f64::from_be_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]])
                }
            };
            out.push(x);
        }
        if let Some((offset, multiplier)) = self.encoder {
            for x in &mut out {
                *x = offset + multiplier * *x;
            }
        }
        Ok(out)
    }

    fn conv_key(&self, slot: &str, rest: &str) -> String {
        format!("{}conversion-set.conversion.{slot}.{rest}", self.prefix)
    }

    fn base_slot(&self) -> &'a str {
        self.hdr
            .opt(&format!("{}conversion-set.conversions.base", self.prefix))
            .unwrap_or("volts")
    }

    fn default_slot(&self) -> &'a str {
        self.hdr
            .opt(&format!(
                "{}conversion-set.conversions.default",
                self.prefix
            ))
            .unwrap_or_else(|| self.base_slot())
    }

    fn is_defined(&self, slot: &str) -> bool {
        self.hdr.opt(&self.conv_key(slot, "defined")) == Some("true")
    }

    /// Linear steps (offset, multiplier) from the base slot to `target`, in application order.
    fn chain(&self, target: &str) -> Result<Vec<(f64, f64)>> {
        let base = self.base_slot();
        let mut steps = Vec::new();
        let mut slot = target.to_string();
        while slot != base {
            if steps.len() >= MAX_CHAIN {
                return Err(AfmError::Unsupported {
                    entry: self.hdr.entry.into(),
                    what: format!(
                        "conversion chain of channel '{}' longer than {MAX_CHAIN} steps (cycle?)",
                        self.name
                    ),
                });
            }
            if !self.is_defined(&slot) {
                return Err(AfmError::BadValue {
                    entry: self.hdr.entry.into(),
                    key: self.conv_key(&slot, "defined"),
                    value: self
                        .hdr
                        .opt(&self.conv_key(&slot, "defined"))
                        .unwrap_or("<absent>")
                        .into(),
                    expected: "true (conversion needed by the chain)".into(),
                });
            }
            steps.push(scaling(self.hdr, &self.conv_key(&slot, "scaling."))?);
            slot = self
                .hdr
                .get(&self.conv_key(&slot, "base-calibration-slot"))?
                .to_string();
        }
        steps.reverse();
        Ok(steps)
    }

    fn unit_of(&self, slot: &str) -> String {
        if slot == self.base_slot() {
            return "V".into();
        }
        self.hdr
            .opt(&self.conv_key(slot, "scaling.unit.unit"))
            .or_else(|| self.hdr.opt(&self.conv_key(slot, "scaling.unit")))
            .unwrap_or("?")
            .to_string()
    }

    /// Volts → the channel's default conversion. Falls back to volts if the default
    /// slot is not defined (JPK marks unused channels that way).
    fn convert_default(&self, mut v: Vec<f64>) -> Result<(Vec<f64>, String, String)> {
        let mut slot = self.default_slot();
        if slot != self.base_slot() && !self.is_defined(slot) {
            slot = self.base_slot();
        }
        for (offset, multiplier) in self.chain(slot)? {
            for x in &mut v {
                *x = offset + multiplier * *x;
            }
        }
        let name = if slot == self.base_slot() {
            "volts"
        } else {
            slot
        };
        Ok((v, self.unit_of(slot), name.to_string()))
    }
}

/// Linear `offsetmultiplier` scaling at `prefix` (`...scaling.`): returns (offset, multiplier).
fn scaling(hdr: Hdr<'_>, prefix: &str) -> Result<(f64, f64)> {
    let type_key = format!("{prefix}type");
    if let Some(t) = hdr.opt(&type_key)
        && t != "linear"
    {
        return Err(AfmError::Unsupported {
            entry: hdr.entry.into(),
            what: format!("scaling type '{t}' (key {type_key}; only 'linear')"),
        });
    }
    let style_key = format!("{prefix}style");
    if let Some(s) = hdr.opt(&style_key)
        && s != "offsetmultiplier"
    {
        return Err(AfmError::Unsupported {
            entry: hdr.entry.into(),
            what: format!("scaling style '{s}' (key {style_key}; only 'offsetmultiplier')"),
        });
    }
    let offset = match hdr.opt(&format!("{prefix}offset")) {
        Some(_) => hdr.finite(&format!("{prefix}offset"))?,
        None => 0.0,
    };
    let multiplier = hdr.finite(&format!("{prefix}multiplier"))?;
    Ok((offset, multiplier))
}

/// vDeflection volts → force, N; returns the calibration used.
///
/// With the file's calibration the conversion chain is followed exactly (volts → distance
/// → force). An override replaces the corresponding multiplier; offsets of the chain
/// are kept.
fn deflection_to_force(
    spec: &ChannelSpec<'_>,
    mut v: Vec<f64>,
    options: &ReadOptions,
) -> Result<(Calibration, Vec<f64>)> {
    let slot_step = |slot: &str| -> Option<(f64, f64)> {
        if !spec.is_defined(slot) {
            return None;
        }
        let (o, m) = scaling(spec.hdr, &spec.conv_key(slot, "scaling.")).ok()?;
        (m.is_finite() && m > 0.0).then_some((o, m))
    };
    if spec.is_defined("force")
        && let Some(base) = spec
            .hdr
            .opt(&spec.conv_key("force", "base-calibration-slot"))
        && base != "distance"
    {
        return Err(AfmError::Unsupported {
            entry: spec.hdr.entry.into(),
            what: format!("vDeflection force conversion based on '{base}' (expected 'distance')"),
        });
    }
    let (d_off, sens, sens_src) = match (options.sensitivity, slot_step("distance")) {
        (Some(s), file) => (file.map_or(0.0, |f| f.0), s, CalibrationSource::Override),
        (None, Some((o, m))) => (o, m, CalibrationSource::File),
        (None, None) => {
            return Err(AfmError::NoCalibration {
                quantity: "deflection sensitivity",
                entry: spec.hdr.entry.into(),
                conversion: "distance".into(),
            });
        }
    };
    let (f_off, k, k_src) = match (options.spring_constant, slot_step("force")) {
        (Some(k), file) => (file.map_or(0.0, |f| f.0), k, CalibrationSource::Override),
        (None, Some((o, m))) => (o, m, CalibrationSource::File),
        (None, None) => {
            return Err(AfmError::NoCalibration {
                quantity: "spring constant",
                entry: spec.hdr.entry.into(),
                conversion: "force".into(),
            });
        }
    };
    for x in &mut v {
        let d = d_off + sens * *x;
        *x = f_off + k * d;
    }
    Ok((
        Calibration {
            spring_constant: k,
            sensitivity: sens,
            spring_constant_source: k_src,
            sensitivity_source: sens_src,
        },
        v,
    ))
}
