//! Mooney–Rivlin / neo-Hookean: closed forms and tangents.

use crate::common;

use nlvid_material::{Incompressible, Mat3, Material3, MembraneMaterial, MooneyRivlin};

fn uniaxial_closed_form(c1: f64, c2: f64, l: f64) -> f64 {
    // σ = 2 (λ² − 1/λ)(C1 + C2/λ) for incompressible uniaxial tension.
    2.0 * (l * l - 1.0 / l) * (c1 + c2 / l)
}

#[test]
fn consistent_tangent_matches_central_differences_up_to_stretch_3() {
    for &(c1, c2) in &[(1000.0, 0.0), (1000.0, 250.0)] {
        let m = MooneyRivlin::new(c1, c2, 50.0 * c1).expect("valid");
        for f in common::test_gradients() {
            let e = common::tangent_error_3d(&m, &(), &f, 0.0);
            assert!(e < 1e-6, "C2 = {c2}, F = {f}: relative error {e:e}");
        }
    }
}

#[test]
fn membrane_tangent_matches_central_differences_up_to_stretch_3() {
    let m = MooneyRivlin::new(1000.0, 300.0, 0.0).expect("valid");
    for l in [[1.0, 1.0], [3.0, 1.0], [1.5, 2.5], [3.0, 3.0], [0.8, 2.0]] {
        let e = common::tangent_error_membrane(&m, &(), l, 0.0);
        assert!(e < 1e-6, "λ = {l:?}: relative error {e:e}");
    }
}

#[test]
fn membrane_uniaxial_and_equibiaxial_match_closed_forms() {
    let (c1, c2) = (1000.0, 300.0);
    let m = MooneyRivlin::new(c1, c2, 0.0).expect("valid");
    for &l in &[1.1, 2.0, 3.0] {
        // Equibiaxial membrane: σ = 2(λ² − λ⁻⁴)(C1 + C2 λ²).
        let r = MembraneMaterial::update(&m, &(), [l, l], 0.0, &mut ()).expect("ok");
        let exact = 2.0 * (l * l - l.powi(-4)) * (c1 + c2 * l * l);
        assert!(
            (r.cauchy[0] - exact).abs() < 1e-12 * exact,
            "{r:?} vs {exact}"
        );
        // Uniaxial: λ2 = λ^{-1/2} gives σ2 = 0 and σ1 of the closed form.
        let r = MembraneMaterial::update(&m, &(), [l, l.powf(-0.5)], 0.0, &mut ()).expect("ok");
        let exact = uniaxial_closed_form(c1, c2, l);
        assert!((r.cauchy[0] - exact).abs() < 1e-12 * exact);
        assert!(r.cauchy[1].abs() < 1e-10 * exact);
    }
}

#[test]
fn penalty_3d_uniaxial_tends_to_incompressible_closed_form() {
    // With K = 1e6·C1 and the lateral stretch solved by bisection for σ22 = 0,
    // the 3D penalty update reproduces the incompressible closed form.
    let (c1, c2) = (1000.0, 200.0);
    let m = MooneyRivlin::new(c1, c2, 1e6 * c1).expect("valid");
    let l = 2.0;
    let s22 = |lt: f64| {
        let f = Mat3::from_diagonal(&nalgebra::Vector3::new(l, lt, lt));
        Material3::update(&m, &(), &f, 0.0, &mut ())
            .expect("ok")
            .cauchy
    };
    let (mut lo, mut hi) = (0.5 / l.sqrt(), 2.0 / l.sqrt());
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if s22(mid)[(1, 1)] > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let s = s22(0.5 * (lo + hi));
    let exact = uniaxial_closed_form(c1, c2, l);
    assert!(
        (s[(0, 0)] - exact).abs() < 1e-4 * exact,
        "{} vs {exact}",
        s[(0, 0)]
    );
}

#[test]
fn simple_shear_gives_mooney_rivlin_viscometric_functions() {
    let (c1, c2) = (1000.0, 300.0);
    let m = MooneyRivlin::new(c1, c2, 0.0).expect("valid");
    for &g in &[0.1, 1.0, 3.0] {
        let f = Mat3::new(1.0, g, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        let t = m.extra_stress(&(), &f, 0.0, &mut ()).expect("ok");
        let n1 = t[(0, 0)] - t[(1, 1)];
        let n2 = t[(1, 1)] - t[(2, 2)];
        assert!((t[(0, 1)] - 2.0 * (c1 + c2) * g).abs() < 1e-12 * c1 * g);
        assert!((n1 - 2.0 * (c1 + c2) * g * g).abs() < 1e-12 * c1 * g * g);
        assert!((n2 + 2.0 * c2 * g * g).abs() < 1e-12 * c1 * g * g);
    }
}

#[test]
fn bad_parameters_and_deformations_are_named() {
    let e = MooneyRivlin::new(-1.0, 0.0, 0.0).expect_err("C1 < 0");
    assert!(e.to_string().contains("`C1` = -1"), "{e}");
    let e = MooneyRivlin::new(1.0, f64::NAN, 0.0).expect_err("NaN");
    assert!(e.to_string().contains("`C2`"), "{e}");
    let e = MooneyRivlin::new(1.0, 0.0, -5.0).expect_err("K < 0");
    assert!(e.to_string().contains("`bulk_modulus`"), "{e}");
    let m = MooneyRivlin::new(1.0, 0.0, 1.0).expect("valid");
    let f = Mat3::from_diagonal(&nalgebra::Vector3::new(-1.0, 1.0, 1.0));
    let e = Material3::update(&m, &(), &f, 0.0, &mut ()).expect_err("det F < 0");
    assert!(e.to_string().contains("det F = -1"), "{e}");
    let e = MembraneMaterial::update(&m, &(), [0.0, 1.0], 0.0, &mut ()).expect_err("λ = 0");
    assert!(e.to_string().contains("λ1 = 0"), "{e}");
    let e = Material3::update(&m, &(), &Mat3::identity(), -1.0, &mut ()).expect_err("dt < 0");
    assert!(e.to_string().contains("dt = -1"), "{e}");
}
