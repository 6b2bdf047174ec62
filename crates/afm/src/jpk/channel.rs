//! Decoding one channel: raw big-endian samples → volts (encoder scaling) → the
//! channel's physical unit along its conversion set.
//!
//! Keys, in the merged segment view of [`super::header`] (`<p>` = `channel.<name>.`):
//!
//! ```text
//! <p>data.type / <p>type            short, integer, long, float, double, raster-data
//! <p>data.encoder.* / <p>encoder.*  type (signedshort, unsignedinteger…), scaling.offset/multiplier
//! <p>conversion-set.*               base slot (volts), default slot, linear steps between slots
//! <p>data.start, <p>data.step       raster-data: computed samples start + step·i, no file
//! ```
//!
//! Format 0.12 writes the first two inline under `data.`; format 2.0 refers to a shared
//! `lcd-info.<n>.` section, which the merged view presents without the `data.` level.

use super::header::Hdr;
use crate::curve::{Calibration, CalibrationSource};
use crate::error::{AfmError, Result};
use crate::jpk::ReadOptions;

/// Longest conversion chain followed (guards against cycles).
const MAX_CHAIN: usize = 16;

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
    /// No file: samples start + step·i.
    Raster,
}

impl Storage {
    fn width(self) -> usize {
        match self {
            Storage::I16 | Storage::U16 => 2,
            Storage::I32 | Storage::U32 | Storage::F32 => 4,
            Storage::I64 | Storage::F64 => 8,
            Storage::Raster => 0,
        }
    }
}

/// How one channel of one segment is stored and converted.
pub(super) struct ChannelSpec<'a> {
    name: String,
    hdr: Hdr<'a>,
    /// `channel.<name>.`
    prefix: String,
    storage: Storage,
    /// Encoder scaling (offset, multiplier) raw → volts; None for float and raster data.
    encoder: Option<(f64, f64)>,
    /// Unit of the encoder output (base slot), usually V.
    base_unit: String,
}

impl<'a> ChannelSpec<'a> {
    pub(super) fn resolve(hdr: Hdr<'a>, ch: &str) -> Result<Self> {
        let prefix = format!("channel.{ch}.");
        let inline = format!("{prefix}data.type");
        let type_key = if hdr.opt(&inline).is_some() {
            inline
        } else {
            format!("{prefix}type")
        };
        let enc_prefix = if hdr.opt(&format!("{prefix}data.encoder.type")).is_some()
            || hdr
                .opt(&format!("{prefix}data.encoder.scaling.multiplier"))
                .is_some()
        {
            format!("{prefix}data.encoder.")
        } else {
            format!("{prefix}encoder.")
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
            "raster-data" => Storage::Raster,
            other => {
                return Err(hdr.unsupported(&type_key, format!("channel data type '{other}'")));
            }
        };
        let encoder = if hdr
            .opt(&format!("{enc_prefix}scaling.multiplier"))
            .is_some()
        {
            Some(scaling(hdr, &format!("{enc_prefix}scaling."))?)
        } else if matches!(storage, Storage::F32 | Storage::F64 | Storage::Raster) {
            None
        } else {
            return Err(hdr.missing(&format!("{enc_prefix}scaling.multiplier")));
        };
        let base_unit = hdr
            .opt(&format!("{enc_prefix}scaling.unit.unit"))
            .or_else(|| hdr.opt(&format!("{prefix}unit.unit")))
            .unwrap_or("V")
            .to_string();
        Ok(ChannelSpec {
            name: ch.to_string(),
            hdr,
            prefix,
            storage,
            encoder,
            base_unit,
        })
    }

    /// True if the samples are computed (raster data) rather than read from a file.
    pub(super) fn is_computed(&self) -> bool {
        self.storage == Storage::Raster
    }

    /// Computed samples of a raster channel: `start + step·i`, i < `points`.
    pub(super) fn raster(&self, points: usize) -> Result<Vec<f64>> {
        let start = self.hdr.finite(&format!("{}data.start", self.prefix))?;
        let step = self.hdr.finite(&format!("{}data.step", self.prefix))?;
        Ok((0..points).map(|i| start + step * i as f64).collect())
    }

    /// Raw big-endian samples → volts (encoder scaling).
    pub(super) fn decode(&self, bytes: &[u8], points: usize, entry: &str) -> Result<Vec<f64>> {
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
        let mut out = Vec::with_capacity(points);
        let s = self.storage;
        for c in bytes[..expected_bytes].chunks_exact(w.max(1)) {
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
                Storage::Raster => 0.0,
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
                let key = self.conv_key(&slot, "base-calibration-slot");
                return Err(self.hdr.unsupported(
                    &key,
                    format!(
                        "conversion chain of channel '{}' longer than {MAX_CHAIN} steps (cycle?)",
                        self.name
                    ),
                ));
            }
            if !self.is_defined(&slot) {
                let key = self.conv_key(&slot, "defined");
                return Err(self.hdr.bad(
                    &key,
                    self.hdr.opt(&key).unwrap_or("<absent>"),
                    "true (conversion needed by the chain)",
                ));
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
            return self.base_unit.clone();
        }
        self.hdr
            .opt(&self.conv_key(slot, "scaling.unit.unit"))
            .or_else(|| self.hdr.opt(&self.conv_key(slot, "scaling.unit")))
            .unwrap_or("?")
            .to_string()
    }

    /// Base-slot samples → the channel's default conversion, as (values, unit, slot name).
    /// Falls back to the base slot if the default slot is not defined (JPK marks unused
    /// conversions that way).
    pub(super) fn convert_default(&self, mut v: Vec<f64>) -> Result<(Vec<f64>, String, String)> {
        let mut slot = self.default_slot();
        if slot != self.base_slot() && !self.is_defined(slot) {
            slot = self.base_slot();
        }
        for (offset, multiplier) in self.chain(slot)? {
            for x in &mut v {
                *x = offset + multiplier * *x;
            }
        }
        let name = if slot == self.base_slot() && self.base_unit == "V" {
            "volts"
        } else {
            slot
        };
        Ok((v, self.unit_of(slot), name.to_string()))
    }

    /// vDeflection volts → force, N; returns the calibration used.
    ///
    /// With the file's calibration the conversion chain is followed exactly (volts →
    /// distance → force). An override replaces the corresponding multiplier; offsets of
    /// the chain are kept.
    pub(super) fn deflection_to_force(
        &self,
        mut v: Vec<f64>,
        options: &ReadOptions,
    ) -> Result<(Calibration, Vec<f64>)> {
        let slot_step = |slot: &str| -> Option<(f64, f64)> {
            if !self.is_defined(slot) {
                return None;
            }
            let (o, m) = scaling(self.hdr, &self.conv_key(slot, "scaling.")).ok()?;
            (m.is_finite() && m > 0.0).then_some((o, m))
        };
        let base_key = self.conv_key("force", "base-calibration-slot");
        if self.is_defined("force")
            && let Some(base) = self.hdr.opt(&base_key)
            && base != "distance"
        {
            return Err(self.hdr.unsupported(
                &base_key,
                format!("vDeflection force conversion based on '{base}' (expected 'distance')"),
            ));
        }
        let no_cal = |quantity, slot: &str| AfmError::NoCalibration {
            quantity,
            entry: self.hdr.locate(&self.conv_key(slot, "defined")).0,
            conversion: slot.into(),
        };
        let (d_off, sens, sens_src) = match (options.sensitivity, slot_step("distance")) {
            (Some(s), file) => (file.map_or(0.0, |f| f.0), s, CalibrationSource::Override),
            (None, Some((o, m))) => (o, m, CalibrationSource::File),
            (None, None) => return Err(no_cal("deflection sensitivity", "distance")),
        };
        let (f_off, k, k_src) = match (options.spring_constant, slot_step("force")) {
            (Some(k), file) => (file.map_or(0.0, |f| f.0), k, CalibrationSource::Override),
            (None, Some((o, m))) => (o, m, CalibrationSource::File),
            (None, None) => return Err(no_cal("spring constant", "force")),
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
}

/// Linear `offsetmultiplier` scaling at `prefix` (`...scaling.`): returns (offset, multiplier).
fn scaling(hdr: Hdr<'_>, prefix: &str) -> Result<(f64, f64)> {
    let type_key = format!("{prefix}type");
    if let Some(t) = hdr.opt(&type_key)
        && t != "linear"
    {
        return Err(hdr.unsupported(&type_key, format!("scaling type '{t}' (only 'linear')")));
    }
    let style_key = format!("{prefix}style");
    if let Some(s) = hdr.opt(&style_key)
        && s != "offsetmultiplier"
    {
        return Err(hdr.unsupported(
            &style_key,
            format!("scaling style '{s}' (only 'offsetmultiplier')"),
        ));
    }
    let offset = match hdr.opt(&format!("{prefix}offset")) {
        Some(_) => hdr.finite(&format!("{prefix}offset"))?,
        None => 0.0,
    };
    let multiplier = hdr.finite(&format!("{prefix}multiplier"))?;
    Ok((offset, multiplier))
}
