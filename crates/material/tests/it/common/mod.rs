//! Helpers shared by the integration tests: central finite differences of
//! the stress updates, written independently of the crate's tangents, and
//! the viscoelastic models the tangent tests check.
#![allow(dead_code)]

use nlvid_material::{
    HistoryRule, Mat3, Material3, MembraneMaterial, MooneyRivlin, PipkinRogers, PronyViscoelastic,
    Tangent3,
};
use nlvid_model::{Prony, Relaxation};

/// Deformation gradients with stretches up to 3, shear and rotation.
pub fn test_gradients() -> Vec<Mat3> {
    let rot = |th: f64| {
        let (s, c) = th.sin_cos();
        Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
    };
    vec![
        Mat3::identity(),
        Mat3::new(
            3.0,
            0.0,
            0.0,
            0.0,
            1.0 / 3f64.sqrt(),
            0.0,
            0.0,
            0.0,
            1.0 / 3f64.sqrt(),
        ),
        Mat3::new(1.3, 0.4, 0.1, -0.2, 0.9, 0.3, 0.05, -0.1, 1.1),
        Mat3::new(2.5, 0.7, 0.0, 0.0, 1.2, 0.2, 0.1, 0.0, 0.35),
        rot(0.7) * Mat3::new(3.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 1.0 / 6.0),
        Mat3::new(1.0, 3.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    ]
}

/// `max |A − A_fd| / max |A|` for `∂P/∂F` at `f`, history `state_n`, step `dt`.
pub fn tangent_error_3d<M: Material3>(m: &M, state_n: &M::State, f: &Mat3, dt: f64) -> f64 {
    let mut trial = state_n.clone();
    let a = m
        .update(state_n, f, dt, &mut trial)
        .expect("update")
        .tangent;
    let mut fd = Tangent3::zeros();
    for k in 0..3 {
        for l in 0..3 {
            let h = 1e-6 * f.abs().max().max(1.0);
            let mut fp = *f;
            fp[(k, l)] += h;
            let mut fm = *f;
            fm[(k, l)] -= h;
            let pp = m
                .update(state_n, &fp, dt, &mut trial)
                .expect("update")
                .first_piola;
            let pm = m
                .update(state_n, &fm, dt, &mut trial)
                .expect("update")
                .first_piola;
            for i in 0..3 {
                for j in 0..3 {
                    fd[(3 * i + j, 3 * k + l)] = (pp[(i, j)] - pm[(i, j)]) / (2.0 * h);
                }
            }
        }
    }
    (a - fd).abs().max() / a.abs().max()
}

/// `max |T − T_fd| / max |T|` for `∂σ_α/∂λ_β` of a membrane update.
pub fn tangent_error_membrane<M: MembraneMaterial>(
    m: &M,
    state_n: &M::State,
    l: [f64; 2],
    dt: f64,
) -> f64 {
    let mut trial = state_n.clone();
    let t = m
        .update(state_n, l, dt, &mut trial)
        .expect("update")
        .tangent;
    let mut err: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for b in 0..2 {
        let h = 1e-6 * l[b];
        let mut lp = l;
        lp[b] += h;
        let mut lm = l;
        lm[b] -= h;
        let sp = m
            .update(state_n, lp, dt, &mut trial)
            .expect("update")
            .cauchy;
        let sm = m
            .update(state_n, lm, dt, &mut trial)
            .expect("update")
            .cauchy;
        for a in 0..2 {
            let fd = (sp[a] - sm[a]) / (2.0 * h);
            err = err.max((t[a][b] - fd).abs());
            scale = scale.max(t[a][b].abs());
        }
    }
    err / scale
}

/// The Pipkin–Rogers model of the tangent tests: G1(t) from 1 kPa and
/// G2(t) from 150 Pa, each relaxing by two Prony terms, a = 0.4 (eq. 2.54),
/// volumetric penalty K = 30 kPa, history integrated with `rule`.
pub fn pipkin_rogers(rule: HistoryRule) -> PipkinRogers {
    let g1 = Relaxation::new(
        "G1",
        1000.0,
        Prony::new("G1", &[(0.3, 0.5), (0.2, 5.0)]).expect("ok"),
    )
    .expect("ok");
    let g2 = Relaxation::new(
        "G2",
        150.0,
        Prony::new("G2", &[(0.6, 0.2), (0.1, 3.0)]).expect("ok"),
    )
    .expect("ok");
    PipkinRogers::new(g1, g2, 0.4, 3.0e4)
        .expect("ok")
        .with_rule(rule)
}

/// The ABAQUS-form viscoelastic model of the tangent tests: Mooney–Rivlin
/// (C1 = 1 kPa, C2 = 200 Pa, K = 30 kPa) relaxing by two Prony
/// terms, history integrated with `rule`.
pub fn prony_visco(rule: HistoryRule) -> PronyViscoelastic {
    let el = MooneyRivlin::new(1000.0, 200.0, 3.0e4).expect("ok");
    PronyViscoelastic::new(el, Prony::new("G", &[(0.4, 0.3), (0.3, 4.0)]).expect("ok"))
        .with_rule(rule)
}
