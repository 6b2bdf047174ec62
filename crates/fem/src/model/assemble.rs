//! Global assembly: the element loop (serial in lanes, or threaded), contact
//! with the probe and the planes, the fluid cavity, and the scatter of
//! element outputs into the global residual and tangent.

use super::*;

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
        if let Some(pool) = &self.pool {
            let (committed, trial) = self.history.split();
            let (mesh, material, geometry, lane_geometry, u) = (
                &self.mesh,
                &self.material,
                &self.geometry,
                &self.lane_geometry,
                &self.u,
            );
            // One task per group of four elements, in lanes as in the
            // serial loop below (so the outputs are bitwise the serial
            // ones); a failing or short group one by one.
            let failures: Vec<Option<(usize, crate::local::PointFailure)>> = pool.install(|| {
                use rayon::prelude::*;
                self.element_outs
                    .par_chunks_mut(4)
                    .zip(trial.par_chunks_mut(4 * np))
                    .enumerate()
                    .map_init(K::LaneOutput::default, |lane_out, (g, (outs, tr))| {
                        let e0 = 4 * g;
                        let gather = |e: usize| {
                            let conn = mesh.connectivity(e);
                            let mut ue = [0.0; 24];
                            for k in 0..nd {
                                ue[k] = u[dim * conn[k / dim] + k % dim];
                            }
                            ue
                        };
                        if let (Some(lane_geo), Ok(four)) = (
                            lane_geometry.get(g),
                            <&mut [K::Output; 4]>::try_from(&mut *outs),
                        ) {
                            let ue: [[f64; 24]; 4] = std::array::from_fn(|l| gather(e0 + l));
                            let mut chunks = tr.chunks_mut(np);
                            let trial = std::array::from_fn(|_| chunks.next().expect("4 elements"));
                            if K::evaluate_lanes(
                                material,
                                lane_geo,
                                std::array::from_fn(|l| &ue[l][..nd]),
                                std::array::from_fn(|l| {
                                    &committed[np * (e0 + l)..np * (e0 + l + 1)]
                                }),
                                trial,
                                dt,
                                fbar,
                                part,
                                lane_out,
                                four.each_mut(),
                            ) {
                                return None;
                            }
                        }
                        outs.iter_mut().zip(tr.chunks_mut(np)).enumerate().find_map(
                            |(l, (out, tr))| {
                                let e = e0 + l;
                                let ue = gather(e);
                                K::evaluate(
                                    material,
                                    &geometry[e],
                                    &ue[..nd],
                                    &committed[np * e..np * e + np],
                                    tr,
                                    dt,
                                    fbar,
                                    part,
                                    out,
                                )
                                .err()
                                .map(|f| (e, f))
                            },
                        )
                    })
                    .collect()
            });
            // The first failing element in element order (deterministic).
            if let Some((element, (point, source))) = failures.into_iter().flatten().next() {
                return Err(FemError::Material {
                    element,
                    point,
                    source,
                });
            }
            for e in 0..self.mesh.element_count() {
                let out = &self.element_outs[e];
                let slots = &self.elem_slots[nd * nd * e..nd * nd * (e + 1)];
                scatter::<M, K>(
                    self.mesh.connectivity(e),
                    out,
                    slots,
                    tangent,
                    &mut self.residual,
                    &mut self.system.values,
                    &mut gross,
                );
            }
        } else {
            let ne = self.mesh.element_count();
            let lanes = !self.lane_geometry.is_empty();
            for e0 in (0..ne).step_by(4) {
                let e1 = (e0 + 4).min(ne);
                // Four elements in lanes; on failure (or a short last group)
                // one by one.
                let mut done = false;
                if lanes && e1 == e0 + 4 {
                    let mut ue = [[0.0; 24]; 4];
                    for (l, uel) in ue.iter_mut().enumerate() {
                        let conn = self.mesh.connectivity(e0 + l);
                        for k in 0..nd {
                            uel[k] = self.u[dim * conn[k / dim] + k % dim];
                        }
                    }
                    let (committed, trial) = self.history.split();
                    let committed = &committed[np * e0..np * e1];
                    let mut tr = trial[np * e0..np * e1].chunks_mut(np);
                    let trial = std::array::from_fn(|_| tr.next().expect("4 elements"));
                    done = K::evaluate_lanes(
                        &self.material,
                        &self.lane_geometry[e0 / 4],
                        std::array::from_fn(|l| &ue[l][..nd]),
                        std::array::from_fn(|l| &committed[np * l..np * (l + 1)]),
                        trial,
                        dt,
                        fbar,
                        part,
                        &mut self.lane_out,
                        self.element_out.each_mut(),
                    );
                }
                for e in e0..e1 {
                    let conn = self.mesh.connectivity(e);
                    let out = &mut self.element_out[e - e0];
                    if !done {
                        let mut ue = [0.0; 24];
                        for k in 0..nd {
                            ue[k] = self.u[dim * conn[k / dim] + k % dim];
                        }
                        let (committed, trial) = self.history.element(e);
                        K::evaluate(
                            &self.material,
                            &self.geometry[e],
                            &ue[..nd],
                            committed,
                            trial,
                            dt,
                            fbar,
                            part,
                            out,
                        )
                        .map_err(|(point, source)| FemError::Material {
                            element: e,
                            point,
                            source,
                        })?;
                    }
                    let slots = &self.elem_slots[nd * nd * e..nd * nd * (e + 1)];
                    scatter::<M, K>(
                        conn,
                        out,
                        slots,
                        tangent,
                        &mut self.residual,
                        &mut self.system.values,
                        &mut gross,
                    );
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

/// Adds one element's residual and tangent into the global arrays.
pub(super) fn scatter<M: Material3, K: ElementKind<M>>(
    conn: &[usize],
    out: &K::Output,
    slots: &[usize],
    tangent: bool,
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
        if tangent {
            let k = K::tangent_row(out, a);
            for b in 0..nd {
                let s = slots[nd * a + b];
                if s != NO_SLOT {
                    values[s] += k[b];
                }
            }
        }
    }
}
