//! Cell geometry from AFM data and images (thesis App. B.2, §5.3).
//!
//! * Eq. B.1 (Bruker ramp mode): `Z[surface] = Z[scanner] − Z[scanstart] + rampsize − Z[non-contact]`,
//!   with Z measured *downward* from the top of the scanner. The cell height is the
//!   difference of the surface positions found on the glass and on the cell.
//! * JPK files carry heights that grow *away* from the sample, so with curves recorded at
//!   the same z-stepper position the height is the contact separation on the cell minus
//!   the contact separation on the glass.
//! * Base diameter of the oblate cell model: √(d1·d2) of two distances measured on an
//!   optical image (§5.3, Bernick et al. 2011).

use crate::curve::ForceCurve;
use crate::error::{AfmError, Result};
use crate::hertz::prepare_approach;
use crate::prepare::ContactMethod;

fn positive(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(AfmError::InvalidInput(format!(
            "{name} must be positive and finite, got {v}"
        )))
    }
}

/// Surface position from a ramp-mode force curve, eq. B.1 (all lengths in m, Z downward).
pub fn surface_position(
    z_scanner: f64,
    z_scan_start: f64,
    ramp_size: f64,
    z_non_contact: f64,
) -> f64 {
    z_scanner - z_scan_start + ramp_size - z_non_contact
}

/// Cell height from the surface positions (eq. B.1) on glass and on the cell:
/// `H = Z_glass − Z_cell` (Z downward, so the glass lies deeper).
///
/// # Errors
/// [`AfmError::InvalidInput`] if the result is not positive (cell surface below glass).
pub fn cell_height_from_surfaces(z_surface_cell: f64, z_surface_glass: f64) -> Result<f64> {
    positive(
        "cell height Z_glass − Z_cell",
        z_surface_glass - z_surface_cell,
    )
}

/// Cell height from two JPK approach curves recorded at the same z-stepper position, one
/// on the cell and one on the nearby glass: difference of their contact separations
/// (contact found with `method` on each extend segment).
///
/// # Errors
/// As [`prepare_approach`]; [`AfmError::InvalidInput`] if the height is not positive.
pub fn cell_height_from_curves(
    cell: &ForceCurve,
    glass: &ForceCurve,
    method: ContactMethod,
) -> Result<f64> {
    let c = prepare_approach(cell, method)?.contact.separation;
    let g = prepare_approach(glass, method)?.contact.separation;
    positive("cell height (contact on cell − contact on glass)", c - g)
}

/// Base diameter `D = √(d1·d2)` from two image distances (m).
///
/// # Errors
/// [`AfmError::InvalidInput`] unless both distances are positive and finite.
pub fn base_diameter(d1: f64, d2: f64) -> Result<f64> {
    Ok((positive("d1", d1)? * positive("d2", d2)?).sqrt())
}
