//! The deformed mesh as a ParaView XML unstructured grid (`.vtu`, VTK
//! file format 0.1, ASCII) and time series as a ParaView collection
//! (`.pvd`).
//!
//! Points are the *current* positions (axisymmetric meshes in the plane
//! y = 0: (r, 0, z)); point data: `displacement` (3 components) and, per
//! measured plate, `contact_pressure` (Pa, nodal force over current
//! tributary area; `contact_pressure_<plate>` when there are several);
//! field data `TimeValue`. Numbers are written in Rust's shortest
//! round-trip form, so a reader gets the same f64 back.

use crate::capsule::{Footprint, PatchSpec};
use crate::kind::{ElementKind, Topology};
use crate::{FemError, Model, Result};
use nlvid_material::Material3;
use std::fmt::Write as _;
use std::path::Path;

/// One named point or cell array.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuArray {
    /// Name shown in ParaView.
    pub name: String,
    /// Components per point (1 scalar, 3 vector).
    pub components: usize,
    /// Values, point-major.
    pub values: Vec<f64>,
}

/// An unstructured grid of one cell type.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuGrid {
    /// Point coordinates.
    pub points: Vec<[f64; 3]>,
    /// Cells (node indices in VTK order).
    pub cells: Vec<Vec<usize>>,
    /// VTK cell type of every cell.
    pub cell_type: u8,
    /// Point data.
    pub point_data: Vec<VtuArray>,
    /// Time (s), written as field data `TimeValue`.
    pub time: f64,
}

fn join(out: &mut String, values: impl Iterator<Item = String>) {
    for (k, v) in values.enumerate() {
        out.push_str(if k % 9 == 0 { "\n          " } else { " " });
        out.push_str(&v);
    }
    out.push('\n');
}

impl VtuGrid {
    /// The file's text.
    ///
    /// # Errors
    /// [`FemError::Mesh`] if a cell refers to a missing point or an array's
    /// length is not its components × the point count.
    pub fn to_xml(&self) -> Result<String> {
        let n = self.points.len();
        if let Some(c) = self.cells.iter().find(|c| c.iter().any(|&a| a >= n)) {
            return Err(FemError::Mesh(format!(
                "VTU cell {c:?} refers to a missing point"
            )));
        }
        for a in &self.point_data {
            if a.components == 0 || a.values.len() != a.components * n {
                return Err(FemError::Mesh(format!(
                    "VTU array `{}` has {} values for {n} points × {} components",
                    a.name,
                    a.values.len(),
                    a.components
                )));
            }
        }
        let mut s = String::new();
        let _ = writeln!(s, r#"<?xml version="1.0"?>"#);
        let _ = writeln!(
            s,
            r#"<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">"#
        );
        let _ = writeln!(s, "  <UnstructuredGrid>");
        let _ = write!(
            s,
            r#"    <FieldData>
      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">"#
        );
        join(&mut s, std::iter::once(format!("{:e}", self.time)));
        let _ = writeln!(s, "      </DataArray>\n    </FieldData>");
        let _ = writeln!(
            s,
            r#"    <Piece NumberOfPoints="{n}" NumberOfCells="{}">"#,
            self.cells.len()
        );
        let _ = writeln!(s, "      <PointData>");
        for a in &self.point_data {
            let _ = write!(
                s,
                r#"        <DataArray type="Float64" Name="{}" NumberOfComponents="{}" format="ascii">"#,
                a.name, a.components
            );
            join(&mut s, a.values.iter().map(|v| format!("{v:e}")));
            let _ = writeln!(s, "        </DataArray>");
        }
        let _ = writeln!(s, "      </PointData>");
        let _ = write!(
            s,
            r#"      <Points>
        <DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">"#
        );
        join(
            &mut s,
            self.points.iter().flatten().map(|v| format!("{v:e}")),
        );
        let _ = writeln!(s, "        </DataArray>\n      </Points>");
        let _ = write!(
            s,
            r#"      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">"#
        );
        join(&mut s, self.cells.iter().flatten().map(|a| a.to_string()));
        let _ = write!(
            s,
            r#"        </DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">"#
        );
        join(
            &mut s,
            self.cells.iter().scan(0usize, |o, c| {
                *o += c.len();
                Some(o.to_string())
            }),
        );
        let _ = write!(
            s,
            r#"        </DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">"#
        );
        join(
            &mut s,
            self.cells.iter().map(|_| self.cell_type.to_string()),
        );
        let _ = writeln!(
            s,
            "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>"
        );
        Ok(s)
    }

    /// Writes the grid to `path`.
    ///
    /// # Errors
    /// As [`VtuGrid::to_xml`]; [`FemError::Io`] naming the file.
    pub fn write(&self, path: &Path) -> Result<()> {
        let text = self.to_xml()?;
        nlvid_study::write_atomic(path, text.as_bytes()).map_err(|source| FemError::Io {
            file: path.to_path_buf(),
            source,
        })
    }
}

/// Writes a ParaView collection (`.pvd`) of `(time, file)` entries, the
/// files named relative to the collection's directory.
///
/// # Errors
/// [`FemError::Io`] naming the file.
pub fn write_pvd(path: &Path, entries: &[(f64, String)]) -> Result<()> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
    );
    for (t, f) in entries {
        let _ = writeln!(s, r#"    <DataSet timestep="{t:e}" part="0" file="{f}"/>"#);
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    nlvid_study::write_atomic(path, s.as_bytes()).map_err(|source| FemError::Io {
        file: path.to_path_buf(),
        source,
    })
}

impl<M: Material3, K: ElementKind<M>> Model<M, K>
where
    K::Mesh: Footprint,
{
    /// The converged deformed mesh with its displacement and the contact
    /// pressure of the plates in `patches` (module docs).
    ///
    /// # Errors
    /// As [`Model::contact_patch`].
    pub fn vtu_grid(&self, patches: &[PatchSpec]) -> Result<VtuGrid> {
        let mesh = self.mesh();
        let dim = K::DIM;
        let u = self.nodal_displacements();
        let nn = mesh.node_count();
        let embed = |p: &[f64]| -> [f64; 3] {
            if p.len() == 3 {
                [p[0], p[1], p[2]]
            } else {
                [p[0], 0.0, p[1]]
            }
        };
        let points = (0..nn)
            .map(|a| {
                let x = embed(mesh.position(a));
                let d = embed(&u[dim * a..dim * a + dim]);
                [x[0] + d[0], x[1] + d[1], x[2] + d[2]]
            })
            .collect();
        let displacement = (0..nn)
            .flat_map(|a| embed(&u[dim * a..dim * a + dim]))
            .collect();
        let mut point_data = vec![VtuArray {
            name: "displacement".into(),
            components: 3,
            values: displacement,
        }];
        for spec in patches {
            let (_, surface, forces, _) = self.plate_surface(spec)?;
            let mut p = vec![0.0; nn];
            for (s, f) in surface.iter().zip(&forces) {
                if s.area > 0.0 {
                    p[s.node] = f.1 / s.area;
                }
            }
            point_data.push(VtuArray {
                name: if patches.len() == 1 {
                    "contact_pressure".into()
                } else {
                    format!("contact_pressure_{}", spec.plane)
                },
                components: 1,
                values: p,
            });
        }
        Ok(VtuGrid {
            points,
            cells: (0..mesh.element_count())
                .map(|e| mesh.connectivity(e).to_vec())
                .collect(),
            cell_type: mesh.vtk_cell_type(),
            point_data,
            time: self.time(),
        })
    }
}
