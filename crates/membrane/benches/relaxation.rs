//! Fig. 2.6 relaxation run: NLV membrane (g1 = 0.2, g2 = 0.3, c = 1/2,
//! γ0 = 0.1), step to D/r0 = 0.53 and 0.78, t0 from 0 to 10 in 100 steps,
//! default geometry (r_s = 1.03, 64 RK4 intervals). Target: < 0.5 s on one
//! core. `principal_reference` runs the same case with the session-1
//! principal-stretch point update (tests/common/reference_pr.rs) for a
//! before/after comparison with the `nlvid-material` adapter.

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_membrane::{ControlKind, Geometry, Loading, PipkinRogersParams, simulate, simulate_with};
use nlvid_protocol::{Quantity, programs};

#[path = "../tests/common/reference_pr.rs"]
mod reference_pr;

fn fig_2_6(c: &mut Criterion) {
    let p = PipkinRogersParams::chapter2(0.2, 0.3, 0.5);
    let mut g = c.benchmark_group("membrane");
    g.sample_size(10);
    for d in [0.53, 0.78] {
        let prog = programs::step(Quantity::Dimensionless, d, 10.0).expect("program");
        let times = (0..=100).map(|k| 0.1 * k as f64).collect();
        let l = Loading::new(ControlKind::Displacement, prog, times).expect("loading");
        g.bench_function(format!("fig_2_6_relaxation_D{d}_100_steps"), |b| {
            b.iter(|| simulate(&p, &Geometry::default(), &l).expect("run"))
        });
        g.bench_function(
            format!("fig_2_6_relaxation_D{d}_100_steps_principal_reference"),
            |b| {
                b.iter(|| {
                    simulate_with(
                        reference_pr::PipkinRogersMembrane { p },
                        1.0,
                        &Geometry::default(),
                        &l,
                    )
                    .expect("run")
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, fig_2_6);
criterion_main!(benches);
