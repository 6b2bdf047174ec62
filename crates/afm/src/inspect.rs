//! What `nlvid inspect` shows of a force curve: a text summary of the file
//! (calibration, segments, channel ranges), a quick Hertz (eq. 1.1) or
//! Lee–Radok Prony fit, and the SVG of data (vs fit).

use std::fmt::Write as _;
use std::path::Path;

use serde_json::json;

use crate::batch::{Batch, Progress, for_each_curve_with};
use crate::error::Result;
use crate::{
    ContactMethod, CreepSettings, ForceCurve, HertzSettings, LeeRadokSettings, ReadOptions,
    SegmentKind, creep_indentation, fit_creep, fit_hertz, fit_lee_radok, hertz_force, plot,
    prepare_approach, prepare_creep, prepare_ramp_hold,
};

/// The quick fits of `nlvid inspect`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum QuickFitKind {
    /// Paraboloidal Hertz fit of the approach (eq. 1.1), E and contact point free.
    Hertz {
        /// Poisson's ratio of the sample.
        poisson: f64,
    },
    /// Lee–Radok Prony fit of the extend + hold segments.
    LeeRadok {
        /// Prony terms (1 to 3).
        terms: usize,
    },
}

/// A quick fit: its results with units, one line of text, and the data
/// and model curves (nN against µm or s) for a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct QuickFit {
    /// `hertz-paraboloid`, `lee-radok-prony` or `lee-radok-creep`.
    pub model: &'static str,
    /// `(key with unit suffix, value)`, e.g. `("youngs_modulus_Pa", 2.3e5)`.
    pub values: Vec<(String, f64)>,
    /// Prony terms of a Lee–Radok fit: `(G_k Pa, τ_k s)` in relaxation, `(J_k 1/Pa, τ_k s)`
    /// in creep (`model` `lee-radok-creep`).
    pub terms: Vec<(f64, f64)>,
    /// One line for people.
    pub text: String,
    /// Abscissae of the plot.
    pub x: Vec<f64>,
    /// Measured force, nN (indentation, µm, for a creep fit).
    pub data: Vec<f64>,
    /// Fitted force, nN (indentation, µm, for a creep fit).
    pub model_force: Vec<f64>,
    /// Abscissa label.
    pub x_label: &'static str,
    /// Ordinate label (of `data` and `model_force`).
    pub y_label: &'static str,
}

impl QuickFit {
    /// JSON: `model`, the values by their unit-suffixed keys, and `terms`
    /// (`g_Pa`, `tau_s`) of a Lee–Radok fit.
    pub fn to_json(&self) -> serde_json::Value {
        let mut m: serde_json::Map<_, _> = self
            .values
            .iter()
            .map(|(k, x)| (k.clone(), json!(x)))
            .collect();
        m.insert("model".into(), json!(self.model));
        if !self.terms.is_empty() {
            let t: Vec<_> = self
                .terms
                .iter()
                .map(|(g, t)| {
                    if self.model == "lee-radok-creep" {
                        json!({"j_per_Pa": g, "tau_s": t})
                    } else {
                        json!({"g_Pa": g, "tau_s": t})
                    }
                })
                .collect();
            m.insert("terms".into(), json!(t));
        }
        m.into()
    }
}

/// Runs a quick fit with probe radius `r` (m).
///
/// # Errors
/// No contact point, too few points, a fit that does not converge.
pub fn quick_fit(
    curve: &ForceCurve,
    kind: QuickFitKind,
    r: f64,
    method: ContactMethod,
) -> Result<QuickFit> {
    let nano = |v: &[f64]| v.iter().map(|f| f * 1e9).collect::<Vec<_>>();
    match kind {
        QuickFitKind::Hertz { poisson: nu } => {
            let a = prepare_approach(curve, method)?;
            let f = fit_hertz(&a.separation, &a.force, &HertzSettings::new(r, nu))?;
            let model: Vec<f64> = a
                .separation
                .iter()
                .map(|s| f.offset + hertz_force(f.contact_point - s, f.youngs_modulus, r, nu))
                .collect();
            Ok(QuickFit {
                model: "hertz-paraboloid",
                values: vec![
                    ("tip_radius_m".into(), r),
                    ("poisson".into(), nu),
                    ("youngs_modulus_Pa".into(), f.youngs_modulus),
                    ("contact_point_m".into(), f.contact_point),
                    ("offset_N".into(), f.offset),
                    ("rmse_N".into(), f.rmse),
                    ("range_normalised_rmse".into(), f.range_normalised_rmse),
                    ("n_points".into(), f.n_points as f64),
                ],
                terms: Vec::new(),
                text: format!(
                    "Hertz (paraboloid, R = {r:e} m, ν = {nu}): E = {:.6e} Pa, contact point = {:.6e} m, offset = {:.3e} N, range-normalised RMSE = {:.4}, {} points",
                    f.youngs_modulus,
                    f.contact_point,
                    f.offset,
                    f.range_normalised_rmse,
                    f.n_points
                ),
                x: a.separation.iter().map(|s| s * 1e6).collect(),
                data: nano(&a.force),
                model_force: nano(&model),
                x_label: "tip-sample separation (um)",
                y_label: "force (nN)",
            })
        }
        QuickFitKind::LeeRadok { terms } if has_creep_pause(curve) => {
            creep_fit(curve, terms, r, method)
        }
        QuickFitKind::LeeRadok { terms } => {
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
            Ok(QuickFit {
                model: "lee-radok-prony",
                values: vec![
                    ("tip_radius_m".into(), r),
                    ("g_inf_Pa".into(), g.g_inf()),
                    ("g0_Pa".into(), g.g0()),
                    ("rmse_N".into(), f.rmse),
                    ("range_normalised_rmse".into(), f.range_normalised_rmse),
                    ("contact_time_s".into(), rh.contact_time),
                    ("iterations".into(), f.iterations as f64),
                    ("starts".into(), f.starts as f64),
                    ("collapsed_terms".into(), f.collapsed as f64),
                ],
                terms: moduli,
                text: format!(
                    "Lee-Radok Prony (R = {r:e} m, {} terms{}): G_inf = {:.4e} Pa; {}; G(0) = {:.4e} Pa; range-normalised RMSE = {:.4} ({} points from contact at t = {:.4} s; best of {} Nelder-Mead starts, {} iterations)",
                    s.n_terms,
                    if f.collapsed > 0 {
                        format!(", {} collapsed to modulus 0 and dropped", f.collapsed)
                    } else {
                        String::new()
                    },
                    g.g_inf(),
                    terms_txt.join("; "),
                    g.g0(),
                    f.range_normalised_rmse,
                    rh.time.len(),
                    rh.contact_time,
                    f.starts,
                    f.iterations
                ),
                x: rh.time.clone(),
                data: nano(&rh.force),
                model_force: nano(&f.force_fit),
                x_label: "time since contact (s)",
                y_label: "force (nN)",
            })
        }
    }
}

/// Whether the segment right after the (first) extend is a constant-force pause.
fn has_creep_pause(curve: &ForceCurve) -> bool {
    curve
        .segments
        .iter()
        .position(|s| s.kind == SegmentKind::Extend)
        .and_then(|i| curve.segments.get(i + 1))
        .is_some_and(|s| s.kind == SegmentKind::Creep)
}

/// Lee–Radok in force control: the Prony creep-compliance fit of extend + constant-force
/// pause ([`fit_creep`]), reported as G(0) = 1/J₀, G∞ = 1/J(∞) and the compliance terms.
fn creep_fit(curve: &ForceCurve, terms: usize, r: f64, method: ContactMethod) -> Result<QuickFit> {
    let data = prepare_creep(curve, method)?;
    let f = fit_creep(&data, &CreepSettings::new(r, terms))?;
    let j = &f.compliance;
    let model = creep_indentation(&data.time, &data.force, j, r);
    let micro = |v: &[f64]| v.iter().map(|d| d * 1e6).collect::<Vec<_>>();
    let terms_txt: Vec<String> = j
        .terms
        .iter()
        .map(|(jk, t)| format!("J = {jk:.4e} 1/Pa, tau = {t:.4e} s"))
        .collect();
    Ok(QuickFit {
        model: "lee-radok-creep",
        values: vec![
            ("tip_radius_m".into(), r),
            ("g0_Pa".into(), j.g0()),
            ("g_inf_Pa".into(), j.g_inf()),
            ("j0_per_Pa".into(), j.j0),
            ("rmse_m".into(), f.rmse),
            ("range_normalised_rmse".into(), f.range_normalised_rmse),
            ("n_points".into(), f.n_points as f64),
            ("collapsed_terms".into(), f.collapsed as f64),
        ],
        terms: j.terms.clone(),
        text: format!(
            "Lee-Radok creep (force clamp; R = {r:e} m, {terms} terms, {} collapsed to 0): G(0) = 1/J0 = {:.4e} Pa; G_inf = {:.4e} Pa; {}; range-normalised RMSE of the indentation = {:.4} ({} points from contact)",
            f.collapsed,
            j.g0(),
            j.g_inf(),
            terms_txt.join("; "),
            f.range_normalised_rmse,
            f.n_points
        ),
        x: data.time.clone(),
        data: micro(&data.indentation),
        model_force: micro(&model),
        x_label: "time since contact (s)",
        y_label: "indentation (um)",
    })
}

/// The file name of a curve's source, for titles.
fn source_name(source: &str) -> String {
    Path::new(source)
        .file_name()
        .map_or_else(|| source.to_string(), |n| n.to_string_lossy().into_owned())
}

/// SVG of force (nN) against time for every segment, or data vs fit.
///
/// # Errors
/// A channel cannot be converted to force; the file cannot be written.
pub fn write_plot(path: &Path, curve: &ForceCurve, fit: Option<&QuickFit>) -> Result<()> {
    let title = source_name(&curve.source);
    if let Some(f) = fit {
        let series = [
            plot::Series {
                label: "data",
                x: &f.x,
                y: &f.data,
            },
            plot::Series {
                label: "fit",
                x: &f.x,
                y: &f.model_force,
            },
        ];
        let title = format!("{title}: data vs fit");
        return plot::write_svg(path, &title, f.x_label, f.y_label, &series);
    }
    let forces: Vec<Vec<f64>> = curve
        .segments
        .iter()
        .map(|s| s.force().map(|f| f.iter().map(|v| v * 1e9).collect()))
        .collect::<Result<_>>()?;
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
    plot::write_svg(path, &title, "time (s)", "force (nN)", &series)
}

/// Smallest and largest value.
pub fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// The text summary of a curve (`n_curves`: curves in its file).
pub fn summary_text(c: &ForceCurve, n_curves: usize) -> String {
    let mut out = String::new();
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
            let (lo, hi) = range(&ch.values);
            let _ = writeln!(
                out,
                "      {:<18} [{}] via {:<10} {lo:.6e} .. {hi:.6e}",
                ch.name, ch.unit, ch.conversion
            );
        }
    }
    out
}

/// The JSON summary of a curve (`n_curves`: curves in its file); with
/// `samples`, every segment's `time_s` and every channel's `values` too.
pub fn summary_json(c: &ForceCurve, n_curves: usize, samples: bool) -> serde_json::Value {
    let source = |s| format!("{s:?}").to_lowercase();
    json!({
        "source": c.source,
        "curves_in_file": n_curves,
        "format_version": c.format_version,
        "instrument": c.instrument,
        "position_m": c.position.map(|(x, y)| [x, y]),
        "calibration": {
            "spring_constant_N_per_m": c.calibration.spring_constant,
            "spring_constant_source": source(c.calibration.spring_constant_source),
            "sensitivity_m_per_V": c.calibration.sensitivity,
            "sensitivity_source": source(c.calibration.sensitivity_source),
        },
        "segments": c.segments.iter().map(|s| {
            let mut seg = json!({
                "index": s.index, "kind": s.kind.as_str(), "name": s.name,
                "points": s.len(), "duration_s": s.duration,
                "t_start_s": s.time.first(), "t_end_s": s.time.last(),
                "channels": s.channels.iter().map(|ch| {
                    let (min, max) = range(&ch.values);
                    let mut v = json!({ "name": ch.name, "unit": ch.unit,
                        "conversion": ch.conversion, "min": min, "max": max });
                    if samples {
                        v["values"] = json!(ch.values);
                    }
                    v
                }).collect::<Vec<_>>(),
            });
            if samples {
                seg["time_s"] = json!(s.time);
            }
            seg
        }).collect::<Vec<_>>(),
    })
}

/// One row of a batch `nlvid inspect`: the curve's calibration and segments, and the
/// quick fit's values (unit-suffixed keys) if one was asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct InspectRow {
    /// The quick fit's model (`hertz-paraboloid`, …), `None` without a fit.
    pub model: Option<&'static str>,
    /// `(key with unit suffix, value)`: `spring_constant_N_per_m`,
    /// `sensitivity_m_per_V`, `segments`, `points`, `duration_s`, then the fit's values
    /// and, for a Prony fit, `term<k>_g_Pa` (`term<k>_j_per_Pa` in creep) and
    /// `term<k>_tau_s`.
    pub values: Vec<(String, f64)>,
}

/// The row of one curve: its summary, and `fit` = (kind, probe radius m) run on it.
///
/// # Errors
/// As [`quick_fit`].
pub fn inspect_row(
    curve: &ForceCurve,
    fit: Option<(QuickFitKind, f64)>,
    method: ContactMethod,
) -> Result<InspectRow> {
    let cal = &curve.calibration;
    let mut values = vec![
        ("spring_constant_N_per_m".to_string(), cal.spring_constant),
        ("sensitivity_m_per_V".to_string(), cal.sensitivity),
        ("segments".to_string(), curve.segments.len() as f64),
        (
            "points".to_string(),
            curve.segments.iter().map(|s| s.len()).sum::<usize>() as f64,
        ),
        (
            "duration_s".to_string(),
            curve.segments.iter().map(|s| s.duration).sum(),
        ),
    ];
    let Some((kind, r)) = fit else {
        return Ok(InspectRow {
            model: None,
            values,
        });
    };
    let f = quick_fit(curve, kind, r, method)?;
    values.extend(f.values);
    let g_key = if f.model == "lee-radok-creep" {
        "j_per_Pa"
    } else {
        "g_Pa"
    };
    for (k, (g, tau)) in f.terms.iter().enumerate() {
        values.push((format!("term{}_{g_key}", k + 1), *g));
        values.push((format!("term{}_tau_s", k + 1), *tau));
    }
    Ok(InspectRow {
        model: Some(f.model),
        values,
    })
}

/// `nlvid inspect FILE`: one curve of an instrument file, the number of
/// curves the file holds, and the quick fit asked for.
#[derive(Debug)]
pub struct Inspection {
    /// The curve.
    pub curve: ForceCurve,
    /// Curves in its file.
    pub n_curves: usize,
    /// The quick fit, if one was asked for.
    pub fit: Option<QuickFit>,
}

impl Inspection {
    /// `curve` (one of the `n_curves` of its file) with the quick fit `fit`
    /// = (kind, probe radius m), if given ([`quick_fit`]).
    ///
    /// # Errors
    /// As [`quick_fit`].
    pub fn new(
        curve: ForceCurve,
        n_curves: usize,
        fit: Option<(QuickFitKind, f64)>,
        method: ContactMethod,
    ) -> Result<Self> {
        let fit = match fit {
            Some((kind, r)) => Some(quick_fit(&curve, kind, r, method)?),
            None => None,
        };
        Ok(Self {
            curve,
            n_curves,
            fit,
        })
    }

    /// [`summary_json`] (with every sample if `samples`) and the fit under `fit`.
    pub fn to_json(&self, samples: bool) -> serde_json::Value {
        let mut v = summary_json(&self.curve, self.n_curves, samples);
        if let Some(f) = &self.fit {
            v["fit"] = f.to_json();
        }
        v
    }

    /// [`summary_text`], the fit's line, and one line per file `written`
    /// (`(what, path)`, e.g. `("CSV", …)`).
    pub fn text(&self, written: &[(&str, &Path)]) -> String {
        let mut out = summary_text(&self.curve, self.n_curves);
        if let Some(f) = &self.fit {
            out += &format!("\n{}\n", f.text);
        }
        for (what, p) in written {
            out += &format!("{what} written to {}\n", p.display());
        }
        out
    }
}

/// What a batch reports on stderr: one `failed: …` line per failure, and
/// a line on the files of folders that are not AFM files.
pub fn batch_warnings<T>(batch: &Batch<T>) -> Vec<String> {
    let mut out: Vec<String> = batch
        .failures
        .iter()
        .map(|f| format!("failed: {f}"))
        .collect();
    if let Some(first) = batch.ignored.first() {
        out.push(format!(
            "skipped {} file(s) that are not AFM files (e.g. {})",
            batch.ignored.len(),
            first.display()
        ));
    }
    out
}

/// `nlvid inspect` on many files: every curve of `inputs` (files, maps, folders, globs;
/// [`crate::batch::for_each_curve_with`]) summarised and optionally fitted, one row per
/// curve; curves that fail are listed with their reason and the batch goes on.
///
/// # Errors
/// Only nonsensical calibration overrides in `options`.
pub fn inspect_batch<P: AsRef<Path>>(
    inputs: &[P],
    options: &ReadOptions,
    fit: Option<(QuickFitKind, f64)>,
    method: ContactMethod,
    progress: &dyn Progress,
) -> Result<Batch<InspectRow>> {
    for_each_curve_with(inputs, options, |c| inspect_row(c, fit, method), progress)
}

/// Quote a CSV field if it needs it (RFC 4180).
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The column keys of a batch's rows, in first-seen order.
fn batch_keys(batch: &Batch<InspectRow>) -> Vec<&str> {
    let mut keys: Vec<&str> = Vec::new();
    for row in &batch.rows {
        for (k, _) in &row.value.values {
            if !keys.contains(&k.as_str()) {
                keys.push(k);
            }
        }
    }
    keys
}

/// A batch as CSV: `file,curve,status,reason,model,<keys…>`, one row per curve analysed
/// (`status` `ok`) then one per failure (`status` `failed`, `reason` the message, values
/// empty); `curve` is empty for a single-curve file or a file that failed as a whole.
pub fn batch_csv(batch: &Batch<InspectRow>) -> String {
    let keys = batch_keys(batch);
    let mut out = String::from("file,curve,status,reason,model");
    for k in &keys {
        out.push(',');
        out += &csv_field(k);
    }
    out.push('\n');
    let curve = |c: Option<usize>| c.map(|i| i.to_string()).unwrap_or_default();
    for row in &batch.rows {
        let v = &row.value;
        let _ = write!(
            out,
            "{},{},ok,,{}",
            csv_field(&row.file.display().to_string()),
            curve(row.curve),
            v.model.unwrap_or("")
        );
        for k in &keys {
            out.push(',');
            if let Some((_, x)) = v.values.iter().find(|(key, _)| key == k) {
                let _ = write!(out, "{x:e}");
            }
        }
        out.push('\n');
    }
    for f in &batch.failures {
        let _ = write!(
            out,
            "{},{},failed,{},",
            csv_field(&f.file.display().to_string()),
            curve(f.curve),
            csv_field(&f.error.to_string())
        );
        out += &",".repeat(keys.len());
        out.push('\n');
    }
    out
}

/// A batch as JSON: `rows` (`file`, `curve`, `model`, the values by key), `failures`
/// (`file`, `curve`, `reason`) and `ignored` (files of folders that are not AFM files).
pub fn batch_json(batch: &Batch<InspectRow>) -> serde_json::Value {
    let rows: Vec<serde_json::Value> = batch
        .rows
        .iter()
        .map(|r| {
            let mut m = serde_json::Map::new();
            m.insert("file".into(), json!(r.file.display().to_string()));
            m.insert("curve".into(), json!(r.curve));
            m.insert("model".into(), json!(r.value.model));
            for (k, x) in &r.value.values {
                m.insert(k.clone(), json!(x));
            }
            m.into()
        })
        .collect();
    let failures: Vec<serde_json::Value> = batch
        .failures
        .iter()
        .map(|f| {
            json!({"file": f.file.display().to_string(), "curve": f.curve,
                   "reason": f.error.to_string()})
        })
        .collect();
    let ignored: Vec<String> = batch
        .ignored
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    json!({"curves": batch.rows.len(), "failed": batch.failures.len(),
           "rows": rows, "failures": failures, "ignored": ignored})
}
