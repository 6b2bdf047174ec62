//! Quadrature-point history (deal.II's `PointHistory`): the converged
//! state at t_n of every Gauss point and the trial state of the step being
//! solved. Committing swaps the two (no copy, no allocation).

use nlvid_material::Material3;

/// Converged and trial material states of all Gauss points.
#[derive(Debug, Clone)]
pub struct History<S> {
    committed: Vec<S>,
    trial: Vec<S>,
    per_element: usize,
}

impl<S: Clone> History<S> {
    /// Undeformed points of `material`: `per_element` for each of
    /// `elements` elements.
    pub fn new<M: Material3<State = S>>(material: &M, elements: usize, per_element: usize) -> Self {
        let s = material.initial_state();
        let points = elements * per_element;
        Self {
            committed: vec![s.clone(); points],
            trial: vec![s; points],
            per_element,
        }
    }

    /// Converged and trial states of element `e`.
    pub fn element(&mut self, e: usize) -> (&[S], &mut [S]) {
        let (a, b) = (self.per_element * e, self.per_element * (e + 1));
        (&self.committed[a..b], &mut self.trial[a..b])
    }

    /// All converged and all trial states (element by element, in order).
    pub(crate) fn split(&mut self) -> (&[S], &mut [S]) {
        (&self.committed, &mut self.trial)
    }

    /// Accepts the trial states of a converged step: they become the
    /// converged states, and the trial vector holds the previous converged
    /// states until the next assembly overwrites them. A swap instead of a
    /// copy, which relies on the contract of [`Material3::update`] (and of
    /// the other point updates): an update writes the trial history and
    /// never relies on what the trial state held before (after a rejected
    /// step it holds the rejected values anyway). The models of
    /// `nlvid-material` obey it: their updates rewrite every field they
    /// later read, and the Prony model's step cache in the trial state is
    /// keyed by the committed state's identity, so a stale cache misses.
    pub fn commit(&mut self) {
        std::mem::swap(&mut self.committed, &mut self.trial);
    }

    /// Converged state of point `p`.
    pub fn committed(&self, p: usize) -> &S {
        &self.committed[p]
    }
}
