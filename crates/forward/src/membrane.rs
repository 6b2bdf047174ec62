//! `model = "membrane"`: the ch. II semi-analytical solver for a
//! fluid-filled Pipkin–Rogers membrane between two plates
//! (`nlvid_membrane::simulate`, eqs. 2.33–2.56), in physical units.
//!
//! Parameters `[G10 (Pa), gamma0, g1_long_term, g2_long_term, tau1 (s),
//! tau2 (s)]` (names as in `docs/theory/model.md`):
//! G1(t) = G10 [g1 + (1 − g1) e^{−t/τ1}], G2(t) = γ0 G10 [g2 + (1 − g2) e^{−t/τ2}]
//! (eq. 2.56; G10 = G1(0), ch. II's modulus; g1, g2 are the long-term
//! *fractions* Gα∞/Gα0, in (0, 1], not Prony weights, hence
//! `g1_long_term`, `g2_long_term`), c = τ1/τ2. The plate displacement D(t)
//! per plate comes from `[protocol]` in metres and is divided by r0; the
//! solver's dimensionless force F/(G10 h0 r0) (eq. 2.47) is multiplied back
//! to newtons.

use nlvid_membrane::{ControlKind, Geometry, Loading, MembraneError, PipkinRogersParams, simulate};
use nlvid_model::{FailureKind, ForwardModel, RunFailure};
use nlvid_protocol::{Program, ProgramBuilder, Quantity};
use nlvid_study::{Bounds, Dimension, Section};

use crate::error::{ForwardError, Result};

/// Parameter names of the membrane model, in order: ch. II's `G10` =
/// G1(0) (Pa), `gamma0` = G2(0)/G1(0), the long-term fractions of eq. 2.56
/// and the two relaxation times (s).
pub const PARAMETERS: [&str; 6] = [
    nlvid_model::names::G10,
    nlvid_model::names::GAMMA0,
    "g1_long_term",
    "g2_long_term",
    "tau1",
    "tau2",
];

/// Settings of the membrane forward model (everything but the six material
/// parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct MembraneSpec {
    /// Undeformed radius r0 [m].
    pub radius: f64,
    /// Wall thickness h0 [m].
    pub wall_thickness: f64,
    /// Inflated radius r_s/r0 (thesis 1.03).
    pub rs: f64,
    /// RK4 intervals on 0 ≤ ψ ≤ π/2.
    pub nodes: usize,
    /// Exponent a of Φ (eq. 2.54), 0 in the thesis's code.
    pub a: f64,
    /// Plate displacement D(t) per plate [m] (from `[protocol]`).
    pub program: Program,
    /// Output points m, equally spaced over the program (breakpoints added).
    pub points: usize,
}

impl MembraneSpec {
    /// Reads `radius`, `wall_thickness`, `rs`, `nodes`, `a` from
    /// `[forward]`; `program` is the `[protocol]` section's displacement
    /// program.
    ///
    /// # Errors
    /// Missing key, wrong unit, out-of-range value (file, line, key).
    pub fn from_section(s: &mut Section, program: Program, points: usize) -> Result<Self> {
        let pos = Bounds::positive();
        let radius = s.req_quantity("radius", Dimension::LENGTH, pos)?;
        let wall_thickness = s.req_quantity("wall_thickness", Dimension::LENGTH, pos)?;
        if wall_thickness >= radius {
            return Err(s
                .invalid("wall_thickness", "must be smaller than `radius`")
                .into());
        }
        let rs = s.f64_or("rs", Bounds::closed_open(1.0, 3.0), 1.03)?;
        let nodes = s
            .opt_usize("nodes", Bounds::closed(8.0, 100_000.0))?
            .unwrap_or(64);
        let a = s.f64_or("a", Bounds::non_negative(), 0.0)?;
        Ok(Self {
            radius,
            wall_thickness,
            rs,
            nodes,
            a,
            program,
            points,
        })
    }

    /// The forward model.
    ///
    /// # Errors
    /// The program is not a displacement program, or the grid is unusable.
    pub fn build(&self) -> Result<MembraneModel> {
        let bad = |message: String| ForwardError::Setting {
            model: "membrane",
            message,
        };
        if self.program.quantity() != Quantity::Displacement {
            return Err(bad(format!(
                "the membrane adapter follows a plate displacement program; [protocol] gives {:?} \
                 (set control = \"displacement\")",
                self.program.quantity()
            )));
        }
        let scaled = scale(&self.program, 1.0 / self.radius).map_err(|e| bad(e.to_string()))?;
        let times = self
            .program
            .uniform_grid(self.points)
            .map_err(|e| bad(e.to_string()))?;
        let loading = Loading::new(ControlKind::Displacement, scaled, times)
            .map_err(|e| bad(e.to_string()))?;
        let geometry = Geometry {
            rs: self.rs,
            nodes: self.nodes,
        };
        geometry.check().map_err(|e| bad(e.to_string()))?;
        let identity = format!(
            "membrane(r0={:e},h0={:e},rs={:e},nodes={},a={:e},program={:?},times={:?})",
            self.radius,
            self.wall_thickness,
            self.rs,
            self.nodes,
            self.a,
            self.program.segments(),
            loading.times
        );
        Ok(MembraneModel {
            r0: self.radius,
            h0: self.wall_thickness,
            a: self.a,
            geometry,
            loading,
            identity,
        })
    }
}

/// `p` with every value multiplied by `factor`, as a dimensionless program.
fn scale(p: &Program, factor: f64) -> nlvid_protocol::Result<Program> {
    let segs = p.segments();
    let (t0, v0) = segs.first().map_or((0.0, 0.0), |s| (s.t0, s.v0));
    let mut b = ProgramBuilder::starting_at(Quantity::Dimensionless, t0, v0 * factor);
    for s in segs {
        b = if s.is_jump() {
            b.jump_to(s.v1 * factor)?
        } else {
            b.line_to(s.t1, s.v1 * factor, s.label)?
        };
    }
    b.build()
}

/// The membrane solver as a [`ForwardModel`]: parameters [`PARAMETERS`]
/// `[G10 (Pa), gamma0, g1_long_term, g2_long_term, tau1 (s), tau2 (s)]`, response F(t) [N] on
/// the solve times (the uniform grid plus the program's breakpoints).
#[derive(Debug, Clone)]
pub struct MembraneModel {
    r0: f64,
    h0: f64,
    a: f64,
    geometry: Geometry,
    loading: Loading,
    identity: String,
}

impl MembraneModel {
    /// The loading (dimensionless D/r0 program, solve times in s).
    pub fn loading(&self) -> &Loading {
        &self.loading
    }
    /// The geometry (r_s, nodes).
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }
    /// The material parameters of one run (eq. 2.56 with c = τ1/τ2).
    pub fn params(&self, p: &[f64]) -> std::result::Result<PipkinRogersParams, RunFailure> {
        let &[g10, gamma0, g1, g2, tau1, tau2] = p else {
            return Err(RunFailure {
                kind: FailureKind::InvalidParameters,
                time: None,
                message: format!(
                    "membrane expects 6 parameters [{}], got {}",
                    PARAMETERS.join(", "),
                    p.len()
                ),
            });
        };
        Ok(PipkinRogersParams {
            g10,
            gamma0,
            g1,
            g2,
            c: tau1 / tau2,
            tau1,
            a: self.a,
        })
    }
}

/// A membrane error as a run failure.
pub fn membrane_failure(e: &MembraneError) -> RunFailure {
    let (kind, time) = match e {
        MembraneError::Input { .. } => (FailureKind::InvalidParameters, None),
        MembraneError::NoConvergence { time, .. } => (FailureKind::NotConverged, Some(*time)),
        MembraneError::Wrinkling { time, .. } | MembraneError::Material { time, .. } => {
            (FailureKind::Other, Some(*time))
        }
    };
    RunFailure {
        kind,
        time,
        message: e.to_string(),
    }
}

impl MembraneModel {
    /// One full run at `p` (SI, the order of `parameter_names`): the
    /// dimensionless history and the profiles kept at the solve times
    /// nearest to `profile_times` (s). Scale the history with
    /// [`MembraneModel::scales`].
    ///
    /// # Errors
    /// Bad parameters; the solver's errors (wrinkling, non-convergence).
    pub fn run_full(
        &self,
        p: &[f64],
        profile_times: &[f64],
    ) -> std::result::Result<nlvid_membrane::MembraneRun, RunFailure> {
        let params = self.params(p)?;
        let loading = self.loading.clone().with_profiles(profile_times);
        simulate(&params, &self.geometry, &loading).map_err(|e| membrane_failure(&e))
    }

    /// The scales of eq. 2.47 at `p`: length r0 (m), wall thickness h0 (m)
    /// and stress G1(0) (Pa): force F = F̄·G1(0)·h0·r0, pressure
    /// p = p̄·G1(0)·h0/r0, tension T = T̄·G1(0)·h0.
    ///
    /// # Errors
    /// A parameter vector of the wrong length.
    pub fn scales(&self, p: &[f64]) -> std::result::Result<(f64, f64, f64), RunFailure> {
        Ok((self.r0, self.h0, self.params(p)?.g10))
    }
}

impl ForwardModel for MembraneModel {
    fn parameter_names(&self) -> Vec<String> {
        PARAMETERS.map(String::from).to_vec()
    }
    fn parameter_units(&self) -> Vec<String> {
        // modulus, ratio, two weights, two times: the units of ch. IV's six
        nlvid_model::names::CAPSULE_UNITS.map(String::from).to_vec()
    }
    fn time_grid(&self) -> &[f64] {
        &self.loading.times
    }
    fn contact_index(&self) -> usize {
        // t = 0 is the undeformed state (D = 0, F = 0).
        1
    }
    fn identity(&self) -> String {
        self.identity.clone()
    }
    fn run(&self, p: &[f64]) -> std::result::Result<Vec<f64>, RunFailure> {
        let params = self.params(p)?;
        let run =
            simulate(&params, &self.geometry, &self.loading).map_err(|e| membrane_failure(&e))?;
        let scale = params.g10 * self.h0 * self.r0;
        Ok(run.force().into_iter().map(|f| f * scale).collect())
    }
}
