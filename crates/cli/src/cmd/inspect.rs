//! `nlvid inspect FILE`: what an AFM instrument file holds (segments, channels,
//! calibration), optionally exported as CSV, plotted as SVG, and given a quick Hertz or
//! Lee–Radok fit.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::{Args as ClapArgs, ValueEnum};
use nlvid_afm::{
    ContactMethod, ForceCurve, HertzSettings, LeeRadokSettings, ReadOptions, fit_hertz,
    fit_lee_radok, plot, prepare_approach, prepare_ramp_hold, read_force_map,
};

/// Arguments of `nlvid inspect`.
#[derive(Debug, ClapArgs)]
pub struct Args {
    /// JPK force file (.jpk-force) or force map (.jpk-force-map).
    pub file: PathBuf,
    /// Write every segment and channel as CSV (unit-suffixed headers) to this file.
    #[arg(long, value_name = "CSV")]
    pub csv: Option<PathBuf>,
    /// Write an SVG plot: force vs time, or data vs fit with --fit.
    #[arg(long, value_name = "SVG")]
    pub plot: Option<PathBuf>,
    /// Set from the global `--json` flag.
    #[arg(skip)]
    pub json: bool,
    /// Spring constant replacing the file's, e.g. "0.12 N/m" (needed if the file has none).
    #[arg(long, value_name = "K")]
    pub spring_constant: Option<String>,
    /// Deflection sensitivity replacing the file's, e.g. "110.28 nm/V".
    #[arg(long, value_name = "S")]
    pub sensitivity: Option<String>,
    /// Curve of a force map to inspect (0-based).
    #[arg(long, default_value_t = 0)]
    pub curve: usize,
    /// Quick fit: Hertz (paraboloid) on the approach, or Lee–Radok Prony on a ramp-hold.
    #[arg(long, value_enum)]
    pub fit: Option<Fit>,
    /// Probe radius for --fit, e.g. "40 nm" or "5 um" (not stored in JPK files).
    #[arg(long, value_name = "R")]
    pub tip_radius: Option<String>,
    /// Poisson ratio of the sample for --fit hertz.
    #[arg(long, default_value_t = 0.5)]
    pub poisson: f64,
    /// Prony terms for --fit lee-radok (1 to 3).
    #[arg(long, default_value_t = 2)]
    pub terms: usize,
    /// Contact-point method.
    #[arg(long, value_enum, default_value_t = Contact::Deviation)]
    pub contact: Contact,
}

/// Fits `inspect` can run.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Fit {
    /// Paraboloidal Hertz fit (eq. 1.1), E and contact point free.
    Hertz,
    /// Lee–Radok Prony fit of the extend + hold segments.
    LeeRadok,
}

/// Contact-point methods.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Contact {
    /// Deviation from the baseline by 5 noise standard deviations.
    Deviation,
    /// Piecewise constant + line least-squares fit.
    Piecewise,
}

/// Parse "<number> <unit>" into SI using `units` (name, divisor: SI = number / divisor);
/// a bare number is SI. Divisors ≥ 1 keep "5 um" exactly 5e-6.
fn quantity(text: &str, flag: &str, units: &[(&str, f64)]) -> anyhow::Result<f64> {
    let t = text.trim();
    let split = t
        .find(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E')
        .or_else(|| t.find(|c: char| c.is_alphabetic() && !c.is_ascii()))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let v: f64 = num
        .trim()
        .parse()
        .with_context(|| format!("--{flag} '{text}': not a number followed by a unit"))?;
    let unit = unit.trim();
    if unit.is_empty() {
        return Ok(v);
    }
    match units.iter().find(|(u, _)| *u == unit) {
        Some((_, d)) => Ok(v / d),
        None => bail!(
            "--{flag} '{text}': unknown unit '{unit}' (use one of {})",
            units.iter().map(|u| u.0).collect::<Vec<_>>().join(", ")
        ),
    }
}

const LENGTH: [(&str, f64); 5] = [
    ("m", 1.0),
    ("mm", 1e3),
    ("um", 1e6),
    ("µm", 1e6),
    ("nm", 1e9),
];

impl Args {
    /// Run the command.
    pub fn run(self) -> anyhow::Result<ExitCode> {
        let options = ReadOptions {
            spring_constant: self
                .spring_constant
                .as_deref()
                .map(|s| {
                    quantity(
                        s,
                        "spring-constant",
                        &[("N/m", 1.0), ("mN/m", 1e3), ("pN/nm", 1e3)],
                    )
                })
                .transpose()?,
            sensitivity: self
                .sensitivity
                .as_deref()
                .map(|s| {
                    quantity(
                        s,
                        "sensitivity",
                        &[("m/V", 1.0), ("nm/V", 1e9), ("um/V", 1e6)],
                    )
                })
                .transpose()?,
        };
        let curves = read_force_map(&self.file, &options)
            .with_context(|| format!("reading {}", self.file.display()))?;
        let n_curves = curves.len();
        let curve = curves.into_iter().nth(self.curve).with_context(|| {
            format!("--curve {}: the file holds {n_curves} curve(s)", self.curve)
        })?;
        let method = match self.contact {
            Contact::Deviation => ContactMethod::default(),
            Contact::Piecewise => ContactMethod::PiecewiseLinear,
        };
        let fit = match self.fit {
            None => None,
            Some(kind) => {
                let r = self.tip_radius.as_deref().context(
                    "--fit needs --tip-radius (the probe radius is not stored in JPK files)",
                )?;
                let r = quantity(r, "tip-radius", &LENGTH)?;
                Some(run_fit(&curve, kind, r, self.poisson, self.terms, method)?)
            }
        };
        if let Some(path) = &self.csv {
            let file = std::fs::File::create(path)
                .with_context(|| format!("creating {}", path.display()))?;
            curve
                .write_csv(std::io::BufWriter::new(file))
                .with_context(|| format!("writing {}", path.display()))?;
        }
        if let Some(path) = &self.plot {
            write_plot(path, &curve, fit.as_ref())?;
        }
        let mut out = String::new();
        if self.json {
            let mut v = summary_json(&curve, n_curves);
            if let Some(f) = &fit {
                v["fit"] = f.json.clone();
            }
            out = serde_json::to_string_pretty(&v)?;
            out.push('\n');
        } else {
            summary_text(&mut out, &curve, n_curves);
            if let Some(f) = &fit {
                out += &format!("\n{}\n", f.text);
            }
            if let Some(p) = &self.csv {
                out += &format!("CSV written to {}\n", p.display());
            }
            if let Some(p) = &self.plot {
                out += &format!("plot written to {}\n", p.display());
            }
        }
        use std::io::Write;
        match std::io::stdout().lock().write_all(out.as_bytes()) {
            Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
            _ => Ok(ExitCode::SUCCESS),
        }
    }
}

struct FitOut {
    text: String,
    json: serde_json::Value,
    x: Vec<f64>,
    data: Vec<f64>,
    model: Vec<f64>,
    x_label: &'static str,
}

fn run_fit(
    curve: &ForceCurve,
    kind: Fit,
    r: f64,
    nu: f64,
    terms: usize,
    method: ContactMethod,
) -> anyhow::Result<FitOut> {
    match kind {
        Fit::Hertz => {
            let a = prepare_approach(curve, method)?;
            let f = fit_hertz(&a.separation, &a.force, &HertzSettings::new(r, nu))?;
            let model: Vec<f64> = a
                .separation
                .iter()
                .map(|s| {
                    f.offset + nlvid_afm::hertz_force(f.contact_point - s, f.youngs_modulus, r, nu)
                })
                .collect();
            Ok(FitOut {
                text: format!(
                    "Hertz (paraboloid, R = {r:e} m, ν = {nu}): E = {:.6e} Pa, contact point = {:.6e} m, offset = {:.3e} N, range-normalised RMSE = {:.4}, {} points",
                    f.youngs_modulus,
                    f.contact_point,
                    f.offset,
                    f.range_normalised_rmse,
                    f.n_points
                ),
                json: serde_json::json!({
                    "model": "hertz-paraboloid", "tip_radius_m": r, "poisson": nu,
                    "youngs_modulus_Pa": f.youngs_modulus, "contact_point_m": f.contact_point,
                    "offset_N": f.offset, "rmse_N": f.rmse,
                    "range_normalised_rmse": f.range_normalised_rmse, "n_points": f.n_points,
                }),
                x: a.separation.iter().map(|s| s * 1e6).collect(),
                data: a.force.iter().map(|v| v * 1e9).collect(),
                model: model.iter().map(|v| v * 1e9).collect(),
                x_label: "tip-sample separation (um)",
            })
        }
        Fit::LeeRadok => {
            let rh = prepare_ramp_hold(curve, method)?;
            let mut s = LeeRadokSettings::new(r);
            s.n_terms = terms;
            let f = fit_lee_radok(&rh.time, &rh.indentation, &rh.force, &s)?;
            let g = &f.relaxation;
            // Term moduli G_k = G0 g_k (Pa).
            let moduli: Vec<(f64, f64)> = g
                .prony()
                .terms()
                .iter()
                .map(|t| (g.g0() * t.weight, t.tau))
                .collect();
            let terms_txt: Vec<String> = moduli
                .iter()
                .map(|(g, t)| format!("G = {g:.4e} Pa, tau = {t:.4e} s"))
                .collect();
            Ok(FitOut {
                text: format!(
                    "Lee-Radok Prony (R = {r:e} m, {} terms): G_inf = {:.4e} Pa; {}; G(0) = {:.4e} Pa; range-normalised RMSE = {:.4} ({} points from contact at t = {:.4} s, {} Nelder-Mead iterations)",
                    s.n_terms,
                    g.g_inf(),
                    terms_txt.join("; "),
                    g.g0(),
                    f.range_normalised_rmse,
                    rh.time.len(),
                    rh.contact_time,
                    f.iterations
                ),
                json: serde_json::json!({
                    "model": "lee-radok-prony", "tip_radius_m": r,
                    "g_inf_Pa": g.g_inf(),
                    "terms": moduli.iter().map(|(g, t)| serde_json::json!({"g_Pa": g, "tau_s": t})).collect::<Vec<_>>(),
                    "g0_Pa": g.g0(), "rmse_N": f.rmse,
                    "range_normalised_rmse": f.range_normalised_rmse,
                    "contact_time_s": rh.contact_time, "iterations": f.iterations,
                }),
                x: rh.time.clone(),
                data: rh.force.iter().map(|v| v * 1e9).collect(),
                model: f.force_fit.iter().map(|v| v * 1e9).collect(),
                x_label: "time since contact (s)",
            })
        }
    }
}

fn write_plot(
    path: &std::path::Path,
    curve: &ForceCurve,
    fit: Option<&FitOut>,
) -> anyhow::Result<()> {
    let title = path_name(&curve.source);
    match fit {
        Some(f) => plot::write_svg(
            path,
            &format!("{title}: data vs fit"),
            f.x_label,
            "force (nN)",
            &[
                plot::Series {
                    label: "data",
                    x: &f.x,
                    y: &f.data,
                },
                plot::Series {
                    label: "fit",
                    x: &f.x,
                    y: &f.model,
                },
            ],
        )?,
        None => {
            let forces: Vec<Vec<f64>> = curve
                .segments
                .iter()
                .map(|s| s.force().map(|f| f.iter().map(|v| v * 1e9).collect()))
                .collect::<Result<_, _>>()?;
            let labels: Vec<String> = curve
                .segments
                .iter()
                .map(|s| format!("{} {}", s.index, s.kind))
                .collect();
            let series: Vec<plot::Series<'_>> = curve
                .segments
                .iter()
                .zip(&forces)
                .zip(&labels)
                .map(|((s, f), l)| plot::Series {
                    label: l,
                    x: &s.time,
                    y: f,
                })
                .collect();
            plot::write_svg(path, &title, "time (s)", "force (nN)", &series)?
        }
    }
    Ok(())
}

fn path_name(source: &str) -> String {
    std::path::Path::new(source)
        .file_name()
        .map_or_else(|| source.to_string(), |n| n.to_string_lossy().into_owned())
}

fn summary_json(c: &ForceCurve, n_curves: usize) -> serde_json::Value {
    serde_json::json!({
        "source": c.source,
        "curves_in_file": n_curves,
        "format_version": c.format_version,
        "instrument": c.instrument,
        "position_m": c.position.map(|(x, y)| [x, y]),
        "calibration": {
            "spring_constant_N_per_m": c.calibration.spring_constant,
            "spring_constant_source": format!("{:?}", c.calibration.spring_constant_source).to_lowercase(),
            "sensitivity_m_per_V": c.calibration.sensitivity,
            "sensitivity_source": format!("{:?}", c.calibration.sensitivity_source).to_lowercase(),
        },
        "segments": c.segments.iter().map(|s| serde_json::json!({
            "index": s.index, "kind": s.kind.as_str(), "name": s.name,
            "points": s.len(), "duration_s": s.duration,
            "t_start_s": s.time.first(), "t_end_s": s.time.last(),
            "channels": s.channels.iter().map(|ch| serde_json::json!({
                "name": ch.name, "unit": ch.unit, "conversion": ch.conversion,
                "min": ch.values.iter().copied().fold(f64::INFINITY, f64::min),
                "max": ch.values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

fn summary_text(out: &mut String, c: &ForceCurve, n_curves: usize) {
    use std::fmt::Write;
    let _ = writeln!(out, "file:        {}", c.source);
    if n_curves > 1 {
        let _ = writeln!(out, "curves:      {n_curves} in the map");
    }
    let _ = writeln!(out, "format:      JPK {}", c.format_version);
    if let Some(i) = &c.instrument {
        let _ = writeln!(out, "instrument:  {i}");
    }
    if let Some((x, y)) = c.position {
        let _ = writeln!(out, "position:    x = {x:e} m, y = {y:e} m");
    }
    let cal = &c.calibration;
    let _ = writeln!(
        out,
        "calibration: spring constant {} N/m ({:?}), sensitivity {} nm/V ({:?})",
        cal.spring_constant,
        cal.spring_constant_source,
        cal.sensitivity * 1e9,
        cal.sensitivity_source
    );
    let _ = writeln!(out, "segments:");
    for s in &c.segments {
        let _ = writeln!(
            out,
            "  {} {:<8} {:<12} {:>6} points  {:>9.4} s  t = {:.4} .. {:.4} s",
            s.index,
            s.kind.as_str(),
            s.name,
            s.len(),
            s.duration,
            s.time.first().copied().unwrap_or(f64::NAN),
            s.time.last().copied().unwrap_or(f64::NAN)
        );
        for ch in &s.channels {
            let lo = ch.values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ch.values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let _ = writeln!(
                out,
                "      {:<18} [{}] via {:<10} {lo:.6e} .. {hi:.6e}",
                ch.name, ch.unit, ch.conversion
            );
        }
    }
}
