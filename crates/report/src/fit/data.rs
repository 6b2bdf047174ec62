//! Loading what a fit needs: each experiment's surrogate (model file, time
//! grid from `meta.json`, measured checking error) and its data file (CSV
//! or `.jpk-force`), checked against the protocol and resampled onto the
//! surrogate's grid. Every error names the file (and row/column where there
//! is one) before any fitting starts.

use std::path::{Path, PathBuf};

use nlvid_inverse::Model as _;
use nlvid_inverse::{
    Calibration, Coordinates, KrigingSurrogate, MeasuredCurve, load_kriging_surrogate,
    ramp_hold_indentation, read_afm_csv, read_compression_csv, segment_weights,
};

use crate::error::{ReportError, Result};
use crate::settings::{
    DataColumns, ExperimentSettings, FitSettings, Protocol, ProtocolKind, RealModelSpec,
};

/// A surrogate ready to fit with, and how good it is.
pub struct Surrogate {
    /// The model file.
    pub path: PathBuf,
    /// The surrogate as a fit model.
    pub model: KrigingSurrogate,
    /// Max eq. 4.4 checking error and the file it came from.
    pub checking: Option<(f64, PathBuf)>,
    /// What the meta-model was built for (its `meta.json`), if stored.
    pub conditions: Option<nlvid_model::BuildConditions>,
    /// Its `meta.json`.
    pub meta: PathBuf,
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
    /// The meta-model domain checks: what differs between the data and what the
    /// meta-model was built for ([`super::domain::check`]).
    pub domain_notes: Vec<String>,
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
fn real_model(spec: &RealModelSpec) -> Result<RealModel> {
    Ok(match spec {
        RealModelSpec::LeeRadok { radius, poisson } => RealModel::LeeRadok {
            radius: *radius,
            poisson: *poisson,
        },
        RealModelSpec::Forward { study } => {
            let mut st = nlvid_study::Study::load(study)?;
            let model = nlvid_forward::from_study(&mut st).map_err(|e| {
                ReportError::InvalidSetting(format!(
                    "{}: real model from [forward]: {e}",
                    study.display()
                ))
            })?;
            RealModel::Forward(model)
        }
    })
}

/// Reads every surrogate and data file named by `settings` and `files`.
///
/// # Errors
/// Unreadable files, malformed data (file, row, column), protocol
/// mismatches, or a number of files that does not match the experiments.
pub fn load(settings: &FitSettings, files: &[PathBuf]) -> Result<Vec<LoadedExperiment>> {
    let files = expand_folders(files)?;
    load_each(settings, &files, "data files", |file| {
        let label = file.file_stem().map_or_else(
            || file.display().to_string(),
            |s| s.to_string_lossy().into(),
        );
        Ok((label, read_curve(file, &settings.columns)?))
    })
}

/// As [`load`], for curves already in memory (SI: time, displacement or
/// indentation, force), each with its default label (a `label` of the
/// experiment's settings takes precedence): the Python bindings' entry.
///
/// # Errors
/// As [`load`], but for reading files.
pub fn load_curves(
    settings: &FitSettings,
    curves: Vec<(String, MeasuredCurve)>,
) -> Result<Vec<LoadedExperiment>> {
    let mut slots: Vec<Option<(String, MeasuredCurve)>> = curves.into_iter().map(Some).collect();
    let n = slots.len();
    let items: Vec<usize> = (0..n).collect();
    load_each(settings, &items, "curves", |&i| {
        slots[i]
            .take()
            .ok_or_else(|| ReportError::InvalidSetting(format!("curve {i} given twice")))
    })
}

/// Pairs each experiment of `settings` with one of `items` (one item per
/// experiment, or every item with the single one), then loads its
/// surrogate and reads its curve with `read` (label, curve).
fn load_each<T>(
    settings: &FitSettings,
    items: &[T],
    what: &str,
    mut read: impl FnMut(&T) -> Result<(String, MeasuredCurve)>,
) -> Result<Vec<LoadedExperiment>> {
    let pairs: Vec<(&ExperimentSettings, &T)> = if settings.repeat {
        items
            .iter()
            .map(|f| (&settings.experiments[0], f))
            .collect()
    } else {
        if items.len() != settings.experiments.len() {
            let one = what.trim_end_matches('s');
            return Err(ReportError::InvalidSetting(format!(
                "{}: {} [[fit.experiment]] tables but {} {what} were given: \
                 give one {one} per experiment, in the same order",
                settings.study.display(),
                settings.experiments.len(),
                items.len()
            )));
        }
        settings.experiments.iter().zip(items).collect()
    };
    let mut out: Vec<LoadedExperiment> = Vec::with_capacity(pairs.len());
    for (exp, item) in pairs {
        let surrogate = load_surrogate(settings, exp, settings.inputs)?;
        if let Some(first) = out.first() {
            same_domain(&first.surrogate, &surrogate)?;
        }
        let times = surrogate.model.times().to_vec();
        let (default_label, curve) = read(item)?;
        let real = exp.real.as_ref().map(real_model).transpose()?;
        let facts = data_facts(&curve, exp, real.as_ref());
        let found = super::domain::check(
            &facts,
            surrogate.conditions.as_ref(),
            &times,
            &surrogate.meta.display().to_string(),
        )
        .map_err(|m| ReportError::Data {
            path: curve.path.clone(),
            line: 0,
            message: m,
        })?;
        // data ending before the grid: fit the overlap (later grid points weigh 0)
        let used = found
            .overlap_end
            .map_or(times.len(), |te| times.iter().filter(|t| **t <= te).count());
        if let Some(p) = &exp.protocol {
            let grid = exp
                .meta
                .as_deref()
                .map_or_else(String::new, |m| format!(", {}", m.display()));
            let t_end = times[..used].last().copied().unwrap_or(0.0);
            let grid = format!("surrogate's time grid{grid}");
            check_protocol(&curve, p, t_end, &settings.study, &grid)?;
        }
        let mut force = curve.resample(curve.force(), &times[..used])?;
        let last = force.last().copied().unwrap_or(0.0);
        force.resize(times.len(), last);
        let mut weights =
            (!exp.segments.is_empty()).then(|| segment_weights(&times, &exp.segments, 1.0));
        if used < times.len() {
            let w = weights.get_or_insert_with(|| vec![1.0; times.len()]);
            w[used..].iter_mut().for_each(|x| *x = 0.0);
        }
        let label = exp.label.clone().unwrap_or(default_label);
        out.push(LoadedExperiment {
            label,
            surrogate,
            curve,
            force,
            weights,
            real,
            domain_notes: found.notes,
        });
    }
    Ok(out)
}

/// Curves fitted with one parameter set are fitted in one domain: every
/// meta-model must carry the same one.
fn same_domain(first: &Surrogate, other: &Surrogate) -> Result<()> {
    let (a, b) = (first.model.domain(), other.model.domain());
    if a != b {
        return Err(ReportError::InvalidSetting(format!(
            "{} and {} were built on different parameter domains ({:?} vs {:?}): \
             curves fitted together need meta-models of one [design] domain",
            first.path.display(),
            other.path.display(),
            a,
            b
        )));
    }
    Ok(())
}

fn load_surrogate(
    settings: &FitSettings,
    exp: &ExperimentSettings,
    inputs: Coordinates,
) -> Result<Surrogate> {
    let (Some(path), Some(meta)) = (&exp.surrogate, &exp.meta) else {
        return Err(ReportError::InvalidSetting(format!(
            "{}: [fit]: `nlvid fit` fits on a surrogate: give `surrogate` and `meta` \
             (model = \"lee-radok\" is for `nlvid cohort`)",
            settings.study.display()
        )));
    };
    let conditions = nlvid_inverse::read_meta(meta)
        .map_err(|e| ReportError::InvalidSetting(format!("meta-model {}: {e}", meta.display())))?
        .conditions;
    let model = load_kriging_surrogate(path, meta, inputs)
        .map_err(|e| ReportError::InvalidSetting(format!("surrogate {}: {e}", path.display())))?;
    let checking = match exp.check_file() {
        Some(p) => Some((read_checking_error(&p)?, p)),
        None => None,
    };
    Ok(Surrogate {
        path: path.clone(),
        model,
        checking,
        conditions,
        meta: meta.clone(),
    })
}

/// The max eq. 4.4 RMSE of a `nlvid --json surrogate check` output.
fn read_checking_error(path: &Path) -> Result<f64> {
    let bad = |message: String| ReportError::Data {
        path: path.to_path_buf(),
        line: 0,
        message,
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| ReportError::io(path, format!("cannot read the checking summary: {e}")))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        bad(format!(
            "not JSON ({e}); expected the summary `nlvid surrogate check` saves"
        ))
    })?;
    match v.get("max").and_then(serde_json::Value::as_f64) {
        Some(e) if e.is_finite() && e >= 0.0 => Ok(e),
        _ => Err(bad(
            "key `max` (largest eq. 4.4 checking error, a number >= 0) missing; \
             expected the summary `nlvid surrogate check` saves"
                .into(),
        )),
    }
}

/// Data paths with each folder (searched recursively) and glob replaced by its curve
/// files (`*.csv` and instrument files such as `.jpk-force`, sorted by path), through the
/// one batch input reader [`nlvid_afm::expand_inputs`].
///
/// # Errors
/// An unreadable folder, a glob matching nothing, or a folder without curve files
/// (naming it).
fn expand_folders(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let is_curve_file = |f: &Path| {
        nlvid_afm::batch::is_afm_file(f)
            || f.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"))
    };
    let mut out = Vec::new();
    for p in paths {
        let found = nlvid_afm::expand_inputs(std::slice::from_ref(p), is_curve_file);
        if let Some(f) = found.failures.first() {
            return Err(ReportError::io(&f.file, f.error.to_string()));
        }
        if p.is_dir() && found.files.is_empty() {
            return Err(ReportError::io(
                p,
                "no curve files (*.csv, .jpk-force, .jpk-force-map, .ibw …) in this folder",
            ));
        }
        out.extend(found.files);
    }
    Ok(out)
}

fn read_curve(path: &Path, columns: &DataColumns) -> Result<MeasuredCurve> {
    let is_jpk = nlvid_afm::batch::is_afm_file(path);
    Ok(match columns {
        DataColumns::Afm(_, cal) if is_jpk => read_jpk(path, cal.as_ref())?,
        DataColumns::Compression(_) if is_jpk => read_jpk(path, None)?,
        DataColumns::Afm(c, Some(cal)) => read_afm_csv(path, c, cal)?,
        DataColumns::Afm(_, None) => {
            return Err(ReportError::InvalidSetting(format!(
                "{}: a CSV AFM curve needs [fit.calibration] spring_constant (instrument \
                 files such as .jpk-force carry their own)",
                path.display()
            )));
        }
        DataColumns::Compression(c) => read_compression_csv(path, c)?,
    })
}

/// A JPK ramp-hold file ([`nlvid_afm::read_ramp_hold`]) as a measured
/// curve; a calibration in the study replaces the file's.
fn read_jpk(path: &Path, cal: Option<&Calibration>) -> Result<MeasuredCurve> {
    let options = nlvid_afm::ReadOptions {
        spring_constant: cal.map(|c| c.spring_constant),
        sensitivity: cal.and_then(|c| c.deflection_sensitivity),
    };
    let c = nlvid_afm::read_ramp_hold(path, &options)
        .map_err(|e| ReportError::io(path, format!("cannot read the JPK ramp-hold curve: {e}")))?;
    // The ramp-hold curve (channels displacement, force, indentation),
    // sample i numbered i + 1.
    Ok(MeasuredCurve::new(path, (1..=c.len()).collect(), c)?)
}

/// Checks `curve` against `[fit.protocol]` (`p`): ramp from 0 at `rate`
/// to `amplitude`, then hold (`kind` ramp-hold) or come back at the same rate
/// (ramp-reverse) to `t_end`, the end of the model's time grid
/// (`grid` names it in the error). The one check of `nlvid fit` and
/// `nlvid cohort`.
///
/// # Errors
/// A ramp longer than the grid (naming `study`); the curve off the
/// protocol beyond its tolerances.
pub fn check_protocol(
    curve: &MeasuredCurve,
    p: &Protocol,
    t_end: f64,
    study: &Path,
    grid: &str,
) -> Result<()> {
    let t_ramp = p.amplitude / p.rate;
    if t_ramp >= t_end {
        return Err(ReportError::InvalidSetting(format!(
            "{}: [fit.protocol] ramp to {:e} m at {:e} m/s takes {t_ramp} s, \
             longer than the {grid} ({t_end} s)",
            study.display(),
            p.amplitude,
            p.rate,
        )));
    }
    let expected_t = [0.0, t_ramp, t_end];
    let expected = match p.kind {
        ProtocolKind::RampHold => ramp_hold_indentation(&expected_t, p.rate, p.amplitude),
        ProtocolKind::RampReverse => {
            vec![0.0, p.amplitude, p.amplitude - p.rate * (t_end - t_ramp)]
        }
    };
    curve.check_protocol(&expected_t, &expected, p.tolerance)?;
    Ok(())
}

/// The data's side of the meta-model domain checks: time span, the experiment's ramp
/// time and depth (`[fit.protocol]`, the largest measured indentation where there is
/// one), and the geometry the re-check model assumes.
fn data_facts(
    curve: &MeasuredCurve,
    exp: &ExperimentSettings,
    real: Option<&RealModel>,
) -> super::domain::DataFacts {
    let t0 = curve.time().first().copied().unwrap_or(0.0);
    let end = curve.time().last().copied().unwrap_or(t0) - t0;
    let peak = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let depth = match curve.indentation() {
        Some(d) if !d.is_empty() => Some(peak(d)),
        _ => exp.protocol.as_ref().map(|p| p.amplitude),
    };
    let built = match real {
        Some(RealModel::Forward(m)) => m.conditions(),
        _ => None,
    };
    let probe_radius_m = match real {
        Some(RealModel::LeeRadok { radius, .. }) => Some(*radius),
        _ => built.as_ref().and_then(|c| c.probe_radius_m),
    };
    super::domain::DataFacts {
        end_time_s: end,
        ramp_time_s: exp.protocol.as_ref().map(|p| p.amplitude / p.rate),
        depth_m: depth,
        probe_radius_m,
        cell_height_m: built.as_ref().and_then(|c| c.cell_height_m),
        cell_diameter_m: built.as_ref().and_then(|c| c.cell_diameter_m),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Protocol;
    use nlvid_inverse::ProtocolTolerance;

    /// A plate history sampled at 0.05 s over 15 s (the thesis's RR at
    /// d = 1.5 mm, 0.2 mm/s down and up, §4.2) or the RH at the same
    /// rate held from 7.5 s.
    fn curve(reverse: bool) -> MeasuredCurve {
        let (rate, d) = (0.2e-3, 1.5e-3);
        let time: Vec<f64> = (0..=300).map(|i| 0.05 * f64::from(i)).collect();
        let displacement = time
            .iter()
            .map(|&t| {
                let down = (rate * t).min(d);
                if reverse && t > d / rate {
                    d - rate * (t - d / rate)
                } else {
                    down
                }
            })
            .collect();
        let force = vec![0.0; time.len()];
        let lines = (2..=302).collect();
        MeasuredCurve::from_columns(
            Path::new("rr.csv"),
            lines,
            (time, displacement, force),
            None,
            None,
        )
        .expect("curve")
    }

    fn protocol(kind: ProtocolKind) -> Protocol {
        Protocol {
            kind,
            rate: 0.2e-3,
            amplitude: 1.5e-3,
            tolerance: ProtocolTolerance::default(),
        }
    }

    #[test]
    fn a_ramp_reverse_protocol_accepts_rr_data_and_refuses_a_hold() {
        let (t_end, grid) = (15.0, "model's time grid");
        let study = Path::new("fit.toml");
        let rr = protocol(ProtocolKind::RampReverse);
        let rh = protocol(ProtocolKind::RampHold);
        check_protocol(&curve(true), &rr, t_end, study, grid).expect("RR data, RR protocol");
        check_protocol(&curve(false), &rh, t_end, study, grid).expect("RH data, RH protocol");
        for (data, p) in [(curve(true), &rh), (curve(false), &rr)] {
            let e = check_protocol(&data, p, t_end, study, grid)
                .expect_err("the other protocol")
                .to_string();
            // the legs part at 7.5 s: 5 % of 1.5 mm is passed 0.375 s later,
            // first at the sample t = 7.9 s (index 158, file line 160)
            assert!(
                e.contains("rr.csv: protocol mismatch at row 160 (t = 7.9 s)"),
                "{e}"
            );
        }
    }
}
