//! App. B.2 cell geometry helpers.

use crate::common;

use common::*;
use nlvid_afm::geometry::{
    base_diameter, cell_height_from_curves, cell_height_from_surfaces, surface_position,
};
use nlvid_afm::{ContactMethod, read_force_curve};

#[test]
fn eq_b1_surface_and_height_by_hand() {
    // Z[scanner] 2000 µm, Z[scanstart] 3 µm, ramp 2 µm, non-contact 1.2 µm → 1997.8 µm
    let cell = surface_position(2000e-6, 3e-6, 2e-6, 1.2e-6);
    assert!((cell - 1997.8e-6).abs() < 1e-15);
    // on glass the stepper went 6 µm deeper: Z[scanner] 2006 µm, non-contact 1.5 µm
    let glass = surface_position(2006e-6, 3e-6, 2e-6, 1.5e-6);
    let h = cell_height_from_surfaces(cell, glass).expect("height");
    assert!((h - 5.7e-6).abs() < 1e-15);
    assert!(cell_height_from_surfaces(glass, cell).is_err());
}

#[test]
fn height_from_curves_is_the_shift_between_identical_curves() {
    let cell = read_force_curve(FD).expect("read");
    let mut glass = cell.clone();
    for seg in &mut glass.segments {
        for ch in &mut seg.channels {
            if ch.unit == "m" {
                ch.values.iter_mut().for_each(|v| *v -= 4.0e-6);
            }
        }
    }
    for m in [ContactMethod::default(), ContactMethod::PiecewiseLinear] {
        let h = cell_height_from_curves(&cell, &glass, m).expect("height");
        assert!((h - 4.0e-6).abs() < 1e-12, "{h}");
        assert!(cell_height_from_curves(&glass, &cell, m).is_err());
    }
}

#[test]
fn base_diameter_is_geometric_mean() {
    assert!((base_diameter(20e-6, 45e-6).expect("d") - 30e-6).abs() < 1e-18);
    assert!(base_diameter(0.0, 1e-6).is_err());
    assert!(base_diameter(f64::NAN, 1e-6).is_err());
}
