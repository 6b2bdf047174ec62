//! Adaptive infill (`nlvid_surrogate::infill`) on the analytic Lee–Radok
//! Hertz model over the Table 5.3 domain: at the same number of runs it
//! beats the plain Latin hypercube on the max checking error (eq. 4.4),
//! it stops at the first round that meets a target, and an interrupted
//! build resumes to the same design and runs as an uninterrupted one.

#![allow(clippy::unwrap_used, clippy::type_complexity)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize};

use nlvid_forward::HertzProny;
use nlvid_model::{Domain, ForwardModel};
use nlvid_surrogate::doe::training_and_checking;
use nlvid_surrogate::infill::{
    InfillSettings, Round, checking_error, checking_set, fit_kept, run_infill,
};
use nlvid_surrogate::{Admissibility, BuildOptions, RunStore, build, load};

use crate::common::{Interrupting, records};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nlvid-infill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Probe 2.5 µm, 2 µm in 1 s then hold to 10 s, 100 output times.
fn model() -> HertzProny {
    HertzProny::new(2.5e-6, 2e-6, 1.0, 10.0, 100).unwrap()
}

fn filters(m: &dyn ForwardModel) -> Admissibility {
    Admissibility {
        min_peak_force: Some(4e-9),
        reject_non_repulsive: true,
        contact_index: m.contact_index(),
    }
}

fn settings(initial: usize, target: Option<f64>) -> InfillSettings {
    InfillSettings {
        initial,
        batch: 5,
        target_max_error: target,
        candidates: 1500,
        proportional_to: Some(0),
        pca_energy: Some(1.0 - 1e-8),
    }
}

const SEED: u64 = 17;

/// The starting design, and the checking set built into `dir` (its
/// admissible runs).
fn setup(
    m: &dyn ForwardModel,
    domain: &Domain,
    initial: usize,
    dir: &Path,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let (train, check) = training_and_checking(domain, initial, 60, SEED, 10, 1e-6).unwrap();
    build(m, &check, dir, &BuildOptions::default()).unwrap();
    let (cx, cy) = checking_set(dir, &filters(m)).unwrap();
    (train, cx, cy)
}

#[allow(clippy::too_many_arguments)]
fn infill(
    m: &dyn ForwardModel,
    domain: &Domain,
    s: &InfillSettings,
    initial: &[Vec<f64>],
    budget: usize,
    store: &Path,
    check: (&[Vec<f64>], &[Vec<f64>]),
    cancel: Option<&AtomicBool>,
) -> Vec<Round> {
    let opts = BuildOptions {
        cancel,
        ..Default::default()
    };
    run_infill(
        m,
        domain,
        s,
        initial,
        budget,
        SEED,
        &filters(m),
        store,
        check,
        &opts,
        &mut |_| Ok(()),
    )
    .unwrap()
}

#[test]
fn infill_beats_the_plain_latin_hypercube_at_the_same_number_of_runs() {
    let (m, domain) = (model(), Domain::table_5_3(0.01).unwrap());
    let dir = tmp("beats");
    let (initial, cx, cy) = setup(&m, &domain, 30, &dir.join("check"));
    assert!(cx.len() >= 40, "{} admissible checking runs", cx.len());
    let budget = 70;
    let s = settings(30, None);
    let rounds = infill(
        &m,
        &domain,
        &s,
        &initial,
        budget,
        &dir.join("train"),
        (&cx, &cy),
        None,
    );
    let last = rounds.last().unwrap();
    assert_eq!(last.runs, budget);
    assert_eq!(rounds.len(), 1 + (budget - 30) / 5);
    let stored = RunStore::existing(dir.join("train"))
        .unwrap()
        .meta()
        .unwrap();
    assert_eq!(stored.design.len(), budget);
    assert_eq!(stored.design[..30], initial[..]);
    assert!(stored.design.iter().all(|x| domain.contains(x, 1e-12)));
    // The plain (ESE) Latin hypercube of the same size and seed.
    let (plain, _) = training_and_checking(&domain, budget, 60, SEED, 10, 1e-6).unwrap();
    build(&m, &plain, &dir.join("plain"), &BuildOptions::default()).unwrap();
    let mm = load(&dir.join("plain"), &filters(&m)).unwrap();
    let k = fit_kept(&mm, &s.kriging_settings(&domain)).unwrap();
    let (plain_max, plain_median) = checking_error(&k, &cx, &cy).unwrap();
    let (max, median) = last.check.unwrap();
    println!(
        "infill {} runs ({} admissible): max {:.3} %, median {:.3} %; plain LHS ({} admissible): \
         max {:.3} %, median {:.3} %",
        last.runs,
        last.admissible,
        100.0 * max,
        100.0 * median,
        mm.x.len(),
        100.0 * plain_max,
        100.0 * plain_median
    );
    assert!(max < 0.5 * plain_max, "infill {max} vs plain {plain_max}");
    // The start of the infill is that Latin hypercube's worse sibling.
    assert!(rounds[0].check.unwrap().0 > max);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn infill_stops_at_the_first_round_that_meets_the_target() {
    let (m, domain) = (model(), Domain::table_5_3(0.01).unwrap());
    let dir = tmp("target");
    let (initial, cx, cy) = setup(&m, &domain, 30, &dir.join("check"));
    let target = 0.01;
    let rounds = infill(
        &m,
        &domain,
        &settings(30, Some(target)),
        &initial,
        200,
        &dir.join("train"),
        (&cx, &cy),
        None,
    );
    let (last, before) = rounds.split_last().unwrap();
    assert!(last.check.unwrap().0 <= target, "{last:?}");
    assert_eq!(last.added, 0);
    assert!(last.runs < 200, "{last:?}");
    assert!(!before.is_empty());
    for r in before {
        assert!(r.check.unwrap().0 > target, "{r:?}");
        assert_eq!(r.added, 5);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn interrupted_infill_resumes_to_the_uninterrupted_design() {
    let (m, domain) = (model(), Domain::table_5_3(0.01).unwrap());
    let dir = tmp("resume");
    let (initial, cx, cy) = setup(&m, &domain, 20, &dir.join("check"));
    let s = settings(20, None);
    let budget = 40;
    let check = (&cx[..], &cy[..]);
    let whole = infill(
        &m,
        &domain,
        &s,
        &initial,
        budget,
        &dir.join("a"),
        check,
        None,
    );
    // Interrupted inside the second added batch, then resumed.
    let cancel = AtomicBool::new(false);
    let stopping = Interrupting {
        inner: model(),
        started: AtomicUsize::new(0),
        after: 27,
        cancel: &cancel,
    };
    let part = infill(
        &stopping,
        &domain,
        &s,
        &initial,
        budget,
        &dir.join("b"),
        check,
        Some(&cancel),
    );
    let done_before = records(&dir.join("b")).len();
    assert!(done_before < budget && done_before >= 25, "{done_before}");
    assert!(part.len() < whole.len());
    let resumed = infill(
        &m,
        &domain,
        &s,
        &initial,
        budget,
        &dir.join("b"),
        check,
        None,
    );
    assert_eq!(resumed.last(), whole.last());
    let (a, b) = (
        RunStore::existing(dir.join("a")).unwrap().meta().unwrap(),
        RunStore::existing(dir.join("b")).unwrap().meta().unwrap(),
    );
    assert_eq!(a, b);
    assert_eq!(records(&dir.join("a")), records(&dir.join("b")));
    // Another starting design is refused, the stored runs are kept.
    let other = &cx[..20.min(cx.len())];
    let e = run_infill(
        &m,
        &domain,
        &s,
        other,
        budget,
        SEED,
        &filters(&m),
        &dir.join("b"),
        check,
        &BuildOptions::default(),
        &mut |_| Ok(()),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("another design"), "{e}");
    assert_eq!(records(&dir.join("b")).len(), budget);
    let _ = std::fs::remove_dir_all(&dir);
}
