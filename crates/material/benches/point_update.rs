//! 3D and membrane material-point updates per second, with consistent
//! tangent, for each model. Target (issue 2): ≥ 2 M/s per core for the
//! 2+2-term Pipkin–Rogers 3D update.
//!
//! `cargo bench -p nlvid-material --bench point_update`
//!
//! Each case is measured twice: `wall/…` in wall-clock time (criterion's
//! default) and `cpu/…` in CPU time of the benchmark thread, which is what
//! "per core" means on a machine shared with other jobs.

use std::hint::black_box;

use criterion::measurement::{Measurement, ValueFormatter, WallTime};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use nlvid_material::{
    Mat3, Material3, MembraneMaterial, MooneyRivlin, PipkinRogers, PronyViscoelastic,
};
use nlvid_model::{Prony, Relaxation};

fn bench_3d<T: Measurement, M: Material3>(c: &mut Criterion<T>, clock: &str, name: &str, m: &M) {
    let mut group = c.benchmark_group(format!("{clock}/update_3d"));
    group.throughput(Throughput::Elements(1));
    let f = Mat3::new(1.3, 0.2, 0.05, -0.1, 0.9, 0.1, 0.02, -0.05, 0.86);
    // A converged history after a few steps, so no branch is trivially zero.
    let mut state = m.initial_state();
    let mut trial = state.clone();
    for n in 1..4 {
        let g = Mat3::identity() + (f - Mat3::identity()) * (n as f64 / 3.0);
        if m.update(&state, &g, 0.01, &mut trial).is_ok() {
            state = trial.clone();
        }
    }
    group.bench_function(name, |b| {
        b.iter(|| {
            let r = m.update(
                black_box(&state),
                black_box(&f),
                black_box(0.01),
                &mut trial,
            );
            black_box(r)
        })
    });
    group.finish();
}

fn bench_membrane<T: Measurement, M: MembraneMaterial>(
    c: &mut Criterion<T>,
    clock: &str,
    name: &str,
    m: &M,
) {
    let mut group = c.benchmark_group(format!("{clock}/update_membrane"));
    group.throughput(Throughput::Elements(1));
    let state = m.initial_state();
    let mut trial = state.clone();
    group.bench_function(name, |b| {
        b.iter(|| {
            let r = m.update(
                black_box(&state),
                black_box([1.4, 1.1]),
                black_box(0.01),
                &mut trial,
            );
            black_box(r)
        })
    });
    group.finish();
}

fn models() -> (MooneyRivlin, PipkinRogers, PronyViscoelastic) {
    let ok = "valid benchmark parameters";
    let mr = MooneyRivlin::new(1000.0, 100.0, 1.0e6).expect(ok);
    let g1 = Relaxation::new(
        "G1",
        1000.0,
        Prony::new("G1", &[(0.3, 0.5), (0.2, 5.0)]).expect(ok),
    )
    .expect(ok);
    let g2 = Relaxation::new(
        "G2",
        100.0,
        Prony::new("G2", &[(0.4, 0.2), (0.2, 3.0)]).expect(ok),
    )
    .expect(ok);
    let pr = PipkinRogers::new(g1, g2, 0.3, 1.0e6).expect(ok);
    // G0 = 2 kPa: C1 = 1 kPa, the cell the benchmark always measured.
    let shear = Relaxation::new(
        "G0",
        2000.0,
        Prony::new("G", &[(0.3, 0.5), (0.2, 5.0)]).expect(ok),
    )
    .expect(ok);
    let pv = PronyViscoelastic::cell(&shear, 1.0e6).expect(ok);
    (mr, pr, pv)
}

/// CPU time of the calling thread, in ns.
struct ThreadCpu(WallTime);

impl Measurement for ThreadCpu {
    type Intermediate = cpu_time::ThreadTime;
    type Value = f64;
    fn start(&self) -> cpu_time::ThreadTime {
        cpu_time::ThreadTime::now()
    }
    fn end(&self, i: cpu_time::ThreadTime) -> f64 {
        i.elapsed().as_secs_f64() * 1e9
    }
    fn add(&self, a: &f64, b: &f64) -> f64 {
        a + b
    }
    fn zero(&self) -> f64 {
        0.0
    }
    fn to_f64(&self, v: &f64) -> f64 {
        *v
    }
    fn formatter(&self) -> &dyn ValueFormatter {
        self.0.formatter()
    }
}

fn point_updates<T: Measurement>(c: &mut Criterion<T>, clock: &str) {
    let (mr, pr, pv) = models();
    bench_3d(c, clock, "mooney_rivlin", &mr);
    bench_3d(c, clock, "pipkin_rogers_2+2", &pr);
    bench_3d(c, clock, "prony_viscoelastic_2", &pv);
    bench_membrane(c, clock, "mooney_rivlin", &mr);
    bench_membrane(c, clock, "pipkin_rogers_2+2", &pr);
    bench_membrane(c, clock, "prony_viscoelastic_2", &pv);
}

fn wall_clock(c: &mut Criterion) {
    point_updates(c, "wall");
}

fn thread_cpu(c: &mut Criterion<ThreadCpu>) {
    point_updates(c, "cpu");
}

fn cpu() -> Criterion<ThreadCpu> {
    Criterion::default().with_measurement(ThreadCpu(WallTime))
}

criterion_group!(wall, wall_clock);
criterion_group! {
    name = cpu_group;
    config = cpu();
    targets = thread_cpu
}
criterion_main!(wall, cpu_group);
