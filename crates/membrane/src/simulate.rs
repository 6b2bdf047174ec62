//! The forward model as one call: parameters, geometry and a loading program
//! in, F(t) (and ψc, p, H1, profiles) on a time grid out.

use nlvid_material::MembraneMaterial;
use nlvid_protocol::Program;
use serde::Serialize;

use crate::{
    Control, Geometry, MembraneError, MembraneSolver, PipkinRogersParams, Result, Solution,
    StepRecord,
};

/// Which quantity the loading program prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ControlKind {
    /// Plate displacement D/r0 (eq. 2.43).
    Displacement,
    /// Contact force F/(G10 h0 r0) (eq. 2.44).
    Force,
}

/// A loading: the prescribed quantity, its program (dimensionless values,
/// eq. 2.47) and the solve times (t0 = t/τ1 when τ1 = 1).
#[derive(Debug, Clone)]
pub struct Loading {
    /// Displacement or force control.
    pub control: ControlKind,
    /// D/r0 or F/(G10 h0 r0) as a function of time.
    pub program: Program,
    /// Strictly increasing solve times; the first is the instantaneous response.
    pub times: Vec<f64>,
    /// Times at which full profiles are kept (nearest solve time is used).
    pub profile_times: Vec<f64>,
}

impl Loading {
    /// A loading solved on `times`; every breakpoint of the program inside
    /// the grid is added so kinks are stepped onto exactly.
    ///
    /// # Errors
    /// [`MembraneError::Input`] when `times` is empty, not increasing or not finite.
    pub fn new(control: ControlKind, program: Program, times: Vec<f64>) -> Result<Self> {
        let mut t = times;
        if t.is_empty() {
            return Err(MembraneError::Input {
                name: "times",
                value: 0.0,
                reason: "at least one solve time is needed".into(),
            });
        }
        let (t0, t1) = (t[0], t[t.len() - 1]);
        for &b in program.breakpoints() {
            if b > t0 && b < t1 {
                t.push(b);
            }
        }
        t.sort_by(f64::total_cmp);
        t.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (1.0 + b.abs()));
        for (i, w) in t.windows(2).enumerate() {
            if !(w[1] > w[0]) || !w[1].is_finite() {
                return Err(MembraneError::Input {
                    name: "times",
                    value: w[1],
                    reason: format!(
                        "solve times must be finite and increasing (index {})",
                        i + 1
                    ),
                });
            }
        }
        Ok(Self {
            control,
            program,
            times: t,
            profile_times: Vec::new(),
        })
    }

    /// Keep profiles at these times.
    pub fn with_profiles(mut self, times: &[f64]) -> Self {
        self.profile_times = times.to_vec();
        self
    }

    fn control_at(&self, t: f64) -> Control {
        let v = self.program.value(t);
        match self.control {
            ControlKind::Displacement => Control::Displacement(v),
            ControlKind::Force => Control::Force(v),
        }
    }
}

/// The result of a forward run.
#[derive(Debug, Clone, Serialize)]
pub struct MembraneRun {
    /// One record per solve time.
    pub history: Vec<StepRecord>,
    /// Full solutions (profiles) at the requested times, in time order.
    pub profiles: Vec<Solution>,
}

impl MembraneRun {
    /// Times of the history.
    pub fn times(&self) -> Vec<f64> {
        self.history.iter().map(|r| r.time).collect()
    }
    /// F(t)/(G10 h0 r0) on the time grid.
    pub fn force(&self) -> Vec<f64> {
        self.history.iter().map(|r| r.force).collect()
    }
}

/// Forward model with the ch. II Pipkin–Rogers membrane: `params` (eqs.
/// 2.53–2.56), `geometry` (r_s, nodes), `loading` → F(t) etc. Uses the
/// params' G10 as the stress scale, so results are dimensionless (eq. 2.47).
///
/// # Errors
/// [`MembraneError::Input`] for bad parameters; the solver's errors
/// (wrinkling, non-convergence) with the time at which they happened.
pub fn simulate(
    params: &PipkinRogersParams,
    geometry: &Geometry,
    loading: &Loading,
) -> Result<MembraneRun> {
    let m = params.check()?;
    simulate_with(m, params.g10, geometry, loading)
}

/// [`simulate`] for any membrane material; `stress_scale` is G10 of eq. 2.47.
///
/// # Errors
/// As [`simulate`].
pub fn simulate_with<M: MembraneMaterial>(
    material: M,
    stress_scale: f64,
    geometry: &Geometry,
    loading: &Loading,
) -> Result<MembraneRun> {
    let mut solver = MembraneSolver::new(material, *geometry, stress_scale)?;
    run_loading(&mut solver, loading)
}

/// Runs `loading` on a prepared solver (e.g. with
/// [`MembraneSolver::allow_compression_in_contact`] or [`MembraneSolver::newton`]
/// changed); the solver must not have been advanced yet.
///
/// # Errors
/// As [`simulate`]; [`MembraneError::Input`] when the solver was already advanced.
pub fn run_loading<M: MembraneMaterial>(
    solver: &mut MembraneSolver<M>,
    loading: &Loading,
) -> Result<MembraneRun> {
    if let Some(t) = solver.time() {
        return Err(MembraneError::Input {
            name: "solver",
            value: t,
            reason: "run_loading needs a fresh solver (it was already advanced to this time)"
                .into(),
        });
    }
    let mut history = Vec::with_capacity(loading.times.len());
    let mut profiles = Vec::new();
    // Index of the solve time nearest to each requested profile time.
    let mut want: Vec<usize> = loading
        .profile_times
        .iter()
        .map(|&tp| {
            let mut best = 0;
            for (i, &t) in loading.times.iter().enumerate() {
                if (t - tp).abs() < (loading.times[best] - tp).abs() {
                    best = i;
                }
            }
            best
        })
        .collect();
    want.sort_unstable();
    want.dedup();
    for (i, &t) in loading.times.iter().enumerate() {
        let sol = solver.advance(t, loading.control_at(t))?;
        history.push(sol.record);
        if want.binary_search(&i).is_ok() {
            profiles.push(sol);
        }
    }
    Ok(MembraneRun { history, profiles })
}
