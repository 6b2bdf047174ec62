//! Thesis-scale group comparison: 23 + 23 cells (Fig. 5.14), G(t) and
//! G(t)/G(0) tested at m = 5095 times; and single tests.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_model::{Prony, Relaxation};
use nlvid_stats::{Method, compare_over_time, group_curves, rank_sum};

fn cells(n: usize, g0: f64, g2: f64, seed: u64) -> Vec<Relaxation> {
    let mut s = seed;
    let mut u = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            // Draw order as before: G0, g1, tau1, g2, tau2.
            let g0 = g0 * (0.5 + u());
            let t1 = (0.2 + 0.1 * u(), 0.3 + 0.7 * u());
            let t2 = (g2 + 0.1 * u(), 5.0 + 15.0 * u());
            Prony::new("G", &[t1, t2])
                .and_then(|p| Relaxation::new("G0", g0, p))
                .unwrap_or_else(|e| panic!("{e}"))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let a = cells(23, 2940.0, 0.3, 1);
    let b = cells(23, 1940.0, 0.45, 2);
    let times: Vec<f64> = (0..5095).map(|i| 52.8 * i as f64 / 5094.0).collect();
    c.bench_function(
        "compare_over_time 23+23 cells x 5095 times (matlab)",
        |bn| {
            bn.iter(|| {
                compare_over_time(black_box(&a), black_box(&b), &times, Method::MATLAB_RANKSUM)
            })
        },
    );
    c.bench_function("group_curves 23 cells x 5095 times", |bn| {
        bn.iter(|| group_curves("A", black_box(&a), &times))
    });
    let x: Vec<f64> = a.iter().map(|p| p.value(52.0)).collect();
    let y: Vec<f64> = b.iter().map(|p| p.value(52.0)).collect();
    c.bench_function("rank_sum exact 23+23", |bn| {
        bn.iter(|| rank_sum(black_box(&x), black_box(&y), Method::Exact))
    });
    c.bench_function("rank_sum asymptotic 23+23", |bn| {
        bn.iter(|| rank_sum(black_box(&x), black_box(&y), Method::ASYMPTOTIC))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
