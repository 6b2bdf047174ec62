//! Speed of one thesis-scale AFM run (setup 1, default mesh, full two-step
//! protocol): the forward model the surrogate stage calls ~1300 times, on
//! one core and with the element loop on two threads. Criterion measures
//! wall time; on a loaded machine use the example
//! (`cargo run -p nlvid-fem --release --example afm_setup1`), which reports
//! the median thread-CPU time of 5 runs and the phase breakdown.
//!
//! `cargo bench -p nlvid-fem --bench afm_run` (also the elastic dome of
//! issue 15).

#![allow(clippy::needless_range_loop, clippy::unwrap_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_fem::afm::{self, AfmSetup};
use nlvid_model::{Prony, Relaxation, names};

fn bench(c: &mut Criterion) {
    // G0 = 1 kPa (shear modulus), g1 = g2 = 0.3, tau1 = 0.5 s, tau2 = 10 s.
    let params = Relaxation::from_named(&names::PRONY2, &[1e3, 0.3, 0.3, 0.5, 10.0]).unwrap();
    faer::set_global_parallelism(faer::Par::Seq);
    let setup = AfmSetup::thesis_setup1();
    let mut two = setup.clone();
    two.settings.threads = 2;
    let mut group = c.benchmark_group("afm");
    group.sample_size(10);
    group.bench_function("setup1_default_mesh_full_protocol", |b| {
        b.iter(|| afm::run(&params, &setup).map(|r| r.peak_force))
    });
    group.bench_function("setup1_default_mesh_full_protocol_2_threads", |b| {
        b.iter(|| afm::run(&params, &two).map(|r| r.peak_force))
    });
    // Issue 15's elastic dome (the example `elastic_dome` is the same run):
    // on the default mesh, and as the benchmark runs it.
    let elastic = Relaxation::new(names::G0, 1e3, Prony::elastic()).unwrap();
    let dome = AfmSetup::elastic_dome();
    group.bench_function("elastic_dome_default_mesh", |b| {
        b.iter(|| afm::run(&elastic, &dome).map(|r| r.peak_force))
    });
    let dome = AfmSetup::elastic_dome_benchmark();
    group.bench_function("elastic_dome_benchmark", |b| {
        b.iter(|| afm::run(&elastic, &dome).map(|r| r.peak_force))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
