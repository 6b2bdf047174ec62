//! Forward models from study files: one place that turns a study's
//! `[forward]` section (and, for the AFM and membrane models, its
//! `[protocol]` section) into a [`nlvid_model::ForwardModel`] — the
//! parameters → force-curve map that meta-model builds, Kriging checks and
//! fits evaluate — and the one Lee–Radok kernel ([`LeeRadok`]) that the
//! analytic model, the fits (`nlvid-inverse`), `nlvid inspect`
//! (`nlvid-afm`) and the demo's curves (`nlvid-report`) evaluate.
//!
//! Models (`model = "…"`):
//! * `hertz-prony` — analytic Lee–Radok ramp-hold indentation (equally
//!   spaced or graded output grid, [`HertzGrid`]) with a
//!   2-term Prony G(t) ([`HertzPronySpec`], [`HertzProny`]); parameters
//!   `[G0, g1, g2, τ1, τ2]`; microseconds per run.
//! * `afm-fe` — the axisymmetric finite-element AFM cell model of thesis
//!   §5.3 (`nlvid_fem::afm::run`) with the two-step script of
//!   `nlvid-protocol` ([`AfmFeSpec`], [`AfmFeModel`]); parameters
//!   `[G0, g1, g2, τ1, τ2]` (eq. 5.1, Table 5.3); seconds to minutes per run.
//! * `membrane` — the ch. II membrane solver (`nlvid_membrane::simulate`)
//!   ([`MembraneSpec`], [`MembraneModel`]); parameters
//!   `[G10, gamma0, g1_long_term, g2_long_term, tau1, tau2]`
//!   ([`MEMBRANE_PARAMETERS`], eq. 2.56: ch. II's G1(0) and long-term
//!   fractions); tenths of a second per run.
//! * `capsule-fe` — the 3D finite-element fluid-filled capsule between
//!   plates of thesis ch. IV (§4.3, `nlvid_fem::plates`) under the RH / RR
//!   programs or a measured plate table ([`CapsuleFeSpec`],
//!   [`CapsuleFeModel`]); parameters `[C1, alpha, g1, g2, tau1, tau2]`
//!   ([`CAPSULE_PARAMETERS`], eqs. 4.1–4.3, Table 4.1); seconds per run.
//!
//! Every model reports SI units (`parameter_units`) and an `identity`
//! string holding every setting, which enters the build's study hash.
//! The study format is in `docs/study-format.md` (`[forward]`).
//!
//! ```
//! use nlvid_forward::from_study;
//! use nlvid_study::Study;
//! let mut study = Study::parse("s.toml", r#"
//! [forward]
//! model = "hertz-prony"
//! probe_radius = "5 um"
//! rate = "1 um/s"
//! ramp = "1 s"
//! hold = "9 s"
//! points = 50
//! "#)?;
//! let model = from_study(&mut study)?;
//! study.finish()?;
//! let f = model.run(&[1000.0, 0.3, 0.2, 0.1, 5.0]).map_err(|e| e.to_string())?;
//! assert_eq!(f.len(), 50);
//! assert_eq!(model.parameter_units(), ["Pa", "1", "1", "s", "s"]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

mod afm_fe;
mod capsule_fe;

pub mod curves;
mod error;
mod hertz;
mod lee_radok;
mod membrane;
pub mod simulate;

use std::time::Duration;

use nlvid_model::{ForwardModel, RunFailure};
use nlvid_protocol::{Loading as ProtocolLoading, ProtocolSettings};
use nlvid_study::FromSection as _;
use nlvid_study::{Bounds, Dimension, Section, Study};

pub use afm_fe::{AfmFeModel, AfmFeSpec, AfmGeometry, fem_failure};
pub use capsule_fe::{
    AreaKind, CapsuleFeModel, CapsuleFeSpec, PARAMETERS as CAPSULE_PARAMETERS, samples_curve,
};

pub use curves::{CurveJob, Noise, afm_curve, afm_curves, measured_csv};
pub use error::{ForwardError, Result};
pub use hertz::{HertzGrid, HertzProny, HertzPronySpec};
pub use lee_radok::{LeeRadok, exp_convolution, exp_convolutions};
pub use membrane::{
    MembraneModel, MembraneSpec, PARAMETERS as MEMBRANE_PARAMETERS, membrane_failure,
};
pub use simulate::{SimulateStudy, Simulation};

/// Which forward model, with all its settings.
#[derive(Debug, Clone, PartialEq)]
pub enum ForwardSpec {
    /// Analytic Lee–Radok Hertz ramp-hold.
    HertzProny(HertzPronySpec),
    /// AFM finite-element cell model.
    AfmFe(AfmFeSpec),
    /// Ch. II membrane solver.
    Membrane(MembraneSpec),
    /// Ch. IV 3D finite-element capsule between plates.
    CapsuleFe(CapsuleFeSpec),
}

impl ForwardSpec {
    /// The model's name in `[forward] model`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::HertzProny(_) => "hertz-prony",
            Self::AfmFe(_) => "afm-fe",
            Self::Membrane(_) => "membrane",
            Self::CapsuleFe(_) => "capsule-fe",
        }
    }
}

/// The `[forward]` section: the model and a test-only delay.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardSettings {
    /// The model.
    pub spec: ForwardSpec,
    /// **Test only**: sleep this long [s] before every run, so that a
    /// build of a cheap model is slow enough to be killed mid-way
    /// (`test_delay = "50 ms"`). Changes nothing else; enters the identity.
    pub test_delay: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    HertzProny,
    AfmFe,
    Membrane,
    CapsuleFe,
}

/// Output points m: `points` in `[forward]` or `output_points`/`sampling`
/// in `[protocol]`, exactly one of them.
fn points(f: &mut Section, protocol: Option<(&Section, &ProtocolSettings)>) -> Result<usize> {
    let here = f.opt_usize("points", Bounds::closed(2.0, 1e7))?;
    let there = protocol.and_then(|(_, p)| p.output_points);
    match (here, there) {
        (Some(m), None) | (None, Some(m)) => Ok(m),
        (Some(_), Some(_)) => Err(f
            .invalid(
                "points",
                "the output grid is also given in [protocol] (output_points/sampling); give it once",
            )
            .into()),
        (None, None) => Err(f
            .invalid(
                "points",
                "missing: number of output time points m (thesis: 5095 for AFM, 1200 for capsules)",
            )
            .into()),
    }
}

/// The `[protocol]` section of a plate model (`membrane`, `capsule-fe`): a
/// displacement program (RH, RR, a measured table, …) and the number of
/// output points (`[forward] points` or `[protocol] output_points`).
fn plate_program(
    study: &mut Study,
    f: &mut Section,
    model: &str,
) -> Result<(nlvid_protocol::Program, usize)> {
    let mut ps = study.section("protocol")?;
    let settings = ProtocolSettings::from_section(&mut ps)?;
    let ProtocolLoading::Program(program) = &settings.loading else {
        return Err(ps
            .invalid(
                "kind",
                format!(
                    "model `{model}` needs a plate program (e.g. kind = \"ramp-hold\"), not the AFM script"
                ),
            )
            .into());
    };
    if program.quantity() != nlvid_protocol::Quantity::Displacement {
        return Err(ps
            .invalid(
                "control",
                format!(
                    "model `{model}` follows a plate displacement program (control = \"displacement\", lengths and times with units)"
                ),
            )
            .into());
    }
    let m = points(f, Some((&ps, &settings)))?;
    ps.finish()?;
    Ok((program.clone(), m))
}

impl ForwardSettings {
    /// Reads `[forward]` (and `[protocol]` for `afm-fe` and `membrane`).
    /// The caller still owns the study and must `finish()` it.
    ///
    /// # Errors
    /// Missing sections or keys, wrong units, out-of-range values, a
    /// `[protocol]` that does not suit the model — each naming file, line
    /// and key.
    pub fn from_study(study: &mut Study) -> Result<Self> {
        let mut f = study.section("forward")?;
        let kind = f.req_enum(
            "model",
            &[
                ("hertz-prony", Kind::HertzProny),
                ("afm-fe", Kind::AfmFe),
                ("membrane", Kind::Membrane),
                ("capsule-fe", Kind::CapsuleFe),
            ],
        )?;
        let test_delay = f.opt_quantity("test_delay", Dimension::TIME, Bounds::non_negative())?;
        let spec = match kind {
            Kind::HertzProny => ForwardSpec::HertzProny(HertzPronySpec::from_section(&mut f)?),
            Kind::AfmFe => {
                let mut ps = study.section("protocol")?;
                let settings = ProtocolSettings::from_section(&mut ps)?;
                let m = points(&mut f, Some((&ps, &settings)))?;
                ps.finish()?;
                ForwardSpec::AfmFe(AfmFeSpec::from_section(&mut f, settings.loading, m)?)
            }
            Kind::Membrane => {
                let (program, m) = plate_program(study, &mut f, "membrane")?;
                ForwardSpec::Membrane(MembraneSpec::from_section(&mut f, program, m)?)
            }
            Kind::CapsuleFe => {
                let (program, m) = plate_program(study, &mut f, "capsule-fe")?;
                ForwardSpec::CapsuleFe(CapsuleFeSpec::from_section(&mut f, program, m)?)
            }
        };
        f.finish()?;
        Ok(Self { spec, test_delay })
    }

    /// The forward model.
    ///
    /// # Errors
    /// Settings the model cannot use (see each spec's `build`).
    pub fn build(&self) -> Result<Box<dyn ForwardModel>> {
        let model: Box<dyn ForwardModel> = match &self.spec {
            ForwardSpec::HertzProny(s) => Box::new(s.build()?),
            ForwardSpec::AfmFe(s) => Box::new(s.build()?),
            ForwardSpec::Membrane(s) => Box::new(s.build()?),
            ForwardSpec::CapsuleFe(s) => Box::new(s.build()?),
        };
        Ok(match self.test_delay {
            Some(d) if d > 0.0 => Box::new(Delayed {
                inner: model,
                delay: d,
            }),
            _ => model,
        })
    }
}

/// Reads `[forward]` (and `[protocol]` when the model needs it) and builds
/// the forward model. The caller must still `finish()` the study.
///
/// # Errors
/// As [`ForwardSettings::from_study`] and [`ForwardSettings::build`].
pub fn from_study(study: &mut Study) -> Result<Box<dyn ForwardModel>> {
    ForwardSettings::from_study(study)?.build()
}

/// Test fixture: a `hertz-prony` `[forward]` section (probe radius, rate,
/// ramp, hold with units; output points).
#[cfg(test)]
pub(crate) fn hertz_forward_toml(
    radius: &str,
    rate: &str,
    ramp: &str,
    hold: &str,
    points: usize,
) -> String {
    format!(
        "[forward]\nmodel = \"hertz-prony\"\nprobe_radius = \"{radius}\"\nrate = \"{rate}\"\n\
         ramp = \"{ramp}\"\nhold = \"{hold}\"\npoints = {points}\n"
    )
}

/// Test-only wrapper: sleeps before every run.
struct Delayed {
    inner: Box<dyn ForwardModel>,
    delay: f64,
}

impl ForwardModel for Delayed {
    fn parameter_names(&self) -> Vec<String> {
        self.inner.parameter_names()
    }
    fn parameter_units(&self) -> Vec<String> {
        self.inner.parameter_units()
    }
    fn time_grid(&self) -> &[f64] {
        self.inner.time_grid()
    }
    fn contact_index(&self) -> usize {
        self.inner.contact_index()
    }
    fn identity(&self) -> String {
        format!("{}+test_delay({:e})", self.inner.identity(), self.delay)
    }
    fn run(&self, params: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        std::thread::sleep(Duration::from_secs_f64(self.delay));
        self.inner.run(params)
    }
}
