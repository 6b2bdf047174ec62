//! Helpers shared by the build tests (`build_resume`, `infill`): a forward
//! model that stops the build part way, as a kill would, and the run
//! records of a store in a comparable form.
#![allow(clippy::unwrap_used)]

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use nlvid_forward::HertzProny;
use nlvid_model::{ForwardModel, RunFailure};
use nlvid_surrogate::RunStore;

/// Wraps a Hertz–Prony model and cancels the build (sets `cancel`, as a
/// kill would stop it) once `after` runs have started.
pub struct Interrupting<'a> {
    pub inner: HertzProny,
    pub started: AtomicUsize,
    pub after: usize,
    pub cancel: &'a AtomicBool,
}

impl ForwardModel for Interrupting<'_> {
    fn parameter_names(&self) -> Vec<String> {
        self.inner.parameter_names()
    }
    fn parameter_units(&self) -> Vec<String> {
        self.inner.parameter_units()
    }
    fn time_grid(&self) -> &[f64] {
        self.inner.time_grid()
    }
    fn identity(&self) -> String {
        self.inner.identity()
    }
    fn contact_index(&self) -> usize {
        self.inner.contact_index()
    }
    fn run(&self, p: &[f64]) -> Result<Vec<f64>, RunFailure> {
        if self.started.fetch_add(1, Ordering::SeqCst) + 1 >= self.after {
            self.cancel.store(true, Ordering::SeqCst);
        }
        self.inner.run(p)
    }
}

/// Every run record of the store in `dir`: (index, parameters, outcome as
/// JSON text), so two stores can be compared with `assert_eq!`.
pub fn records(dir: &Path) -> Vec<(usize, Vec<f64>, String)> {
    RunStore::existing(dir)
        .unwrap()
        .all()
        .unwrap()
        .into_iter()
        .map(|r| {
            let out = serde_json::to_string(&r.outcome).unwrap();
            (r.index, r.params, out)
        })
        .collect()
}
