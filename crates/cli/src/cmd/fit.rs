//! `nlvid fit <study.toml> DATA.csv [DATA2.csv …]`: fit one parameter set
//! to one or several measured curves on a Kriging surrogate (thesis §4.4.1
//! step 5, §4.4.2, §5.4.1, eq. 5.3), then re-check with the real forward
//! model when the study names one (analytic Lee–Radok Hertz for AFM).
//!
//! Reads the study's `[fit]` section (see docs/cli/fit.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context as _, bail};
use nlvid_inverse::{
    AfmColumns, Calibration, CompressionColumns, Coordinates, Domain, KrigingSurrogate,
    LeeRadokHertz, MeasuredCurve, Model, MultiStart, PronyShear, ProtocolTolerance, Segment,
    SurrogateFit, SurrogateFitter, load_kriging_surrogate, ramp_hold_indentation,
    range_normalised_rmse, read_afm_csv, read_compression_csv, segment_weights,
};
use nlvid_study::{Bounds, Dimension, Section, Study};
use serde_json::json;

use super::{Context, Run};
use crate::output::print_json;

/// Raw arguments of `nlvid fit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The study file (TOML) with a `[fit]` section.
    pub study: PathBuf,
    /// Measured curves (CSV, columns named in `[fit.columns]`), fitted together with one parameter set.
    #[arg(required = true)]
    pub data: Vec<PathBuf>,
    /// Directory for SVG plots of data vs fitted curve (one per data file).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Override `[fit] starts`.
    #[arg(long)]
    pub starts: Option<usize>,
    /// Override `[fit] seed`.
    #[arg(long)]
    pub seed: Option<u64>,
}

/// The real forward model named by the study.
#[derive(Debug, Clone)]
enum RealModel {
    LeeRadok { radius: f64, poisson: f64 },
}

/// Validated configuration.
pub struct Config {
    surrogate: KrigingSurrogate,
    /// (label, measured curve, force on the surrogate grid).
    data: Vec<(String, MeasuredCurve, Vec<f64>)>,
    weights: Option<Vec<f64>>,
    starts: usize,
    seed: u64,
    real: Option<RealModel>,
    checking_error: Option<f64>,
    modulus_times: Vec<f64>,
    plot: Option<PathBuf>,
    study_name: String,
}

#[derive(Clone, Copy)]
enum DataKind {
    Afm,
    Compression,
}

fn resolve(base: &Path, p: PathBuf) -> PathBuf {
    if p.is_absolute() { p } else { base.join(p) }
}

fn read_domain(s: &mut Section) -> anyhow::Result<Domain> {
    let name = s.req_str("domain")?;
    let eps = s.f64_or("epsilon", Bounds::closed_open(0.0, 0.98), 0.01)?;
    match name.as_str() {
        "table-5.3" => Ok(Domain::prony2_table_5_3(eps)?),
        other => Err(s
            .invalid(
                "domain",
                format!("unknown domain `{other}` (available: table-5.3)"),
            )
            .into()),
    }
}

impl Run for Args {
    type Config = Config;

    fn validate(self, _ctx: &Context) -> anyhow::Result<Config> {
        let mut study = Study::load(&self.study)?;
        let base = study.base_dir().to_path_buf();
        let mut s = study.section("fit")?;
        let model_path = resolve(&base, s.req_path("surrogate")?);
        let meta_path = resolve(&base, s.req_path("meta")?);
        let coords = s.enum_or(
            "inputs",
            &[
                ("physical", Coordinates::Physical),
                ("unit", Coordinates::Unit),
            ],
            Coordinates::Physical,
        )?;
        let domain = read_domain(&mut s)?;
        let kind = s.req_enum(
            "data",
            &[
                ("afm", DataKind::Afm),
                ("compression", DataKind::Compression),
            ],
        )?;
        let starts = match self.starts {
            Some(n) => n,
            None => s.opt_usize("starts", Bounds::at_least(1.0))?.unwrap_or(8),
        };
        let seed = match self.seed {
            Some(v) => v,
            None => s.opt_u64("seed")?.unwrap_or(1),
        };
        let checking_error = s.opt_f64("checking_error", Bounds::closed(0.0, 1.0))?;
        let modulus_times = s
            .opt_quantities("modulus_times", Dimension::TIME, Bounds::positive())?
            .unwrap_or_else(|| vec![0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 52.0]);

        let mut cols = s.subsection("columns")?;
        let time_col = cols.req_str("time")?;
        let (afm_cols, comp_cols) = match kind {
            DataKind::Afm => (
                Some(AfmColumns {
                    time: time_col,
                    piezo: cols.req_str("piezo")?,
                    deflection: cols.req_str("deflection")?,
                }),
                None,
            ),
            DataKind::Compression => (
                None,
                Some(CompressionColumns {
                    time: time_col,
                    displacement: cols.req_str("displacement")?,
                    force: cols.req_str("force")?,
                    contact_area: cols.opt_str("contact_area")?,
                }),
            ),
        };
        cols.finish()?;
        let calibration = match kind {
            DataKind::Afm => {
                let mut c = s.subsection("calibration")?;
                let cal = Calibration {
                    spring_constant: c.req_quantity(
                        "spring_constant",
                        Dimension::STIFFNESS,
                        Bounds::positive(),
                    )?,
                    deflection_sensitivity: c.opt_quantity(
                        "deflection_sensitivity",
                        Dimension::LENGTH_PER_VOLTAGE,
                        Bounds::positive(),
                    )?,
                };
                c.finish()?;
                Some(cal)
            }
            DataKind::Compression => None,
        };
        // Expected ramp-hold of the controlled displacement (AFM piezo /
        // plate), for the protocol check.
        let mut p = s.subsection("protocol")?;
        let rate = p.req_quantity("rate", Dimension::VELOCITY, Bounds::positive())?;
        let amplitude = p.req_quantity("amplitude", Dimension::LENGTH, Bounds::positive())?;
        let tol = ProtocolTolerance {
            duration: p.f64_or("duration_tolerance", Bounds::closed(0.0, 1.0), 0.02)?,
            displacement: p.f64_or("displacement_tolerance", Bounds::closed(0.0, 1.0), 0.05)?,
        };
        p.finish()?;
        let segments: Vec<Segment> = s
            .tables("segment")?
            .into_iter()
            .map(|mut t| -> anyhow::Result<Segment> {
                let seg = Segment {
                    start: t.req_quantity("start", Dimension::TIME, Bounds::non_negative())?,
                    end: t.req_quantity("end", Dimension::TIME, Bounds::non_negative())?,
                    weight: t.req_f64("weight", Bounds::non_negative())?,
                };
                t.finish()?;
                Ok(seg)
            })
            .collect::<anyhow::Result<_>>()?;
        let real = match s.opt_subsection("real_model")? {
            None => None,
            Some(mut r) => {
                let name = r.req_str("model")?;
                if name != "lee-radok" {
                    bail!(
                        "{}: [fit.real_model] model = `{name}`: available: lee-radok \
                         (membrane and FE re-checks are not wired into `fit` yet)",
                        self.study.display()
                    );
                }
                let m = RealModel::LeeRadok {
                    radius: r.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?,
                    poisson: r.f64_or("poisson", Bounds::closed(0.0, 0.5), 0.5)?,
                };
                r.finish()?;
                Some(m)
            }
        };
        s.finish()?;

        let surrogate = load_kriging_surrogate(&model_path, &meta_path, domain, coords)?;
        let times = surrogate.times().to_vec();

        // Ramp from 0 at `rate` to `amplitude`, then hold to the grid's end.
        let t_end = times.last().copied().unwrap_or(0.0);
        let t_ramp = amplitude / rate;
        if t_ramp >= t_end {
            bail!(
                "{}: [fit.protocol] ramp to {amplitude:e} m at {rate:e} m/s takes {t_ramp} s, \
                 longer than the surrogate's time grid ({t_end} s)",
                self.study.display()
            );
        }
        let expected_t = vec![0.0, t_ramp, t_end];
        let expected = ramp_hold_indentation(&expected_t, rate, amplitude);
        let mut data = Vec::new();
        for path in &self.data {
            let is_jpk = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("jpk-force"));
            let curve = match (&afm_cols, &comp_cols, &calibration) {
                (_, _, cal) if is_jpk => read_jpk_ramp_hold(path, cal.as_ref())?,
                (Some(c), _, Some(cal)) => read_afm_csv(path, c, cal)?,
                (_, Some(c), _) => read_compression_csv(path, c)?,
                _ => bail!("internal: data kind without columns"),
            };
            curve.check_protocol(&expected_t, &expected, tol)?;
            let force = curve.resample(&curve.force, &times)?;
            let label = path.file_stem().map_or_else(
                || path.display().to_string(),
                |s| s.to_string_lossy().into(),
            );
            data.push((label, curve, force));
        }
        let weights = (!segments.is_empty()).then(|| segment_weights(&times, &segments, 1.0));
        Ok(Config {
            surrogate,
            data,
            weights,
            starts,
            seed,
            real,
            checking_error,
            modulus_times,
            plot: self.plot,
            study_name: self.study.display().to_string(),
        })
    }

    fn execute(c: Config, ctx: &Context) -> anyhow::Result<ExitCode> {
        let fitter = SurrogateFitter::new(c.surrogate, c.weights.clone())?;
        let curves: Vec<(&str, &[f64])> = c
            .data
            .iter()
            .map(|(label, _, force)| (label.as_str(), force.as_slice()))
            .collect();
        let t0 = std::time::Instant::now();
        let SurrogateFit {
            fit,
            per_curve: per_sur,
            response: fitted,
        } = fitter.fit(
            &curves,
            &MultiStart::new().with_starts(c.starts)?.with_seed(c.seed),
        )?;
        let seconds = t0.elapsed().as_secs_f64();
        let x = fit.best.x.clone();
        let times = fitter.times().to_vec();

        // Re-run the real model at the optimum (AFM: with each curve's own
        // measured indentation history on the grid).
        let mut real_misfits = Vec::new();
        if let Some(RealModel::LeeRadok { radius, poisson }) = &c.real {
            for (label, curve, force) in &c.data {
                let Some(delta) = &curve.indentation else {
                    bail!("{label}: the Lee-Radok re-check needs an indentation (AFM data)");
                };
                // The hereditary integral starts from rest at t = 0: run the
                // model on 0 ∪ grid and drop the first value.
                let skip = usize::from(times[0] > 0.0);
                let grid: Vec<f64> = (skip == 1)
                    .then_some(0.0)
                    .into_iter()
                    .chain(times.iter().copied())
                    .collect();
                let delta = curve.resample(delta, &grid)?;
                let m = LeeRadokHertz::new(
                    fitter.surrogate().domain().clone(),
                    grid,
                    &delta,
                    *radius,
                    *poisson,
                )?;
                let y = m.response(&x)?[skip..].to_vec();
                real_misfits.push(range_normalised_rmse(&y, force, c.weights.as_deref())?);
            }
        }
        let agree: Option<bool> = match (c.checking_error, real_misfits.is_empty()) {
            (Some(e), false) => Some(
                per_sur
                    .iter()
                    .zip(&real_misfits)
                    .all(|(a, b)| (a - b).abs() <= e),
            ),
            _ => None,
        };
        let shear = PronyShear::from_parameters(fitter.surrogate().domain(), &x)?;
        let modulus = shear.curve(&c.modulus_times);

        let mut plots = Vec::new();
        if let Some(dir) = &c.plot {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            for (label, _, force) in &c.data {
                let path = dir.join(format!("fit-{label}.svg"));
                nlvid_surrogate::check::plot_svg(
                    &path,
                    &format!("{label}: data (solid) vs surrogate fit (dashed)"),
                    &times,
                    force,
                    &fitted,
                )?;
                plots.push(path);
            }
        }

        if ctx.json {
            let params = fit.parameters()?;
            print_json(&json!({
                "study": c.study_name,
                "parameters": params.rows.iter().map(|(n, v, u)| json!({"name": n, "value": v, "unit": u})).collect::<Vec<_>>(),
                "misfit_surrogate": per_sur,
                "misfit_real": if real_misfits.is_empty() { serde_json::Value::Null } else { json!(real_misfits) },
                "checking_error": c.checking_error,
                "surrogate_and_real_agree": agree,
                "on_bound": fit.on_bound(),
                "fit": fit,
                "modulus": modulus,
                "seconds": seconds,
                "plots": plots,
            }))?;
        } else {
            println!(
                "fit of {} curve(s) on the surrogate ({seconds:.3} s):",
                c.data.len()
            );
            print!("{fit}");
            for (k, (label, _, _)) in c.data.iter().enumerate() {
                match real_misfits.get(k) {
                    Some(r) => println!(
                        "{label}: misfit surrogate {:.4} %, real model re-run {:.4} %",
                        100.0 * per_sur[k],
                        100.0 * r
                    ),
                    None => println!(
                        "{label}: misfit surrogate {:.4} % (no real model named: not re-checked)",
                        100.0 * per_sur[k]
                    ),
                }
            }
            match (agree, c.checking_error) {
                (Some(true), Some(e)) => println!(
                    "surrogate and re-run misfits agree within the checking error {:.4} %",
                    100.0 * e
                ),
                (Some(false), Some(e)) => println!(
                    "WARNING: surrogate and re-run misfits differ by more than the checking error {:.4} %: \
                     refine the surrogate near the optimum",
                    100.0 * e
                ),
                _ => {}
            }
            println!("{:>10} {:>14} {:>14}", "t [s]", "G(t) [Pa]", "E(t)=3G [Pa]");
            for p in &modulus {
                println!("{:>10.4} {:>14.6e} {:>14.6e}", p.time, p.shear, p.young);
            }
            for p in &plots {
                println!("plot written to {}", p.display());
            }
        }
        Ok(ExitCode::SUCCESS)
    }
}

/// Read a JPK ramp-hold curve (extend, then constant-height pause) as a
/// measured AFM curve: time from the contact point, F, δ, and the piezo travel
/// Z = δ + F/k since contact (§5.2.2, δ = Z − d with d = F/k). A calibration in
/// the study replaces the file's.
fn read_jpk_ramp_hold(
    path: &Path,
    cal: Option<&nlvid_inverse::Calibration>,
) -> anyhow::Result<MeasuredCurve> {
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
}
