//! Axisymmetric membrane elements: 2-node straight meridian elements of an
//! incompressible membrane in plane stress (thesis ch. II; §2.5.2 checks
//! the semi-analytical solution against ABAQUS membrane elements).
//!
//! The reference meridian is a polyline in the (R, Z) half-plane; each
//! element has a reference thickness h₀. Along an element with reference
//! length L and current length ℓ the meridional stretch is λ1 = ℓ/L
//! (constant), and at a point with reference and current radii R, r the hoop
//! stretch is λ2 = r/R (eqs. 2.17–2.20 with straight elements). The
//! thickness stretch is λ3 = 1/(λ1 λ2) (incompressibility), and the point
//! update is any [`MembraneMaterial`] (for ch. II's Pipkin–Rogers membrane,
//! `nlvid_material::PipkinRogers` through its plane-stress update, which
//! returns the principal Cauchy stresses σ1, σ2 and ∂σ_α/∂λ_β).
//!
//! The element is the stationary point of
//! `Π_e = Σ_q w_q Ŵ(λ1, λ2(ξ_q))`, `w_q = 2π R_q L h₀ ω_q` (two-point Gauss
//! on the element), with `∂Ŵ/∂λ_α = σ_α/λ_α` (for an incompressible
//! membrane λ_α ∂Ŵ/∂λ_α = τ_α − τ_3 = σ_α, eq. 2.21–2.24). So the residual
//! is `Σ_q w_q Σ_α (σ_α/λ_α) ∂λ_α/∂u` and the tangent
//! `Σ_q w_q [Σ_αβ A_αβ ∂λ_α/∂u ∂λ_β/∂u + (σ1/λ1) ∂²λ1/∂u²]` with
//! `A_αβ = (∂σ_α/∂λ_β)/λ_α − δ_αβ σ_α/λ_α²` (λ2 is linear in u).
//! For a history-dependent material the stresses and tangent are the
//! algorithmic ones of the point update, so the tangent is consistent.
//!
//! Principal directions: without torsion the meridian and the hoop are
//! principal, so the update in principal stretches is exact.

use crate::kind::{ElementKind, Topology};
use crate::local::bad_length;
use crate::local::{PointFailure, TangentPart};
use crate::sets::NamedSets;
use crate::{FemError, Model, Result};
use nlvid_material::{Mat3, Material3, MaterialError, MembraneMaterial};

/// Two-point Gauss rule on [0, 1]: (ξ, ω).
const GAUSS: [(f64, f64); 2] = [
    (0.211_324_865_405_187_1, 0.5),
    (0.788_675_134_594_812_9, 0.5),
];

/// An axisymmetric membrane: 2-node meridian elements in the (r, z)
/// half-plane with a thickness per element.
///
/// Node sets carry supports; a *surface* (contact, cavity) is an ordered
/// node set (a polyline).
#[derive(Debug, Clone)]
pub struct MembraneMesh {
    /// Node coordinates (r, z) in metres.
    pub nodes: Vec<[f64; 2]>,
    /// Element connectivity (two nodes along the meridian).
    pub elements: Vec<[usize; 2]>,
    /// Reference thickness h₀ of each element (m).
    pub thickness: Vec<f64>,
    pub(crate) sets: NamedSets<usize>,
}

impl MembraneMesh {
    /// A mesh from raw parts.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if a node index is out of range, a coordinate is
    /// not finite, a node has r < 0, an element has zero length, or a
    /// thickness is not positive (naming the element), or the thickness list
    /// does not match the elements.
    pub fn new(
        nodes: Vec<[f64; 2]>,
        elements: Vec<[usize; 2]>,
        thickness: Vec<f64>,
    ) -> Result<Self> {
        for (i, p) in nodes.iter().enumerate() {
            if !p[0].is_finite() || !p[1].is_finite() || p[0] < -1e-12 * (1.0 + p[1].abs()) {
                return Err(FemError::Mesh(format!(
                    "membrane node {i} at (r, z) = ({}, {}): r must be ≥ 0 and finite",
                    p[0], p[1]
                )));
            }
        }
        if thickness.len() != elements.len() {
            return Err(FemError::Mesh(format!(
                "membrane mesh: {} thicknesses for {} elements",
                thickness.len(),
                elements.len()
            )));
        }
        for (e, (conn, &h)) in elements.iter().zip(&thickness).enumerate() {
            if conn.iter().any(|&a| a >= nodes.len()) {
                return Err(FemError::Mesh(format!(
                    "membrane element {e} refers to a missing node"
                )));
            }
            let (a, b) = (nodes[conn[0]], nodes[conn[1]]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            if !(len > 0.0) {
                return Err(FemError::Mesh(format!(
                    "membrane element {e} has zero length"
                )));
            }
            if !(h > 0.0 && h.is_finite()) {
                return Err(FemError::Mesh(format!(
                    "membrane element {e} has thickness {h}: must be positive"
                )));
            }
            // Both nodes on the axis: no revolved area.
            if a[0] <= 0.0 && b[0] <= 0.0 {
                return Err(FemError::Mesh(format!(
                    "membrane element {e} lies on the axis (r = 0 at both nodes)"
                )));
            }
        }
        Ok(Self {
            nodes,
            elements,
            thickness,
            sets: NamedSets::new("node"),
        })
    }

    /// Adds (or replaces) a named node set.
    pub fn set_nodes(&mut self, name: &str, nodes: Vec<usize>) {
        self.sets.insert(name, nodes);
    }

    /// The node set called `name`.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if there is no such set.
    pub fn nodes_in(&self, name: &str) -> Result<&[usize]> {
        self.sets.get(name)
    }

    /// The upper quarter meridian of a spherical membrane of radius
    /// `radius` and thickness `thickness`, from the pole (ψ = 0) to the
    /// equator (ψ = π/2) in `n` elements equally spaced in ψ (the material
    /// nodes ψ_j = jπ/(2n) of ch. II's solver).
    ///
    /// Sets: `axis` (the pole), `equator`, and the ordered surface
    /// `meridian` (all nodes from the pole to the equator; the contact
    /// surface and, with the symmetry plane z = 0 and the axis, the cavity
    /// boundary).
    ///
    /// # Errors
    /// [`FemError::Setting`] for a non-positive radius or thickness or
    /// fewer than two elements.
    pub fn spherical(radius: f64, thickness: f64, n: usize) -> Result<Self> {
        for (name, v) in [
            ("membrane radius", radius),
            ("membrane thickness", thickness),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(FemError::Setting {
                    name,
                    value: v,
                    reason: "must be positive and finite (m)",
                });
            }
        }
        if n < 2 {
            return Err(FemError::Setting {
                name: "membrane elements",
                value: n as f64,
                reason: "use at least 2 elements along the meridian",
            });
        }
        let nodes = (0..=n)
            .map(|j| {
                let (s, c) = match j {
                    0 => (0.0, 1.0),
                    _ if j == n => (1.0, 0.0),
                    _ => (0.5 * std::f64::consts::PI * j as f64 / n as f64).sin_cos(),
                };
                [radius * s, radius * c]
            })
            .collect();
        let elements = (0..n).map(|e| [e, e + 1]).collect();
        let mut mesh = Self::new(nodes, elements, vec![thickness; n])?;
        mesh.set_nodes("axis", vec![0]);
        mesh.set_nodes("equator", vec![n]);
        mesh.set_nodes("meridian", (0..=n).collect());
        Ok(mesh)
    }
}

impl Topology for MembraneMesh {
    type Point = [f64; 2];
    type Cell = [usize; 2];
    const VTK_CELL: u8 = 3;
    fn parts(&self) -> (&[[f64; 2]], &[[usize; 2]], &NamedSets<usize>) {
        (&self.nodes, &self.elements, &self.sets)
    }
}

/// Axisymmetric membranes ([`MembraneMesh`], module docs): dofs (u_r, u_z)
/// per node, 2-node elements, two Gauss points each.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Membrane;

/// Reference data of one Gauss point of a membrane element.
#[derive(Debug, Clone, Copy)]
pub struct MembraneGauss {
    /// Shape functions (N₁, N₂) = (1 − ξ, ξ).
    pub n: [f64; 2],
    /// Reference radius R and height Z.
    pub x: [f64; 2],
    /// Weight 2π R L h₀ ω (m³).
    pub weight: f64,
}

/// Reference data of one membrane element.
#[derive(Debug, Clone, Copy)]
pub struct MembraneGeometry {
    /// Reference nodal positions.
    pub x: [[f64; 2]; 2],
    /// Reference length L.
    pub length: f64,
    /// Gauss points.
    pub points: [MembraneGauss; 2],
}

/// Residual and tangent of one membrane element (dofs r₁, z₁, r₂, z₂; the
/// tangent full, the model reads the triangle it stores).
pub type MembraneOutput = crate::local::LocalOutput<4>;

fn geometry(x: [[f64; 2]; 2], thickness: f64) -> MembraneGeometry {
    let length = (x[1][0] - x[0][0]).hypot(x[1][1] - x[0][1]);
    let points = GAUSS.map(|(xi, w)| {
        let n = [1.0 - xi, xi];
        let p = [
            n[0] * x[0][0] + n[1] * x[1][0],
            n[0] * x[0][1] + n[1] * x[1][1],
        ];
        MembraneGauss {
            n,
            x: p,
            weight: 2.0 * std::f64::consts::PI * p[0] * length * thickness * w,
        }
    });
    MembraneGeometry { x, length, points }
}

/// Current chord, its length and the stretches at every Gauss point.
fn kinematics(g: &MembraneGeometry, u: &[f64; 4]) -> ([f64; 2], f64, [[f64; 2]; 2]) {
    let x1 = [g.x[0][0] + u[0], g.x[0][1] + u[1]];
    let x2 = [g.x[1][0] + u[2], g.x[1][1] + u[3]];
    let d = [x2[0] - x1[0], x2[1] - x1[1]];
    let ell = d[0].hypot(d[1]);
    let l1 = ell / g.length;
    let stretches = g.points.map(|p| {
        let r = p.n[0] * x1[0] + p.n[1] * x2[0];
        [l1, r / p.x[0]]
    });
    (d, ell, stretches)
}

/// Internal force and tangent of one membrane element (module docs);
/// writes the trial history of its two points.
///
/// # Errors
/// The failing point and the material's error (a non-positive stretch: the
/// element collapsed or crossed the axis).
#[allow(clippy::too_many_arguments)]
pub fn membrane_element<M>(
    material: &M,
    g: &MembraneGeometry,
    u: &[f64; 4],
    state_n: &[M::State],
    trial: &mut [M::State],
    dt: f64,
    part: TangentPart,
    out: &mut MembraneOutput,
) -> std::result::Result<(), PointFailure>
where
    M: Material3 + MembraneMaterial,
{
    out.r = [0.0; 4];
    out.k = [[0.0; 4]; 4];
    let (d, ell, stretches) = kinematics(g, u);
    if !(ell > 0.0) || !ell.is_finite() {
        return Err((
            0,
            MaterialError::Deformation(format!("membrane element collapsed (length {ell:e})")),
        ));
    }
    // ∂λ1/∂u and ∂²λ1/∂u² = ±(I − n nᵀ)/(ℓ L).
    let c = 1.0 / (ell * g.length);
    let dl1 = [-d[0] * c, -d[1] * c, d[0] * c, d[1] * c];
    let n = [d[0] / ell, d[1] / ell];
    let q = [
        [1.0 - n[0] * n[0], -n[0] * n[1]],
        [-n[0] * n[1], 1.0 - n[1] * n[1]],
    ];
    for (k, p) in g.points.iter().enumerate() {
        let [l1, l2] = stretches[k];
        let resp =
            <M as MembraneMaterial>::update(material, &state_n[k], [l1, l2], dt, &mut trial[k])
                .map_err(|e| (k, e))?;
        let dl2 = [p.n[0] / p.x[0], 0.0, p.n[1] / p.x[0], 0.0];
        let s = resp.cauchy;
        let nominal = [s[0] / l1, s[1] / l2];
        for a in 0..4 {
            out.r[a] += p.weight * (nominal[0] * dl1[a] + nominal[1] * dl2[a]);
        }
        if part == TangentPart::None {
            continue;
        }
        let lam = [l1, l2];
        let mut m = [[0.0; 2]; 2];
        for al in 0..2 {
            for be in 0..2 {
                m[al][be] = resp.tangent[al][be] / lam[al]
                    - if al == be {
                        s[al] / (lam[al] * lam[al])
                    } else {
                        0.0
                    };
            }
        }
        let grads = [dl1, dl2];
        let geo = p.weight * nominal[0] * c;
        for a in 0..4 {
            for b in 0..4 {
                let mut v = 0.0;
                for al in 0..2 {
                    for be in 0..2 {
                        v += m[al][be] * grads[al][a] * grads[be][b];
                    }
                }
                let sign = if (a < 2) == (b < 2) { 1.0 } else { -1.0 };
                out.k[a][b] += p.weight * v + sign * geo * q[a % 2][b % 2];
            }
        }
    }
    Ok(())
}

impl<M> ElementKind<M> for Membrane
where
    M: Material3 + MembraneMaterial,
{
    const DIM: usize = 2;
    const NODES: usize = 2;
    const POINTS: usize = 2;
    type Mesh = MembraneMesh;
    type Geometry = MembraneGeometry;
    type Output = MembraneOutput;
    type LaneGeometry = ();
    type LaneOutput = ();

    fn lane_geometry(_: [&Self::Geometry; 4]) {}

    fn geometry(mesh: &MembraneMesh) -> Result<Vec<MembraneGeometry>> {
        Ok(mesh
            .elements
            .iter()
            .zip(&mesh.thickness)
            .map(|(conn, &h)| geometry(conn.map(|a| mesh.nodes[a]), h))
            .collect())
    }

    fn evaluate(
        material: &M,
        geometry: &MembraneGeometry,
        u: &[f64],
        state_n: &[M::State],
        trial: &mut [M::State],
        dt: f64,
        _fbar: bool,
        part: TangentPart,
        out: &mut MembraneOutput,
    ) -> std::result::Result<(), PointFailure> {
        let u: &[f64; 4] = u.try_into().map_err(|_| bad_length(u.len()))?;
        membrane_element(material, geometry, u, state_n, trial, dt, part, out)
    }

    /// `Σ_q w_q ψ(diag(λ1, λ2, 1/(λ1 λ2)))`.
    fn energy(g: &MembraneGeometry, u: &[f64], _fbar: bool, psi: &dyn Fn(&Mat3) -> f64) -> f64 {
        let Ok(u) = <&[f64; 4]>::try_from(u) else {
            return f64::NAN;
        };
        let (_, _, stretches) = kinematics(g, u);
        g.points
            .iter()
            .zip(stretches)
            .map(|(p, [l1, l2])| {
                p.weight
                    * psi(&Mat3::from_diagonal(&nalgebra::Vector3::new(
                        l1,
                        l2,
                        1.0 / (l1 * l2),
                    )))
            })
            .sum()
    }
}

/// Stretches and stresses at one Gauss point of a membrane model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembranePoint {
    /// Element index.
    pub element: usize,
    /// Reference position (R, Z) (m).
    pub reference: [f64; 2],
    /// Current position (r, z) (m).
    pub current: [f64; 2],
    /// Meridional and hoop stretches λ1, λ2.
    pub stretches: [f64; 2],
    /// Principal Cauchy stresses σ1 (meridional), σ2 (hoop) (Pa).
    pub stress: [f64; 2],
}

impl<M> Model<M, Membrane>
where
    M: Material3 + MembraneMaterial,
{
    /// Converged nodal displacements, (u_r, u_z) per node.
    pub fn membrane_displacements(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.nodal_displacements()
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
    }

    /// Stretches and stresses at every Gauss point (element order) in the
    /// converged state. The stress is the point update at the converged
    /// stretches with the converged history and Δt = 0, which is the
    /// converged stress itself (a zero step leaves the hereditary integrals
    /// unchanged).
    ///
    /// # Errors
    /// [`FemError::Material`] if a point cannot be evaluated.
    pub fn membrane_points(&self) -> Result<Vec<MembranePoint>> {
        let (material, geometry, history, u) = self.converged_parts();
        let mut out = Vec::with_capacity(2 * geometry.len());
        let mut scratch = material.initial_state();
        for (e, g) in geometry.iter().enumerate() {
            let conn = self.mesh().elements[e];
            let ue = [
                u[2 * conn[0]],
                u[2 * conn[0] + 1],
                u[2 * conn[1]],
                u[2 * conn[1] + 1],
            ];
            let (_, _, stretches) = kinematics(g, &ue);
            for (q, p) in g.points.iter().enumerate() {
                let state = history.committed(2 * e + q);
                let resp = <M as MembraneMaterial>::update(
                    material,
                    state,
                    stretches[q],
                    0.0,
                    &mut scratch,
                )
                .map_err(|source| FemError::Material {
                    element: e,
                    point: q,
                    source,
                })?;
                out.push(MembranePoint {
                    element: e,
                    reference: p.x,
                    current: [
                        p.n[0] * (g.x[0][0] + ue[0]) + p.n[1] * (g.x[1][0] + ue[2]),
                        p.n[0] * (g.x[0][1] + ue[1]) + p.n[1] * (g.x[1][1] + ue[3]),
                    ],
                    stretches: stretches[q],
                    stress: resp.cauchy,
                });
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlvid_material::{MooneyRivlin, PipkinRogers, PointState};
    use nlvid_model::{Prony, Relaxation};

    fn pipkin_rogers() -> PipkinRogers {
        let g1 = Relaxation::new("G1", 1.0e6, Prony::new("G1", &[(0.5, 0.7)]).unwrap()).unwrap();
        let g2 = Relaxation::new("G2", 0.2e6, Prony::new("G2", &[(0.3, 0.2)]).unwrap()).unwrap();
        PipkinRogers::new(g1, g2, 0.1, 0.0).unwrap()
    }

    fn element() -> MembraneGeometry {
        geometry([[0.3e-3, 0.9e-3], [0.5e-3, 0.75e-3]], 2e-5)
    }

    /// Residual of the element with history `state` over `dt` at `u`.
    fn residual<M>(m: &M, g: &MembraneGeometry, u: &[f64; 4], st: &[M::State], dt: f64) -> [f64; 4]
    where
        M: Material3 + MembraneMaterial,
    {
        let mut trial = st.to_vec();
        let mut out = <Membrane as ElementKind<M>>::output();
        membrane_element(m, g, u, st, &mut trial, dt, TangentPart::None, &mut out).unwrap();
        out.r
    }

    fn check_tangent<M>(m: &M, st: &[M::State], dt: f64, u: [f64; 4])
    where
        M: Material3 + MembraneMaterial,
    {
        let g = element();
        let mut trial = st.to_vec();
        let mut out = <Membrane as ElementKind<M>>::output();
        membrane_element(m, &g, &u, st, &mut trial, dt, TangentPart::Full, &mut out).unwrap();
        let kmax = out.k.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
        let h = 1e-10;
        for b in 0..4 {
            let (mut up, mut um) = (u, u);
            up[b] += h;
            um[b] -= h;
            let (rp, rm) = (residual(m, &g, &up, st, dt), residual(m, &g, &um, st, dt));
            for a in 0..4 {
                let fd = (rp[a] - rm[a]) / (2.0 * h);
                assert!(
                    (fd - out.k[a][b]).abs() < 1e-6 * kmax,
                    "K[{a}][{b}] = {} vs fd {fd}",
                    out.k[a][b]
                );
                assert!((out.k[a][b] - out.k[b][a]).abs() < 1e-9 * kmax);
            }
        }
    }

    #[test]
    fn tangent_matches_finite_differences_elastic_and_with_history() {
        let u = [0.05e-3, 0.02e-3, 0.09e-3, -0.03e-3];
        let mr = MooneyRivlin::new(1e6, 0.1e6, 0.0).unwrap();
        check_tangent(&mr, &[(), ()], 0.0, u);
        // Pipkin–Rogers with a history from an earlier step.
        let pr = pipkin_rogers();
        let g = element();
        let st0 = vec![pr.initial_state(); 2];
        let mut st1 = st0.clone();
        let mut out = <Membrane as ElementKind<PipkinRogers>>::output();
        let u0 = [0.02e-3, 0.01e-3, 0.03e-3, -0.01e-3];
        membrane_element(
            &pr,
            &g,
            &u0,
            &st0,
            &mut st1,
            0.0,
            TangentPart::None,
            &mut out,
        )
        .unwrap();
        check_tangent(&pr, &st1, 0.3, u);
    }

    #[test]
    fn residual_is_the_gradient_of_the_element_energy() {
        // Mooney–Rivlin: Ŵ = C1(I1 − 3) + C2(I2 − 3) with λ3 = 1/(λ1 λ2).
        let (c1, c2) = (1e6, 0.1e6);
        let mr = MooneyRivlin::new(c1, c2, 0.0).unwrap();
        let psi = |f: &Mat3| {
            let l = [f[(0, 0)], f[(1, 1)], f[(2, 2)]];
            let i1 = l.iter().map(|x| x * x).sum::<f64>();
            let i2 = (l[0] * l[1]).powi(2) + (l[1] * l[2]).powi(2) + (l[0] * l[2]).powi(2);
            c1 * (i1 - 3.0) + c2 * (i2 - 3.0)
        };
        let g = element();
        let u = [0.05e-3, 0.02e-3, 0.09e-3, -0.03e-3];
        let r = residual(&mr, &g, &u, &[(), ()], 0.0);
        let e = |u: &[f64; 4]| <Membrane as ElementKind<MooneyRivlin>>::energy(&g, u, true, &psi);
        let h = 1e-10;
        for a in 0..4 {
            let (mut up, mut um) = (u, u);
            up[a] += h;
            um[a] -= h;
            let fd = (e(&up) - e(&um)) / (2.0 * h);
            assert!(
                (fd - r[a]).abs() < 1e-6 * r.iter().fold(0.0f64, |m, x| m.max(x.abs())),
                "{a}: {fd} vs {}",
                r[a]
            );
        }
    }

    #[test]
    fn collapsed_or_axis_crossing_element_is_a_material_error() {
        let mr = MooneyRivlin::new(1e6, 0.1e6, 0.0).unwrap();
        let g = geometry([[0.25, 1.0], [0.5, 0.75]], 0.01);
        let mut out = <Membrane as ElementKind<MooneyRivlin>>::output();
        let mut trial = [(), ()];
        // Node 1 moved onto node 0; both nodes pushed across the axis.
        for u in [[0.0, 0.0, -0.25, 0.25], [-0.4, 0.0, -0.6, 0.0]] {
            let step = membrane_element(
                &mr,
                &g,
                &u,
                &[(), ()],
                &mut trial,
                0.0,
                TangentPart::Full,
                &mut out,
            );
            assert!(step.is_err(), "{u:?}");
        }
    }

    #[test]
    fn bad_meshes_are_rejected_with_the_element_named() {
        let e =
            MembraneMesh::new(vec![[0.0, 1.0], [0.0, 1.0]], vec![[0, 1]], vec![1e-3]).unwrap_err();
        assert!(e.to_string().contains("element 0"), "{e}");
        let e =
            MembraneMesh::new(vec![[0.0, 1.0], [1.0, 0.0]], vec![[0, 1]], vec![-1e-3]).unwrap_err();
        assert!(e.to_string().contains("thickness"), "{e}");
        let e =
            MembraneMesh::new(vec![[-1.0, 1.0], [1.0, 0.0]], vec![[0, 1]], vec![1e-3]).unwrap_err();
        assert!(e.to_string().contains("node 0"), "{e}");
        assert!(MembraneMesh::spherical(1.0, 0.01, 1).is_err());
    }
}
