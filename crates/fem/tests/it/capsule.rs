//! A fluid-filled spherical capsule of uniform wall squeezed between rigid
//! plates (the verification case of issue 16): the 3D eighth model against
//! the axisymmetric model of the same engine, and eighth, quarter and full
//! 3D models against each other.

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use nlvid_fem::shell::ShellPart;
use nlvid_fem::{ContactPatch, LiftOff, PatchSpec, Symmetry};

use crate::common::{self, R};

#[derive(Debug, Clone, Copy)]
struct Outcome {
    /// Force on the top plate, whole capsule (N).
    force: f64,
    /// Cavity pressure (Pa).
    pressure: f64,
    /// Cavity reference volume, whole capsule (m³).
    volume: f64,
    /// Contact radius (m) from the lift-off profile along the outer
    /// meridian (`nlvid_fem::capsule` module docs).
    radius: f64,
}

/// Contact radius of the top plate's patch: the library's lift-off reading
/// of the contact edge (`nlvid_fem::capsule`), asserted resolved.
fn contact_radius(patch: &ContactPatch) -> f64 {
    let a = patch.semi_axes[0];
    assert!(
        a.is_finite() && a > 0.0,
        "contact edge not resolved: {patch:?}"
    );
    a
}

/// The axisymmetric model with `n_arc` elements along the meridian.
fn axisymmetric(n_arc: usize) -> Outcome {
    let model = common::squeezed_axisymmetric(n_arc);
    let last = *model.records().last().unwrap();
    let patch = model
        .contact_patch(&PatchSpec {
            plane: 0,
            surface: "outer".into(),
            symmetry: Symmetry::AXISYMMETRIC_HALF,
            lift_off: LiftOff::Solid,
        })
        .unwrap();
    Outcome {
        force: last.plane_force,
        pressure: last.cavity_pressure,
        // The model is the upper half (symmetry plane z = 0).
        volume: 2.0 * model.cavity_reference_volume().unwrap(),
        radius: contact_radius(&patch),
    }
}

/// A 3D model of `part` with m divisions per cube-sphere patch edge (2m
/// elements along a quarter meridian, as the axisymmetric `n_arc` = 2m).
fn solid(part: ShellPart, m: usize) -> Outcome {
    let model = common::squeezed_solid(part, m);
    let last = *model.records().last().unwrap();
    if part != ShellPart::Eighth {
        assert!(
            (last.base_force / last.plane_force - 1.0).abs() < 1e-6,
            "{last:?}"
        );
    }
    // The top plate's patch (the plate above, index 0, in every part).
    let patch = model
        .contact_patch(&PatchSpec {
            plane: 0,
            surface: "outer".into(),
            symmetry: Symmetry::FULL,
            lift_off: LiftOff::Solid,
        })
        .unwrap();
    let (copies_force, copies_volume) = match part {
        ShellPart::Eighth => (4.0, 8.0),
        ShellPart::Quarter => (4.0, 4.0),
        ShellPart::Full => (1.0, 1.0),
    };
    Outcome {
        force: copies_force * last.plane_force,
        pressure: last.cavity_pressure,
        volume: copies_volume * model.cavity_reference_volume().unwrap(),
        radius: contact_radius(&patch),
    }
}

#[test]
fn eighth_model_agrees_with_the_axisymmetric_model() {
    // Same meridian spacing (π/4m), same four layers, same material and
    // penalty; the 3D model adds the circumferential discretisation.
    // Refining m = 8 → 16 the differences fall at second order, to below
    // 0.5 % in force and 1 % in contact radius.
    let mut rows = Vec::new();
    for m in [8, 16] {
        let axi = axisymmetric(2 * m);
        let eighth = solid(ShellPart::Eighth, m);
        let df = eighth.force / axi.force - 1.0;
        let dp = eighth.pressure / axi.pressure - 1.0;
        let da = eighth.radius / axi.radius - 1.0;
        let dv = eighth.volume / axi.volume - 1.0;
        eprintln!(
            "m = {m}: force 3D {:.6e} N vs axisymmetric {:.6e} N ({df:+.2e}); pressure {dp:+.2e}; \
             contact radius {:.5e} vs {:.5e} m ({da:+.2e}); V₀ {dv:+.2e}",
            eighth.force, axi.force, eighth.radius, axi.radius
        );
        rows.push((df, da));
    }
    let (df, da) = rows[1];
    assert!(df.abs() < 5e-3, "force differs by {df:e}");
    assert!(da.abs() < 1e-2, "contact radius differs by {da:e}");
    assert!(
        rows[0].0.abs() > 2.0 * df.abs(),
        "force difference should shrink with the mesh: {rows:?}"
    );
}

#[test]
fn eighth_quarter_and_full_models_agree() {
    let m = 4;
    let eighth = solid(ShellPart::Eighth, m);
    let quarter = solid(ShellPart::Quarter, m);
    let full = solid(ShellPart::Full, m);
    for (name, other) in [("quarter", quarter), ("full", full)] {
        eprintln!("{name}: {other:?} vs eighth {eighth:?}");
        for (what, a, b) in [
            ("force", other.force, eighth.force),
            ("pressure", other.pressure, eighth.pressure),
            ("volume", other.volume, eighth.volume),
            ("contact radius", other.radius, eighth.radius),
        ] {
            assert!((a / b - 1.0).abs() < 1e-6, "{name} {what}: {a} vs {b}");
        }
    }
    // Sanity: a squeezed capsule, pressurised.
    assert!(eighth.force > 0.0 && eighth.pressure > 0.0 && eighth.radius > 0.2 * R);
}
