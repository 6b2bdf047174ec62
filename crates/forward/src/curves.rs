//! The curve writer: synthetic AFM force curves of a study's forward model
//! at a list of parameter sets, in the format of a measured curve (`time
//! [s]`, `piezo [um]`, `deflection [nm]`, the columns `nlvid fit` and
//! `nlvid cohort` read), with seeded Gaussian measurement noise on the
//! deflection. Used by `nlvid simulate --parameters` and by the bundled
//! demo's data generator (`nlvid_report::demo`).
//!
//! - `afm-fe`: the FE cell model with a spring cantilever, its outputs
//!   written at the requested sample times by the solver's dense output
//!   (docs/theory/fem.md, "Dense output"): Z(t) the piezo program, the
//!   deflection F/k.
//! - `hertz-prony`: the analytic Lee–Radok ramp-hold on its own output grid
//!   (the sample times must be 0 or points of that grid); its indentation
//!   δ(t) is known in closed form, so Z = δ + F/k with the caller's k.
//!
//! Noise: N(0, σ²) on the force, σ = `relative` × the curve's peak
//! (noise-free) force, written on the deflection as σ/k; each curve draws
//! from its own ChaCha8 stream seeded by (`seed`, index of the set), so a
//! curve's noise does not depend on the other sets or on the thread that
//! ran it.

use std::fmt::Write as _;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{ForwardError, Result};
use crate::{ForwardSettings, ForwardSpec, fem_failure};
use nlvid_model::Curve;

/// Measurement noise of the written curves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Standard deviation as a fraction of each curve's peak force.
    pub relative: f64,
    /// Seed of the noise streams.
    pub seed: u64,
}

/// One synthetic AFM curve is an [`nlvid_model::Curve`] on the forward
/// model's clock (0 at the start of the piezo program) with the channels
/// of `nlvid simulate`'s AFM curves: `piezo` (Z, m), `deflection`
/// ((F + noise)/k, m) and `force` (noise-free F, N).
fn afm_samples(time: Vec<f64>, piezo: Vec<f64>, force: Vec<f64>, k: f64) -> Result<Curve> {
    let deflection = force.iter().map(|f| f / k).collect();
    Curve::new(time)
        .and_then(|c| c.with("piezo", "m", piezo))
        .and_then(|c| c.with("deflection", "m", deflection))
        .and_then(|c| c.with("force", "N", force))
        .map_err(|e| setting("curve writer", e.to_string()))
}

/// A channel of a curve made by [`afm_curve`] (empty if absent).
fn channel<'a>(curve: &'a Curve, name: &str) -> &'a [f64] {
    curve.values(name).unwrap_or_default()
}

/// An AFM curve of [`afm_curve`] as the CSV of a measured curve:
/// `time [s]`, `piezo [um]`, `deflection [nm]`, 4 / 6 / 4 decimals.
pub fn measured_csv(curve: &Curve) -> String {
    let (piezo, deflection) = (channel(curve, "piezo"), channel(curve, "deflection"));
    let mut csv = String::from("time [s],piezo [um],deflection [nm]\n");
    for (i, t) in curve.time().iter().enumerate() {
        let _ = writeln!(
            csv,
            "{:.4},{:.6},{:.4}",
            t,
            piezo[i] * 1e6,
            deflection[i] * 1e9
        );
    }
    csv
}

/// Largest noise-free force [N] of a curve of [`afm_curve`].
pub fn peak_force(curve: &Curve) -> f64 {
    channel(curve, "force")
        .iter()
        .fold(0.0f64, |a, &b| a.max(b))
}

/// A standard normal deviate by Box–Muller (u1 in (0, 1]).
pub fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

fn setting(model: &'static str, message: String) -> ForwardError {
    ForwardError::Setting { model, message }
}

/// The noise-free curve of `forward` at parameters `x` (model order,
/// SI) at the sample times `times` [s]. `spring_constant` [N/m] is the
/// cantilever's: for `afm-fe` it must equal `[forward] spring_constant`
/// (the FE model deflects that spring); for `hertz-prony` (a rigid
/// indenter model) it converts the force into the deflection column.
///
/// # Errors
/// A model that cannot write AFM curves (membrane, a rigid afm-fe
/// cantilever), a spring constant that disagrees with the model's, sample
/// times off the hertz-prony grid, or a failed run (with its message).
pub fn afm_curve(
    forward: &ForwardSettings,
    x: &[f64],
    times: &[f64],
    spring_constant: f64,
) -> Result<Curve> {
    if !(spring_constant > 0.0 && spring_constant.is_finite()) {
        return Err(setting(
            "curve writer",
            format!("spring constant {spring_constant} N/m: must be positive"),
        ));
    }
    if times.windows(2).any(|w| !(w[1] > w[0])) || times.iter().any(|t| !t.is_finite()) {
        return Err(setting(
            "curve writer",
            "sample times must be finite and increasing".into(),
        ));
    }
    match &forward.spec {
        ForwardSpec::AfmFe(spec) => {
            let Some(k) = spec.spring_constant else {
                return Err(setting(
                    "afm-fe",
                    "the curve writer needs a spring cantilever ([forward] spring_constant), \
                     not cantilever = \"rigid\": a rigid probe has no deflection"
                        .into(),
                ));
            };
            if (k / spring_constant - 1.0).abs() > 1e-12 {
                return Err(setting(
                    "afm-fe",
                    format!(
                        "[forward] spring_constant = {k} N/m but the curves are written for a \
                         {spring_constant} N/m cantilever"
                    ),
                ));
            }
            let mut setup = spec.setup()?;
            let end = setup.piezo.last().map_or(0.0, |p| p.0);
            if let Some(&t) = times.iter().find(|&&t| t < 0.0 || t > end * (1.0 + 1e-12)) {
                return Err(setting(
                    "afm-fe",
                    format!("sample time {t} s outside the piezo program [0, {end} s]"),
                ));
            }
            setup.output_times = times.to_vec();
            let params = nlvid_model::Relaxation::from_named(&nlvid_model::names::PRONY2, x)
                .map_err(|e| setting("afm-fe", e.to_string()))?;
            let run = nlvid_fem::afm::run(&params, &setup)
                .map_err(|e| setting("afm-fe", fem_failure(&e).to_string()))?;
            afm_samples(run.time, run.piezo, run.force, k)
        }
        ForwardSpec::HertzProny(spec) => {
            let model = spec.build()?;
            let grid = nlvid_model::ForwardModel::time_grid(&model).to_vec();
            let f = nlvid_model::ForwardModel::run(&model, x)
                .map_err(|e| setting("hertz-prony", e.to_string()))?;
            let mut force = Vec::with_capacity(times.len());
            for &t in times {
                if t == 0.0 {
                    force.push(0.0);
                    continue;
                }
                let j = grid.partition_point(|&g| g < t * (1.0 - 1e-9));
                match grid.get(j) {
                    Some(&g) if (g - t).abs() <= 1e-9 * t.abs().max(1.0) => force.push(f[j]),
                    _ => {
                        return Err(setting(
                            "hertz-prony",
                            format!(
                                "sample time {t} s is not on the model's output grid \
                                 ({} points over (0, {} s])",
                                grid.len(),
                                spec.ramp + spec.hold
                            ),
                        ));
                    }
                }
            }
            let piezo = times
                .iter()
                .zip(&force)
                .map(|(&t, &f)| spec.indentation(t) + f / spring_constant)
                .collect();
            afm_samples(times.to_vec(), piezo, force, spring_constant)
        }
        ForwardSpec::Membrane(_) => Err(setting(
            "membrane",
            "the curve writer writes AFM curves (afm-fe, hertz-prony); the membrane model is \
             run by `nlvid membrane`"
                .into(),
        )),
        ForwardSpec::CapsuleFe(_) => Err(setting(
            "capsule-fe",
            "the curve writer writes AFM curves (afm-fe, hertz-prony); capsule curves are \
             written by `nlvid simulate` (examples/capsule/regenerate.sh)"
                .into(),
        )),
    }
}

/// Adds the measurement noise of curve number `index` to its deflection
/// (σ = `noise.relative` × peak force, divided by k).
///
/// # Errors
/// As [`add_noise_from`].
pub fn add_noise(
    curve: &mut Curve,
    noise: Noise,
    index: usize,
    spring_constant: f64,
) -> Result<()> {
    if !(noise.relative > 0.0) {
        return Ok(());
    }
    let mut rng = ChaCha8Rng::seed_from_u64(noise.seed);
    rng.set_stream(index as u64);
    add_noise_from(curve, noise.relative, &mut rng, spring_constant)
}

/// Adds noise of sd `relative` × peak force to the deflection, one
/// deviate per sample in time order from `rng` (the caller's stream).
///
/// # Errors
/// A noisy deflection that is not finite (a non-finite `relative` or
/// spring constant).
pub fn add_noise_from(
    curve: &mut Curve,
    relative: f64,
    rng: &mut ChaCha8Rng,
    spring_constant: f64,
) -> Result<()> {
    let sd = relative * peak_force(curve);
    let deflection = channel(curve, "force")
        .iter()
        .map(|&f| (f + sd * standard_normal(rng)) / spring_constant)
        .collect();
    curve
        .replace("deflection", deflection)
        .map_err(|e| setting("curve writer", e.to_string()))
}

/// The curves of every parameter set in `sets` (each in model order, SI),
/// with noise, run in parallel on the current rayon pool (results in the
/// order of `sets`, bitwise independent of the number of threads).
///
/// # Errors
/// As [`afm_curve`]; the first failing set (by index) is reported with its
/// index and parameters.
pub fn afm_curves(
    forward: &ForwardSettings,
    sets: &[Vec<f64>],
    times: &[f64],
    spring_constant: f64,
    noise: Noise,
) -> Result<Vec<Curve>> {
    if !(noise.relative >= 0.0 && noise.relative.is_finite()) {
        return Err(setting(
            "curve writer",
            format!("noise {}: must be a finite fraction ≥ 0", noise.relative),
        ));
    }
    sets.par_iter()
        .enumerate()
        .map(|(i, x)| {
            let mut c = afm_curve(forward, x, times, spring_constant).map_err(|e| {
                setting(
                    "curve writer",
                    format!("parameter set {} ({x:?}): {e}", i + 1),
                )
            })?;
            add_noise(&mut c, noise, i, spring_constant)?;
            Ok(c)
        })
        .collect()
}

/// Reads a table of parameter sets: a CSV whose header names the model's
/// parameters (`names`, any order, SI values) and optionally a `name`
/// column (the curve's file stem; default `curve-001`, …). Blank lines and
/// lines starting with `#` are skipped.
///
/// # Errors
/// A missing or unknown column, a value that is not a finite number, no
/// rows — each naming the file and line.
pub fn read_parameter_sets(
    text: &str,
    file: &str,
    names: &[String],
) -> Result<Vec<(String, Vec<f64>)>> {
    let bad =
        |line: usize, message: String| setting("curve writer", format!("{file}:{line}: {message}"));
    let mut rows = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((h, header)) = rows.next() else {
        return Err(bad(
            1,
            "empty table: expected a header naming the parameters".into(),
        ));
    };
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let name_col = cols.iter().position(|c| *c == "name");
    if let Some(c) = cols
        .iter()
        .find(|c| **c != "name" && !names.iter().any(|n| n == *c))
    {
        return Err(bad(
            h + 1,
            format!(
                "unknown column `{c}`: the model's parameters are {}",
                names.join(", ")
            ),
        ));
    }
    let mut index = Vec::with_capacity(names.len());
    for n in names {
        match cols.iter().position(|c| c == n) {
            Some(j) => index.push(j),
            None => return Err(bad(h + 1, format!("missing column `{n}` (SI units)"))),
        }
    }
    let mut sets = Vec::new();
    for (l, line) in rows {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != cols.len() {
            return Err(bad(
                l + 1,
                format!("{} values for {} columns", cells.len(), cols.len()),
            ));
        }
        let mut x = Vec::with_capacity(names.len());
        for (n, &j) in names.iter().zip(&index) {
            match cells[j].parse::<f64>() {
                Ok(v) if v.is_finite() => x.push(v),
                _ => {
                    return Err(bad(
                        l + 1,
                        format!("`{n}` = `{}`: not a finite number", cells[j]),
                    ));
                }
            }
        }
        let name = match name_col {
            Some(j) if !cells[j].is_empty() => cells[j].to_string(),
            _ => format!("curve-{:03}", sets.len() + 1),
        };
        sets.push((name, x));
    }
    if sets.is_empty() {
        return Err(bad(h + 1, "no parameter sets below the header".into()));
    }
    Ok(sets)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        nlvid_model::names::PRONY2.map(String::from).to_vec()
    }

    #[test]
    fn parameter_table_reads_named_and_unnamed_rows_in_any_column_order() {
        let t = "# sets\nname,g1,G0,g2,tau1,tau2\na,0.3,1000,0.2,0.5,10\n,0.1,500,0.1,1,5\n";
        let s = read_parameter_sets(t, "p.csv", &names()).expect("table");
        assert_eq!(s[0], ("a".into(), vec![1000.0, 0.3, 0.2, 0.5, 10.0]));
        assert_eq!(s[1], ("curve-002".into(), vec![500.0, 0.1, 0.1, 1.0, 5.0]));
    }

    #[test]
    fn parameter_table_errors_name_file_line_and_column() {
        let e = read_parameter_sets("G0,g1,g2,tau1\n1,2,3,4\n", "p.csv", &names())
            .expect_err("missing tau2")
            .to_string();
        assert!(e.contains("p.csv:1") && e.contains("tau2"), "{e}");
        let e = read_parameter_sets("G0,g1,g2,tau1,tau2\n1,x,3,4,5\n", "p.csv", &names())
            .expect_err("bad number")
            .to_string();
        assert!(e.contains("p.csv:2") && e.contains("g1"), "{e}");
    }

    fn forward(text: &str) -> ForwardSettings {
        let mut study = nlvid_study::Study::parse("s.toml", text).expect("toml");
        ForwardSettings::from_study(&mut study).expect("forward")
    }

    /// hertz-prony: Z − d is the nominal indentation 2 µm/s · min(t, 1 s)
    /// (closed form), d·k the model's force on its grid, 0 at t = 0.
    #[test]
    fn hertz_curve_piezo_minus_deflection_is_the_nominal_indentation() {
        let fwd = forward(&crate::hertz_forward_toml(
            "2.5 um", "2 um/s", "1 s", "3 s", 40,
        ));
        let x = [1000.0, 0.3, 0.2, 0.5, 10.0];
        let times: Vec<f64> = std::iter::once(0.0)
            .chain((1..=40).map(|i| 4.0 * i as f64 / 40.0))
            .collect();
        let k = 0.12;
        let c = afm_curve(&fwd, &x, &times, k).expect("curve");
        let model = fwd.build().expect("model");
        let f = model.run(&x).expect("run");
        let (piezo, deflection) = (channel(&c, "piezo"), channel(&c, "deflection"));
        for (i, &t) in times.iter().enumerate() {
            let delta = 2e-6 * t.min(1.0);
            assert!((piezo[i] - deflection[i] - delta).abs() < 1e-18, "t = {t}");
            let expected = if i == 0 { 0.0 } else { f[i - 1] };
            assert_eq!(deflection[i], expected / k, "t = {t}");
        }
        let e = afm_curve(&fwd, &x, &[0.05], k)
            .expect_err("off the grid")
            .to_string();
        assert!(e.contains("not on the model's output grid"), "{e}");
    }

    /// Settings the writer refuses, each before any FE run.
    #[test]
    fn afm_fe_writer_refuses_a_rigid_probe_a_foreign_spring_and_bad_times() {
        let fe = "[forward]\nmodel = \"afm-fe\"\nheight = \"12.22 um\"\n\
            diameter = \"28.88 um\"\npoints = 11\n";
        let protocol = "[protocol]\nkind = \"ramp-hold\"\ndisplacement = \"2 um\"\n\
            speed = \"2 um/s\"\nhold = \"1 s\"\n";
        let x = [1000.0, 0.3, 0.2, 0.5, 10.0];
        let rigid = forward(&format!("{fe}cantilever = \"rigid\"\n{protocol}"));
        let e = afm_curve(&rigid, &x, &[0.0, 1.0], 0.12)
            .expect_err("rigid")
            .to_string();
        assert!(e.contains("spring cantilever"), "{e}");
        let spring = forward(&format!("{fe}spring_constant = \"0.12 N/m\"\n{protocol}"));
        let e = afm_curve(&spring, &x, &[0.0, 1.0], 0.1)
            .expect_err("k")
            .to_string();
        assert!(e.contains("spring_constant"), "{e}");
        let e = afm_curve(&spring, &x, &[0.0, 5.0], 0.12)
            .expect_err("late")
            .to_string();
        assert!(e.contains("outside the piezo program"), "{e}");
        let e = afm_curve(&spring, &x, &[1.0, 0.5], 0.12)
            .expect_err("order")
            .to_string();
        assert!(e.contains("increasing"), "{e}");
    }

    /// Noise: per-curve streams, σ = relative × peak, zero mean; the
    /// sample sd of 20000 draws is within 2 % of σ.
    #[test]
    fn noise_has_the_requested_sd_and_depends_only_on_seed_and_index() {
        let n = 20_000;
        let force: Vec<f64> = (0..n).map(|i| if i == 0 { 2e-8 } else { 1e-8 }).collect();
        let time = (0..n).map(|i| i as f64).collect();
        let clean = afm_samples(time, vec![0.0; n], force.clone(), 1.0).expect("curve");
        let noise = Noise {
            relative: 0.01,
            seed: 7,
        };
        let k = 0.1;
        let mut a = clean.clone();
        add_noise(&mut a, noise, 3, k).expect("noise");
        let mut b = clean.clone();
        add_noise(&mut b, noise, 3, k).expect("noise");
        let mut c = clean.clone();
        add_noise(&mut c, noise, 4, k).expect("noise");
        assert_eq!(a, b);
        assert_ne!(channel(&a, "deflection"), channel(&c, "deflection"));
        assert_eq!(channel(&a, "force"), &force[..]);
        let e: Vec<f64> = channel(&a, "deflection")
            .iter()
            .zip(&force)
            .map(|(d, f)| d * k - f)
            .collect();
        let mean = e.iter().sum::<f64>() / n as f64;
        let sd = (e.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64).sqrt();
        let sigma = 0.01 * 2e-8;
        assert!((sd / sigma - 1.0).abs() < 0.02, "sd {sd} vs {sigma}");
        assert!(mean.abs() < 4.0 * sigma / (n as f64).sqrt(), "mean {mean}");
    }
}

/// `nlvid simulate --parameters`: a study's forward model (`[forward]`,
/// `[protocol]`) and a table of parameter sets, written as one measured
/// curve per set.
#[derive(Debug)]
pub struct CurveJob {
    /// The forward model's settings.
    pub forward: ForwardSettings,
    /// `(file stem, parameters in model order)` per curve.
    pub sets: Vec<(String, Vec<f64>)>,
    /// Noise on the deflection.
    pub noise: Noise,
    /// Cantilever spring constant of the deflection column (N/m).
    pub spring_constant: f64,
}

impl CurveJob {
    /// Reads the study's `[forward]` (other stages' sections are left to
    /// them) and the parameter table. `spring_constant` (N/m) is required
    /// for rigid-indenter models and refused for `afm-fe`, which deflects
    /// its own `[forward] spring_constant`.
    ///
    /// # Errors
    /// Study errors (file, line, key); a missing or refused spring
    /// constant; an unreadable or malformed table (file, line).
    pub fn load(
        study: &std::path::Path,
        table: &std::path::Path,
        spring_constant: Option<f64>,
        noise: Noise,
    ) -> Result<Self> {
        let mut s = nlvid_study::Study::load(study)?;
        let forward = ForwardSettings::from_study(&mut s)?;
        for other in [
            "parameters",
            "design",
            "build",
            "fit",
            "probe",
            "material",
            "loading",
        ] {
            s.root().skip(other);
        }
        let _ = s.root().opt_str("title")?;
        s.finish()?;
        let spring_constant = match (&forward.spec, spring_constant) {
            (ForwardSpec::AfmFe(spec), None) => spec.spring_constant.ok_or_else(|| {
                setting(
                    "curve writer",
                    format!(
                        "{}: the curve writer needs a spring cantilever ([forward] spring_constant)",
                        study.display()
                    ),
                )
            })?,
            (ForwardSpec::AfmFe(_), Some(_)) => {
                return Err(setting(
                    "curve writer",
                    "--spring-constant: afm-fe deflects its own [forward] spring_constant".into(),
                ));
            }
            (_, Some(k)) => k,
            (_, None) => {
                return Err(setting(
                    "curve writer",
                    "--spring-constant (N/m) is needed for the deflection column of a \
                     rigid-indenter model"
                        .into(),
                ));
            }
        };
        let names = forward.build()?.parameter_names();
        let text = std::fs::read_to_string(table).map_err(|e| {
            setting(
                "curve writer",
                format!("cannot read {}: {e}", table.display()),
            )
        })?;
        let sets = read_parameter_sets(&text, &table.display().to_string(), &names)?;
        Ok(Self {
            forward,
            sets,
            noise,
            spring_constant,
        })
    }

    /// One line on what [`CurveJob::write`] wrote: `files` of `samples`
    /// samples each into `out_dir`, with the noise.
    pub fn summary(&self, files: usize, samples: usize, out_dir: &std::path::Path) -> String {
        format!(
            "wrote {files} curves ({samples} samples each, noise {} of the peak force, seed {}) into {}\n",
            self.noise.relative,
            self.noise.seed,
            out_dir.display()
        )
    }

    /// Runs every set (in parallel) and writes `<stem>.csv` into `out_dir`
    /// atomically; returns the files and the number of samples per curve.
    ///
    /// # Errors
    /// A failed run (its model's message); a file that cannot be written.
    pub fn write(&self, out_dir: &std::path::Path) -> Result<(Vec<std::path::PathBuf>, usize)> {
        let model = self.forward.build()?;
        let times = model.time_grid().to_vec();
        let xs: Vec<Vec<f64>> = self.sets.iter().map(|s| s.1.clone()).collect();
        let curves = afm_curves(&self.forward, &xs, &times, self.spring_constant, self.noise)?;
        std::fs::create_dir_all(out_dir).map_err(|e| {
            setting(
                "curve writer",
                format!("cannot create {}: {e}", out_dir.display()),
            )
        })?;
        let mut files = Vec::with_capacity(curves.len());
        for ((name, _), c) in self.sets.iter().zip(&curves) {
            let path = out_dir.join(format!("{name}.csv"));
            nlvid_study::write_atomic(&path, measured_csv(c).as_bytes()).map_err(|e| {
                setting(
                    "curve writer",
                    format!("cannot write {}: {e}", path.display()),
                )
            })?;
            files.push(path);
        }
        Ok((files, times.len()))
    }
}
