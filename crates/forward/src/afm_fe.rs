//! `model = "afm-fe"`: the axisymmetric finite-element AFM cell model of
//! thesis §5.3 (`nlvid_fem::afm::run`) driven by the two-step script of
//! `nlvid-protocol` (force-controlled engagement, then the piezo program
//! of Fig. 5.2) or by any continuous piezo program Z(t) without engagement,
//! parameters `[G0, g1, g2, τ1, τ2]` of eq. 5.1 / Table 5.3 — and, with
//! `geometry = "inputs"` (issue 17, beyond the thesis), the cell height and
//! base diameter `[H, D]` (m) after them, so one meta-model covers cells of
//! different shapes.
//!
//! `nlvid simulate`, `nlvid build` and `nlvid fit` (real model) read these
//! same `[forward]` keys with the same defaults; the defaults are the fem
//! crate's (`AfmSetup::thesis_setup1`: the mesh graded to the contact,
//! κ/G0 = 200), which give the verified setup-1 forces
//! (docs/theory/forward.md, docs/theory/fem.md "Mesh graded to the contact").

use nlvid_fem::FemError;
use nlvid_fem::afm::{AfmSetup, Cantilever, Engagement, MeshLayout, MeshSpec};
use nlvid_model::{FailureKind, ForwardModel, Relaxation, RunFailure, names};
use nlvid_protocol::{Loading as ProtocolLoading, Program, Quantity};
use nlvid_study::{Bounds, Dimension, Section};

use crate::error::{ForwardError, Result};

/// Where the cell's height and base diameter come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AfmGeometry {
    /// One shape for every run (`[forward] height`, `diameter`): the
    /// thesis's mean geometry of a setup (§5.4.2).
    Fixed {
        /// Cell height H [m].
        height: f64,
        /// Cell base diameter D [m].
        diameter: f64,
    },
    /// `geometry = "inputs"`: H and D are the 6th and 7th parameters
    /// ([`names::GEOMETRY`], m), their ranges study parameters of
    /// `[design.parameters]`.
    Inputs,
}

/// Settings of the AFM finite-element forward model (everything but the
/// five material parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct AfmFeSpec {
    /// The cell's shape: fixed, or the inputs `H`, `D`.
    pub geometry: AfmGeometry,
    /// Probe radius [m].
    pub probe_radius: f64,
    /// Cantilever spring constant k [N/m]; `None`: rigid (δ = Z).
    pub spring_constant: Option<f64>,
    /// From `[protocol]`: the two-step AFM script (engagement + piezo
    /// program), or a continuous piezo program Z(t) driven directly.
    pub loading: ProtocolLoading,
    /// Output points m, equally spaced over step 2 (thesis: 5095).
    pub points: usize,
    /// Mesh: graded to the contact (default), or the sessions-1–3 Coons
    /// patch with `coons` = (elements per side, coarsest/finest spacing
    /// ratio toward the contact).
    pub mesh: AfmMesh,
    /// Bulk modulus over G0 (near-incompressibility).
    pub bulk_ratio: f64,
    /// Largest time step in ramps, as a fraction of the ramp duration.
    pub ramp_step_fraction: f64,
    /// Largest time step in holds [s].
    pub hold_step_max: f64,
}

impl AfmFeSpec {
    /// Reads the `[forward]` keys (`height`, `diameter` or
    /// `geometry = "inputs"`, `probe_radius`,
    /// `spring_constant` or `cantilever = "rigid"`, `points`, `mesh`
    /// (`"graded"` or `"coons"`), `mesh_refinement` (graded),
    /// `elements_per_side` and `mesh_bias` (coons), `bulk_ratio`,
    /// `ramp_step_fraction`, `hold_step_max`); `loading` is the
    /// `[protocol]` section's. Defaults are those of
    /// `AfmSetup::thesis_setup1` (probe radius 2.5 µm, the mesh graded to
    /// the contact, bulk ratio 200, ramp step fraction 0.1, hold step 2 s).
    ///
    /// # Errors
    /// Missing key, wrong unit, out-of-range value (file, line, key).
    pub fn from_section(s: &mut Section, loading: ProtocolLoading, points: usize) -> Result<Self> {
        let pos = Bounds::positive();
        let d = AfmSetup::thesis_setup1();
        for (old, new) in [
            ("k", "spring_constant"),
            ("bias", "mesh_bias"),
            ("rigid", "cantilever = \"rigid\""),
        ] {
            if s.has(old) {
                return Err(s.invalid(old, format!("this key is now `{new}`")).into());
            }
        }
        let inputs = s.opt_enum("geometry", &[("fixed", false), ("inputs", true)])?;
        let geometry = if inputs == Some(true) {
            for key in ["height", "diameter"] {
                if s.has(key) {
                    return Err(s
                        .invalid(
                            key,
                            "with geometry = \"inputs\" the cell's height H and base diameter D \
                             are parameters: give their ranges in [design.parameters] \
                             (e.g. H = { range = [\"9.8 um\", \"14.7 um\"] }) and their values \
                             in [parameters]",
                        )
                        .into());
                }
            }
            AfmGeometry::Inputs
        } else {
            AfmGeometry::Fixed {
                height: s.req_quantity("height", Dimension::LENGTH, pos)?,
                diameter: s.req_quantity("diameter", Dimension::LENGTH, pos)?,
            }
        };
        let probe_radius = s.quantity_or("probe_radius", Dimension::LENGTH, pos, d.probe_radius)?;
        let rigid = match s.opt_str("cantilever")?.as_deref() {
            None | Some("spring") => false,
            Some("rigid") => true,
            Some(other) => {
                return Err(s
                    .invalid(
                        "cantilever",
                        format!("`{other}`: expected \"spring\" or \"rigid\""),
                    )
                    .into());
            }
        };
        let k = s.opt_quantity("spring_constant", Dimension::STIFFNESS, pos)?;
        let spring_constant = match (rigid, k) {
            (true, Some(_)) => {
                return Err(s
                    .invalid(
                        "spring_constant",
                        "a rigid cantilever has no spring constant",
                    )
                    .into());
            }
            (true, None) => None,
            (false, Some(k)) => Some(k),
            (false, None) => {
                return Err(s
                    .invalid(
                        "spring_constant",
                        "missing: give the cantilever's spring constant (e.g. \"0.12 N/m\") or cantilever = \"rigid\"",
                    )
                    .into());
            }
        };
        let mesh = AfmMesh::from_section(s, &d)?;
        let bulk_ratio = s.f64_or("bulk_ratio", Bounds::at_least(1.0), d.bulk_ratio)?;
        let ramp_step_fraction = s.f64_or(
            "ramp_step_fraction",
            Bounds::open_closed(0.0, 1.0),
            d.ramp_step_fraction,
        )?;
        let hold_step_max =
            s.quantity_or("hold_step_max", Dimension::TIME, pos, d.hold_step_max)?;
        Ok(Self {
            geometry,
            probe_radius,
            spring_constant,
            loading,
            points,
            mesh,
            bulk_ratio,
            ramp_step_fraction,
            hold_step_max,
        })
    }

    /// The finite-element setup: the thesis's setup 1 with every setting
    /// of this spec written over it (so solver settings not named here keep
    /// the fem crate's defaults). With `geometry = "inputs"` its height and
    /// diameter are setup 1's until a run sets them from its parameters.
    ///
    /// # Errors
    /// The script is invalid.
    pub fn setup(&self) -> Result<AfmSetup> {
        let bad = |e: nlvid_protocol::ProtocolError| ForwardError::Setting {
            model: "afm-fe",
            message: e.to_string(),
        };
        let (piezo, engagement) = match &self.loading {
            ProtocolLoading::Afm(script) => (
                script.piezo().map_err(bad)?,
                Engagement {
                    force: script.engage.setpoint_force,
                    ramp: script.engage.ramp_time,
                    hold: script.engage.hold,
                },
            ),
            ProtocolLoading::Program(p) => {
                if p.quantity() != Quantity::Displacement {
                    return Err(ForwardError::Setting {
                        model: "afm-fe",
                        message: "[protocol]: the piezo program must be a displacement \
                                  (control = \"displacement\", lengths with units)"
                            .into(),
                    });
                }
                if let Some(j) = p.segments().iter().find(|s| s.is_jump()) {
                    return Err(ForwardError::Setting {
                        model: "afm-fe",
                        message: format!(
                            "[protocol]: the piezo program jumps at t = {} s; the FE model \
                             needs a continuous Z(t)",
                            j.t0
                        ),
                    });
                }
                // No engagement step: the probe starts touching the cell.
                let none = Engagement {
                    force: 0.0,
                    ramp: 1.0,
                    hold: 0.0,
                };
                (p.clone(), none)
            }
        };
        let mut setup = AfmSetup::thesis_setup1();
        if let AfmGeometry::Fixed { height, diameter } = self.geometry {
            setup.height = height;
            setup.diameter = diameter;
        }
        setup.probe_radius = self.probe_radius;
        setup.cantilever = match self.spring_constant {
            Some(stiffness) => Cantilever::Spring { stiffness },
            None => Cantilever::Rigid,
        };
        setup.engagement = engagement;
        setup.piezo = breakpoints(&piezo);
        match self.mesh {
            AfmMesh::Graded { refinement } => {
                if let MeshLayout::ContactGraded(spec) = setup.mesh_layout {
                    setup.mesh_layout = MeshLayout::ContactGraded(spec.refined(refinement));
                }
            }
            AfmMesh::Coons(spec) => {
                setup.mesh_layout = MeshLayout::Coons;
                setup.mesh = spec;
            }
        }
        setup.bulk_ratio = self.bulk_ratio;
        let t0 = piezo.start();
        setup.output_times = piezo
            .uniform_grid(self.points)
            .map_err(bad)?
            .into_iter()
            .map(|t| t - t0)
            .collect();
        setup.ramp_step_fraction = self.ramp_step_fraction;
        setup.hold_step_max = self.hold_step_max;
        Ok(setup)
    }

    /// The forward model.
    ///
    /// # Errors
    /// As [`AfmFeSpec::setup`].
    pub fn build(&self) -> Result<AfmFeModel> {
        let model = AfmFeModel::new(self.setup()?);
        Ok(match self.geometry {
            AfmGeometry::Fixed { .. } => model,
            AfmGeometry::Inputs => model.with_geometry_inputs(),
        })
    }
}

/// The cell mesh of `[forward] mesh`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AfmMesh {
    /// Rings graded to the contact (the default, converged from
    /// δ = 0.05 µm), each element split `refinement` times per direction
    /// (1: the default density; 2, 4: the convergence study's meshes).
    Graded {
        /// Refinement factor (≥ 1).
        refinement: usize,
    },
    /// The sessions-1–3 single transfinite patch (kept to reproduce
    /// earlier numbers; 2 % off at δ = 0.25 µm on 35 × 35).
    Coons(MeshSpec),
}

impl AfmMesh {
    /// `mesh = "graded" | "coons"`, with `mesh_refinement` (graded) or
    /// `elements_per_side`, `mesh_bias` (coons). A key of the other layout
    /// is an error saying which layout it belongs to.
    fn from_section(s: &mut Section, defaults: &AfmSetup) -> Result<Self> {
        let coons = s.opt_enum("mesh", &[("graded", false), ("coons", true)])?;
        let coons = coons.unwrap_or(false);
        if coons {
            if s.has("mesh_refinement") {
                return Err(s
                    .invalid(
                        "mesh_refinement",
                        "refines the graded mesh; with mesh = \"coons\" set elements_per_side",
                    )
                    .into());
            }
            let elements_per_side = s
                .opt_usize("elements_per_side", Bounds::closed(2.0, 10_000.0))?
                .unwrap_or(defaults.mesh.elements_per_side);
            let bias = s.f64_or("mesh_bias", Bounds::at_least(1.0), defaults.mesh.bias)?;
            return Ok(Self::Coons(MeshSpec {
                elements_per_side,
                bias,
            }));
        }
        for key in ["elements_per_side", "mesh_bias"] {
            if s.has(key) {
                return Err(s
                    .invalid(
                        key,
                        "sizes the Coons-patch mesh, which is no longer the default: the default \
                         mesh is graded to the contact (mesh = \"graded\", refine it with \
                         mesh_refinement = 2); add mesh = \"coons\" to keep the old mesh",
                    )
                    .into());
            }
        }
        let refinement = s
            .opt_usize("mesh_refinement", Bounds::closed(1.0, 16.0))?
            .unwrap_or(1);
        Ok(Self::Graded { refinement })
    }
}

/// The piezo program as (t, Z) points (every breakpoint, linear between),
/// its clock shifted to start at t = 0 (step 2 starts at 0).
fn breakpoints(p: &Program) -> Vec<(f64, f64)> {
    let mut pts = Vec::with_capacity(p.segments().len() + 1);
    for seg in p.segments() {
        if pts.is_empty() {
            pts.push((seg.t0, seg.v0));
        }
        pts.push((seg.t1, seg.v1));
    }
    let t0 = pts.first().map_or(0.0, |p| p.0);
    for p in &mut pts {
        p.0 -= t0;
    }
    pts
}

/// The AFM finite-element model as a [`ForwardModel`]: parameters
/// `[G0 (Pa), g1, g2, τ1 (s), τ2 (s)]` (Table 5.3 order of `nlvid build`),
/// followed by `[H (m), D (m)]` when the geometry is an input
/// ([`AfmFeModel::with_geometry_inputs`]); response F(t) [N] on the setup's
/// output times (step-2 clock).
#[derive(Debug, Clone)]
pub struct AfmFeModel {
    setup: AfmSetup,
    identity: String,
    geometry_inputs: bool,
}

impl AfmFeModel {
    /// Wrap a setup.
    pub fn new(setup: AfmSetup) -> Self {
        // Debug of the whole setup: every field (geometry, cantilever,
        // engagement, piezo points, mesh, grid, solver settings) enters the
        // study hash, including fields added to AfmSetup later.
        let identity = format!("afm-fe({setup:?})");
        Self {
            setup,
            identity,
            geometry_inputs: false,
        }
    }

    /// The same model with the cell height H and base diameter D as the
    /// 6th and 7th parameters (m): each run uses its own shape instead of
    /// the setup's (issue 17, per-cell geometry).
    #[must_use]
    pub fn with_geometry_inputs(mut self) -> Self {
        self.geometry_inputs = true;
        self.identity = format!("afm-fe[geometry inputs H, D]({:?})", self.setup);
        self
    }

    /// The finite-element setup.
    pub fn setup(&self) -> &AfmSetup {
        &self.setup
    }

    /// G(t) of eq. 5.1 and the finite-element setup of one run at `p`
    /// (the model's parameter order): the setup itself, or with geometry
    /// inputs a copy with height `p[5]` and diameter `p[6]`.
    ///
    /// # Errors
    /// Wrong parameter count, invalid Prony parameters, a non-positive
    /// shape ([`FailureKind::InvalidParameters`]).
    pub fn at(
        &self,
        p: &[f64],
    ) -> std::result::Result<(Relaxation, std::borrow::Cow<'_, AfmSetup>), RunFailure> {
        let invalid = |message: String| RunFailure {
            kind: FailureKind::InvalidParameters,
            time: None,
            message: format!("afm-fe: {message}"),
        };
        let n = names::PRONY2.len() + if self.geometry_inputs { 2 } else { 0 };
        if p.len() != n {
            return Err(invalid(format!(
                "{} parameters given, the model has {n} ({})",
                p.len(),
                self.parameter_names().join(", ")
            )));
        }
        // Parameters in `names::PRONY2` order (G0 the shear modulus).
        let params = Relaxation::from_named(&names::PRONY2, &p[..names::PRONY2.len()])
            .map_err(|e| invalid(e.to_string()))?;
        if !self.geometry_inputs {
            return Ok((params, std::borrow::Cow::Borrowed(&self.setup)));
        }
        let (height, diameter) = (p[5], p[6]);
        if !(height > 0.0 && diameter > 0.0 && height.is_finite() && diameter.is_finite()) {
            return Err(invalid(format!(
                "cell height H = {height:e} m and base diameter D = {diameter:e} m must be \
                 positive"
            )));
        }
        let mut setup = self.setup.clone();
        setup.height = height;
        setup.diameter = diameter;
        Ok((params, std::borrow::Cow::Owned(setup)))
    }
}

/// A finite-element error as a run failure (non-convergence keeps its time).
pub fn fem_failure(e: &FemError) -> RunFailure {
    let (kind, time) = match e {
        FemError::NonConvergence(nc) => (FailureKind::NotConverged, Some(nc.time)),
        FemError::Setting { .. } | FemError::Material { .. } => {
            (FailureKind::InvalidParameters, None)
        }
        // Mesh, sparse solver, and whatever the fem crate adds later.
        _ => (FailureKind::Other, None),
    };
    RunFailure {
        kind,
        time,
        message: e.to_string(),
    }
}

impl ForwardModel for AfmFeModel {
    fn parameter_names(&self) -> Vec<String> {
        let geometry: &[&str] = if self.geometry_inputs {
            &names::GEOMETRY
        } else {
            &[]
        };
        names::PRONY2
            .iter()
            .chain(geometry)
            .map(|s| s.to_string())
            .collect()
    }
    fn parameter_units(&self) -> Vec<String> {
        let geometry: &[&str] = if self.geometry_inputs {
            &names::GEOMETRY_UNITS
        } else {
            &[]
        };
        names::PRONY2_UNITS
            .iter()
            .chain(geometry)
            .map(|s| s.to_string())
            .collect()
    }
    fn time_grid(&self) -> &[f64] {
        &self.setup.output_times
    }
    fn identity(&self) -> String {
        self.identity.clone()
    }
    fn conditions(&self) -> Option<nlvid_model::BuildConditions> {
        let s = &self.setup;
        let end = s.output_times.last().copied().unwrap_or(0.0);
        // the piezo history's travel and the time it is reached (the ramp's end)
        let z0 = s.piezo.first().map_or(0.0, |p| p.1);
        let (t_ramp, travel) = s.piezo.iter().fold((0.0, 0.0f64), |(t, a), &(ti, zi)| {
            if (zi - z0).abs() > a {
                (ti, (zi - z0).abs())
            } else {
                (t, a)
            }
        });
        let key = |q: &str, k: &str| (q.to_string(), k.to_string());
        Some(nlvid_model::BuildConditions {
            model: "afm-fe".into(),
            probe_radius_m: Some(s.probe_radius),
            ramp_time_s: Some(t_ramp),
            hold_time_s: Some((end - t_ramp).max(0.0)),
            depth_m: Some(travel),
            end_time_s: end,
            // an input shape is each run's own: no one geometry to check data against
            cell_height_m: (!self.geometry_inputs).then_some(s.height),
            cell_diameter_m: (!self.geometry_inputs).then_some(s.diameter),
            keys: vec![
                key("probe_radius_m", "[forward] probe_radius"),
                key("ramp_time_s", "[protocol] (ramp duration)"),
                key("hold_time_s", "[protocol] (hold duration)"),
                key("depth_m", "[protocol] (piezo travel)"),
                key("end_time_s", "[protocol] (hold duration: grid end)"),
                key("cell_height_m", "[forward] height"),
                key("cell_diameter_m", "[forward] diameter"),
            ],
        })
    }
    fn run(&self, p: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        let (params, setup) = self.at(p)?;
        nlvid_fem::afm::run(&params, &setup)
            .map(|r| r.force)
            .map_err(|e| fem_failure(&e))
    }
}
