//! Table 2.1: initial unloading slopes (tangent over the first unloading step).
#![allow(clippy::unwrap_used)]
use nlvid_membrane::*;
use nlvid_protocol::{Quantity, programs};
fn run(p: PipkinRogersParams, dmax: f64, su: f64, label: &str) {
    let prog = programs::load_unload(Quantity::Dimensionless, dmax, 1.0, su, 0.0).unwrap();
    let tm = dmax;
    let mut times: Vec<f64> = (0..=200).map(|k| tm * k as f64 / 200.0).collect();
    for k in 1..=20 {
        times.push(tm + 1e-3 * k as f64 / 20.0);
    }
    let l = Loading::new(ControlKind::Displacement, prog, times).unwrap();
    let r = simulate(&p, &Geometry::default(), &l).unwrap();
    let h = &r.history;
    let i = h.iter().position(|x| (x.time - tm).abs() < 1e-12).unwrap();
    let s1 = (h[i].force - h[i + 1].force) / (h[i].displacement - h[i + 1].displacement);
    let s20 = (h[i].force - h[i + 20].force) / (h[i].displacement - h[i + 20].displacement);
    let sl = (h[i].force - h[i - 1].force) / (h[i].displacement - h[i - 1].displacement);
    eprintln!(
        "{label} D={dmax} su={su}: F={:.4} unload slope {s1:.3} / {s20:.3}, load slope {sl:.3}",
        h[i].force
    );
}
/// Table 2.1 exploration (prints slopes; run with `--ignored --nocapture`).
#[test]
#[ignore = "reproduction run, prints Table 2.1 slopes"]
fn table_2_1_unloading_slopes() {
    let nle = PipkinRogersParams {
        g1: 1.0,
        g2: 1.0,
        ..Default::default()
    };
    let qlv = PipkinRogersParams {
        g1: 0.2,
        g2: 0.2,
        c: 1.0,
        ..Default::default()
    };
    let nlv1 = PipkinRogersParams {
        g1: 0.2,
        g2: 0.6,
        c: 1.0,
        ..Default::default()
    };
    let nlv2 = PipkinRogersParams {
        g1: 0.2,
        g2: 0.6,
        c: 0.5,
        ..Default::default()
    };
    for d in [0.28, 0.78] {
        run(nle, d, 1.0, "NLE");
        for su in [1.0, 0.2] {
            run(qlv, d, su, "QLV");
            run(nlv1, d, su, "NLV c=1");
            run(nlv2, d, su, "NLV c=.5");
        }
    }
}
