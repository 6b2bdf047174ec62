//! The problem shared by the surrogate examples (and the cell-domain
//! accuracy test): the analytic Hertz–Prony ramp-hold model (5 µm probe,
//! 1 µm/s for 1 s, hold to 10 s, 200 outputs) on the 5-parameter cell
//! domain, N training sites and 200 checking sites (seed 42).
#![allow(dead_code)] // each example uses a part

use nlvid_forward::HertzProny;
use nlvid_model::{Domain, ForwardModel};
use nlvid_surrogate::doe::training_and_checking;

/// Domain, training and checking sites (physical units) and the model's
/// responses at them.
pub type CellProblem = (
    Domain,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
    Vec<Vec<f64>>,
);

/// Number of outputs (time points) of the model.
pub const OUTPUTS: usize = 200;

/// Number of checking sites.
pub const N_CHECK: usize = 200;

/// The forward model of the problem.
pub fn cell_model() -> HertzProny {
    HertzProny::new(5e-6, 1e-6, 1.0, 10.0, OUTPUTS).expect("valid settings")
}

/// The problem with `n` training sites, the model run at every site:
/// `(domain, train, check, y_train, y_check)`.
pub fn cell_problem(n: usize) -> Result<CellProblem, Box<dyn std::error::Error>> {
    let domain = Domain::cell_study();
    let model = cell_model();
    let (train, check) = training_and_checking(&domain, n, N_CHECK, 42, 30, 1e-6)?;
    let run =
        |xs: &[Vec<f64>]| -> Result<Vec<Vec<f64>>, _> { xs.iter().map(|x| model.run(x)).collect() };
    let yt = run(&train)?;
    let yc = run(&check)?;
    Ok((domain, train, check, yt, yc))
}

/// Kriging inputs of a site: natural log on the domain's log axes (as the
/// design is drawn).
pub fn kriging_inputs(domain: &Domain, x: &[f64]) -> Vec<f64> {
    x.iter()
        .zip(domain.params())
        .map(|(v, p)| if p.is_log() { v.ln() } else { *v })
        .collect()
}
