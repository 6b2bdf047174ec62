//! Errors of figure drawing.

use std::path::PathBuf;

/// Why a figure could not be drawn or written.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FigureError {
    /// `plotters` failed to lay out or draw the figure.
    #[error("drawing the figure failed: {0}")]
    Draw(String),
    /// The SVG file could not be written.
    #[error("{path}: cannot write the figure: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's message.
        message: String,
    },
}

impl FigureError {
    /// What went wrong, without the file name (for callers that put the
    /// file or figure name into their own error).
    pub fn message(&self) -> String {
        match self {
            FigureError::Draw(m) => m.clone(),
            FigureError::Io { message, .. } => message.clone(),
        }
    }
}

/// Result of this crate.
pub type Result<T> = std::result::Result<T, FigureError>;

pub(crate) fn draw_err(e: impl std::fmt::Display) -> FigureError {
    FigureError::Draw(e.to_string())
}
