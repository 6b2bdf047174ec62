//! The parts of a model besides mesh and material: supports, the rigid
//! probe and planes, the fluid cavity, and the per-step loads
//! ([`Control`]).

use super::*;

/// Displacement component of a support.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// Radial (axisymmetric models).
    R,
    /// Axial (axisymmetric) or vertical (3D).
    Z,
    /// x (3D models).
    X,
    /// y (3D models).
    Y,
}

impl Component {
    /// The component's index among a node's `dim` dofs, if it has one.
    pub(super) fn index(self, dim: usize) -> Option<usize> {
        match (self, dim) {
            (Component::R, 2) | (Component::X, 3) => Some(0),
            (Component::Y, 3) => Some(1),
            (Component::Z, _) => Some(dim - 1),
            _ => None,
        }
    }

    pub(super) fn checked_index(self, dim: usize) -> Result<usize> {
        self.index(dim).ok_or(FemError::Setting {
            name: "support component",
            value: dim as f64,
            reason: "R and Z apply to axisymmetric models (2 dofs per node), X, Y and Z to 3D ones",
        })
    }
}

/// A prescribed displacement on every node of a named set; its value at
/// time t is `value × Control::support_scale`.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// Node set name.
    pub set: String,
    /// Constrained component.
    pub component: Component,
    /// Displacement at support scale 1 (m).
    pub value: f64,
}

impl Support {
    /// A fixed (zero) displacement.
    pub fn fixed(set: &str, component: Component) -> Self {
        Self {
            set: set.to_owned(),
            component,
            value: 0.0,
        }
    }
}

/// A rigid sphere moving along the axis, in frictionless penalty contact
/// with an ordered surface node set.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereProbe {
    /// Sphere radius (m).
    pub radius: f64,
    /// Height of the centre at w = 0 (m).
    pub centre_z: f64,
    /// Ordered surface node set that may touch it.
    pub surface: String,
}

/// A rigid horizontal plane (normal along z), in frictionless penalty
/// contact with a surface that may separate from it again.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidPlane {
    /// The surface that may touch it: an ordered node set (axisymmetric) or
    /// a face set (3D).
    pub surface: String,
    /// Where it is and which way it faces.
    pub side: PlaneSide,
}

/// Position of a [`RigidPlane`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlaneSide {
    /// Above the body, facing down, at height [`Control::plane_z`] (the
    /// moving plate).
    Above,
    /// Below the body, facing up, fixed at this height (m).
    Below(f64),
}

impl RigidPlane {
    /// The plane above `surface` driven by [`Control::plane_z`].
    pub fn above(surface: &str) -> Self {
        Self {
            surface: surface.to_owned(),
            side: PlaneSide::Above,
        }
    }

    /// A fixed plane at height `z` below `surface`.
    pub fn below(surface: &str, z: f64) -> Self {
        Self {
            surface: surface.to_owned(),
            side: PlaneSide::Below(z),
        }
    }
}

/// The fluid filling a [`Cavity`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fluid {
    /// Volume conserved exactly (the thesis's oil, §4.3): p is a Lagrange
    /// multiplier.
    Incompressible,
    /// Linear barotropic fluid p = K_f (V₀ + ΔV_in − V)/V₀.
    Compressible {
        /// Bulk modulus K_f (Pa).
        bulk_modulus: f64,
    },
}

/// A closed fluid-filled cavity bounded by a surface of the body (and by
/// symmetry planes through the origin, which need no cells; see
/// [`crate::cavity`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Cavity {
    /// Its boundary: an ordered (r, z) node polyline (axisymmetric) or a
    /// face set (3D) with consistently oriented faces.
    pub boundary: String,
    /// The fluid.
    pub fluid: Fluid,
}

/// Everything a model holds besides its mesh and material.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Parts {
    /// Prescribed displacements (supports, symmetry rollers).
    pub supports: Vec<Support>,
    /// The rigid sphere (axisymmetric models only).
    pub probe: Option<SphereProbe>,
    /// Rigid planes.
    pub planes: Vec<RigidPlane>,
    /// A fluid cavity.
    pub cavity: Option<Cavity>,
}

impl Parts {
    /// The eighth of a fluid-filled capsule compressed by a plate
    /// (§4.3): symmetry rollers on the planes x = 0, y = 0, z = 0 (node
    /// sets `x0`, `y0`, `z0` of [`crate::ellipsoidal_shell`]), a rigid
    /// plate above the outer surface (`outer`) and the fluid in the
    /// cavity bounded by `inner`.
    pub fn eighth_capsule(fluid: Fluid) -> Self {
        Self {
            supports: vec![
                Support::fixed("x0", Component::X),
                Support::fixed("y0", Component::Y),
                Support::fixed("z0", Component::Z),
            ],
            planes: vec![RigidPlane::above("outer")],
            cavity: Some(Cavity {
                boundary: "inner".into(),
                fluid,
            }),
            ..Self::default()
        }
    }
}

/// How the probe's vertical displacement w is driven.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProbeDrive {
    /// w prescribed (m): the rigid-cantilever option.
    Displacement(f64),
    /// A downward force (N) on the probe: force-controlled engagement.
    Force(f64),
    /// A spring of `stiffness` (N/m) between the probe and a point whose
    /// vertical displacement is `free_end` (m): the cantilever.
    Spring {
        /// Spring constant k (N/m).
        stiffness: f64,
        /// Displacement of the spring's free end (m, z up).
        free_end: f64,
    },
}

/// Loads at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Control {
    /// Probe drive.
    pub probe: ProbeDrive,
    /// Plane height (m), if there is a plane.
    pub plane_z: f64,
    /// Scale of the prescribed support displacements.
    pub support_scale: f64,
    /// Volume of fluid injected into the cavity since t = 0 (m³; the
    /// cavity's own volume units: the full revolved volume for
    /// axisymmetric models, the modelled part for cut 3D models).
    pub fluid_injected: f64,
}

impl Default for Control {
    fn default() -> Self {
        Self {
            probe: ProbeDrive::Displacement(0.0),
            plane_z: f64::INFINITY,
            support_scale: 1.0,
            fluid_injected: 0.0,
        }
    }
}
