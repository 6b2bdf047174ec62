//! A JPK ramp-hold (stress-relaxation) file as the one curve type
//! ([`nlvid_model::Curve`]) that fits read: time from the contact point,
//! force F = k d, indentation δ = Z − d and the piezo travel since contact
//! Z = δ + F/k (§5.2.2, δ = Z − d with d = F/k).

use std::path::Path;

use nlvid_model::Curve;

use crate::error::{AfmError, Result};
use crate::{ContactMethod, JpkArchive, ReadOptions, prepare_ramp_hold, read_ibw_bytes};

/// Reads a `.jpk-force` ramp-hold curve (extend, then constant-height
/// pause) and cuts it at the contact point (default [`ContactMethod`]):
/// channels `displacement` (piezo travel since contact, m), `force` (N) and
/// `indentation` (m). `options` replace the file's calibration.
///
/// # Errors
/// The file cannot be read, has no ramp-hold segments or no contact point
/// (each error names the file).
pub fn read_ramp_hold(path: &Path, options: &ReadOptions) -> Result<Curve> {
    read_ramp_hold_curve(path, None, options)
}

/// As [`read_ramp_hold`] for any instrument file (JPK single curve, force map or QI,
/// Asylum `.ibw`) and curve `curve` of it (`None`: the first). Only that curve is
/// decoded, so a damaged other curve of the map does not matter.
///
/// # Errors
/// As [`read_ramp_hold`]; a curve index beyond the file's curves. Each error names
/// the file and, for a map, the curve.
pub fn read_ramp_hold_curve(
    path: &Path,
    curve: Option<usize>,
    options: &ReadOptions,
) -> Result<Curve> {
    let which = curve.map_or_else(String::new, |i| format!(" curve {i}"));
    let named = |e: AfmError| AfmError::InvalidInput(format!("{}{which}: {e}", path.display()));
    let bytes = std::fs::read(path).map_err(|source| AfmError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let name = path.display().to_string();
    let is_ibw = path
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("ibw"));
    let curve = if is_ibw {
        match curve {
            None | Some(0) => read_ibw_bytes(&bytes, &name, options).map_err(named)?,
            Some(i) => {
                return Err(named(AfmError::InvalidInput(format!(
                    "an .ibw file holds one curve, asked for curve {i}"
                ))));
            }
        }
    } else {
        let archive = JpkArchive::open(&bytes, &name, options).map_err(named)?;
        let i = curve.unwrap_or(0);
        if i >= archive.len() {
            return Err(named(AfmError::InvalidInput(format!(
                "the file holds {} curve(s)",
                archive.len()
            ))));
        }
        archive.read(i).map_err(named)?
    };
    let k = curve.calibration.spring_constant;
    let ramp = prepare_ramp_hold(&curve, ContactMethod::default()).map_err(named)?;
    let displacement = ramp
        .indentation
        .iter()
        .zip(&ramp.force)
        .map(|(d, f)| d + f / k)
        .collect();
    Curve::new(ramp.time)
        .and_then(|c| c.with("displacement", "m", displacement))
        .and_then(|c| c.with("force", "N", ramp.force))
        .and_then(|c| c.with("indentation", "m", ramp.indentation))
        .map_err(|e| named(AfmError::InvalidInput(e.to_string())))
}

#[cfg(test)]
mod tests {
    use super::*;

    const RELAXATION: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/fmt-jpk-sr_cell1-0008.jpk-force"
    );

    #[test]
    fn jpk_ramp_hold_reads_as_a_curve_from_contact() {
        let curve = read_ramp_hold(Path::new(RELAXATION), &ReadOptions::default()).unwrap();
        let n = curve.len();
        assert!(n > 7000, "extend after contact + 7680-point hold, got {n}");
        assert_eq!(curve.time()[0], 0.0);
        let force = curve.values("force").unwrap();
        let delta = curve.values("indentation").unwrap();
        let z = curve.values("displacement").unwrap();
        // δ starts at the contact point and grows to a few µm on a cell.
        assert!(delta[0].abs() < 0.1e-6, "δ(0) = {}", delta[0]);
        let peak = force.iter().copied().fold(f64::MIN, f64::max);
        assert!(peak > 0.0);
        // Stress relaxation: the force at the end of the hold is below the peak.
        assert!(force[n - 1] < 0.9 * peak);
        // Z − δ = d = F/k with the file's calibration.
        let k = crate::read_force_curve(RELAXATION)
            .unwrap()
            .calibration
            .spring_constant;
        for i in [0, n / 2, n - 1] {
            assert!(((z[i] - delta[i]) * k - force[i]).abs() <= 1e-12 * force[i].abs().max(1e-12));
        }
    }

    #[test]
    fn a_non_jpk_file_with_the_jpk_extension_is_an_error_naming_it() {
        let dir = std::env::temp_dir().join(format!("nlvid-afm-jpk-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cell.jpk-force");
        std::fs::write(&path, b"time,force\n0,1\n").unwrap();
        let err = read_ramp_hold(&path, &ReadOptions::default()).unwrap_err();
        assert!(err.to_string().contains("cell.jpk-force"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
