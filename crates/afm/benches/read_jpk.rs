//! Reading the 10 000-point JPK relaxation file (target ≤ 20 ms).

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const SR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/fmt-jpk-sr_cell1-0008.jpk-force"
);

fn bench(c: &mut Criterion) {
    let bytes = std::fs::read(SR).unwrap_or_default();
    c.bench_function("read_jpk_sr_cell1_from_disk", |b| {
        b.iter(|| nlvid_afm::read_force_curve(black_box(SR)))
    });
    c.bench_function("read_jpk_sr_cell1_in_memory", |b| {
        b.iter(|| {
            nlvid_afm::read_jpk_bytes(black_box(&bytes), "sr", &nlvid_afm::ReadOptions::default())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
