//! Quadrature-point history (deal.II's `PointHistory`): the converged
//! state at t_n of every Gauss point and the trial state of the step being
//! solved. Committing copies trial over converged without allocating.

use nlvid_material::Material3;

/// Converged and trial material states of all Gauss points.
#[derive(Debug, Clone)]
pub struct History<S> {
    committed: Vec<S>,
    trial: Vec<S>,
}

impl<S: Clone> History<S> {
    /// `points` undeformed points of `material`.
    pub fn new<M: Material3<State = S>>(material: &M, points: usize) -> Self {
        let s = material.initial_state();
        Self {
            committed: vec![s.clone(); points],
            trial: vec![s; points],
        }
    }

    /// Converged and trial states of element `e` (four points).
    pub fn element(&mut self, e: usize) -> (&[S], &mut [S]) {
        (
            &self.committed[4 * e..4 * e + 4],
            &mut self.trial[4 * e..4 * e + 4],
        )
    }

    /// All converged and all trial states (four per element, in order).
    pub(crate) fn split(&mut self) -> (&[S], &mut [S]) {
        (&self.committed, &mut self.trial)
    }

    /// Accepts the trial states of a converged step.
    pub fn commit(&mut self) {
        self.committed.clone_from_slice(&self.trial);
    }

    /// Converged state of point `p`.
    pub fn committed(&self, p: usize) -> &S {
        &self.committed[p]
    }
}
