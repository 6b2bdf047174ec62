//! Criterion bench: a cohort of 100 cells (2 groups × 50, the demo's
//! distributions) fitted from scratch with the analytic Lee–Radok model,
//! 8 multistart starts each, all cores. Target once a surrogate exists:
//! ≤ 20 s on the 2-core machine. Run: `cargo bench -p nlvid-report`.

use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_report::cohort::{self, RunOptions};
use nlvid_report::demo::{DemoSpec, write_demo};
use nlvid_report::settings::CohortSettings;

fn bench(c: &mut Criterion) {
    let root = std::env::temp_dir().join(format!("nlvid-report-bench-{}", std::process::id()));
    let spec = DemoSpec {
        cells_per_group: 50,
        ..DemoSpec::default()
    };
    let Ok(files) = write_demo(&spec, &root.join("study")) else {
        eprintln!("cannot write the bench study under {}", root.display());
        return;
    };
    let (Ok(settings), Ok(cells)) = (
        CohortSettings::load(&files.study),
        cohort::discover(&files.data),
    ) else {
        eprintln!("bench study unreadable");
        return;
    };
    assert_eq!(cells.len(), 100);
    let out: PathBuf = root.join("out");
    let mut g = c.benchmark_group("cohort");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(30));
    g.bench_function("100 cells, Lee-Radok, 8 starts", |b| {
        b.iter(|| {
            // A fresh output directory: nothing may be reused.
            let _ = std::fs::remove_dir_all(&out);
            let run = cohort::run_cohort(
                &settings,
                &files.study,
                &files.data,
                &cells,
                &out,
                &RunOptions::default(),
            );
            match run {
                Ok(r) => assert_eq!(r.fitted, 100),
                Err(e) => panic!("cohort failed: {e}"),
            }
        });
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&root);
}

criterion_group!(benches, bench);
criterion_main!(benches);
