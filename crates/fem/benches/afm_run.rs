//! Speed of one thesis-scale AFM run (setup 1, default mesh, full two-step
//! protocol): the forward model the surrogate stage calls ~1300 times.
//!
//! `cargo bench -p nlvid-fem --bench afm_run`

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_fem::afm::{self, AfmParams, AfmSetup};

fn bench(c: &mut Criterion) {
    let params = AfmParams {
        g0: 1e3,
        g1: 0.3,
        tau1: 0.5,
        g2: 0.3,
        tau2: 10.0,
    };
    let setup = AfmSetup::thesis_setup1();
    let mut group = c.benchmark_group("afm");
    group.sample_size(10);
    group.bench_function("setup1_default_mesh_full_protocol", |b| {
        b.iter(|| afm::run(&params, &setup).map(|r| r.peak_force))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
