//! The study's `[fit]` section as validated settings (docs/cli/fit.md).
//!
//! One experiment's settings (surrogate, time grid, protocol, segment
//! weights, real model) sit either directly in `[fit]` — then every data
//! file is such an experiment — or in `[[fit.experiment]]` tables, one per
//! data file in command-line order (several experiments at once, §4.4.2).

use std::path::{Path, PathBuf};

use nlvid_inverse::{
    AfmColumns, Calibration, CompressionColumns, Coordinates, ProtocolTolerance, Segment,
};
use nlvid_study::{Bounds, Dimension, Section, Study};

/// What kind of measured data the files hold.
#[derive(Debug, Clone)]
pub enum DataColumns {
    /// AFM: time, piezo Z, deflection (V, m or N) with a calibration.
    Afm(AfmColumns, Calibration),
    /// Plate compression: time, displacement, force, optional contact area.
    Compression(CompressionColumns),
}

/// Expected controlled displacement: ramp at `rate` to `amplitude`, then
/// hold to the end of the surrogate's time grid.
#[derive(Debug, Clone, Copy)]
pub struct Protocol {
    /// Ramp rate (m/s).
    pub rate: f64,
    /// Ramp amplitude (m).
    pub amplitude: f64,
    /// Tolerances of the protocol check.
    pub tolerance: ProtocolTolerance,
}

/// The real forward model that re-checks the optimum.
#[derive(Debug, Clone)]
pub enum RealModelSpec {
    /// Analytic Lee–Radok Hertz, run with each curve's measured indentation.
    LeeRadok {
        /// Probe radius (m).
        radius: f64,
        /// Poisson's ratio.
        poisson: f64,
    },
    /// The model of a study's `[forward]` section (`nlvid_forward`:
    /// hertz-prony, afm-fe, membrane), run on its own grid and interpolated
    /// onto the surrogate's.
    Forward {
        /// The study file holding `[forward]` (default: the fit study).
        study: PathBuf,
    },
}

/// One experiment: which surrogate predicts it, under which protocol.
#[derive(Debug, Clone)]
pub struct ExperimentSettings {
    /// Label (default: the data file's stem).
    pub label: Option<String>,
    /// Model file of `nlvid surrogate fit`.
    pub surrogate: PathBuf,
    /// `meta.json` of `nlvid build --export` (names, time grid).
    pub meta: PathBuf,
    /// JSON of `nlvid --json surrogate check` (its `max` is the checking
    /// error); `None`: the default `<model>.check.json` if it exists.
    pub checking: Option<PathBuf>,
    /// Expected loading.
    pub protocol: Protocol,
    /// Eq. 5.3 weights per time segment.
    pub segments: Vec<Segment>,
    /// Real model for the re-check.
    pub real: Option<RealModelSpec>,
}

/// Everything `[fit]` says.
#[derive(Debug, Clone)]
pub struct FitSettings {
    /// The study file.
    pub study: PathBuf,
    /// Coordinates the surrogates were fitted on.
    pub inputs: Coordinates,
    /// Columns and calibration of the data files.
    pub columns: DataColumns,
    /// Multistart starts.
    pub starts: usize,
    /// Multistart seed.
    pub seed: u64,
    /// Times of the printed G(t), E(t).
    pub modulus_times: Vec<f64>,
    /// Experiments; `repeat` says whether the single one applies to every file.
    pub experiments: Vec<ExperimentSettings>,
    /// True when the experiment settings sit directly in `[fit]`.
    pub repeat: bool,
}

/// Reads `[fit]` of `study` (`starts`/`seed` overridden when given).
///
/// # Errors
/// Any missing, unknown or invalid key, with the file, line and key.
pub fn read(path: &Path, starts: Option<usize>, seed: Option<u64>) -> anyhow::Result<FitSettings> {
    let mut study = Study::load(path)?;
    let mut s = study.section("fit")?;
    let inputs = s.enum_or(
        "inputs",
        &[
            ("physical", Coordinates::Physical),
            ("unit", Coordinates::Unit),
        ],
        Coordinates::Physical,
    )?;
    reject_domain_keys(&mut s)?;
    let columns = read_columns(&mut s)?;
    // Read the keys even when the command line overrides them (so they are
    // validated and not reported as unknown).
    let starts = starts.unwrap_or(s.opt_usize("starts", Bounds::at_least(1.0))?.unwrap_or(8));
    let seed = seed.unwrap_or(s.opt_u64("seed")?.unwrap_or(1));
    if s.has("checking_error") {
        return Err(s
            .invalid(
                "checking_error",
                "a typed checking error is no longer read: give `checking = \"model.check.json\"` \
                 (the output of `nlvid --json surrogate check`), or put that file next to the \
                 surrogate model as <model>.check.json",
            )
            .into());
    }
    let modulus_times = s
        .opt_quantities("modulus_times", Dimension::TIME, Bounds::non_negative())?
        .unwrap_or_else(|| vec![0.0, 0.1, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 52.0]);
    let tables = s.tables("experiment")?;
    let (experiments, repeat) = if tables.is_empty() {
        (vec![read_experiment(&mut s, path)?], true)
    } else {
        let mut out = Vec::with_capacity(tables.len());
        for mut t in tables {
            out.push(read_experiment(&mut t, path)?);
            t.finish()?;
        }
        (out, false)
    };
    // Other sections ([forward], [design], ...) belong to other commands.
    s.finish()?;
    Ok(FitSettings {
        study: path.to_path_buf(),
        inputs,
        columns,
        starts,
        seed,
        modulus_times,
        experiments,
        repeat,
    })
}

/// The parameter domain is the one each meta-model was designed on, read
/// from its `meta.json`; `domain`/`epsilon` in `[fit]` are refused with
/// what to do instead.
fn reject_domain_keys(s: &mut Section) -> anyhow::Result<()> {
    for key in ["domain", "epsilon"] {
        if s.has(key) {
            return Err(s
                .invalid(
                    key,
                    "the parameter domain (bounds, g1 + g2 <= 1 - epsilon) is now read from the \
                     meta-model's meta.json, written by `nlvid build --export` from the build \
                     study's [design] section: remove `domain` and `epsilon` from [fit]",
                )
                .into());
        }
    }
    Ok(())
}

fn read_columns(s: &mut Section) -> anyhow::Result<DataColumns> {
    #[derive(Clone, Copy)]
    enum Kind {
        Afm,
        Compression,
    }
    let kind = s.req_enum(
        "data",
        &[("afm", Kind::Afm), ("compression", Kind::Compression)],
    )?;
    let mut cols = s.subsection("columns")?;
    let time = cols.req_str("time")?;
    let out = match kind {
        Kind::Afm => {
            let names = AfmColumns {
                time,
                piezo: cols.req_str("piezo")?,
                deflection: cols.req_str("deflection")?,
            };
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
            DataColumns::Afm(names, cal)
        }
        Kind::Compression => DataColumns::Compression(CompressionColumns {
            time,
            displacement: cols.req_str("displacement")?,
            force: cols.req_str("force")?,
            contact_area: cols.opt_str("contact_area")?,
        }),
    };
    cols.finish()?;
    Ok(out)
}

/// One experiment's keys, from `[fit]` itself or a `[[fit.experiment]]`.
fn read_experiment(s: &mut Section, study: &Path) -> anyhow::Result<ExperimentSettings> {
    let label = s.opt_str("label")?;
    let surrogate = s.req_path("surrogate")?;
    let meta = s.req_path("meta")?;
    let checking = s.opt_path("checking")?;
    let mut p = s.subsection("protocol")?;
    let protocol = Protocol {
        rate: p.req_quantity("rate", Dimension::VELOCITY, Bounds::positive())?,
        amplitude: p.req_quantity("amplitude", Dimension::LENGTH, Bounds::positive())?,
        tolerance: ProtocolTolerance {
            duration: p.f64_or("duration_tolerance", Bounds::closed(0.0, 1.0), 0.02)?,
            displacement: p.f64_or("displacement_tolerance", Bounds::closed(0.0, 1.0), 0.05)?,
        },
    };
    p.finish()?;
    let mut segments = Vec::new();
    for mut t in s.tables("segment")? {
        let seg = Segment {
            start: t.req_quantity("start", Dimension::TIME, Bounds::non_negative())?,
            end: t.req_quantity("end", Dimension::TIME, Bounds::non_negative())?,
            weight: t.req_f64("weight", Bounds::non_negative())?,
        };
        if seg.end <= seg.start {
            return Err(t
                .invalid("end", "a segment must end after it starts")
                .into());
        }
        t.finish()?;
        segments.push(seg);
    }
    let real = match s.opt_subsection("real_model")? {
        None => None,
        Some(mut r) => {
            let name = r.req_str("model")?;
            let spec = match name.as_str() {
                "lee-radok" => RealModelSpec::LeeRadok {
                    radius: r.req_quantity("radius", Dimension::LENGTH, Bounds::positive())?,
                    poisson: r.f64_or("poisson", Bounds::closed(0.0, 0.5), 0.5)?,
                },
                "forward" => RealModelSpec::Forward {
                    study: r.opt_path("study")?.unwrap_or_else(|| study.to_path_buf()),
                },
                other => {
                    return Err(r
                        .invalid(
                            "model",
                            format!(
                                "unknown real model `{other}` (available: lee-radok; forward = \
                                 the [forward] section of `study`, default this file)"
                            ),
                        )
                        .into());
                }
            };
            r.finish()?;
            Some(spec)
        }
    };
    Ok(ExperimentSettings {
        label,
        surrogate,
        meta,
        checking,
        protocol,
        segments,
        real,
    })
}
