//! A surrogate as the CLI stores it, and fitting measured curves on it
//! (thesis §4.4.1 step 5, §5.4.1, eq. 5.3).
//!
//! The files: the model file of `nlvid surrogate fit` (a serialised
//! [`KrigingModel`]) and the `meta.json` sidecar of `nlvid build --export`
//! (`parameter_names` in the surrogate's input order, `time_s` the output
//! grid, `domain` the parameter domain the design was drawn in — the fit's
//! domain, read back rather than rebuilt). [`SurrogateMisfit`] is the eq. 5.3 objective on such surrogates,
//! each through its fast form ([`Precomputed`]: the reduced PCA form of
//! [`crate::ReducedMisfit`] for PCA-reduced surrogates, the Gram form of
//! [`crate::BasisMisfit`] otherwise); `nlvid fit` uses it. [`SurrogateFitter`]
//! holds one surrogate with its precomputation and fits one cell's curves
//! with a seeded [`MultiStart`] (`nlvid cohort`).

use std::path::Path;
use std::sync::Arc;

use nalgebra::DMatrix;
use nlvid_model::Domain;
use nlvid_surrogate::KrigingModel;

use crate::basis::{BasisExperiment, BasisModel, gram};
use crate::error::{InverseError, Result};
use crate::fixed::{Fixed, FixedInputs};
use crate::misfit::{Objective, check_shared_parameters};
use crate::model::Model;
use crate::optimise::{FitResult, MultiStart};
use crate::reduced::{Projection, ReducedExperiment, ReducedModel, projection};
use crate::surrogate::{Coordinates, KrigingSurrogate};

/// The `meta.json` sidecar of `nlvid build --export`: what the surrogate's
/// inputs and outputs are.
#[derive(Debug, Clone, PartialEq)]
pub struct SurrogateMeta {
    /// Parameter names in the surrogate's input order.
    pub parameter_names: Vec<String>,
    /// Time grid of the outputs, s.
    pub time_s: Vec<f64>,
    /// The parameter domain of the design (its names are
    /// `parameter_names`, in order).
    pub domain: Domain,
    /// What the forward model behind the meta-model was built for (protocol, time
    /// span, geometry); `None` for meta-models exported before it was stored.
    pub conditions: Option<nlvid_model::BuildConditions>,
}

fn io(path: &Path, message: impl std::fmt::Display) -> InverseError {
    InverseError::Io {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Reads a `meta.json` sidecar (keys `parameter_names`, `time_s`,
/// `domain`).
///
/// # Errors
/// [`InverseError::Io`] naming the file and the missing or malformed key;
/// a file without `domain` (written before the domain was stored) says how
/// to re-export it.
pub fn read_meta(path: &Path) -> Result<SurrogateMeta> {
    let text = std::fs::read_to_string(path).map_err(|e| io(path, format!("cannot read: {e}")))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| io(path, format!("not JSON: {e}")))?;
    let parameter_names: Vec<String> = serde_json::from_value(v["parameter_names"].clone())
        .map_err(|e| io(path, format!("key `parameter_names` (list of names): {e}")))?;
    let time_s: Vec<f64> = serde_json::from_value(v["time_s"].clone())
        .map_err(|e| io(path, format!("key `time_s` (time grid, s): {e}")))?;
    if time_s.is_empty() || time_s.windows(2).any(|w| !(w[1] > w[0])) {
        return Err(io(
            path,
            "key `time_s`: the time grid must be non-empty and strictly increasing",
        ));
    }
    let domain = match v.get("domain") {
        None | Some(serde_json::Value::Null) => {
            return Err(io(
                path,
                "key `domain` missing: this meta-model was exported before meta.json stored its \
                 parameter domain. Re-export it with `nlvid build <build-study.toml> --store \
                 <store> --export <dir>` (finished runs are reused, nothing is re-run), or \
                 `nlvid build --design X.csv --domain domain.toml ... --export <dir>`",
            ));
        }
        Some(d) => serde_json::from_value::<Domain>(d.clone()).map_err(|e| {
            io(
                path,
                format!("key `domain` (parameters with bounds and scales, constraints): {e}"),
            )
        })?,
    };
    domain
        .check_names(&parameter_names)
        .map_err(|e| io(path, format!("keys `domain` and `parameter_names`: {e}")))?;
    let conditions = match v.get("conditions") {
        None | Some(serde_json::Value::Null) => None,
        Some(c) => Some(serde_json::from_value(c.clone()).map_err(|e| {
            io(
                path,
                format!("key `conditions` (what the meta-model was built for): {e}"),
            )
        })?),
    };
    Ok(SurrogateMeta {
        parameter_names,
        time_s,
        domain,
        conditions,
    })
}

/// Reads a model file of `nlvid surrogate fit` and its `meta.json` and
/// wraps them as a [`KrigingSurrogate`] on the domain `meta.json` stores.
///
/// # Errors
/// Unreadable or malformed files (naming them); sizes that do not match
/// the domain ([`KrigingSurrogate::new`]).
pub fn load_kriging_surrogate(
    model: &Path,
    meta: &Path,
    coordinates: Coordinates,
) -> Result<KrigingSurrogate> {
    let m = read_meta(meta)?;
    let bytes = std::fs::read(model).map_err(|e| io(model, format!("cannot read: {e}")))?;
    let kriging: KrigingModel = serde_json::from_slice(&bytes).map_err(|e| {
        io(
            model,
            format!("not a model file of `nlvid surrogate fit`: {e}"),
        )
    })?;
    KrigingSurrogate::new(kriging, m.domain, m.time_s, coordinates).map_err(|e| {
        io(
            model,
            format!("does not match {} and its domain: {e}", meta.display()),
        )
    })
}

/// What a fit on one Kriging surrogate precomputes once per surrogate and
/// weights, shared by every data set (and thread).
#[derive(Debug, Clone)]
pub enum Precomputed {
    /// PCA-reduced surrogate: √W A = Q R of the reduced form (O(m·r²) once,
    /// O(N·q·n + r²) per evaluation).
    Reduced(Arc<Projection>),
    /// Otherwise the Gram matrix B W Bᵀ of the basis form (O(N²·m) once;
    /// [`crate::BasisMisfit`], which falls back to the direct O(N·m) residual
    /// where its sum cancels).
    Gram(Arc<DMatrix<f64>>),
}

impl Precomputed {
    /// The reduced form when the surrogate is PCA-reduced
    /// ([`KrigingSurrogate::is_reduced`]), else the Gram form.
    ///
    /// # Errors
    /// Weights of the wrong length or negative.
    pub fn new(surrogate: &KrigingSurrogate, weights: Option<&[f64]>) -> Result<Self> {
        if surrogate.is_reduced() {
            Ok(Self::Reduced(projection(surrogate, weights)?))
        } else {
            Ok(Self::Gram(gram(surrogate, weights)?))
        }
    }
}

enum Part<'a> {
    Reduced(ReducedExperiment<&'a KrigingSurrogate>),
    Basis(BasisExperiment<&'a KrigingSurrogate>),
}

/// The summed eq. 5.3 misfit of curves fitted with one parameter set on
/// Kriging surrogates (one per curve, possibly different), each through
/// its fast form ([`Precomputed`]). Reported values (the fit's misfit,
/// per-curve misfits) are computed from the predicted curve directly.
pub struct SurrogateMisfit<'a> {
    parts: Vec<Part<'a>>,
}

/// One curve of a [`SurrogateMisfit`].
pub struct SurrogateCurve<'a> {
    /// Label for reports.
    pub label: &'a str,
    /// The surrogate predicting it.
    pub surrogate: &'a KrigingSurrogate,
    /// [`Precomputed::new`]`(surrogate, weights)`.
    pub precomputed: &'a Precomputed,
    /// The curve on the surrogate's time grid.
    pub data: &'a [f64],
    /// Per-point weights (None = all 1), the ones `precomputed` was made with.
    pub weights: Option<&'a [f64]>,
}

impl<'a> SurrogateMisfit<'a> {
    /// Combines curves (at least one, same parameter names).
    ///
    /// # Errors
    /// Bad data (length, non-finite, zero range) naming the curve;
    /// surrogates with different parameters.
    pub fn new(curves: &[SurrogateCurve<'a>]) -> Result<Self> {
        check_shared_parameters(curves.iter().map(|c| (c.label, Model::domain(c.surrogate))))?;
        let mut parts = Vec::with_capacity(curves.len());
        for c in curves {
            parts.push(match c.precomputed {
                Precomputed::Reduced(p) => Part::Reduced(ReducedExperiment::new(
                    c.label,
                    c.surrogate,
                    p.clone(),
                    c.data,
                )?),
                Precomputed::Gram(g) => Part::Basis(BasisExperiment::new(
                    c.label,
                    c.surrogate,
                    g.clone(),
                    c.data,
                    c.weights,
                )?),
            });
        }
        Ok(Self { parts })
    }
}

impl Objective for SurrogateMisfit<'_> {
    fn domain(&self) -> &Domain {
        match &self.parts[0] {
            Part::Reduced(e) => ReducedModel::domain(&e.model),
            Part::Basis(e) => BasisModel::domain(&e.model),
        }
    }

    fn value(&self, x: &[f64]) -> Result<f64> {
        let mut total = 0.0;
        for p in &self.parts {
            total += match p {
                Part::Reduced(e) => e.eval(x, false)?.0,
                Part::Basis(e) => e.eval(x, false)?.0,
            };
        }
        Ok(total)
    }

    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        let mut total = 0.0;
        let mut grad = vec![0.0; x.len()];
        for p in &self.parts {
            let (v, g) = match p {
                Part::Reduced(e) => e.eval(x, true)?,
                Part::Basis(e) => e.eval(x, true)?,
            };
            total += v;
            for (a, b) in grad.iter_mut().zip(g) {
                *a += b;
            }
        }
        Ok((total, grad))
    }

    fn per_experiment(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.parts
            .iter()
            .map(|p| match p {
                Part::Reduced(e) => e.direct(x),
                Part::Basis(e) => e.eval(x, false).map(|(v, _)| v),
            })
            .collect()
    }

    fn final_value(&self, x: &[f64]) -> Result<f64> {
        Ok(self.per_experiment(x)?.iter().sum())
    }
}

/// A surrogate ready to fit many cells: the fast form's precomputation
/// ([`Precomputed`]) is done once and shared by every fit (and thread).
#[derive(Debug, Clone)]
pub struct SurrogateFitter {
    surrogate: KrigingSurrogate,
    weights: Option<Vec<f64>>,
    precomputed: Precomputed,
}

/// One fit on the surrogate.
#[derive(Debug, Clone)]
pub struct SurrogateFit {
    /// The multistart result (best point, alternatives, bound hits).
    pub fit: FitResult,
    /// Eq. 5.3 misfit of each curve at the best point.
    pub per_curve: Vec<f64>,
    /// The surrogate's response at the best point, on [`SurrogateFitter::times`].
    pub response: Vec<f64>,
}

impl SurrogateFitter {
    /// Prepares `surrogate` for fitting with optional per-time-point
    /// weights (eq. 5.3; None = all 1): O(m·r²) once for a PCA-reduced
    /// surrogate, O(N²·m) otherwise.
    ///
    /// # Errors
    /// Weights of the wrong length.
    pub fn new(surrogate: KrigingSurrogate, weights: Option<Vec<f64>>) -> Result<Self> {
        let precomputed = Precomputed::new(&surrogate, weights.as_deref())?;
        Ok(Self {
            surrogate,
            weights,
            precomputed,
        })
    }

    /// The surrogate.
    pub fn surrogate(&self) -> &KrigingSurrogate {
        &self.surrogate
    }

    /// The surrogate's time grid (s): measured curves must be resampled
    /// onto it.
    pub fn times(&self) -> &[f64] {
        BasisModel::times(&self.surrogate)
    }

    /// Fits one parameter set to `curves` (label, force on [`Self::times`]):
    /// the sum of their eq. 5.3 misfits, minimised by `multistart`.
    ///
    /// # Errors
    /// Bad data (length, non-finite, zero range) naming the curve; no start
    /// converged.
    pub fn fit(&self, curves: &[(&str, &[f64])], multistart: &MultiStart) -> Result<SurrogateFit> {
        let none = FixedInputs::none(Model::domain(&self.surrogate));
        self.fit_fixed(curves, multistart, &none)
    }

    /// As [`SurrogateFitter::fit`] with the inputs of `fixed` held at their
    /// values (e.g. the cell's height and diameter): the fit, its
    /// [`FitResult::domain`] and best point are the free parameters'.
    ///
    /// # Errors
    /// As [`SurrogateFitter::fit`]; `fixed` made for another domain.
    pub fn fit_fixed(
        &self,
        curves: &[(&str, &[f64])],
        multistart: &MultiStart,
        fixed: &FixedInputs,
    ) -> Result<SurrogateFit> {
        let parts: Vec<SurrogateCurve<'_>> = curves
            .iter()
            .map(|(label, force)| SurrogateCurve {
                label,
                surrogate: &self.surrogate,
                precomputed: &self.precomputed,
                data: force,
                weights: self.weights.as_deref(),
            })
            .collect();
        let misfit = Fixed::objective(SurrogateMisfit::new(&parts)?, fixed.clone())?;
        let fit = multistart.fit(&misfit)?;
        let per_curve = misfit.per_experiment(&fit.best.x)?;
        let response = self.surrogate.response(&fixed.expand(&fit.best.x))?;
        Ok(SurrogateFit {
            fit,
            per_curve,
            response,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("nlvid-sfile-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// The Table 5.3 domain as `nlvid build --export` stores it.
    fn domain_json() -> String {
        serde_json::to_string(&Domain::table_5_3(0.01).unwrap()).unwrap()
    }

    #[test]
    fn meta_errors_name_the_file_and_the_key() {
        let d = tmp("meta");
        let p = d.join("meta.json");
        std::fs::write(&p, r#"{"parameter_names": ["G0"]}"#).unwrap();
        let e = read_meta(&p).unwrap_err().to_string();
        assert!(e.contains("meta.json") && e.contains("time_s"), "{e}");
        std::fs::write(&p, r#"{"parameter_names": ["G0"], "time_s": [1.0, 0.5]}"#).unwrap();
        let e = read_meta(&p).unwrap_err().to_string();
        assert!(e.contains("strictly increasing"), "{e}");
        let names = r#""parameter_names": ["G0","g1","g2","tau1","tau2"]"#;
        std::fs::write(&p, format!(r#"{{{names}, "time_s": [0.5, 1.0]}}"#)).unwrap();
        let e = read_meta(&p).unwrap_err().to_string();
        assert!(
            e.contains("meta.json") && e.contains("`domain` missing") && e.contains("--export"),
            "{e}"
        );
        let swapped = r#""parameter_names": ["G0","g1","tau1","g2","tau2"]"#;
        let text = format!(
            r#"{{{swapped}, "time_s": [0.5, 1.0], "domain": {}}}"#,
            domain_json()
        );
        std::fs::write(&p, text).unwrap();
        let e = read_meta(&p).unwrap_err().to_string();
        assert!(e.contains("do not match the domain"), "{e}");
        let broken = domain_json().replace("4000.0", "-1.0");
        let text = format!(r#"{{{names}, "time_s": [0.5, 1.0], "domain": {broken}}}"#);
        std::fs::write(&p, text).unwrap();
        let e = read_meta(&p).unwrap_err().to_string();
        assert!(e.contains("key `domain`") && e.contains("G0"), "{e}");
        let text = format!(
            r#"{{{names}, "time_s": [0.5, 1.0], "domain": {}}}"#,
            domain_json()
        );
        std::fs::write(&p, text).unwrap();
        let m = read_meta(&p).unwrap();
        assert_eq!(m.parameter_names, nlvid_model::names::PRONY2);
        assert_eq!(m.time_s, vec![0.5, 1.0]);
        assert_eq!(m.domain, Domain::table_5_3(0.01).unwrap());
    }

    #[test]
    fn a_model_file_that_is_not_a_kriging_model_is_named() {
        let d = tmp("model");
        let meta = d.join("meta.json");
        std::fs::write(
            &meta,
            format!(
                r#"{{"parameter_names": ["G0","g1","g2","tau1","tau2"], "time_s": [1.0], "domain": {}}}"#,
                domain_json()
            ),
        )
        .unwrap();
        let model = d.join("model.json");
        std::fs::write(&model, "{}").unwrap();
        let e = load_kriging_surrogate(&model, &meta, Coordinates::Physical)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("model.json") && e.contains("nlvid surrogate fit"),
            "{e}"
        );
    }
}
