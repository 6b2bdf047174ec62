//! Loading what a fit needs: each experiment's surrogate (model file, time
//! grid from `meta.json`, measured checking error) and its data file
//! (CSV or `.jpk-force`), checked against the protocol and resampled onto
//! the surrogate's grid. Every error names the file (and row/column where
//! there is one) before any fitting starts.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use nlvid_inverse::Model as _;
use nlvid_inverse::{
    Calibration, Coordinates, KrigingSurrogate, MeasuredCurve, load_kriging_surrogate,
    ramp_hold_indentation, read_afm_csv, read_compression_csv, segment_weights,
};

use super::config::{DataColumns, ExperimentSettings, FitSettings, RealModelSpec};

/// A surrogate ready to fit with, and how good it is.
pub struct Surrogate {
    /// The model file.
    pub path: PathBuf,
    /// The surrogate as a fit model.
    pub model: KrigingSurrogate,
    /// Max eq. 4.4 checking error and the file it came from.
    pub checking: Option<(f64, PathBuf)>,
}

/// One measured curve with everything it is fitted and checked with.
pub struct LoadedExperiment {
    /// Label in reports.
    pub label: String,
    /// Its surrogate.
    pub surrogate: Surrogate,
    /// The curve as read (SI).
    pub curve: MeasuredCurve,
    /// Measured force on the surrogate's time grid.
    pub force: Vec<f64>,
    /// Eq. 5.3 weights on the grid (None: all 1).
    pub weights: Option<Vec<f64>>,
    /// Real model for the re-check.
    pub real: Option<RealModel>,
}

/// A real model ready to re-run.
pub enum RealModel {
    /// Lee–Radok Hertz with this curve's indentation (built at the re-check).
    LeeRadok {
        /// Probe radius (m).
        radius: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
    /// A study's forward model.
    Forward(Box<dyn nlvid_model::ForwardModel>),
}

/// Sets up the real model named by `spec` (a `[forward]` section is read
/// and checked now, before any fitting).
fn real_model(spec: &RealModelSpec) -> anyhow::Result<RealModel> {
    Ok(match spec {
        RealModelSpec::LeeRadok { radius, poisson } => RealModel::LeeRadok {
            radius: *radius,
            poisson: *poisson,
        },
        RealModelSpec::Forward { study } => {
            let mut st = nlvid_study::Study::load(study)?;
            let model = nlvid_forward::from_study(&mut st)
                .with_context(|| format!("{}: real model from [forward]", study.display()))?;
            RealModel::Forward(model)
        }
    })
}

/// Reads every surrogate and data file named by `settings` and `files`.
///
/// # Errors
/// Unreadable files, malformed data (file, row, column), protocol
/// mismatches, or a number of files that does not match the experiments.
pub fn load(settings: &FitSettings, files: &[PathBuf]) -> anyhow::Result<Vec<LoadedExperiment>> {
    let pairs: Vec<(&ExperimentSettings, &PathBuf)> = if settings.repeat {
        files
            .iter()
            .map(|f| (&settings.experiments[0], f))
            .collect()
    } else {
        if files.len() != settings.experiments.len() {
            bail!(
                "{}: {} [[fit.experiment]] tables but {} data files were given: \
                 give one data file per experiment, in the same order",
                settings.study.display(),
                settings.experiments.len(),
                files.len()
            );
        }
        settings.experiments.iter().zip(files).collect()
    };
    let mut out: Vec<LoadedExperiment> = Vec::with_capacity(pairs.len());
    for (exp, file) in pairs {
        let surrogate = load_surrogate(exp, settings.inputs)?;
        if let Some(first) = out.first() {
            same_domain(&first.surrogate, &surrogate)?;
        }
        let times = surrogate.model.times().to_vec();
        let curve = read_curve(file, &settings.columns)?;
        check_protocol(&curve, exp, &times, &settings.study)?;
        let force = curve.resample(&curve.force, &times)?;
        let weights =
            (!exp.segments.is_empty()).then(|| segment_weights(&times, &exp.segments, 1.0));
        let label = exp.label.clone().unwrap_or_else(|| {
            file.file_stem().map_or_else(
                || file.display().to_string(),
                |s| s.to_string_lossy().into(),
            )
        });
        out.push(LoadedExperiment {
            label,
            surrogate,
            curve,
            force,
            weights,
            real: exp.real.as_ref().map(real_model).transpose()?,
        });
    }
    Ok(out)
}

/// Curves fitted with one parameter set are fitted in one domain: every
/// meta-model must carry the same one.
fn same_domain(first: &Surrogate, other: &Surrogate) -> anyhow::Result<()> {
    let (a, b) = (first.model.domain(), other.model.domain());
    if a != b {
        bail!(
            "{} and {} were built on different parameter domains ({:?} vs {:?}): \
             curves fitted together need meta-models of one [design] domain",
            first.path.display(),
            other.path.display(),
            a,
            b
        );
    }
    Ok(())
}

fn load_surrogate(exp: &ExperimentSettings, inputs: Coordinates) -> anyhow::Result<Surrogate> {
    let model = load_kriging_surrogate(&exp.surrogate, &exp.meta, inputs)
        .with_context(|| format!("surrogate {}", exp.surrogate.display()))?;
    let checking = match &exp.checking {
        Some(p) => Some((read_checking_error(p)?, p.clone())),
        None => {
            let p = default_checking_path(&exp.surrogate);
            if p.is_file() {
                Some((read_checking_error(&p)?, p))
            } else {
                None
            }
        }
    };
    Ok(Surrogate {
        path: exp.surrogate.clone(),
        model,
        checking,
    })
}

/// `model.json` → `model.check.json`: where `nlvid surrogate check
/// model.json ...` saves its summary and `nlvid fit` looks for it.
pub fn default_checking_path(model: &Path) -> PathBuf {
    crate::cmd::surrogate::checking_summary_path(model)
}

/// The max eq. 4.4 RMSE of a `nlvid --json surrogate check` output.
fn read_checking_error(path: &Path) -> anyhow::Result<f64> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the checking summary {}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: not JSON (expected the summary `nlvid surrogate check` saves)",
            path.display()
        )
    })?;
    match v.get("max").and_then(serde_json::Value::as_f64) {
        Some(e) if e.is_finite() && e >= 0.0 => Ok(e),
        _ => bail!(
            "{}: key `max` (largest eq. 4.4 checking error, a number >= 0) missing; \
             expected the summary `nlvid surrogate check` saves",
            path.display()
        ),
    }
}

fn read_curve(path: &Path, columns: &DataColumns) -> anyhow::Result<MeasuredCurve> {
    let is_jpk = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("jpk-force"));
    Ok(match columns {
        DataColumns::Afm(_, cal) if is_jpk => read_jpk_ramp_hold(path, Some(cal))?,
        DataColumns::Compression(_) if is_jpk => read_jpk_ramp_hold(path, None)?,
        DataColumns::Afm(c, cal) => read_afm_csv(path, c, cal)?,
        DataColumns::Compression(c) => read_compression_csv(path, c)?,
    })
}

/// Ramp from 0 at `rate` to `amplitude`, then hold to the grid's end.
fn check_protocol(
    curve: &MeasuredCurve,
    exp: &ExperimentSettings,
    times: &[f64],
    study: &Path,
) -> anyhow::Result<()> {
    let p = &exp.protocol;
    let t_end = times.last().copied().unwrap_or(0.0);
    let t_ramp = p.amplitude / p.rate;
    if t_ramp >= t_end {
        bail!(
            "{}: [fit.protocol] ramp to {:e} m at {:e} m/s takes {t_ramp} s, \
             longer than the surrogate's time grid ({t_end} s, {})",
            study.display(),
            p.amplitude,
            p.rate,
            exp.meta.display()
        );
    }
    let expected_t = [0.0, t_ramp, t_end];
    let expected = ramp_hold_indentation(&expected_t, p.rate, p.amplitude);
    curve.check_protocol(&expected_t, &expected, p.tolerance)?;
    Ok(())
}

/// Read a JPK ramp-hold curve (extend, then constant-height pause) as a
/// measured AFM curve: time from the contact point, F, δ, and the piezo travel
/// Z = δ + F/k since contact (§5.2.2, δ = Z − d with d = F/k). A calibration in
/// the study replaces the file's.
pub fn read_jpk_ramp_hold(path: &Path, cal: Option<&Calibration>) -> anyhow::Result<MeasuredCurve> {
    let options = nlvid_afm::ReadOptions {
        spring_constant: cal.map(|c| c.spring_constant),
        sensitivity: cal.and_then(|c| c.deflection_sensitivity),
    };
    let curve = nlvid_afm::read_force_curve_with(path, &options)
        .with_context(|| format!("{}: cannot read the JPK file", path.display()))?;
    let k = curve.calibration.spring_constant;
    let ramp = nlvid_afm::prepare_ramp_hold(&curve, nlvid_afm::ContactMethod::default())
        .with_context(|| format!("{}: cannot cut a ramp-hold curve", path.display()))?;
    let displacement = ramp
        .indentation
        .iter()
        .zip(&ramp.force)
        .map(|(d, f)| d + f / k)
        .collect();
    Ok(MeasuredCurve {
        path: path.to_path_buf(),
        lines: (1..=ramp.time.len()).collect(),
        time: ramp.time,
        displacement,
        force: ramp.force,
        indentation: Some(ramp.indentation),
        contact_area: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const RELAXATION: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../afm/tests/data/fmt-jpk-sr_cell1-0008.jpk-force"
    );

    #[test]
    fn jpk_ramp_hold_reads_as_a_measured_curve_from_contact() {
        let curve = read_jpk_ramp_hold(Path::new(RELAXATION), None).unwrap();
        let n = curve.time.len();
        assert!(n > 7000, "extend after contact + 7680-point hold, got {n}");
        assert_eq!(curve.force.len(), n);
        assert_eq!(curve.displacement.len(), n);
        assert_eq!(curve.time[0], 0.0);
        assert!(curve.time.windows(2).all(|w| w[1] > w[0]));
        let delta = curve.indentation.as_ref().unwrap();
        // δ starts at the contact point and grows to a few µm on a cell.
        assert!(delta[0].abs() < 0.1e-6, "δ(0) = {}", delta[0]);
        let peak = curve.force.iter().copied().fold(f64::MIN, f64::max);
        assert!(peak > 0.0);
        // Stress relaxation: the force at the end of the hold is below the peak.
        assert!(curve.force[n - 1] < 0.9 * peak);
    }

    #[test]
    fn a_non_jpk_file_with_the_jpk_extension_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("nlvid-fit-jpk-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cell.jpk-force");
        std::fs::write(&path, b"time,force\n0,1\n").unwrap();
        let err = read_jpk_ramp_hold(&path, None).unwrap_err();
        assert!(format!("{err:#}").contains("cell.jpk-force"), "{err:#}");
    }

    #[test]
    fn the_checking_summary_sits_next_to_the_model() {
        assert_eq!(
            default_checking_path(Path::new("work/model.json")),
            Path::new("work/model.check.json")
        );
    }
}
