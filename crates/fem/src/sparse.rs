//! Sparse global tangent: a fixed compressed-column pattern built once per
//! mesh, slot tables that let the element loop add into it without
//! searching, and an LU factorisation whose symbolic part (ordering,
//! elimination structure) is computed once and reused at every Newton
//! iteration (faer 0.24).
//!
//! LU rather than Cholesky: the tangent of a Newton iterate is not
//! guaranteed positive definite (the probe dof has no stiffness before it
//! touches, softening materials, F-bar with a non-symmetric material
//! tangent), and LU with partial pivoting handles all of these.

use crate::{FemError, Result};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// Slot marking an entry that belongs to an eliminated (prescribed) dof.
pub(crate) const NO_SLOT: usize = usize::MAX;

/// The tangent matrix: pattern, values and reusable factorisation.
pub(crate) struct SparseSystem {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    pub(crate) values: Vec<f64>,
    lu_symbolic: SymbolicLu<usize>,
}

impl std::fmt::Debug for SparseSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SparseSystem(n = {}, nnz = {})",
            self.n,
            self.values.len()
        )
    }
}

impl SparseSystem {
    /// Builds the pattern from lists of coupled equations (each list is a
    /// dense block: every pair in it is a nonzero).
    pub(crate) fn new(n: usize, blocks: &[Vec<usize>]) -> Result<Self> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for block in blocks {
            for &c in block {
                for &r in block {
                    cols[c].push(r);
                }
            }
        }
        for (i, col) in cols.iter_mut().enumerate() {
            col.push(i);
            col.sort_unstable();
            col.dedup();
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for col in &cols {
            row_idx.extend_from_slice(col);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let lu_symbolic = SymbolicLu::try_new(symbolic.as_ref())
            .map_err(|e| FemError::Solver(format!("symbolic LU: {e:?}")))?;
        Ok(Self {
            n,
            symbolic,
            values: vec![0.0; nnz],
            lu_symbolic,
        })
    }

    /// Position of entry (row, col) in `values`.
    pub(crate) fn slot(&self, row: usize, col: usize) -> Result<usize> {
        let s = self.symbolic.as_ref();
        let start = s.col_ptr()[col];
        let end = s.col_ptr()[col + 1];
        s.row_idx()[start..end]
            .binary_search(&row)
            .map(|k| start + k)
            .map_err(|_| FemError::Solver(format!("entry ({row}, {col}) missing from the pattern")))
    }

    /// Slot table of a dense block of equations (`NO_SLOT` where either
    /// equation is eliminated), row-major.
    pub(crate) fn block_slots(&self, eqs: &[usize], out: &mut Vec<usize>) -> Result<()> {
        out.clear();
        for &r in eqs {
            for &c in eqs {
                if r == NO_SLOT || c == NO_SLOT {
                    out.push(NO_SLOT);
                } else {
                    out.push(self.slot(r, c)?);
                }
            }
        }
        Ok(())
    }

    /// Number of equations.
    pub(crate) fn dim(&self) -> usize {
        self.n
    }

    /// Factorises the current values and solves `K x = rhs` in place.
    pub(crate) fn solve(&self, rhs: &mut [f64]) -> Result<()> {
        let mat = SparseColMatRef::new(self.symbolic.as_ref(), &self.values);
        let lu = Lu::try_new_with_symbolic(self.lu_symbolic.clone(), mat)
            .map_err(|e| FemError::Solver(format!("numeric LU: {e:?}")))?;
        let col = faer::ColMut::from_slice_mut(rhs);
        lu.solve_in_place(col.as_mat_mut());
        if rhs.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(FemError::Solver(
                "singular tangent (non-finite solution)".into(),
            ))
        }
    }
}
