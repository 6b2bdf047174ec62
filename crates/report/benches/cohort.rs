//! Criterion bench: a cohort of 100 cells (2 groups × 50, the demo's
//! distributions, curves made by the demo's forward model with 1 % noise)
//! fitted from scratch on the demo's pre-built Kriging meta-model
//! (`examples/demo/metamodel/`), 8 multistart starts each, all cores.
//! Target (issue 7): ≤ 20 s on the 2-core machine. Run:
//! `cargo bench -p nlvid-report --bench cohort`.

use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_report::cohort::{self, RunOptions};
use nlvid_report::demo::{DemoSpec, write_demo_data};
use nlvid_report::settings::{CohortSettings, FitModel};

fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let p = e?.path();
        if let Some(name) = p.file_name() {
            std::fs::copy(&p, to.join(name))?;
        }
    }
    Ok(())
}

fn bench(c: &mut Criterion) {
    let root = std::env::temp_dir().join(format!("nlvid-report-bench-{}", std::process::id()));
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let study_dir = root.join("study");
    let copied = std::fs::create_dir_all(&study_dir)
        .and_then(|()| std::fs::copy(repo.join("study.toml"), study_dir.join("study.toml")))
        .and_then(|_| {
            std::fs::copy(
                repo.join("metamodel.toml"),
                study_dir.join("metamodel.toml"),
            )
        })
        .and_then(|_| copy_dir(&repo.join("metamodel"), &study_dir.join("metamodel")));
    if let Err(e) = copied {
        eprintln!("cannot copy the demo study to {}: {e}", study_dir.display());
        return;
    }
    let spec = DemoSpec {
        cells_per_group: 50,
        ..DemoSpec::default()
    };
    let files = match write_demo_data(
        &spec,
        &study_dir.join("study.toml"),
        &study_dir.join("metamodel.toml"),
    ) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("cannot write the bench cells: {e}");
            return;
        }
    };
    let (Ok(settings), Ok(cells)) = (
        CohortSettings::load(&files.study),
        cohort::discover(&files.data),
    ) else {
        eprintln!("bench study unreadable");
        return;
    };
    assert_eq!(settings.model, FitModel::Surrogate);
    assert_eq!(cells.len(), 100);
    let out: PathBuf = root.join("out");
    let mut g = c.benchmark_group("cohort");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(30));
    g.bench_function("100 cells, Kriging meta-model, 8 starts", |b| {
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
