//! `nlvid inspect FILE`: what an AFM instrument file holds (segments,
//! channels, calibration), optionally exported as CSV, plotted as SVG, and
//! given a quick Hertz or Lee–Radok fit ([`nlvid_afm::quick_fit`]).
//! `nlvid inspect FILES… | FOLDER | 'GLOB'`: one row per curve
//! ([`nlvid_afm::inspect_batch`]), failures listed, a progress bar. See
//! docs/cli/inspect.md.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args as ClapArgs, ValueEnum};
use nlvid_afm::{ContactMethod, Inspection, QuickFitKind, ReadOptions};
use nlvid_study::Dimension;

use crate::output::{emit, write_atomic};

/// A quantity with a unit, or a bare number in SI.
/// A positive quantity in SI (a bare number is taken as SI); negative
/// values reach here (`allow_hyphen_values`) and are refused by name.
fn si(text: &str, dim: Dimension) -> Result<f64, String> {
    let v = match nlvid_study::Quantity::parse(text) {
        Ok(q) if q.dim == Dimension::NONE => q.value,
        _ => crate::args::quantity(text, dim)?,
    };
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("`{text}` must be positive"))
    }
}

/// Arguments of `nlvid inspect`.
#[derive(Debug, ClapArgs)]
pub struct Args {
    /// AFM file (.jpk-force, .jpk-force-map, .jpk-qi-data, .ibw); several files,
    /// folders (searched recursively) or quoted globs ("data/*.jpk-force") run a batch:
    /// one row per curve (CSV on stdout, or JSON), failures listed.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Batch: write the per-curve table (CSV) to this file instead of stdout.
    #[arg(long, value_name = "CSV")]
    pub table: Option<PathBuf>,
    /// Write every segment and channel as CSV (unit-suffixed headers) to this file.
    #[arg(long, value_name = "CSV")]
    pub csv: Option<PathBuf>,
    /// Write an SVG plot: force vs time, or data vs fit with --fit.
    #[arg(long, value_name = "SVG")]
    pub plot: Option<PathBuf>,
    /// With --json: include every sample (time and channel values of each segment).
    #[arg(long)]
    pub samples: bool,
    /// Spring constant replacing the file's, e.g. "0.12 N/m" (needed if the file has none).
    #[arg(long, value_name = "K", allow_hyphen_values = true, value_parser = |s: &str| si(s, Dimension::STIFFNESS))]
    pub spring_constant: Option<f64>,
    /// Deflection sensitivity replacing the file's, e.g. "110.28 nm/V".
    #[arg(long, value_name = "S", allow_hyphen_values = true, value_parser = |s: &str| si(s, Dimension::LENGTH_PER_VOLTAGE))]
    pub sensitivity: Option<f64>,
    /// Curve of a force map to inspect (0-based).
    #[arg(long, default_value_t = 0)]
    pub curve: usize,
    /// Quick fit: Hertz (paraboloid) on the approach, or Lee–Radok Prony on a ramp-hold.
    #[arg(long, value_enum)]
    pub fit: Option<Fit>,
    /// Probe radius for --fit, e.g. "40 nm" or "5 um" (not stored in JPK files).
    #[arg(long, value_name = "R", allow_hyphen_values = true, value_parser = |s: &str| si(s, Dimension::LENGTH))]
    pub tip_radius: Option<f64>,
    /// Poisson ratio of the sample for --fit hertz.
    #[arg(long, default_value_t = 0.5)]
    pub poisson: f64,
    /// Prony terms for --fit lee-radok (1 to 3).
    #[arg(long, default_value_t = 2)]
    pub terms: usize,
    /// Contact-point method: deviation (from the baseline by 5 noise standard
    /// deviations) or piecewise (constant + line least-squares fit).
    #[arg(long, default_value = "deviation", value_parser = ContactMethod::from_name)]
    pub contact: ContactMethod,
}

/// Fits `inspect` can run.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Fit {
    /// Paraboloidal Hertz fit (eq. 1.1), E and contact point free.
    Hertz,
    /// Lee–Radok Prony fit of the extend + hold segments.
    LeeRadok,
}

/// A progress bar over the files of a batch ([`crate::progress::bar`]).
struct Bar(indicatif::ProgressBar);

impl nlvid_afm::Progress for Bar {
    fn start(&self, files: usize) {
        self.0.set_length(files as u64);
    }
    fn file_done(&self) {
        self.0.inc(1);
    }
}

impl Args {
    /// True when the inputs are a batch: several, a folder, a glob, or `--table`.
    fn is_batch(&self) -> bool {
        let f = &self.files[0];
        self.files.len() > 1
            || self.table.is_some()
            || f.is_dir()
            || (!f.exists() && f.to_string_lossy().contains(['*', '?', '[']))
    }

    /// The fit asked for: (kind, probe radius).
    fn fit_kind(&self) -> anyhow::Result<Option<(QuickFitKind, f64)>> {
        let Some(kind) = self.fit else {
            return Ok(None);
        };
        let r = self
            .tip_radius
            .context("--fit needs --tip-radius (the probe radius is not stored in JPK files)")?;
        let kind = match kind {
            Fit::Hertz => QuickFitKind::Hertz {
                poisson: self.poisson,
            },
            Fit::LeeRadok => QuickFitKind::LeeRadok { terms: self.terms },
        };
        Ok(Some((kind, r)))
    }

    fn read_options(&self) -> ReadOptions {
        ReadOptions {
            spring_constant: self.spring_constant,
            sensitivity: self.sensitivity,
        }
    }

    /// Run the command.
    ///
    /// # Errors
    /// Unreadable file, a missing calibration, a fit that fails, unwritable outputs.
    pub fn run(self, json: bool) -> anyhow::Result<ExitCode> {
        if self.is_batch() {
            return self.run_batch(json);
        }
        for p in [&self.csv, &self.plot].into_iter().flatten() {
            nlvid_study::check_output_file(p)?;
        }
        let file = &self.files[0];
        let curves = nlvid_afm::read_force_map(file, &self.read_options())
            .with_context(|| format!("reading {}", file.display()))?;
        let n_curves = curves.len();
        let curve = curves.into_iter().nth(self.curve).with_context(|| {
            format!("--curve {}: the file holds {n_curves} curve(s)", self.curve)
        })?;
        let one = Inspection::new(curve, n_curves, self.fit_kind()?, self.contact)?;
        if let Some(path) = &self.csv {
            let mut buf = Vec::new();
            one.curve.write_csv(&mut buf)?;
            write_atomic(path, &buf)?;
        }
        if let Some(path) = &self.plot {
            nlvid_afm::write_plot(path, &one.curve, one.fit.as_ref())?;
        }
        let written: Vec<(&str, &std::path::Path)> = [("CSV", &self.csv), ("plot", &self.plot)]
            .into_iter()
            .filter_map(|(what, p)| Some((what, p.as_deref()?)))
            .collect();
        emit(json, &one.to_json(self.samples), &one.text(&written))?;
        Ok(ExitCode::SUCCESS)
    }

    /// Batch mode: one row per curve, failures listed on stderr (and in the table);
    /// exit status 3 when any curve failed, as `nlvid cohort`.
    fn run_batch(self, json: bool) -> anyhow::Result<ExitCode> {
        for (flag, used) in [
            ("--csv", self.csv.is_some()),
            ("--plot", self.plot.is_some()),
            ("--samples", self.samples),
            ("--curve", self.curve != 0),
        ] {
            if used {
                anyhow::bail!(
                    "{flag} applies to one curve of one file; with several files, a folder or \
                     a glob, inspect writes one row per curve (use --table OUT.csv or --json)"
                );
            }
        }
        if let Some(p) = &self.table {
            nlvid_study::check_output_file(p)?;
        }
        let (options, fit) = (self.read_options(), self.fit_kind()?);
        let bar = Bar(crate::progress::bar(0, "files"));
        let batch = nlvid_afm::inspect_batch(&self.files, &options, fit, self.contact, &bar)?;
        bar.0.finish_and_clear();
        for line in nlvid_afm::batch_warnings(&batch) {
            eprintln!("{line}");
        }
        let csv = nlvid_afm::batch_csv(&batch);
        let text = match &self.table {
            Some(p) => {
                write_atomic(p, csv.as_bytes())?;
                let (n, failed) = (batch.rows.len(), batch.failures.len());
                format!(
                    "{n} curve(s) analysed, {failed} failed; table written to {}\n",
                    p.display()
                )
            }
            None => csv,
        };
        emit(json, &nlvid_afm::batch_json(&batch), &text)?;
        if batch.failures.is_empty() {
            Ok(ExitCode::SUCCESS)
        } else {
            eprintln!(
                "error: {} curve(s) or file(s) failed ({} analysed)",
                batch.failures.len(),
                batch.rows.len()
            );
            Ok(ExitCode::from(super::cohort::CELLS_FAILED))
        }
    }
}
