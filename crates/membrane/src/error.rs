//! Errors of the membrane crate.

/// What can go wrong in a membrane simulation.
#[derive(Debug, thiserror::Error)]
pub enum MembraneError {
    /// A parameter, geometry value or loading program is out of range.
    #[error("invalid input `{name}` = {value}: {reason}")]
    Input {
        /// Name of the offending input as users write it.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What to change.
        reason: String,
    },
    /// A principal tension became non-positive: the membrane wrinkles and the
    /// tension-only membrane theory of §2.3 has no solution.
    #[error(
        "wrinkling at t = {time:.6}: principal tension {which} = {tension:.4e} (G10·h0 units) \
         at ψ = {psi:.4} rad ({deg:.2}°) with {control}; {advice}",
        deg = psi.to_degrees()
    )]
    Wrinkling {
        /// Time at which the step failed.
        time: f64,
        /// Reference angle ψ of the point where the tension is non-positive.
        psi: f64,
        /// `"T1"` (meridional) or `"T2"` (circumferential).
        which: &'static str,
        /// The tension found (dimensionless T/(G10 h0)).
        tension: f64,
        /// The control target of the failed step.
        control: String,
        /// What to change.
        advice: &'static str,
    },
    /// Newton on (λ0, ψc, p) did not converge.
    #[error(
        "no convergence at t = {time:.6} with {control}: {quantity} residual {residual:.3e} \
         after {iterations} Newton iterations; {advice}"
    )]
    NoConvergence {
        /// Time at which the step failed.
        time: f64,
        /// The control target of the failed step.
        control: String,
        /// The residual that did not vanish (the largest one).
        quantity: &'static str,
        /// Its value at the last iterate.
        residual: f64,
        /// Newton iterations done.
        iterations: usize,
        /// What to change.
        advice: String,
    },
    /// The material point update failed.
    #[error("material update failed at ψ = {psi:.4} rad, t = {time:.6}: {source}")]
    Material {
        /// Reference angle of the point.
        psi: f64,
        /// Time of the step.
        time: f64,
        /// The material error.
        source: nlvid_material::MaterialError,
    },
}

/// Result alias of the membrane crate.
pub type Result<T> = std::result::Result<T, MembraneError>;
