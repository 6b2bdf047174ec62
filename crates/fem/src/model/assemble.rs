//! Global assembly: the element loop (serial in lanes, or threaded), contact
//! with the probe and the planes, the fluid cavity, and the scatter of
//! element outputs into the global residual and tangent.

use super::*;
use crate::local::PointFailure;

impl<M: Material3, K: ElementKind<M>> Model<M, K> {
    pub(super) fn assemble(&mut self, ctl: &Control, dt: f64, tangent: bool) -> Result<Assembly> {
        let clock = cpu_time::ThreadTime::now();
        let out = self.assemble_inner(ctl, dt, tangent);
        self.counters.assembly_seconds += clock.elapsed().as_secs_f64();
        out
    }

    pub(super) fn assemble_inner(
        &mut self,
        ctl: &Control,
        dt: f64,
        tangent: bool,
    ) -> Result<Assembly> {
        self.counters.assemblies += 1;
        if !tangent {
            self.counters.residual_only_assemblies += 1;
        }
        self.residual.fill(0.0);
        if tangent {
            self.system.values.fill(0.0);
        }
        let mut gross = 0.0;
        let fbar = self.settings.fbar;
        let part = match (tangent, self.settings.symmetric) {
            (false, _) => TangentPart::None,
            (true, true) => TangentPart::Lower,
            (true, false) => TangentPart::Full,
        };
        let clock = cpu_time::ThreadTime::now();
        let dim = K::DIM;
        let nd = K::NODES * dim;
        let np = K::POINTS;
        let ne = self.mesh.element_count();
        let Self {
            mesh,
            material,
            geometry,
            lane_geometry,
            u,
            history,
            pool,
            element_outs,
            element_out,
            lane_out,
            elem_slots,
            residual,
            system,
            ..
        } = self;
        let (committed, trial) = history.split();
        let elements = ElementLoop::<M, K> {
            mesh,
            material,
            geometry,
            lane_geometry,
            u,
            committed,
            dt,
            fbar,
            part,
        };
        let failure = |(element, (point, source))| FemError::Material {
            element,
            point,
            source,
        };
        let mut add = |e: usize, out: &K::Output| {
            scatter::<M, K>(
                mesh.connectivity(e),
                out,
                &elem_slots[nd * nd * e..nd * nd * (e + 1)],
                part,
                residual,
                &mut system.values,
                &mut gross,
            );
        };
        if let Some(pool) = pool {
            // One task per group of four elements; the outputs are added
            // in element order, so the sums are the serial loop's.
            let failures: Vec<std::result::Result<(), _>> = pool.install(|| {
                use rayon::prelude::*;
                element_outs
                    .par_chunks_mut(4)
                    .zip(trial.par_chunks_mut(4 * np))
                    .enumerate()
                    .map_init(K::LaneOutput::default, |lane_out, (g, (outs, tr))| {
                        elements.group(4 * g, tr, lane_out, outs)
                    })
                    .collect()
            });
            // The first failing element in element order (deterministic).
            if let Some(Err(f)) = failures.into_iter().find(std::result::Result::is_err) {
                return Err(failure(f));
            }
            for (e, out) in element_outs.iter().enumerate() {
                add(e, out);
            }
        } else {
            for e0 in (0..ne).step_by(4) {
                let e1 = (e0 + 4).min(ne);
                let outs = &mut element_out[..e1 - e0];
                elements
                    .group(e0, &mut trial[np * e0..np * e1], lane_out, outs)
                    .map_err(failure)?;
                for (l, out) in outs.iter().enumerate() {
                    add(e0 + l, out);
                }
            }
        }
        self.counters.element_seconds += clock.elapsed().as_secs_f64();
        let mut asm = Assembly {
            scale: gross.sqrt(),
            ..Assembly::default()
        };
        let nn = self.mesh.node_count();
        let wdof = dim * nn;
        let w_free = !matches!(ctl.probe, ProbeDrive::Displacement(_));
        if let Some((probe, surface)) = &mut self.probe {
            let sums = surface.assemble(
                &self.positions2,
                &self.u,
                wdof,
                Obstacle::Sphere {
                    centre_z: probe.centre_z + self.u[wdof],
                    radius: probe.radius,
                },
                w_free,
                tangent,
                &mut self.residual,
                &mut self.system.values,
            );
            asm.contact_force = sums.force;
            asm.penetration = sums.penetration;
            asm.active = sums.active;
            asm.scale = asm.scale.max(asm.contact_force.abs());
        }
        for (side, set) in &self.planes {
            // Gap g and its derivative ∂g/∂z: above, g = z_plane − z; below,
            // g = z − z_plane.
            let (z_plane, dg) = match *side {
                PlaneSide::Above => (ctl.plane_z, -1.0),
                PlaneSide::Below(zb) => (zb, 1.0),
            };
            for (k, &a) in set.nodes.iter().enumerate() {
                let z = self.mesh.position(a)[dim - 1] + self.u[dim * a + dim - 1];
                let g = if dg < 0.0 { z_plane - z } else { z - z_plane };
                if g > 0.0 {
                    continue;
                }
                let eps = set.eps[k];
                if dg < 0.0 {
                    self.residual[dim * a + dim - 1] -= eps * g;
                    asm.plane_force -= eps * g;
                } else {
                    self.residual[dim * a + dim - 1] += eps * g;
                    asm.base_force -= eps * g;
                }
                if tangent {
                    let s = set.slots[k][4];
                    if s != NO_SLOT {
                        self.system.values[s] += eps;
                    }
                }
            }
            asm.scale = asm.scale.max(if dg < 0.0 {
                asm.plane_force.abs()
            } else {
                asm.base_force.abs()
            });
        }
        if let Some(cav) = &mut self.cavity {
            let (p, v) = cav.assemble(
                &self.mesh,
                dim,
                &self.u,
                ctl.fluid_injected,
                tangent,
                &mut self.residual,
                &mut self.system.values,
            );
            asm.pressure = p;
            asm.volume = v;
            // The pressure's force on the wall, p V₀^{2/3}.
            asm.scale = asm.scale.max(p.abs() * cav.v0.powf(2.0 / 3.0));
        }
        if self.probe.is_some() {
            let weq = self.dof_eq[wdof];
            let diag = self.system.slot(weq, weq)?;
            match ctl.probe {
                ProbeDrive::Displacement(_) => {
                    if tangent {
                        self.system.values[diag] = self.probe_diag;
                    }
                }
                ProbeDrive::Force(force) => {
                    self.residual[wdof] += force;
                    asm.scale = asm.scale.max(force.abs());
                }
                ProbeDrive::Spring {
                    stiffness,
                    free_end,
                } => {
                    let spring = stiffness * (self.u[wdof] - free_end);
                    self.residual[wdof] += spring;
                    asm.scale = asm.scale.max(spring.abs());
                    if tangent {
                        self.system.values[diag] += stiffness;
                    }
                }
            }
        }
        for (d, &eq) in self.dof_eq.iter().enumerate() {
            if eq != NO_SLOT {
                self.rhs[eq] = -self.residual[d];
            }
        }
        if !w_free && self.probe.is_some() {
            self.rhs[self.dof_eq[wdof]] = 0.0;
        }
        Ok(asm)
    }
}

impl CavityModel {
    /// Current positions of a cell's nodes, flattened (`dim` per node).
    pub(super) fn positions(
        mesh: &impl Topology,
        dim: usize,
        u: &[f64],
        nodes: &[usize],
        out: &mut [f64],
    ) {
        for (k, &a) in nodes.iter().enumerate() {
            let x = mesh.position(a);
            for i in 0..dim {
                out[dim * k + i] = x[i] + u[dim * a + i];
            }
        }
    }

    /// Signed volume Σ cells (times `sign`) at displacements `u`.
    pub(super) fn volume(&self, mesh: &impl Topology, dim: usize, u: &[f64]) -> f64 {
        let mut x = [0.0; 12];
        let mut v = 0.0;
        match &self.cells {
            CavityCells::Segments(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    v += segment_volume(&[[x[0], x[1]], [x[2], x[3]]]).0;
                }
            }
            CavityCells::Quads(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    v += quad_volume(&[
                        [x[0], x[1], x[2]],
                        [x[3], x[4], x[5]],
                        [x[6], x[7], x[8]],
                        [x[9], x[10], x[11]],
                    ])
                    .0;
                }
            }
        }
        self.sign * v
    }

    /// Adds the fluid's terms of the potential (module docs) to the
    /// residual and, if `tangent`, to the matrix; returns (p, V).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn assemble(
        &mut self,
        mesh: &impl Topology,
        dim: usize,
        u: &[f64],
        injected: f64,
        tangent: bool,
        residual: &mut [f64],
        values: &mut [f64],
    ) -> (f64, f64) {
        let s = u[self.dof];
        let p = self.k * s;
        let sign = self.sign;
        let (dvdu, normals, cell_slots) = (&mut self.dvdu, &mut self.normals, &self.cell_slots);
        dvdu.fill(0.0);
        normals.fill(0.0);
        let mut x = [0.0; 12];
        let mut volume = 0.0;
        let mut cell = 0;
        // One cell's volume v, gradient and Hessian (local dofs, node-major).
        let mut add_cell = |nodes: &[usize],
                            v: f64,
                            grad: &[f64],
                            hess: &dyn Fn(usize, usize) -> f64,
                            normal: &[f64]| {
            volume += v;
            let n = grad.len();
            for (k, (&g, &a)) in grad.iter().zip(normal).enumerate() {
                dvdu[dim * nodes[k / dim] + k % dim] += sign * g;
                normals[dim * nodes[k / dim] + k % dim] += sign * a;
            }
            if tangent {
                let slots = &cell_slots[cell..cell + n * n];
                for r in 0..n {
                    for c in 0..n {
                        let slot = slots[n * r + c];
                        if slot != NO_SLOT {
                            values[slot] -= p * sign * hess(r, c);
                        }
                    }
                }
            }
            cell += n * n;
        };
        match &self.cells {
            CavityCells::Segments(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    let seg = [[x[0], x[1]], [x[2], x[3]]];
                    let (v, g, h) = segment_volume(&seg);
                    add_cell(c, v, &g, &|r, c| h[r][c], &segment_area_normals(&seg));
                }
            }
            CavityCells::Quads(cells) => {
                for c in cells {
                    Self::positions(mesh, dim, u, c, &mut x);
                    let quad = [
                        [x[0], x[1], x[2]],
                        [x[3], x[4], x[5]],
                        [x[6], x[7], x[8]],
                        [x[9], x[10], x[11]],
                    ];
                    let (v, g, h) = quad_volume(&quad);
                    add_cell(c, v, &g, &|r, c| h[r][c], &quad_area_normals(&quad));
                }
            }
        }
        let volume = self.sign * volume;
        for &(d, on_plane) in &self.loaded {
            residual[d] -= p * if on_plane {
                self.normals[d]
            } else {
                self.dvdu[d]
            };
        }
        for &(d, rs, sr) in &self.coupling {
            if tangent {
                values[rs] -= self.k * self.dvdu[d];
                if sr != NO_SLOT {
                    values[sr] -= self.k * self.dvdu[d];
                }
            }
        }
        residual[self.dof] = -self.k * (volume - self.v0 - injected)
            - self.k * self.k * s * self.v0 * self.compliance;
        if tangent {
            values[self.diagonal] -= self.k * self.k * self.v0 * self.compliance;
        }
        (p, volume)
    }
}

/// What every element evaluation of one assembly reads.
struct ElementLoop<'a, M: Material3, K: ElementKind<M>> {
    mesh: &'a K::Mesh,
    material: &'a M,
    geometry: &'a [K::Geometry],
    /// Per group of four elements, empty without a lane form.
    lane_geometry: &'a [K::LaneGeometry],
    u: &'a [f64],
    committed: &'a [M::State],
    dt: f64,
    fbar: bool,
    part: TangentPart,
}

impl<M: Material3, K: ElementKind<M>> ElementLoop<'_, M, K> {
    /// Element `e`'s dofs.
    fn dofs(&self, e: usize) -> [f64; 24] {
        let dim = K::DIM;
        let conn = self.mesh.connectivity(e);
        let mut ue = [0.0; 24];
        for k in 0..K::NODES * dim {
            ue[k] = self.u[dim * conn[k / dim] + k % dim];
        }
        ue
    }

    /// The elements from `e0`, as many as `outs` (at most four), their
    /// trial histories `trial`: four at once in lanes where the element
    /// kind and material have a lane form, else — and for a group that
    /// fails in any lane, which rewrites its trial histories — one by one
    /// (bitwise the same outputs either way).
    ///
    /// # Errors
    /// The first failing element of the group and where it failed.
    fn group(
        &self,
        e0: usize,
        trial: &mut [M::State],
        lane_out: &mut K::LaneOutput,
        outs: &mut [K::Output],
    ) -> std::result::Result<(), (usize, PointFailure)> {
        let (nd, np) = (K::NODES * K::DIM, K::POINTS);
        // The lane form reads the dofs from `u` itself: copying each
        // element's dofs into a local array first was ≈ 1.5 % of the
        // thesis run (memmove).
        if let (Some(lane_geo), Ok(four)) = (
            self.lane_geometry.get(e0 / 4),
            <&mut [K::Output; 4]>::try_from(&mut *outs),
        ) {
            let mut chunks = trial.chunks_mut(np);
            let lanes_trial = std::array::from_fn(|_| chunks.next().expect("4 elements"));
            if K::evaluate_lanes(
                self.material,
                lane_geo,
                self.u,
                std::array::from_fn(|l| self.mesh.connectivity(e0 + l)),
                std::array::from_fn(|l| &self.committed[np * (e0 + l)..np * (e0 + l + 1)]),
                lanes_trial,
                self.dt,
                self.fbar,
                self.part,
                lane_out,
                four.each_mut(),
            ) {
                return Ok(());
            }
        }
        for (l, (out, tr)) in outs.iter_mut().zip(trial.chunks_mut(np)).enumerate() {
            let e = e0 + l;
            K::evaluate(
                self.material,
                &self.geometry[e],
                &self.dofs(e)[..nd],
                &self.committed[np * e..np * (e + 1)],
                tr,
                self.dt,
                self.fbar,
                self.part,
                out,
            )
            .map_err(|f| (e, f))?;
        }
        Ok(())
    }
}

/// Adds one element's residual and, unless `part` is
/// [`TangentPart::None`], its tangent into the global arrays: with
/// [`TangentPart::Lower`] only the entries `b ≤ a` of row `a` (the only ones
/// computed, and the only ones the symmetric slot table has slots for).
pub(super) fn scatter<M: Material3, K: ElementKind<M>>(
    conn: &[usize],
    out: &K::Output,
    slots: &[usize],
    part: TangentPart,
    residual: &mut [f64],
    values: &mut [f64],
    gross: &mut f64,
) {
    let dim = K::DIM;
    let nd = K::NODES * dim;
    let r = K::residual(out);
    for a in 0..nd {
        residual[dim * conn[a / dim] + a % dim] += r[a];
        *gross += r[a] * r[a];
        if part != TangentPart::None {
            let k = K::tangent_row(out, a);
            let end = if part == TangentPart::Lower {
                a + 1
            } else {
                nd
            };
            for b in 0..end {
                let s = slots[nd * a + b];
                if s != NO_SLOT {
                    values[s] += k[b];
                }
            }
        }
    }
}
