//! Meta-model builds: interruption + resume equals an uninterrupted build;
//! merged shards equal the unsharded build; failures and filters counted.

#![allow(clippy::unwrap_used, clippy::type_complexity)]

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicUsize};

use nlvid_forward::HertzProny;
use nlvid_model::{Domain, FailureKind, ForwardModel, Parameter, RunFailure, Scale};
use nlvid_surrogate::doe::{SampleSettings, sample};
use nlvid_surrogate::{Admissibility, BuildOptions, Shard, build, export, load, merge};

use crate::common::{Interrupting, records};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("nlvid-surrogate-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The cell-study domain (`Domain::cell_study`) with g1 + g2 ≤ 0.95.
fn cell_domain() -> Domain {
    Domain::new(Domain::cell_study().params().to_vec())
        .and_then(|d| d.with_sum_constraint(&["g1", "g2"], 0.95))
        .unwrap()
}

fn model() -> HertzProny {
    HertzProny::new(5e-6, 1e-6, 1.0, 10.0, 40).unwrap()
}

#[test]
fn interrupted_then_resumed_build_equals_uninterrupted_build() {
    let design = sample(
        &cell_domain(),
        &SampleSettings {
            n: 60,
            seed: 4,
            optimise_iterations: 3,
        },
    )
    .unwrap();
    let full = tmp("full");
    let s = build(&model(), &design, &full, &BuildOptions::default()).unwrap();
    assert_eq!((s.ran, s.skipped, s.failed, s.remaining), (60, 0, 0, 0));

    let part = tmp("part");
    let cancel = AtomicBool::new(false);
    let m = Interrupting {
        inner: model(),
        started: AtomicUsize::new(0),
        after: 17,
        cancel: &cancel,
    };
    let s1 = build(
        &m,
        &design,
        &part,
        &BuildOptions {
            cancel: Some(&cancel),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(s1.remaining > 0 && s1.ran >= 17, "{s1:?}");
    // A half-written temporary file, as a kill during a write leaves it.
    std::fs::write(
        part.join("runs").join("000059.tmp999"),
        b"{\"index\": 59, \"par",
    )
    .unwrap();
    let s2 = build(&model(), &design, &part, &BuildOptions::default()).unwrap();
    assert_eq!(s2.skipped, s1.ran);
    assert_eq!(s2.ran, 60 - s1.ran);
    assert_eq!(records(&full), records(&part));
    let _ = std::fs::remove_dir_all(&full);
    let _ = std::fs::remove_dir_all(&part);
}

#[test]
fn merged_shards_equal_the_unsharded_build() {
    let design = sample(
        &cell_domain(),
        &SampleSettings {
            n: 25,
            seed: 8,
            optimise_iterations: 3,
        },
    )
    .unwrap();
    let full = tmp("unsharded");
    build(&model(), &design, &full, &BuildOptions::default()).unwrap();
    let mut dirs = vec![];
    for i in 1..=3 {
        let d = tmp(&format!("shard{i}"));
        let shard = Shard::parse(&format!("{i}/3")).unwrap();
        let s = build(
            &model(),
            &design,
            &d,
            &BuildOptions {
                shard: Some(shard),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(s.in_shard, (0..25).filter(|k| k % 3 == i - 1).count());
        dirs.push(d);
    }
    let merged = tmp("merged");
    assert_eq!(merge(&dirs, &merged).unwrap(), 25);
    assert_eq!(records(&full), records(&merged));
    for d in dirs.iter().chain([&full, &merged]) {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_store_of_another_study_is_refused() {
    let d1 = sample(
        &cell_domain(),
        &SampleSettings {
            n: 5,
            seed: 1,
            optimise_iterations: 0,
        },
    )
    .unwrap();
    let d2 = sample(
        &cell_domain(),
        &SampleSettings {
            n: 5,
            seed: 2,
            optimise_iterations: 0,
        },
    )
    .unwrap();
    let dir = tmp("other");
    build(&model(), &d1, &dir, &BuildOptions::default()).unwrap();
    let e = build(&model(), &d2, &dir, &BuildOptions::default()).unwrap_err();
    assert!(e.to_string().contains("another study"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Fails for large G0, returns attractive force for small tau1.
struct Flaky(HertzProny);

impl ForwardModel for Flaky {
    fn parameter_names(&self) -> Vec<String> {
        self.0.parameter_names()
    }
    fn parameter_units(&self) -> Vec<String> {
        self.0.parameter_units()
    }
    fn time_grid(&self) -> &[f64] {
        self.0.time_grid()
    }
    fn identity(&self) -> String {
        "flaky".into()
    }
    fn run(&self, p: &[f64]) -> Result<Vec<f64>, RunFailure> {
        if p[0] > 3000.0 {
            return Err(RunFailure {
                kind: FailureKind::NotConverged,
                time: Some(0.5),
                message: "Newton stalled".into(),
            });
        }
        let mut f = self.0.run(p)?;
        if p[3] < 0.03 {
            f[30] = -1e-12;
        }
        Ok(f)
    }
}

#[test]
fn failures_and_filters_are_counted_and_exported() {
    let design = sample(
        &cell_domain(),
        &SampleSettings {
            n: 40,
            seed: 3,
            optimise_iterations: 0,
        },
    )
    .unwrap();
    let dir = tmp("flaky");
    let m = Flaky(model());
    let s = build(&m, &design, &dir, &BuildOptions::default()).unwrap();
    let n_fail = design.iter().filter(|x| x[0] > 3000.0).count();
    assert_eq!(s.failed, n_fail);
    assert!(n_fail > 0);
    let filt = Admissibility {
        min_peak_force: Some(1e-9),
        reject_non_repulsive: true,
        contact_index: 0,
    };
    let mm = load(&dir, &filt).unwrap();
    // Expected counts, filters applied in order (peak first), computed
    // here from the model directly.
    let (mut below, mut rep) = (0, 0);
    for x in design.iter().filter(|x| x[0] <= 3000.0) {
        let peak = model().run(x).unwrap().into_iter().fold(f64::MIN, f64::max);
        if peak < 1e-9 {
            below += 1;
        } else if x[3] < 0.03 {
            rep += 1;
        }
    }
    let c = &mm.counts;
    assert_eq!(c.failed, n_fail);
    assert_eq!((c.below_peak, c.non_repulsive), (below, rep));
    assert!(below > 0 && rep > 0, "{c:?}");
    assert_eq!(c.kept + c.failed + c.below_peak + c.non_repulsive, 40);
    let out = dir.join("export");
    export(&mm, &out, Some(&cell_domain())).unwrap();
    // meta.json stores the domain; it reads back equal (and checked).
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("meta.json")).unwrap()).unwrap();
    let back: Domain = serde_json::from_value(meta["domain"].clone()).unwrap();
    assert_eq!(back, cell_domain());
    // A domain of other parameters, or one the runs lie outside, is refused.
    let other = Domain::new(vec![Parameter::new("E", "Pa", 1.0, 2.0, Scale::Linear)]).unwrap();
    let e = export(&mm, &out, Some(&other)).unwrap_err().to_string();
    assert!(e.contains("do not match the domain"), "{e}");
    let narrow = Domain::table_5_3(0.01).unwrap();
    let e = export(&mm, &out, Some(&narrow)).unwrap_err().to_string();
    assert!(e.contains("lies outside it"), "{e}");
    let y = std::fs::read(out.join("Y.npy")).unwrap();
    assert_eq!(&y[..6], b"\x93NUMPY");
    let hl = u16::from_le_bytes([y[8], y[9]]) as usize;
    assert_eq!((10 + hl) % 64, 0);
    assert_eq!(y.len() - 10 - hl, c.kept * 40 * 8);
    let status = std::fs::read_to_string(out.join("status.csv")).unwrap();
    assert!(status.contains("Newton stalled"));
    let _ = std::fs::remove_dir_all(&dir);
}
