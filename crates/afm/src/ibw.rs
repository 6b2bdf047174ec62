//! Asylum Research force curves: Igor binary wave files (`.ibw`, version 5).
//!
//! Layout (Igor Pro Technical Note PTN003, version 5 only):
//!
//! ```text
//! BinHeader5    64 B   version (i16 = 5), checksum, wfmSize, formulaSize, noteSize,
//!                      dataEUnitsSize, dimEUnitsSize[4], dimLabelsSize[4], sIndicesSize, options…
//! WaveHeader5  320 B   npnts @12, type @16 (2 = f32, 4 = f64, 8/16/32 = i8/i16/i32, |64 unsigned),
//!                      nDim[4] @68, sfA[4] @84, sfB[4] @116, dimUnits[4][4] @152
//! data                 npnts values, column-major (point index fastest)
//! formula, note, data units, dimension units, dimension labels (32 B each), …
//! ```
//!
//! The byte order is the writer's: a version that reads as 5 little-endian means a
//! little-endian file. An Asylum force curve is a 2-D wave, one column per channel,
//! named by the labels of dimension 1 (`Raw` piezo Z, `Defl` deflection, `ZSnsr` Z
//! sensor, all in m). The note is `Key: Value` lines separated by `\r`; it gives the
//! spring constant (`SpringConstant`, N/m), the sensitivity (`InvOLS`, m/V) and the
//! segments: `Indexes: 0,i1,i2,…` (last sample of each segment) with
//! `Direction: NaN,d1,d2,…` (1 extend, −1 retract, 0 dwell).
//!
//! Conversions (as afmformats does): force = `Defl`·k; JPK-style heights growing away
//! from the sample: `height` = −`Raw`, `measuredHeight` = −`ZSnsr`. Time from the wave's
//! x scaling (`sfB[0] + i·sfA[0]` when its unit is s), else `1/NumPtsPerSec`.

use std::collections::HashMap;

use crate::curve::{Calibration, CalibrationSource, Channel, ForceCurve, Segment, SegmentKind};
use crate::error::{AfmError, Result};
use crate::jpk::{ReadOptions, check_override};

const BIN_HEADER: usize = 64;
const WAVE_HEADER: usize = 320;
const LABEL: usize = 32;

/// Little- or big-endian reads at byte offsets, every one bounds-checked.
struct Bytes<'a> {
    b: &'a [u8],
    le: bool,
}

impl Bytes<'_> {
    fn get<const N: usize>(&self, at: usize, what: &str) -> Result<[u8; N]> {
        self.b
            .get(at..at + N)
            .and_then(|s| s.try_into().ok())
            .ok_or_else(|| AfmError::NotIbw {
                detail: format!(
                    "file ends before {what} (byte {at}, {} bytes)",
                    self.b.len()
                ),
            })
    }
    fn i16(&self, at: usize, what: &str) -> Result<i16> {
        let v = self.get::<2>(at, what)?;
        Ok(if self.le {
            i16::from_le_bytes(v)
        } else {
            i16::from_be_bytes(v)
        })
    }
    fn i32(&self, at: usize, what: &str) -> Result<i32> {
        let v = self.get::<4>(at, what)?;
        Ok(if self.le {
            i32::from_le_bytes(v)
        } else {
            i32::from_be_bytes(v)
        })
    }
    fn f64(&self, at: usize, what: &str) -> Result<f64> {
        let v = self.get::<8>(at, what)?;
        Ok(if self.le {
            f64::from_le_bytes(v)
        } else {
            f64::from_be_bytes(v)
        })
    }
    /// A size field: non-negative.
    fn size(&self, at: usize, what: &str) -> Result<usize> {
        let v = self.i32(at, what)?;
        usize::try_from(v).map_err(|_| AfmError::NotIbw {
            detail: format!("{what} is negative ({v})"),
        })
    }
    /// Sample `i` of a wave of type code `ty` starting at `at`.
    fn sample(&self, ty: i16, at: usize) -> Result<f64> {
        let w = "wave data";
        Ok(match ty {
            2 => {
                let v = self.get::<4>(at, w)?;
                f64::from(if self.le {
                    f32::from_le_bytes(v)
                } else {
                    f32::from_be_bytes(v)
                })
            }
            4 => self.f64(at, w)?,
            8 => f64::from(self.get::<1>(at, w)?[0] as i8),
            0x48 => f64::from(self.get::<1>(at, w)?[0]),
            0x10 => f64::from(self.i16(at, w)?),
            0x50 => f64::from(self.i16(at, w)? as u16),
            0x20 => f64::from(self.i32(at, w)?),
            0x60 => f64::from(self.i32(at, w)? as u32),
            _ => unreachable!("type checked in read_ibw_bytes"),
        })
    }
}

fn width(ty: i16) -> Option<usize> {
    match ty {
        2 => Some(4),
        4 => Some(8),
        8 | 0x48 => Some(1),
        0x10 | 0x50 => Some(2),
        0x20 | 0x60 => Some(4),
        _ => None,
    }
}

/// A NUL-padded C string field.
fn cstr(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    b[..end].iter().map(|&c| char::from(c)).collect()
}

/// Read an Asylum Research `.ibw` force curve held in memory; `source` names it in
/// errors and in [`ForceCurve::source`].
///
/// # Errors
/// [`AfmError::NotIbw`] if the bytes are not an Igor binary wave of version 5 with a
/// 2-D force-curve layout (the message says which part is missing or inconsistent),
/// [`AfmError::MissingKey`] / [`AfmError::BadValue`] for note keys (entry `note`),
/// [`AfmError::NoCalibration`] without a spring constant or sensitivity (unless
/// overridden); never panics on any input bytes.
pub fn read_ibw_bytes(bytes: &[u8], source: &str, options: &ReadOptions) -> Result<ForceCurve> {
    check_override(options)?;
    let le = match bytes.get(0..2) {
        Some(&[a, b]) if i16::from_le_bytes([a, b]) == 5 => true,
        Some(&[a, b]) if i16::from_be_bytes([a, b]) == 5 => false,
        Some(&[a, b]) => {
            let v = i16::from_le_bytes([a, b]);
            return Err(
                if (1..=3).contains(&v) || (1..=3).contains(&i16::from_be_bytes([a, b])) {
                    AfmError::Unsupported {
                        entry: source.into(),
                        what: "Igor binary wave version below 5".into(),
                    }
                } else {
                    AfmError::NotIbw {
                        detail: "the first two bytes are not an Igor binary wave version".into(),
                    }
                },
            );
        }
        _ => {
            return Err(AfmError::NotIbw {
                detail: "file shorter than 2 bytes".into(),
            });
        }
    };
    let r = Bytes { b: bytes, le };
    let wfm_size = r.size(4, "wfmSize")?;
    let formula_size = r.size(8, "formulaSize")?;
    let note_size = r.size(12, "noteSize")?;
    let data_eunits = r.size(16, "dataEUnitsSize")?;
    let mut dim_eunits = 0usize;
    let mut labels_size = [0usize; 4];
    for d in 0..4 {
        dim_eunits = dim_eunits.saturating_add(r.size(20 + 4 * d, "dimEUnitsSize")?);
        labels_size[d] = r.size(36 + 4 * d, "dimLabelsSize")?;
    }
    let wh = BIN_HEADER;
    let npnts = r.size(wh + 12, "npnts")?;
    let ty = r.i16(wh + 16, "type")?;
    let w = width(ty).ok_or_else(|| AfmError::Unsupported {
        entry: source.into(),
        what: format!("Igor wave type code {ty} (complex or text waves)"),
    })?;
    let mut n_dim = [0usize; 4];
    for (d, n) in n_dim.iter_mut().enumerate() {
        *n = r.size(wh + 68 + 4 * d, "nDim")?;
    }
    let (rows, cols) = (n_dim[0], n_dim[1].max(1));
    if n_dim[2] > 1 || rows.checked_mul(cols) != Some(npnts) || npnts == 0 {
        return Err(AfmError::NotIbw {
            detail: format!(
                "wave of {npnts} points with dimensions {n_dim:?}: not a 2-D force curve"
            ),
        });
    }
    let data_at = BIN_HEADER + WAVE_HEADER;
    let data_bytes = npnts.checked_mul(w).ok_or_else(|| AfmError::NotIbw {
        detail: format!("absurd point count {npnts}"),
    })?;
    if wfm_size < WAVE_HEADER + data_bytes || bytes.len() < data_at + data_bytes {
        return Err(AfmError::Truncated {
            entry: format!("{source}: wave data"),
            expected: npnts,
            expected_bytes: data_bytes,
            found_bytes: bytes.len().saturating_sub(data_at),
        });
    }
    let dt = r.f64(wh + 84, "sfA")?;
    let t0 = r.f64(wh + 116, "sfB")?;
    let x_unit = cstr(r.get::<4>(wh + 152, "dimUnits")?.as_slice());
    // Sections after the wave data.
    let note_at = BIN_HEADER + wfm_size + formula_size;
    let note = bytes
        .get(note_at..note_at.saturating_add(note_size))
        .ok_or_else(|| AfmError::Truncated {
            entry: format!("{source}: note"),
            expected: note_size,
            expected_bytes: note_size,
            found_bytes: bytes.len().saturating_sub(note_at),
        })?;
    let note: String = note.iter().map(|&c| char::from(c)).collect();
    let notes: HashMap<&str, &str> = note
        .split(['\r', '\n'])
        .filter_map(|l| l.split_once(':'))
        .map(|(k, v)| (k.trim(), v.trim()))
        .collect();
    let labels_at = note_at + note_size + data_eunits + dim_eunits + labels_size[0];
    let names: Vec<String> = if labels_size[1] >= LABEL * (cols + 1) {
        (0..cols)
            .map(|j| {
                let at = labels_at + LABEL * (j + 1);
                bytes
                    .get(at..at + LABEL)
                    .map(cstr)
                    .ok_or_else(|| AfmError::Truncated {
                        entry: format!("{source}: dimension labels"),
                        expected: cols,
                        expected_bytes: LABEL * (cols + 1),
                        found_bytes: bytes.len().saturating_sub(labels_at),
                    })
            })
            .collect::<Result<_>>()?
    } else {
        return Err(AfmError::NotIbw {
            detail: "no column labels (dimension 1): cannot tell deflection from height".into(),
        });
    };
    let column = |j: usize| -> Result<Vec<f64>> {
        (0..rows)
            .map(|i| r.sample(ty, data_at + (j * rows + i) * w))
            .collect()
    };
    let find = |cands: &[&str]| names.iter().position(|n| cands.contains(&n.as_str()));
    let note_num = |key: &str| -> Result<Option<f64>> {
        match notes.get(key) {
            None => Ok(None),
            Some(v) => v.parse::<f64>().map(Some).map_err(|_| AfmError::BadValue {
                entry: format!("{source}: note"),
                key: key.into(),
                value: (*v).into(),
                expected: "a number".into(),
            }),
        }
    };
    let positive = |v: Option<f64>| v.filter(|x| x.is_finite() && *x > 0.0);
    let file_k = positive(note_num("SpringConstant")?);
    let file_s = positive(note_num("InvOLS")?);
    let (k, k_src) = match (options.spring_constant, file_k) {
        (Some(k), _) => (k, CalibrationSource::Override),
        (None, Some(k)) => (k, CalibrationSource::File),
        (None, None) => {
            return Err(AfmError::NoCalibration {
                quantity: "spring constant",
                entry: format!("{source}: note"),
                conversion: "SpringConstant".into(),
            });
        }
    };
    let (sens, s_src) = match (options.sensitivity, file_s) {
        (Some(s), _) => (s, CalibrationSource::Override),
        (None, Some(s)) => (s, CalibrationSource::File),
        (None, None) => {
            return Err(AfmError::NoCalibration {
                quantity: "deflection sensitivity",
                entry: format!("{source}: note"),
                conversion: "InvOLS".into(),
            });
        }
    };
    let defl = find(&["Defl", "Deflection"]).ok_or_else(|| AfmError::MissingChannel {
        segment: 0,
        channel: "Defl".into(),
        available: names.join(", "),
    })?;
    // Defl (m) = volts · InvOLS: a sensitivity override rescales it.
    let rescale = match file_s {
        Some(fs) if s_src == CalibrationSource::Override => sens / fs,
        _ => 1.0,
    };
    if s_src == CalibrationSource::Override && file_s.is_none() {
        return Err(AfmError::InvalidInput(format!(
            "{source}: a sensitivity override needs the file's InvOLS to undo (Defl is stored in m)"
        )));
    }
    let mut all: Vec<Channel> = Vec::new();
    for (j, name) in names.iter().enumerate() {
        let v = column(j)?;
        let (name, unit, conv, v) = if j == defl {
            let f = v.iter().map(|d| d * rescale * k).collect();
            ("vDeflection".to_string(), "N", "force", f)
        } else if ["Raw", "Height"].contains(&name.as_str()) {
            (
                "height".to_string(),
                "m",
                "nominal",
                v.iter().map(|x| -x).collect(),
            )
        } else if ["ZSnsr", "ZSensor"].contains(&name.as_str()) {
            (
                "measuredHeight".to_string(),
                "m",
                "nominal",
                v.iter().map(|x| -x).collect(),
            )
        } else {
            (name.clone(), "", "raw", v)
        };
        all.push(Channel {
            name,
            unit: unit.into(),
            conversion: conv.into(),
            values: v,
        });
    }
    let dt = if x_unit == "s" && dt.is_finite() && dt > 0.0 {
        dt
    } else {
        match positive(note_num("NumPtsPerSec")?) {
            Some(rate) => 1.0 / rate,
            None => {
                return Err(AfmError::MissingKey {
                    entry: format!("{source}: note"),
                    key: "NumPtsPerSec (the wave has no time scaling)".into(),
                });
            }
        }
    };
    let t0 = if x_unit == "s" && t0.is_finite() {
        t0
    } else {
        0.0
    };
    let bounds = segments_of(&notes, rows, source)?;
    let mut segments = Vec::new();
    for (index, (range, kind)) in bounds.into_iter().enumerate() {
        segments.push(Segment {
            index,
            kind,
            name: kind.to_string(),
            duration: range.len() as f64 * dt,
            time: range.clone().map(|i| t0 + i as f64 * dt).collect(),
            channels: all
                .iter()
                .map(|c| Channel {
                    values: c.values[range.clone()].to_vec(),
                    ..c.clone()
                })
                .collect(),
        });
    }
    Ok(ForceCurve {
        source: source.into(),
        format_version: "ibw 5".into(),
        instrument: notes.get("MicroscopeModel").map(|s| (*s).to_string()),
        position: None,
        calibration: Calibration {
            spring_constant: k,
            sensitivity: sens,
            spring_constant_source: k_src,
            sensitivity_source: s_src,
        },
        segments,
    })
}

/// Sample ranges and kinds of the segments from the note's `Indexes` and `Direction`;
/// the whole wave as one extend segment when the note has neither.
fn segments_of(
    notes: &HashMap<&str, &str>,
    rows: usize,
    source: &str,
) -> Result<Vec<(std::ops::Range<usize>, SegmentKind)>> {
    let (Some(ix), Some(dir)) = (notes.get("Indexes"), notes.get("Direction")) else {
        return Ok(vec![(0..rows, SegmentKind::Extend)]);
    };
    let bad = |key: &str, value: &str| AfmError::BadValue {
        entry: format!("{source}: note"),
        key: key.into(),
        value: value.into(),
        expected: format!(
            "increasing sample indexes below {rows}, one direction (1, −1, 0) per index"
        ),
    };
    let ix: Vec<usize> = ix
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse::<usize>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad("Indexes", ix))?;
    let dir: Vec<&str> = dir
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect();
    if ix.len() < 2
        || dir.len() != ix.len()
        || ix.windows(2).any(|w| w[1] <= w[0])
        || ix[ix.len() - 1] >= rows
    {
        return Err(bad("Indexes", notes["Indexes"]));
    }
    let mut out = Vec::new();
    for j in 1..ix.len() {
        let start = if j == 1 { ix[0] } else { ix[j - 1] + 1 };
        let kind = match dir[j].parse::<f64>() {
            Ok(d) if d > 0.0 => SegmentKind::Extend,
            Ok(d) if d < 0.0 => SegmentKind::Retract,
            Ok(0.0) => SegmentKind::Hold,
            _ => return Err(bad("Direction", notes["Direction"])),
        };
        out.push((start..ix[j] + 1, kind));
    }
    Ok(out)
}
