//! Sparse global tangent: a fixed compressed-column pattern built once per
//! mesh, slot tables that let the element loop add into it without
//! searching, and an LU factorisation whose symbolic part (ordering,
//! elimination structure) is computed once and reused at every Newton
//! iteration (faer 0.24).
//!
//! Cholesky first, LU as the fallback: the tangent is the Hessian of one
//! potential (symmetric) and near equilibrium of a stable body positive
//! definite, where sparse Cholesky is 10–50× faster than sparse LU in
//! faer 0.24 (measured, `lu_timing`). A Newton iterate whose tangent is not
//! positive definite (probe without contact, softening) falls back to LU
//! with partial pivoting; a material with a non-symmetric tangent should
//! set `Settings::symmetric = false`.

use crate::{FemError, Result};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// Slot marking an entry that belongs to an eliminated (prescribed) dof.
pub(crate) const NO_SLOT: usize = usize::MAX;

/// The tangent matrix: pattern, values and reusable factorisation.
pub(crate) struct SparseSystem {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    pub(crate) values: Vec<f64>,
    lu_symbolic: SymbolicLu<usize>,
    llt_symbolic: SymbolicLlt<usize>,
    pub(crate) symmetric: bool,
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
        let llt_symbolic = SymbolicLlt::try_new(symbolic.as_ref(), faer::Side::Lower)
            .map_err(|e| FemError::Solver(format!("symbolic Cholesky: {e:?}")))?;
        Ok(Self {
            n,
            symbolic,
            values: vec![0.0; nnz],
            lu_symbolic,
            llt_symbolic,
            symmetric: true,
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

    /// Factorises the current values and solves `K x = rhs` in place:
    /// Cholesky of the lower triangle when the tangent is symmetric and it
    /// succeeds (positive definite), LU otherwise. Ok(true) if Cholesky
    /// did it.
    pub(crate) fn solve(&self, rhs: &mut [f64]) -> Result<bool> {
        let mat = SparseColMatRef::new(self.symbolic.as_ref(), &self.values);
        let llt = if self.symmetric {
            Llt::try_new_with_symbolic(self.llt_symbolic.clone(), mat, faer::Side::Lower).ok()
        } else {
            None
        };
        let col = faer::ColMut::from_slice_mut(rhs);
        let cholesky = llt.is_some();
        if let Some(llt) = llt {
            llt.solve_in_place(col.as_mat_mut());
        } else {
            let lu = Lu::try_new_with_symbolic(self.lu_symbolic.clone(), mat)
                .map_err(|e| FemError::Solver(format!("numeric LU: {e:?}")))?;
            lu.solve_in_place(col.as_mat_mut());
        }
        if rhs.iter().all(|x| x.is_finite()) {
            Ok(cholesky)
        } else {
            Err(FemError::Solver(
                "singular tangent (non-finite solution)".into(),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 5-point Laplacian on an m×m grid (plus a tiny shift).
    fn laplacian(m: usize) -> SparseSystem {
        let id = |i: usize, j: usize| j * m + i;
        let mut blocks = Vec::new();
        for j in 0..m {
            for i in 0..m {
                if i + 1 < m {
                    blocks.push(vec![id(i, j), id(i + 1, j)]);
                }
                if j + 1 < m {
                    blocks.push(vec![id(i, j), id(i, j + 1)]);
                }
            }
        }
        let mut s = SparseSystem::new(m * m, &blocks).unwrap();
        for c in 0..m * m {
            for r in 0..m * m {
                if let Ok(k) = s.slot(r, c) {
                    s.values[k] = if r == c { 4.01 } else { -1.0 };
                }
            }
        }
        s
    }

    #[test]
    fn lu_solves_laplacian() {
        let s = laplacian(6);
        let x: Vec<f64> = (0..36).map(|i| (i as f64).sin()).collect();
        // b = K x
        let mut b = vec![0.0; 36];
        for c in 0..36 {
            for r in 0..36 {
                if let Ok(k) = s.slot(r, c) {
                    b[r] += s.values[k] * x[c];
                }
            }
        }
        s.solve(&mut b).unwrap();
        for i in 0..36 {
            assert!((b[i] - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    #[ignore = "timing probe: cargo test -p nlvid-fem --release --lib lu_timing -- --ignored --nocapture"]
    fn lu_timing() {
        for m in [24, 48] {
            let s = laplacian(m);
            let mut b = vec![1.0; m * m];
            let t = std::time::Instant::now();
            for _ in 0..20 {
                b.fill(1.0);
                s.solve(&mut b).unwrap();
            }
            eprintln!(
                "n = {}: {:.3} ms per factorise+solve",
                m * m,
                t.elapsed().as_secs_f64() / 20.0 * 1e3
            );
            let sym = faer::sparse::linalg::solvers::SymbolicLlt::try_new(
                s.symbolic.as_ref(),
                faer::Side::Lower,
            )
            .unwrap();
            let t = std::time::Instant::now();
            for _ in 0..20 {
                let mat = SparseColMatRef::new(s.symbolic.as_ref(), &s.values);
                let llt = faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(
                    sym.clone(),
                    mat,
                    faer::Side::Lower,
                )
                .unwrap();
                b.fill(1.0);
                llt.solve_in_place(faer::ColMut::from_slice_mut(&mut b).as_mat_mut());
            }
            eprintln!(
                "n = {}: LLT {:.3} ms per factorise+solve",
                m * m,
                t.elapsed().as_secs_f64() / 20.0 * 1e3
            );
        }
    }
}
