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
//! A force map (`.jpk-force-map`, `.jpk-qi-data`) holds the same tree once per curve under
//! `index/<n>/`; a QI series (`.jpk-qi-series`) and a curve extracted from a map have the
//! single-curve tree. Segment headers may refer to the shared header for their channel
//! descriptions and segment settings (see [`header`]).
//!
//! Decoding a channel: raw integer (or float) → volts with the *encoder* scaling
//! `v = offset + multiplier·raw`; then along the channel's conversion set from the
//! base slot (`volts`) to the default slot, each step `y = offset + multiplier·x`
//! (`vDeflection`: volts → distance [m] → force [N]).

mod channel;
mod header;

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::io::Cursor;
use std::path::Path;

use zip::ZipArchive;

use crate::curve::{Calibration, Channel, ForceCurve, Segment, SegmentKind};
use crate::error::{AfmError, Result};
use channel::ChannelSpec;
use header::{Hdr, Merged, Props, SHARED, Shared, read_entry, read_props};

type Zip<'a> = ZipArchive<Cursor<&'a [u8]>>;

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
/// As [`read_force_curve`]; the first curve that fails fails the whole file (see
/// [`read_jpk_each`] to keep the others); never panics on any input bytes.
pub fn read_jpk_bytes(
    bytes: &[u8],
    source: &str,
    options: &ReadOptions,
) -> Result<Vec<ForceCurve>> {
    read_jpk_each(bytes, source, options)?
        .into_iter()
        .map(|(_, c)| c)
        .collect()
}

/// Decode a JPK file held in memory curve by curve: file-level damage (not a ZIP, no
/// JPK header, no segments) is an error; each curve of a map is returned with its index
/// (`None` for a single-curve file) and its own result, so one bad curve does not lose
/// the others.
///
/// # Errors
/// As [`JpkArchive::open`].
pub fn read_jpk_each(
    bytes: &[u8],
    source: &str,
    options: &ReadOptions,
) -> Result<Vec<(Option<usize>, Result<ForceCurve>)>> {
    let archive = JpkArchive::open(bytes, source, options)?;
    Ok((0..archive.len())
        .map(|i| (archive.index(i), archive.read(i)))
        .collect())
}

/// A JPK archive held in memory, opened: headers read and curves located, no channel
/// decoded yet. [`JpkArchive::read`] decodes one curve; it takes `&self`, so the curves
/// of a map can be decoded in parallel.
pub struct JpkArchive<'a> {
    zip: Zip<'a>,
    source: String,
    names: HashSet<String>,
    header: Props,
    shared: Option<Shared>,
    format_version: String,
    instrument: Option<String>,
    /// (curve index in the map or None, segment ids), in index order.
    curves: Vec<(Option<usize>, BTreeSet<usize>)>,
    options: ReadOptions,
}

impl<'a> JpkArchive<'a> {
    /// Open the archive `bytes`, named `source` in errors and in [`ForceCurve::source`].
    ///
    /// # Errors
    /// [`AfmError::NotZip`], [`AfmError::NotJpk`], or a reader error in the top-level or
    /// shared header; [`AfmError::InvalidInput`] for a nonsensical calibration override.
    pub fn open(bytes: &'a [u8], source: &str, options: &ReadOptions) -> Result<Self> {
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
        // A curve extracted from a map keeps the map's curve header
        // (`type=force-scan-series`) in place of the file header.
        let extracted = header
            .get("type")
            .is_some_and(|t| t.trim() == "force-scan-series");
        if !header.contains_key("jpk-data-file")
            && !header.contains_key("file-format-version")
            && !extracted
        {
            return Err(AfmError::NotJpk {
                detail: "header.properties has neither 'jpk-data-file' nor 'file-format-version' nor 'type=force-scan-series'"
                    .into(),
            });
        }
        let shared_props = if names.contains(SHARED) {
            Some(read_props(&mut zip, SHARED)?)
        } else {
            None
        };
        let format_version = header
            .get("file-format-version")
            .or_else(|| shared_props.as_ref()?.get("file-format-version"))
            .cloned()
            .unwrap_or_else(|| {
                if shared_props.is_some() {
                    "2.0"
                } else {
                    "unknown"
                }
                .into()
            });
        let shared = shared_props.as_ref().map(Shared::new);
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
                detail:
                    "archive mixes a single-curve segments/ tree with force-map index/<n>/ curves"
                        .into(),
            });
        }
        if layout.is_empty() {
            return Err(AfmError::NotJpk {
                detail: "no segments/<n>/segment-header.properties in the archive".into(),
            });
        }
        Ok(JpkArchive {
            zip,
            source: source.to_string(),
            names,
            header,
            shared,
            format_version,
            instrument,
            curves: layout.into_iter().collect(),
            options: *options,
        })
    }

    /// Number of curves (1 for a single-curve file).
    pub fn len(&self) -> usize {
        self.curves.len()
    }

    /// True if the archive holds no curve (never after a successful [`JpkArchive::open`]).
    pub fn is_empty(&self) -> bool {
        self.curves.is_empty()
    }

    /// Index in the map of the `i`-th curve (`None` for a single-curve file).
    pub fn index(&self, i: usize) -> Option<usize> {
        self.curves.get(i).and_then(|c| c.0)
    }

    /// Decode the `i`-th curve (0-based position, not the map index).
    ///
    /// # Errors
    /// Reader errors of that curve ([`AfmError`]); [`AfmError::InvalidInput`] if `i` is
    /// out of range.
    pub fn read(&self, i: usize) -> Result<ForceCurve> {
        let (index, seg_ids) = self.curves.get(i).ok_or_else(|| {
            AfmError::InvalidInput(format!(
                "{}: curve {i} requested, the file holds {}",
                self.source,
                self.curves.len()
            ))
        })?;
        let (prefix, name) = match index {
            None => (String::new(), self.source.clone()),
            Some(i) => (format!("index/{i}/"), format!("{}#{i}", self.source)),
        };
        let mut zip = self.zip.clone();
        let curve_header = if prefix.is_empty() {
            None
        } else {
            let entry = format!("{prefix}header.properties");
            if self.names.contains(&entry) {
                Some(read_props(&mut zip, &entry)?)
            } else {
                None
            }
        };
        let position = curve_header
            .as_ref()
            .and_then(position_of)
            .or_else(|| position_of(&self.header));
        let ctx = Ctx {
            shared: self.shared.as_ref(),
            options: &self.options,
        };
        let mut curve = read_curve(&mut zip, &self.names, &prefix, seg_ids, &ctx)?;
        curve.source = name;
        curve.format_version = self.format_version.clone();
        curve.instrument = self.instrument.clone();
        curve.position = position;
        Ok(curve)
    }
}

pub(crate) fn check_override(options: &ReadOptions) -> Result<()> {
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

struct Ctx<'a> {
    shared: Option<&'a Shared>,
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
        let merged = Merged::new(&entry, props, ctx.shared)?;
        let (segment, cal) = read_segment(zip, names, &dir, merged.hdr(), index, t0, ctx)?;
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
        .ok_or_else(|| hdr.missing(style_key))?;
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
        let spec = ChannelSpec::resolve(hdr, ch)?;
        let points = match hdr.opt(&format!("channel.{ch}.data.num-points")) {
            Some(_) => hdr.usize(&format!("channel.{ch}.data.num-points"))?,
            None => n,
        };
        let volts = if spec.is_computed() {
            spec.raster(points)?
        } else {
            let file_key = format!("channel.{ch}.data.file.name");
            let file = hdr.get(&file_key)?;
            let format_key = format!("channel.{ch}.data.file.format");
            if let Some(fmt) = hdr.opt(&format_key)
                && fmt != "raw"
            {
                return Err(hdr.unsupported(
                    &format_key,
                    format!("channel file format '{fmt}' (only 'raw')"),
                ));
            }
            let entry = format!("{dir}{file}");
            if !names.contains(&entry) {
                return Err(AfmError::Corrupt {
                    entry,
                    detail: format!(
                        "channel file named by {file_key} in {} is missing from the archive",
                        hdr.entry()
                    ),
                });
            }
            let bytes = read_entry(zip, &entry)?;
            spec.decode(&bytes, points, &entry)?
        };
        let (values, unit, conversion) = if ch == "vDeflection" {
            let (cal, force) = spec.deflection_to_force(volts, ctx.options)?;
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
            entry: hdr.entry().into(),
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
