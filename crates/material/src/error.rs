//! Errors of the material crate.

/// What can go wrong in a material model.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// A parameter is outside its admissible domain.
    #[error("material parameter `{name}` = {value} is out of range: {reason}")]
    Parameter {
        /// Parameter name as users write it.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// What the admissible range is.
        reason: &'static str,
    },
    /// A relaxation modulus or Prony series is inadmissible (the shared
    /// vocabulary's check, naming the series and term).
    #[error(transparent)]
    Model(#[from] nlvid_model::ModelError),
    /// The deformation cannot be evaluated (e.g. det F ≤ 0, a stretch ≤ 0).
    #[error("inadmissible deformation: {0}")]
    Deformation(String),
    /// A time increment is negative or not finite.
    #[error("time increment dt = {0} is inadmissible: it must be finite and ≥ 0")]
    TimeStep(f64),
    /// A loading history for a homogeneous driver is inadmissible.
    #[error("loading history: {0}")]
    Loading(String),
}

/// Result alias of the material crate.
pub type Result<T> = std::result::Result<T, MaterialError>;
