//! The crate's error type.

/// What can go wrong while turning a study into a forward model.
#[derive(Debug, thiserror::Error)]
pub enum ForwardError {
    /// A bad or missing key in the study file (names file, line and key).
    #[error(transparent)]
    Study(#[from] nlvid_study::StudyError),
    /// A setting that is valid on its own but unusable for the model
    /// (e.g. a loading program the membrane solver cannot follow).
    #[error("forward model `{model}`: {message}")]
    Setting {
        /// Model name (`hertz-prony`, `afm-fe`, `membrane`).
        model: &'static str,
        /// What is wrong and what to change.
        message: String,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, ForwardError>;
