//! Errors of the vocabulary types.

/// Result with [`ModelError`].
pub type Result<T> = std::result::Result<T, ModelError>;

/// A value that does not fit the vocabulary's rules, with what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A Prony term is out of its domain (`series` names the series,
    /// `index` is 1-based).
    #[error("Prony series `{series}`, term {index}: {reason}")]
    PronyTerm {
        /// Which series (e.g. "G", "G10").
        series: String,
        /// 1-based term index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A named parameter value is out of its domain.
    #[error("parameter `{name}` = {value}: {reason}")]
    Parameter {
        /// Parameter name.
        name: String,
        /// Offending value (SI).
        value: f64,
        /// What is wrong.
        reason: String,
    },
    /// A parameter domain is malformed.
    #[error("parameter domain: {0}")]
    Domain(String),
    /// A parameter vector has the wrong length.
    #[error("expected {expected} parameters ({names}), got {got}")]
    ParameterCount {
        /// Expected count.
        expected: usize,
        /// Names in order.
        names: String,
        /// Actual count.
        got: usize,
    },
    /// A curve is malformed.
    #[error("curve: {0}")]
    Curve(String),
}
