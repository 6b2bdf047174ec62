//! `model = "capsule-fe"`: the 3D finite-element fluid-filled capsule of
//! thesis ch. IV (§4.3) squeezed between two rigid plates by the RH / RR
//! programs of §4.2 or a measured plate history (`nlvid_fem::plates`),
//! parameters `[C1, alpha, g1, g2, tau1, tau2]` of eqs. 4.1–4.3 over
//! Table 4.1 ([`PARAMETERS`], `nlvid_model::Domain::table_4_1`).
//!
//! The wall is incompressible Mooney–Rivlin (C1, C2 = αC1, eq. 4.1; bulk
//! modulus `bulk_ratio` × G0, G0 = 2(C1 + C2)) with a two-term Prony
//! series (eqs. 4.2–4.3), meshed by `nlvid_fem::shell` (one eighth of the
//! ellipsoid, 8-node F-bar hexahedra, `layers` through the wall); the oil is
//! an incompressible cavity (or compressible with `fluid_bulk_modulus`);
//! the plates are frictionless penalty planes that allow separation. The
//! `[protocol]` program is d(t), the approach of the two plates (the whole
//! capsule, compression positive), e.g. `kind = "ramp-hold"`, `target =
//! "1.5 mm"`, `rate = "5 mm/s"`, `hold = "10 s"` (RH), `kind =
//! "ramp-reverse"`, `peak = "1.5 mm"`, `rate = "0.2 mm/s"` (RR) or `kind =
//! "table"` with the measured history (§4.3: the overshoot matters).
//!
//! The response of [`ForwardModel::run`] is the plate force (N) of the whole
//! capsule on `points` output times equally spaced over the program (the
//! thesis's 1200); [`CapsuleFeModel::run_curve`] adds the contact area (two
//! ways, §4.4.3), fluid pressure and volume, the plate approach and the
//! loss-of-contact flags as channels of one [`Curve`], with the run's notes
//! (the plate lost the capsule, contact lost inside the patch).

use nlvid_fem::shell::{ShellPart, ShellSpec, ellipsoidal_shell};
use nlvid_fem::{
    Fluid, LiftOff, Mesh3, Model, Parts, PatchSpec, PlateProgram, PlateRun, Settings, Solid,
    Symmetry, run_plate_program,
};
use nlvid_material::PronyViscoelastic;
use nlvid_model::{Curve, FailureKind, ForwardModel, RunFailure, names};
use nlvid_protocol::{Program, Quantity};
use nlvid_study::{Bounds, Dimension, Section};

use crate::error::{ForwardError, Result};
use crate::fem_failure;

/// Parameter names of the capsule model, in order (`names::CAPSULE`).
pub const PARAMETERS: [&str; 6] = names::CAPSULE;

/// Which contact area is the response channel `contact_area` of
/// [`CapsuleFeModel::run_curve`] (both are always in the curve).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AreaKind {
    /// π a b through the contact edge on the long- and short-axis
    /// pressure paths (§4.4.3, what the thesis reported).
    Ellipse,
    /// Area carrying positive contact pressure.
    Pressure,
}

/// Settings of the capsule forward model (everything but the six material
/// parameters). Defaults are the thesis's capsule (§4.3) and the default
/// force mesh of docs/theory/fem.md.
#[derive(Debug, Clone, PartialEq)]
pub struct CapsuleFeSpec {
    /// The capsule's eighth: outer semi-axes (half the study's `axes` 2a,
    /// 2b, 2c; the plates press along the third), wall thickness t1, t2, t3
    /// at the ends of the axes, the thickness law's exponent, elements
    /// through the wall (thesis: 4) and element size (0.3 mm: the default
    /// force mesh, docs/theory/fem.md).
    pub shell: ShellSpec,
    /// Wall bulk modulus over G0 = 2(C1 + C2) (near-incompressibility).
    pub bulk_ratio: f64,
    /// Fluid bulk modulus (Pa); `None`: incompressible (the thesis's oil).
    pub fluid_bulk_modulus: Option<f64>,
    /// The plates' approach d(t) (m), from `[protocol]`.
    pub program: Program,
    /// Output points, equally spaced over the program (thesis: 1200).
    pub points: usize,
    /// Steps per stage, at least (`PlateProgram::min_steps`).
    pub min_steps: usize,
    /// Step onto every output time instead of interpolating.
    pub exact_outputs: bool,
    /// Which area is the `contact_area` channel.
    pub contact_area: AreaKind,
}

impl CapsuleFeSpec {
    /// Reads the `[forward]` keys `axes`, `wall_thickness` (both required,
    /// three lengths each), `thickness_exponent` (2), `layers` (4),
    /// `element_size` ("0.3 mm"), `bulk_ratio` (1000),
    /// `fluid_bulk_modulus` (absent: incompressible), `min_steps` (20),
    /// `exact_outputs` (false), `contact_area` ("ellipse" | "pressure");
    /// `program` is `[protocol]`'s plate displacement program.
    ///
    /// # Errors
    /// Missing key, wrong unit, out-of-range value (file, line, key); a
    /// wall as thick as the capsule.
    pub fn from_section(s: &mut Section, program: Program, points: usize) -> Result<Self> {
        let pos = Bounds::positive();
        let three = |s: &mut Section, key: &str| -> Result<[f64; 3]> {
            let v = s.req_quantities(key, Dimension::LENGTH, pos)?;
            <[f64; 3]>::try_from(v.as_slice()).map_err(|_| {
                s.invalid(
                    key,
                    format!(
                        "expected three lengths (along the long axis and the two short ones, \
                         the plates pressing along the third), got {}",
                        v.len()
                    ),
                )
                .into()
            })
        };
        let axes = three(s, "axes")?;
        let wall_thickness = three(s, "wall_thickness")?;
        if let Some(k) = (0..3).find(|&k| 2.0 * wall_thickness[k] >= axes[k]) {
            return Err(s
                .invalid(
                    "wall_thickness",
                    format!(
                        "wall {} of {:.4} mm leaves no cavity inside the axis of {:.4} mm",
                        k + 1,
                        wall_thickness[k] * 1e3,
                        axes[k] * 1e3
                    ),
                )
                .into());
        }
        let thickness_exponent = s.f64_or("thickness_exponent", Bounds::at_least(1.0), 2.0)?;
        let layers = s
            .opt_usize("layers", Bounds::closed(1.0, 64.0))?
            .unwrap_or(4);
        let element_size = s.quantity_or("element_size", Dimension::LENGTH, pos, 0.3e-3)?;
        let bulk_ratio = s.f64_or("bulk_ratio", Bounds::at_least(1.0), 1e3)?;
        let fluid_bulk_modulus = s.opt_quantity("fluid_bulk_modulus", Dimension::PRESSURE, pos)?;
        let min_steps = s
            .opt_usize("min_steps", Bounds::closed(1.0, 100_000.0))?
            .unwrap_or(20);
        let exact_outputs = s.opt_bool("exact_outputs")?.unwrap_or(false);
        let contact_area = s.enum_or(
            "contact_area",
            &[
                ("ellipse", AreaKind::Ellipse),
                ("pressure", AreaKind::Pressure),
            ],
            AreaKind::Ellipse,
        )?;
        Ok(Self {
            shell: ShellSpec {
                semi_axes: axes.map(|a| 0.5 * a),
                thickness: wall_thickness,
                thickness_exponent,
                layers,
                element_size,
                part: ShellPart::Eighth,
            },
            bulk_ratio,
            fluid_bulk_modulus,
            program,
            points,
            min_steps,
            exact_outputs,
            contact_area,
        })
    }

    /// The thesis capsule (§4.3: 2a = 9.96 mm, 2b = 2c = 6.51 mm, t1 =
    /// 0.62 mm, t2 = t3 = 0.4 mm) on the default force mesh, driven by
    /// `program` with `points` output times.
    pub fn thesis(program: Program, points: usize) -> Self {
        Self {
            shell: ShellSpec::thesis_capsule(0.3e-3),
            bulk_ratio: 1e3,
            fluid_bulk_modulus: None,
            program,
            points,
            min_steps: 20,
            exact_outputs: false,
            contact_area: AreaKind::Ellipse,
        }
    }

    /// The forward model: meshes the capsule once and checks the program
    /// and output times against it (a program that crushes the capsule
    /// past its walls, jumps, starts pressed or is not a displacement is
    /// refused here, before any run).
    ///
    /// # Errors
    /// [`ForwardError::Setting`] with the mesher's or the check's message.
    pub fn build(&self) -> Result<CapsuleFeModel> {
        let bad = |message: String| ForwardError::Setting {
            model: "capsule-fe",
            message,
        };
        if self.program.quantity() != Quantity::Displacement {
            return Err(bad(format!(
                "[protocol]: the plates follow a displacement program; it gives {:?} \
                 (set control = \"displacement\", lengths with units)",
                self.program.quantity()
            )));
        }
        let mesh = ellipsoidal_shell(&self.shell).map_err(|e| bad(e.to_string()))?;
        let times = self
            .program
            .uniform_grid(self.points)
            .map_err(|e| bad(e.to_string()))?;
        let mut plate = PlateProgram::new(self.program.clone(), times, patch(), "inner");
        plate.min_steps = self.min_steps;
        plate.exact_outputs = self.exact_outputs;
        plate
            .check(&mesh)
            .map_err(|e| bad(format!("[protocol]: {e}")))?;
        let identity = format!("capsule-fe({self:?})");
        Ok(CapsuleFeModel {
            spec: self.clone(),
            mesh,
            plate,
            identity,
        })
    }
}

/// The measured plate (the top one, index 0), on the outer surface of the
/// eighth.
fn patch() -> PatchSpec {
    PatchSpec {
        plane: 0,
        surface: "outer".into(),
        symmetry: Symmetry::EIGHTH,
        lift_off: LiftOff::Solid,
    }
}

/// The capsule finite-element model as a [`ForwardModel`]: parameters
/// [`PARAMETERS`] `[C1 (Pa), alpha, g1, g2, tau1 (s), tau2 (s)]`, response
/// the plate force F(t) (N) of the whole capsule on the output times.
#[derive(Debug, Clone)]
pub struct CapsuleFeModel {
    spec: CapsuleFeSpec,
    mesh: Mesh3,
    plate: PlateProgram,
    identity: String,
}

fn invalid(message: String) -> RunFailure {
    RunFailure::new(
        FailureKind::InvalidParameters,
        format!("capsule-fe: {message}"),
    )
}

impl CapsuleFeModel {
    /// The settings.
    pub fn spec(&self) -> &CapsuleFeSpec {
        &self.spec
    }

    /// The eighth-capsule mesh (hexahedra and nodes).
    pub fn mesh(&self) -> &Mesh3 {
        &self.mesh
    }

    /// The wall material at `p` (eqs. 4.1–4.3): Mooney–Rivlin C1, C2 = αC1
    /// with bulk modulus `bulk_ratio` × 2(C1 + C2) and the two Prony terms.
    ///
    /// # Errors
    /// A parameter vector of the wrong length or values the material
    /// refuses (C1 ≤ 0, α < 0, g1 + g2 ≥ 1, τ ≤ 0), naming them.
    pub fn material(&self, p: &[f64]) -> std::result::Result<PronyViscoelastic, RunFailure> {
        let &[c1, alpha, g1, g2, tau1, tau2] = p else {
            return Err(invalid(format!(
                "expects 6 parameters [{}], got {}",
                PARAMETERS.join(", "),
                p.len()
            )));
        };
        if !(c1 > 0.0 && c1.is_finite() && alpha >= 0.0 && alpha.is_finite()) {
            return Err(invalid(format!(
                "C1 = {c1} Pa must be positive and alpha = {alpha} non-negative"
            )));
        }
        let g0 = 2.0 * c1 * (1.0 + alpha);
        PronyViscoelastic::capsule(c1, alpha, (g1, tau1), (g2, tau2), self.spec.bulk_ratio * g0)
            .map_err(|e| invalid(e.to_string()))
    }

    /// One run at `p`: every converged step, the samples on the output
    /// times and the notes (`nlvid_fem::PlateRun`).
    ///
    /// # Errors
    /// Bad parameters; the engine's errors (non-convergence naming the
    /// time and, for a collapsing element, the element).
    pub fn run_plates(&self, p: &[f64]) -> std::result::Result<PlateRun, RunFailure> {
        let material = self.material(p)?;
        let parts = Parts::eighth_capsule(match self.spec.fluid_bulk_modulus {
            None => Fluid::Incompressible,
            Some(bulk_modulus) => Fluid::Compressible { bulk_modulus },
        });
        // Full Newton steps may land inside the plate while the load passes
        // through zero (RR, separation); `atol` replaces rtol × a vanishing
        // force (docs/theory/fem.md, "Planes, supports, tolerance").
        let settings = Settings {
            residual_growth: 1e6,
            atol: 1e-9,
            ..Settings::default()
        };
        let mut model = Model::<_, Solid>::build(self.mesh.clone(), material, &parts, settings)
            .map_err(|e| fem_failure(&e))?;
        run_plate_program(&mut model, &self.plate).map_err(|e| fem_failure(&e))
    }

    /// One run at `p` as a [`Curve`] on the output times — `force` (N),
    /// `contact_area` (m², the [`AreaKind`] of the settings),
    /// `ellipse_area`, `pressure_area`, `lost_area` (m²), `pressure` (Pa),
    /// `volume` (m³), `plate_displacement` (m), `in_contact` and
    /// `lost_contact` (1/0) — and the run's notes.
    ///
    /// # Errors
    /// As [`CapsuleFeModel::run_plates`]; a non-finite output.
    pub fn run_curve(&self, p: &[f64]) -> std::result::Result<(Curve, Vec<String>), RunFailure> {
        let run = self.run_plates(p)?;
        let curve = samples_curve(&run, self.spec.contact_area)
            .map_err(|e| RunFailure::new(FailureKind::BadResponse, format!("capsule-fe: {e}")))?;
        Ok((curve, run.notes))
    }
}

/// The samples of a plate run as a curve (channels of
/// [`CapsuleFeModel::run_curve`]).
///
/// # Errors
/// Non-finite values or times that do not increase.
pub fn samples_curve(run: &PlateRun, area: AreaKind) -> nlvid_model::Result<Curve> {
    let s = &run.samples;
    let col = |f: &dyn Fn(&nlvid_fem::PlateSample) -> f64| s.iter().map(f).collect::<Vec<_>>();
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    let contact = match area {
        AreaKind::Ellipse => col(&|x| x.ellipse_area),
        AreaKind::Pressure => col(&|x| x.pressure_area),
    };
    Curve::new(col(&|x| x.time))?
        .with("force", "N", col(&|x| x.force))?
        .with("contact_area", "m^2", contact)?
        .with("ellipse_area", "m^2", col(&|x| x.ellipse_area))?
        .with("pressure_area", "m^2", col(&|x| x.pressure_area))?
        .with("lost_area", "m^2", col(&|x| x.lost_area))?
        .with("pressure", "Pa", col(&|x| x.pressure))?
        .with("volume", "m^3", col(&|x| x.volume))?
        .with("plate_displacement", "m", col(&|x| x.plate_displacement))?
        .with("in_contact", "1", col(&|x| flag(x.in_contact)))?
        .with("lost_contact", "1", col(&|x| flag(x.lost_contact)))
}

impl ForwardModel for CapsuleFeModel {
    fn parameter_names(&self) -> Vec<String> {
        PARAMETERS.map(String::from).to_vec()
    }
    fn parameter_units(&self) -> Vec<String> {
        names::CAPSULE_UNITS.map(String::from).to_vec()
    }
    fn time_grid(&self) -> &[f64] {
        &self.plate.output_times
    }
    fn contact_index(&self) -> usize {
        // t = 0 is the undeformed capsule (d = 0, F = 0).
        1
    }
    fn identity(&self) -> String {
        self.identity.clone()
    }
    fn run(&self, p: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        let run = self.run_plates(p)?;
        Ok(run.samples.iter().map(|s| s.force).collect())
    }
}
