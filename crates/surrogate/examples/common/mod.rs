//! The problem shared by the surrogate examples (and the cell-domain
//! accuracy test): the analytic Hertz–Prony ramp-hold model (5 µm probe,
//! 1 µm/s for 1 s, hold to 10 s, 200 outputs) on the 5-parameter cell
//! domain, N training sites and 200 checking sites (seed 42).
#![allow(dead_code)] // each example uses a part

use nlvid_surrogate::doe::{Domain, training_and_checking};
use nlvid_surrogate::{ForwardModel, HertzProny};

/// Design, model and responses of the rmse_vs_n problem.
pub struct CellProblem {
    /// The 5-parameter cell domain.
    pub domain: Domain,
    /// The forward model.
    pub model: HertzProny,
    /// Training sites (physical units).
    pub train: Vec<Vec<f64>>,
    /// Checking sites (physical units).
    pub check: Vec<Vec<f64>>,
    /// Model responses at the training sites.
    pub y_train: Vec<Vec<f64>>,
    /// Model responses at the checking sites.
    pub y_check: Vec<Vec<f64>>,
}

/// Number of outputs (time points) of the model.
pub const OUTPUTS: usize = 200;

/// Number of checking sites.
pub const N_CHECK: usize = 200;

/// The forward model of the problem.
pub fn cell_model() -> HertzProny {
    HertzProny::new(5e-6, 1e-6, 1.0, 10.0, OUTPUTS)
}

/// The problem with `n` training sites, the model run at every site.
pub fn cell_problem(n: usize) -> Result<CellProblem, Box<dyn std::error::Error>> {
    let domain = Domain::cell_study();
    let model = cell_model();
    let (train, check) = training_and_checking(&domain, n, N_CHECK, 42, 30, 1e-6)?;
    let run =
        |xs: &[Vec<f64>]| -> Result<Vec<Vec<f64>>, _> { xs.iter().map(|x| model.run(x)).collect() };
    let y_train = run(&train)?;
    let y_check = run(&check)?;
    Ok(CellProblem {
        domain,
        model,
        train,
        check,
        y_train,
        y_check,
    })
}

/// Kriging inputs of a site: natural log on the domain's log axes (as the
/// design is drawn).
pub fn kriging_inputs(domain: &Domain, x: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(&domain.axes)
        .map(|(v, a)| if a.log { v.ln() } else { *v })
        .collect()
}
