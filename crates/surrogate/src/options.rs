//! The options of `nlvid surrogate fit` (docs/cli/surrogate.md) turned into
//! [`KrigingSettings`] for a table of inputs: columns are named, θ bounds
//! default to [`ThetaSearch::default_for`].

use crate::error::{Result, SurrogateError};
use crate::kriging::{KrigingSettings, OutputScale, ThetaSearch};
use crate::optimise::OptimiserSettings;
use crate::table::Table;
use crate::{Correlation, Regression};

/// What a user chooses for a Kriging fit.
#[derive(Debug, Clone)]
pub struct FitOptions {
    /// Regression polynomial.
    pub regression: Regression,
    /// Correlation family.
    pub correlation: Correlation,
    /// Fixed θ (no search).
    pub theta: Option<Vec<f64>>,
    /// Start of the θ search (default of the correlation when `None`).
    pub theta0: Option<Vec<f64>>,
    /// Lower θ bounds.
    pub lower: Option<Vec<f64>>,
    /// Upper θ bounds.
    pub upper: Option<Vec<f64>>,
    /// DACE's boxmin instead of the multistart optimiser.
    pub boxmin: bool,
    /// Settings of the multistart optimiser.
    pub optimiser: OptimiserSettings,
    /// Keep this variance fraction of the outputs' principal components.
    pub pca: Option<f64>,
    /// Nugget on the diagonal of R.
    pub nugget: f64,
    /// Krige ln y.
    pub log_outputs: bool,
    /// Every output ∝ this input column; with a slope, ∝ exp(slope · x).
    pub proportional_to: Option<(String, Option<f64>)>,
    /// Input columns kriged in ln x.
    pub log_inputs: Vec<String>,
}

impl FitOptions {
    /// The settings for inputs with the columns of `x`.
    ///
    /// # Errors
    /// A column name that `x` does not have (listing its columns).
    pub fn settings(self, x: &Table) -> Result<KrigingSettings> {
        let d = x.header.len();
        let column = |flag: &str, col: &str| {
            x.column(col).ok_or_else(|| {
                SurrogateError::InvalidInput(format!(
                    "--{flag} {col}: no such column (columns: {:?})",
                    x.header
                ))
            })
        };
        let mut s = KrigingSettings::new(self.regression, self.correlation, d);
        s.nugget = self.nugget;
        s.pca_energy = self.pca;
        s.log_outputs = self.log_outputs;
        if !self.log_inputs.is_empty() {
            s.log_inputs = vec![false; d];
            for col in &self.log_inputs {
                s.log_inputs[column("log-inputs", col)?] = true;
            }
        }
        if let Some((col, slope)) = &self.proportional_to {
            let input = column("proportional-to", col)?;
            s.output_scale = Some(match slope {
                Some(slope) => OutputScale::Exp {
                    input,
                    slope: *slope,
                },
                None => OutputScale::Linear { input },
            });
        }
        if let Some(t) = self.theta {
            s.theta = ThetaSearch::Fixed(t);
        } else if let ThetaSearch::Optimise {
            theta0,
            lower,
            upper,
            ..
        } = ThetaSearch::default_for(self.correlation, d)
        {
            let (theta0, lower, upper) = (
                self.theta0.unwrap_or(theta0),
                self.lower.unwrap_or(lower),
                self.upper.unwrap_or(upper),
            );
            s.theta = if self.boxmin {
                ThetaSearch::Boxmin {
                    theta0,
                    lower,
                    upper,
                }
            } else {
                ThetaSearch::Optimise {
                    theta0,
                    lower,
                    upper,
                    settings: self.optimiser,
                }
            };
        }
        Ok(s)
    }
}
