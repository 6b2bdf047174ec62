//! A homogeneous-deformation history as the one curve type
//! ([`nlvid_model::Curve`]): what `nlvid material` writes.

use nlvid_model::{Curve, ModelError};

use crate::homogeneous::{Mode, Sample};

/// `stretch` (or `shear`), the principal Cauchy stresses `sigma_1..3` (Pa)
/// and, for simple shear, `sigma_11`, `sigma_22`, `sigma_12` and the normal
/// stress differences `N_1` = σ11 − σ22, `N_2` = σ22 − σ33 (Pa), against
/// time (s).
///
/// # Errors
/// Times that do not increase (a jump in the history), non-finite stresses.
pub fn samples_curve(samples: &[Sample], mode: Mode) -> Result<Curve, ModelError> {
    let col = |f: &dyn Fn(&Sample) -> f64| samples.iter().map(f).collect::<Vec<f64>>();
    let shear = mode == Mode::SimpleShear;
    let name = if shear { "shear" } else { "stretch" };
    let mut curve = Curve::new(col(&|s| s.time))?.with(name, "1", col(&|s| s.value))?;
    for k in 0..3 {
        curve = curve.with(&format!("sigma_{}", k + 1), "Pa", col(&|s| s.principal[k]))?;
    }
    if shear {
        let m = |i: usize, j: usize| col(&|s| s.cauchy[(i, j)]);
        let diff = |a: Vec<f64>, b: Vec<f64>| a.iter().zip(&b).map(|(x, y)| x - y).collect();
        curve = curve
            .with("sigma_11", "Pa", m(0, 0))?
            .with("sigma_22", "Pa", m(1, 1))?
            .with("sigma_12", "Pa", m(0, 1))?
            .with("N_1", "Pa", diff(m(0, 0), m(1, 1)))?
            .with("N_2", "Pa", diff(m(1, 1), m(2, 2)))?;
    }
    Ok(curve)
}
