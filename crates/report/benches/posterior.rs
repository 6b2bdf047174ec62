//! Criterion bench: the posterior of one cell (issue 17's "≤ 2 s") on the
//! demo's pre-built FE meta-model (`examples/demo/metamodel/`, N = 970
//! runs): the first cell of each of the demo's groups
//! (`examples/demo/data/`, curves made by the FE cell model), fitted
//! once outside the timing, then `sample_posterior` with the default
//! `[posterior]` settings (4 ensembles × 16 walkers, R̂ ≤ 1.01, delayed
//! acceptance) on 1 thread and on 2 (the same draws). Run:
//! `cargo bench -p nlvid-report --bench posterior`.
//!
//! The distribution over the 100 cells of the coverage cohort, hard cells
//! included, is printed by the `posterior_cells` example (`threads=2`).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use nlvid_inverse::posterior::{PosteriorSettings, sample_posterior};
use nlvid_report::cell::{CellModel, fit_cell};
use nlvid_report::cohort::discover;
use nlvid_report::settings::CohortSettings;

fn bench(c: &mut Criterion) {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/demo");
    let settings = CohortSettings::load(&demo.join("study.toml")).expect("demo study");
    let model = CellModel::load(&settings).expect("demo meta-model");
    let CellModel::Surrogate(fitter, _) = &model else {
        panic!("the demo study fits a meta-model");
    };
    let inputs = discover(&demo.join("data")).expect("demo data");
    let mut g = c.benchmark_group("posterior");
    g.sample_size(10);
    for group in ["A-stiff", "B-soft"] {
        let input = inputs
            .iter()
            .find(|i| i.group == group)
            .expect("a cell of the group");
        let fitted = fit_cell(&settings, &model, input);
        let x_hat: Vec<f64> = fitted.parameters.iter().map(|p| p.value).collect();
        for threads in [1, 2] {
            let ps = PosteriorSettings {
                seed: settings.seed,
                threads,
                ..PosteriorSettings::new(settings.hold_end)
            };
            let name = format!("{} ({group}), {threads} thread(s)", fitted.cell);
            g.bench_function(name, |b| {
                b.iter(|| {
                    let p = sample_posterior(
                        fitter.surrogate(),
                        &fitted.data,
                        (&x_hat, &fitted.other_optima),
                        &ps,
                    )
                    .expect("posterior");
                    assert!(p.rhat_max <= 1.01, "R-hat {}", p.rhat_max);
                    p
                });
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
