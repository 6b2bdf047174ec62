//! Force curves given as columns — an afmformats data object
//! (`afmformats.AFMForceDistance`, `AFMStressRelaxation`,
//! `AFMCreepCompliance`: anything with `obj["force"]` …) or a plain dict
//! of arrays — turned into the one in-memory curve `nlvid_afm::ForceCurve`
//! that nlvid's own JPK reader produces. Duck-typed: afmformats is never
//! imported.
//!
//! Columns (afmformats' names, SI): `force` [N] → channel `vDeflection`,
//! `height (measured)` [m] → `measuredHeight`, `height (piezo)` [m] →
//! `height`, `time` [s], `segment` (0, 1, … in recording order). Metadata
//! (the object's `.metadata`, or the `metadata` argument): `spring
//! constant` [N/m] (required), `sensitivity` [m/V], `instrument`,
//! `position x`/`position y` [m], `path`, `enum`, `imaging mode`.
//!
//! afmformats does not record what each segment does, so its kind is
//! inferred from the piezo height (JPK heights grow away from the sample):
//! a segment whose height changes by less than 10 % of the largest change
//! of any segment is a pause — `hold`, or `creep` when the imaging mode is
//! `creep-compliance` — else `extend` when the height falls, `retract`
//! when it rises. This is what nlvid's reader reads from the JPK headers
//! for every public test file (crates/py/tests/test_afmformats.py).

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::vector;
use crate::errors::input;
use nlvid_afm::{Calibration, CalibrationSource, Channel, ForceCurve, Segment, SegmentKind};

/// afmformats column → (nlvid channel, unit, conversion slot).
const CHANNELS: [(&str, &str, &str, &str); 3] = [
    ("force", "vDeflection", "N", "force"),
    ("height (measured)", "measuredHeight", "m", "nominal"),
    ("height (piezo)", "height", "m", "nominal"),
];

/// A pause moves the piezo by less than this fraction of the largest move.
const PAUSE_FRACTION: f64 = 0.1;

const HINT: &str = "give an afmformats data object or a dict of arrays with afmformats' \
    column names: force [N], height (measured) and/or height (piezo) [m], time [s], segment";

/// Column `name` of `data` as float64 values, or `None` when absent.
fn column(data: &Bound<'_, PyAny>, name: &str) -> PyResult<Option<Vec<f64>>> {
    let Ok(col) = data.get_item(name) else {
        return Ok(None);
    };
    let np = data.py().import("numpy")?;
    let arr = np
        .call_method1("ascontiguousarray", (col,))
        .and_then(|a| a.call_method1("astype", ("float64",)))
        .map_err(|e| input(format!("column `{name}`: not numeric ({e})")))?;
    let v = vector(&arr, &format!("column `{name}`"))?;
    Ok(Some(v.values().into_owned()))
}

fn required(data: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    column(data, name)?.ok_or_else(|| input(format!("no column `{name}`: {HINT}")))
}

/// A metadata value as a float, if present and numeric.
fn meta_f64(meta: Option<&Bound<'_, PyAny>>, key: &str) -> Option<f64> {
    meta?.get_item(key).ok()?.extract::<f64>().ok()
}

fn meta_str(meta: Option<&Bound<'_, PyAny>>, key: &str) -> Option<String> {
    let v = meta?.get_item(key).ok()?;
    if v.is_none() {
        return None;
    }
    v.str().ok().map(|s| s.to_string())
}

/// The curve in `data` (see the module doc); `metadata` replaces
/// `data.metadata`; `source` names it in messages and summaries.
pub(crate) fn force_curve(
    data: &Bound<'_, PyAny>,
    metadata: Option<&Bound<'_, PyAny>>,
    source: Option<String>,
) -> PyResult<ForceCurve> {
    if data.get_item("force").is_err() {
        return Err(input(format!(
            "a {} has no column `force`: {HINT}",
            data.get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        )));
    }
    let own_meta = data.getattr("metadata").ok().filter(|m| !m.is_none());
    let meta = metadata.cloned().or(own_meta);
    let meta = meta.as_ref();
    let time = required(data, "time")?;
    let segment = required(data, "segment")?;
    let n = time.len();
    let mut cols = Vec::new();
    for (col, name, unit, conversion) in CHANNELS {
        if let Some(v) = column(data, col)? {
            if v.len() != n {
                return Err(input(format!(
                    "column `{col}` has {} values but `time` has {n}: give columns of one length",
                    v.len()
                )));
            }
            cols.push((name, unit, conversion, v));
        }
    }
    if segment.len() != n {
        return Err(input(format!(
            "column `segment` has {} values but `time` has {n}: give columns of one length",
            segment.len()
        )));
    }
    if n == 0 {
        return Err(input("the curve has no samples"));
    }
    // Segment runs, in recording order.
    let mut runs: Vec<(usize, usize, usize)> = Vec::new(); // (id, start, end)
    for (i, &s) in segment.iter().enumerate() {
        if !(s >= 0.0 && s.fract() == 0.0 && s < 1e6) {
            return Err(input(format!(
                "column `segment`: value {s} at index {i} is not a segment number 0, 1, …"
            )));
        }
        let id = s as usize;
        match runs.last_mut() {
            Some(r) if r.0 == id => r.2 = i + 1,
            Some(r) if id < r.0 => {
                return Err(input(format!(
                    "column `segment`: segment {id} at index {i} follows segment {}; \
                     give the samples in recording order",
                    r.0
                )));
            }
            _ => runs.push((id, i, i + 1)),
        }
    }
    let spring_constant = meta_f64(meta, "spring constant")
        .filter(|k| k.is_finite() && *k > 0.0)
        .ok_or_else(|| {
            input(
                "metadata: no positive `spring constant` [N/m]: the force curve needs the \
                 cantilever's k (give metadata={\"spring constant\": 0.1, ...})",
            )
        })?;
    let creep = meta_str(meta, "imaging mode")
        .or_else(|| {
            data.getattr("modality")
                .ok()
                .and_then(|m| m.extract::<String>().ok())
        })
        .is_some_and(|m| m == "creep-compliance");
    let piezo = cols
        .iter()
        .find(|c| c.0 == "height")
        .or_else(|| cols.iter().find(|c| c.0 == "measuredHeight"))
        .map(|c| c.3.clone())
        .ok_or_else(|| input(format!("no height column: {HINT}")))?;
    let moves: Vec<f64> = runs
        .iter()
        .map(|&(_, a, b)| piezo[b - 1] - piezo[a])
        .collect();
    let largest = moves.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let mut segments = Vec::with_capacity(runs.len());
    for (k, &(id, a, b)) in runs.iter().enumerate() {
        let kind = if moves[k].abs() < PAUSE_FRACTION * largest {
            if creep {
                SegmentKind::Creep
            } else {
                SegmentKind::Hold
            }
        } else if moves[k] < 0.0 {
            SegmentKind::Extend
        } else {
            SegmentKind::Retract
        };
        // The recorded duration: up to the next segment's first sample, the
        // last one's by its sample spacing.
        let end = match runs.get(k + 1) {
            Some(&(_, next, _)) => time[next],
            None if b - a > 1 => time[b - 1] + (time[b - 1] - time[b - 2]),
            None => time[b - 1],
        };
        segments.push(Segment {
            index: id,
            kind,
            name: format!("segment {id}"),
            duration: end - time[a],
            time: time[a..b].to_vec(),
            channels: cols
                .iter()
                .map(|(name, unit, conversion, v)| Channel {
                    name: (*name).to_string(),
                    unit: (*unit).to_string(),
                    conversion: (*conversion).to_string(),
                    values: v[a..b].to_vec(),
                })
                .collect(),
        });
    }
    let source = source.unwrap_or_else(|| match (meta_str(meta, "path"), meta_str(meta, "enum")) {
        (Some(p), Some(e)) => format!("{p}:{e}"),
        (Some(p), None) => p,
        _ => "<columns>".to_string(),
    });
    let position = match (meta_f64(meta, "position x"), meta_f64(meta, "position y")) {
        (Some(x), Some(y)) => Some((x, y)),
        _ => None,
    };
    Ok(ForceCurve {
        source,
        format_version: meta_str(meta, "format").unwrap_or_else(|| "columns".into()),
        instrument: meta_str(meta, "instrument"),
        position,
        calibration: Calibration {
            spring_constant,
            sensitivity: meta_f64(meta, "sensitivity").unwrap_or(f64::NAN),
            spring_constant_source: CalibrationSource::File,
            sensitivity_source: CalibrationSource::File,
        },
        segments,
    })
}

/// `metadata` as a dict, for `ForceCurve.from_columns`'s signature check.
pub(crate) fn optional_mapping<'py>(
    m: Option<Bound<'py, PyAny>>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    match m {
        Some(m) if m.is_none() => Ok(None),
        Some(m) if m.cast::<PyDict>().is_ok() || m.hasattr("__getitem__")? => Ok(Some(m)),
        Some(m) => Err(input(format!(
            "metadata: expected a dict, got {}",
            m.get_type()
                .name()
                .map_or_else(|_| "?".into(), |n| n.to_string())
        ))),
        None => Ok(None),
    }
}
