//! Frictionless penalty contact of a surface polyline with a rigid sphere
//! (the AFM probe, moving along the axis with the unknown w),
//! **integrated along the surface segments** (axisymmetric models; the
//! rigid planes of 2D and 3D models keep nodal penalties, `model/assemble.rs`).
//!
//! Potential: Π_c = ∫_Γ ½ κ ⟨−g⟩² dA₀ with dA₀ = 2π r dS the reference
//! area, κ = `penalty` · G / L the pressure per unit penetration (G the
//! shear modulus at F = I, L the segment's reference length; penetration
//! ≈ p L / (penalty G)), and g interpolated linearly between the gaps of
//! the segment's two nodes (the nodes' distances to the obstacle), so the
//! gap is exact at the nodes as before. The integral over the closed part
//! of each segment is exact (split at the root of g).
//!
//! Why integrated and not lumped at the nodes (sessions 1–3): with nodal
//! penalties the contact force jumps in slope each time the contact edge
//! reaches a node, so F(δ) scatters by ±1 % on a mesh with 5–10 nodes in
//! the contact radius (Hertz check: −0.8 … −2.6 %); integrated, the edge
//! moves continuously through each segment and F(δ) is smooth. Why the
//! linear gap and not the gap of the interpolated surface point: a straight
//! segment whose ends lie on the sphere is a chord inside it, so its
//! interior points would penetrate by up to L²/8R and push the surface out
//! (measured on the dome: +3 % at δ = 0.05 µm on the 35×35 mesh).

use crate::Result;
use crate::sparse::{NO_SLOT, SparseSystem};

/// Gauss–Legendre rule on [0, 1] (abscissa, weight; weights sum 1),
/// 3 points: exact for the cubic integrand r g² of an active interval.
const GAUSS_3: [(f64, f64); 3] = [
    (0.112_701_665_379_258_31, 5.0 / 18.0),
    (0.5, 8.0 / 18.0),
    (0.887_298_334_620_741_7, 5.0 / 18.0),
];

/// The rigid obstacle at one instant (an enum so that other analytic
/// surfaces can join).
#[derive(Debug, Clone, Copy)]
pub(crate) enum Obstacle {
    /// Sphere on the axis: centre height (m, current), radius (m); its
    /// vertical displacement is the unknown w.
    Sphere {
        /// Current centre height.
        centre_z: f64,
        /// Radius.
        radius: f64,
    },
}

struct Segment {
    /// Positions of its two nodes in the surface list.
    ends: [usize; 2],
    /// Reference radii of its nodes (m).
    radii: [f64; 2],
    /// 2π L (L the reference length, m).
    two_pi_l: f64,
    /// Penalty κ (Pa/m).
    kappa: f64,
    /// Slots over (u_ar, u_az, u_br, u_bz, w), row-major 5×5.
    slots: [usize; 25],
}

/// Gap data of one surface node at the current displacements.
#[derive(Debug, Default, Clone, Copy)]
struct NodeGap {
    /// Gap (m, negative = penetration).
    g: f64,
    /// Outward normal of the obstacle at the node's closest point.
    n: [f64; 2],
    /// 1/|x − c|: curvature of the gap.
    inv_dist: f64,
}

/// Gap of the point `x` (deformed) to `obstacle`.
fn node_gap(x: [f64; 2], obstacle: Obstacle) -> NodeGap {
    match obstacle {
        Obstacle::Sphere { centre_z, radius } => {
            let d = [x[0], x[1] - centre_z];
            let dist = (d[0] * d[0] + d[1] * d[1]).sqrt();
            if dist > 0.0 {
                NodeGap {
                    g: dist - radius,
                    n: [d[0] / dist, d[1] / dist],
                    inv_dist: 1.0 / dist,
                }
            } else {
                NodeGap {
                    g: f64::INFINITY,
                    n: [0.0, -1.0],
                    inv_dist: 0.0,
                }
            }
        }
    }
}

/// The contact surface of one obstacle.
pub(crate) struct ContactSurface {
    nodes: Vec<usize>,
    segments: Vec<Segment>,
    /// Largest penalty stiffness of one segment, κ × its area (N/m): the
    /// scale of the probe row when w is prescribed.
    stiffness_scale: f64,
    /// Work array: gap data per surface node.
    gaps: Vec<NodeGap>,
}

/// What one contact assembly adds up.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct ContactSums {
    /// Upward force of the body on the obstacle (N).
    pub force: f64,
    /// Deepest penetration at a node (m, ≥ 0).
    pub penetration: f64,
    /// Segments in contact.
    pub active: usize,
}

/// Equation blocks a surface couples: each segment's two nodes and w.
pub(crate) fn blocks(surface: &[usize], dof_eq: &[usize], w_eq: Option<usize>) -> Vec<Vec<usize>> {
    surface
        .windows(2)
        .map(|s| {
            [
                dof_eq[2 * s[0]],
                dof_eq[2 * s[0] + 1],
                dof_eq[2 * s[1]],
                dof_eq[2 * s[1] + 1],
                w_eq.unwrap_or(NO_SLOT),
            ]
            .into_iter()
            .filter(|&e| e != NO_SLOT)
            .collect()
        })
        .collect()
}

impl ContactSurface {
    /// The segments of the ordered node list `surface`; `w_eq` the probe's
    /// equation; `modulus` the shear modulus at F = I.
    pub(crate) fn new(
        nodes: &[[f64; 2]],
        surface: &[usize],
        dof_eq: &[usize],
        w_eq: Option<usize>,
        penalty: f64,
        modulus: f64,
        system: &SparseSystem,
    ) -> Result<Self> {
        let mut segments = Vec::with_capacity(surface.len().saturating_sub(1));
        let mut tmp = Vec::with_capacity(25);
        let mut stiffness_scale: f64 = 0.0;
        for (k, s) in surface.windows(2).enumerate() {
            let (a, b) = (nodes[s[0]], nodes[s[1]]);
            let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            let kappa = penalty * modulus / length.max(f64::MIN_POSITIVE);
            let two_pi_l = 2.0 * std::f64::consts::PI * length;
            stiffness_scale = stiffness_scale.max(kappa * two_pi_l * 0.5 * (a[0] + b[0]));
            let eqs = [
                dof_eq[2 * s[0]],
                dof_eq[2 * s[0] + 1],
                dof_eq[2 * s[1]],
                dof_eq[2 * s[1] + 1],
                w_eq.unwrap_or(NO_SLOT),
            ];
            system.block_slots(&eqs, &mut tmp)?;
            let mut slots = [NO_SLOT; 25];
            slots.copy_from_slice(&tmp);
            segments.push(Segment {
                ends: [k, k + 1],
                radii: [a[0], b[0]],
                two_pi_l,
                kappa,
                slots,
            });
        }
        Ok(Self {
            nodes: surface.to_vec(),
            segments,
            stiffness_scale,
            gaps: vec![NodeGap::default(); surface.len()],
        })
    }

    /// Smallest gap of a surface node to `obstacle` at displacements `u`
    /// (m; +∞ for an empty surface).
    pub(crate) fn min_gap(&self, nodes: &[[f64; 2]], u: &[f64], obstacle: Obstacle) -> f64 {
        self.nodes
            .iter()
            .map(|&a| {
                node_gap(
                    [nodes[a][0] + u[2 * a], nodes[a][1] + u[2 * a + 1]],
                    obstacle,
                )
                .g
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// κ × area of the stiffest segment (N/m).
    pub(crate) fn stiffness_scale(&self) -> f64 {
        self.stiffness_scale
    }

    /// Adds the contact residual (and tangent) at displacements `u`
    /// (nodal (u_r, u_z) pairs, then w at `w_dof`). `w_coupled`: the w
    /// row and column take part (false for a prescribed w).
    ///
    /// The gap is interpolated linearly between the nodal gaps,
    /// g(ξ) = N_a g_a + N_b g_b, and ∫ ½ κ ⟨−g⟩² 2π r L dξ is integrated
    /// exactly over the closed part of each segment (split at the root of
    /// g, 3-point Gauss on the cubic r g²), so the force is smooth in the
    /// displacements as the contact edge crosses a segment. With the
    /// moments S_xy = ∫ N_x N_y dA and T_x = ∫ κ g N_x dA over the closed
    /// part: residual T_a ∇g_a + T_b ∇g_b; tangent
    /// κ Σ S_xy ∇g_x ∇g_yᵀ + T_a ∇²g_a + T_b ∇²g_b (the boundary terms of
    /// the moving split vanish with the integrand).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn assemble(
        &mut self,
        nodes: &[[f64; 2]],
        u: &[f64],
        w_dof: usize,
        obstacle: Obstacle,
        w_coupled: bool,
        tangent: bool,
        residual: &mut [f64],
        values: &mut [f64],
    ) -> ContactSums {
        let mut sums = ContactSums::default();
        for (gap, &a) in self.gaps.iter_mut().zip(&self.nodes) {
            let x = [nodes[a][0] + u[2 * a], nodes[a][1] + u[2 * a + 1]];
            *gap = node_gap(x, obstacle);
            if gap.g.is_finite() {
                sums.penetration = sums.penetration.max(-gap.g);
            }
        }
        let gaps = &self.gaps;
        for seg in &self.segments {
            let (ga, gb) = (gaps[seg.ends[0]], gaps[seg.ends[1]]);
            if ga.g > 0.0 && gb.g > 0.0 {
                continue;
            }
            if !(ga.g.is_finite() && gb.g.is_finite()) {
                continue;
            }
            // Closed part [x0, x1] of the segment (g ≤ 0).
            let (x0, x1) = if ga.g <= 0.0 && gb.g <= 0.0 {
                (0.0, 1.0)
            } else {
                let root = ga.g / (ga.g - gb.g);
                if ga.g <= 0.0 {
                    (0.0, root)
                } else {
                    (root, 1.0)
                }
            };
            if !(x1 > x0) {
                continue;
            }
            sums.active += 1;
            let (mut saa, mut sab, mut sbb, mut ta, mut tb) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for &(q, w) in &GAUSS_3 {
                let xi = x0 + (x1 - x0) * q;
                let (na, nb) = (1.0 - xi, xi);
                let r = na * seg.radii[0] + nb * seg.radii[1];
                let area = seg.two_pi_l * r * (x1 - x0) * w;
                let g = na * ga.g + nb * gb.g;
                saa += area * na * na;
                sab += area * na * nb;
                sbb += area * nb * nb;
                ta += seg.kappa * area * g * na;
                tb += seg.kappa * area * g * nb;
            }
            // ∇g over (u_ar, u_az, u_br, u_bz, w): the sphere moves with w.
            let da = [ga.n[0], ga.n[1], 0.0, 0.0, -ga.n[1]];
            let db = [0.0, 0.0, gb.n[0], gb.n[1], -gb.n[1]];
            let mut r = [0.0; 5];
            for i in 0..5 {
                r[i] = ta * da[i] + tb * db[i];
            }
            sums.force += ta * ga.n[1] + tb * gb.n[1];
            let dofs = [
                2 * self.nodes[seg.ends[0]],
                2 * self.nodes[seg.ends[0]] + 1,
                2 * self.nodes[seg.ends[1]],
                2 * self.nodes[seg.ends[1]] + 1,
                w_dof,
            ];
            let m = if w_coupled { 5 } else { 4 };
            for i in 0..m {
                residual[dofs[i]] += r[i];
            }
            if !tangent {
                continue;
            }
            let kappa = seg.kappa;
            // ∇²g_x = B_xᵀ (I − n nᵀ) B_x / |d|, B_x picking (u_x, −w).
            let hess = |gap: &NodeGap, off: usize, i: usize, j: usize| -> f64 {
                let pick = |k: usize| -> Option<(usize, f64)> {
                    match k {
                        _ if k == off => Some((0, 1.0)),
                        _ if k == off + 1 => Some((1, 1.0)),
                        4 => Some((1, -1.0)),
                        _ => None,
                    }
                };
                match (pick(i), pick(j)) {
                    (Some((a, sa)), Some((b, sb))) => {
                        let p = f64::from(u8::from(a == b)) - gap.n[a] * gap.n[b];
                        sa * sb * p * gap.inv_dist
                    }
                    _ => 0.0,
                }
            };
            for i in 0..m {
                for j in 0..m {
                    let s = seg.slots[5 * i + j];
                    if s == NO_SLOT {
                        continue;
                    }
                    let mut v = kappa
                        * (saa * da[i] * da[j]
                            + sab * (da[i] * db[j] + db[i] * da[j])
                            + sbb * db[i] * db[j]);
                    if ga.inv_dist != 0.0 || gb.inv_dist != 0.0 {
                        v += ta * hess(&ga, 0, i, j) + tb * hess(&gb, 2, i, j);
                    }
                    values[s] += v;
                }
            }
        }
        sums
    }
}
