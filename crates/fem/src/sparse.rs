//! Sparse global tangent: a fixed compressed-column pattern built once per
//! mesh, slot tables that let the element loop add into it without
//! searching, and a factorisation whose symbolic part (AMD ordering,
//! supernodal elimination structure) is computed once and reused at every
//! Newton iteration (faer 0.24).
//!
//! Supernodal LDLᵀ first, LU as the fallback: the tangent is the Hessian of
//! one potential (symmetric), but not always positive definite (the
//! curvature term of penalty contact, a probe with few contacts), so
//! Cholesky (LLᵀ) failed on a quarter of the thesis-run iterations and sent
//! them to LU, which is 5–10× slower. LDLᵀ without pivoting handles
//! symmetric indefinite matrices with non-zero pivots; its solution is
//! accepted only if the residual ‖K x − b‖ is at round-off level, otherwise
//! (zero or tiny pivot) LU with partial pivoting solves again. Factor
//! storage and workspace are allocated once. A material with a
//! non-symmetric tangent should set `Settings::symmetric = false`.

use crate::{FemError, Result};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Par};

/// Slot marking an entry that belongs to an eliminated (prescribed) dof.
pub(crate) const NO_SLOT: usize = usize::MAX;

/// Relative residual ‖K x − b‖∞ / (‖K‖∞ ‖x‖∞ + ‖b‖∞) above which an LDLᵀ
/// solution (no pivoting) is distrusted and the system is solved again by
/// LU with partial pivoting.
const LDLT_RESIDUAL_LIMIT: f64 = 1e-9;

/// The tangent matrix: pattern, values and reusable factorisation.
pub(crate) struct SparseSystem {
    n: usize,
    symbolic: SymbolicSparseColMat<usize>,
    pub(crate) values: Vec<f64>,
    lu_symbolic: SymbolicLu<usize>,
    chol_symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    stack: MemBuffer,
    rhs_copy: Vec<f64>,
    pub(crate) symmetric: bool,
}

impl std::fmt::Debug for SparseSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SparseSystem(n = {}, nnz = {}, nnz(L) = {})",
            self.n,
            self.values.len(),
            self.l_values.len()
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
        let chol_symbolic = factorize_symbolic_cholesky(
            symbolic.as_ref(),
            faer::Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                // Supernodal (dense-block kernels) measured 2.5× faster than
                // simplicial on the 2500-equation cell model (docs/theory/fem.md).
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| FemError::Solver(format!("symbolic Cholesky: {e:?}")))?;
        let req = StackReq::any_of(&[
            chol_symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
            chol_symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        Ok(Self {
            n,
            symbolic,
            values: vec![0.0; nnz],
            lu_symbolic,
            l_values: vec![0.0; chol_symbolic.len_val()],
            chol_symbolic,
            stack: MemBuffer::new(req),
            rhs_copy: vec![0.0; n],
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

    /// Relative residual of `x` as a solution of `K x = b` (module docs).
    fn relative_residual(&self, x: &[f64], b: &[f64]) -> f64 {
        let s = self.symbolic.as_ref();
        let mut kx = vec![0.0; self.n];
        let mut knorm = vec![0.0; self.n];
        for c in 0..self.n {
            for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
                let r = s.row_idx()[k];
                kx[r] += self.values[k] * x[c];
                knorm[r] += self.values[k].abs();
            }
        }
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        let err = kx
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        let den = inf(&knorm) * inf(x) + inf(b);
        if den > 0.0 { err / den } else { err }
    }

    /// Factorises the current values and solves `K x = rhs` in place:
    /// LDLᵀ of the lower triangle (fill-reducing AMD ordering, symbolic
    /// analysis reused, no allocation) when the tangent is symmetric and the
    /// solution's residual is at round-off level; LU with partial pivoting
    /// otherwise. Ok(true) if LDLᵀ did it.
    pub(crate) fn solve(&mut self, rhs: &mut [f64]) -> Result<bool> {
        let mat = SparseColMatRef::new(self.symbolic.as_ref(), &self.values);
        if self.symmetric {
            self.rhs_copy.copy_from_slice(rhs);
            let stack = MemStack::new(&mut self.stack);
            let ok = self
                .chol_symbolic
                .factorize_numeric_ldlt(
                    &mut self.l_values,
                    mat,
                    faer::Side::Lower,
                    LdltRegularization::default(),
                    Par::Seq,
                    stack,
                    Default::default(),
                )
                .is_ok();
            if ok {
                let ldlt = LdltRef::new(&self.chol_symbolic, &self.l_values);
                let col = faer::ColMut::from_slice_mut(rhs);
                ldlt.solve_in_place_with_conj(
                    Conj::No,
                    col.as_mat_mut(),
                    Par::Seq,
                    MemStack::new(&mut self.stack),
                );
                if rhs.iter().all(|x| x.is_finite())
                    && self.relative_residual(rhs, &self.rhs_copy) <= LDLT_RESIDUAL_LIMIT
                {
                    return Ok(true);
                }
            }
            rhs.copy_from_slice(&self.rhs_copy);
        }
        let lu = Lu::try_new_with_symbolic(self.lu_symbolic.clone(), mat)
            .map_err(|e| FemError::Solver(format!("numeric LU: {e:?}")))?;
        let col = faer::ColMut::from_slice_mut(rhs);
        lu.solve_in_place(col.as_mat_mut());
        if rhs.iter().all(|x| x.is_finite()) {
            Ok(false)
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

    fn matvec(s: &SparseSystem, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        let mut b = vec![0.0; n];
        for c in 0..n {
            for r in 0..n {
                if let Ok(k) = s.slot(r, c) {
                    b[r] += s.values[k] * x[c];
                }
            }
        }
        b
    }

    #[test]
    fn ldlt_solves_positive_definite_laplacian() {
        let mut s = laplacian(6);
        let x: Vec<f64> = (0..36).map(|i| (i as f64).sin()).collect();
        let mut b = matvec(&s, &x);
        assert!(s.solve(&mut b).unwrap(), "LDLᵀ expected");
        for i in 0..36 {
            assert!((b[i] - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn ldlt_solves_symmetric_indefinite_system() {
        // Shift the Laplacian (eigenvalues 4.01 − 4 cos… ∈ (0.01, 8)) by −3:
        // symmetric, indefinite, non-singular.
        let mut s = laplacian(6);
        for c in 0..36 {
            let k = s.slot(c, c).unwrap();
            s.values[k] -= 3.0;
        }
        let x: Vec<f64> = (0..36).map(|i| (0.3 * i as f64).cos()).collect();
        let mut b = matvec(&s, &x);
        s.solve(&mut b).unwrap();
        for i in 0..36 {
            assert!((b[i] - x[i]).abs() < 1e-10, "{i}: {} vs {}", b[i], x[i]);
        }
    }

    #[test]
    fn zero_pivot_falls_back_to_lu() {
        // [[0, 1], [1, 0]]: LDLᵀ without pivoting meets a zero pivot; LU
        // with partial pivoting solves it.
        let mut s = SparseSystem::new(2, &[vec![0, 1]]).unwrap();
        let k01 = s.slot(0, 1).unwrap();
        let k10 = s.slot(1, 0).unwrap();
        s.values[k01] = 1.0;
        s.values[k10] = 1.0;
        let mut b = vec![2.0, 3.0];
        assert!(!s.solve(&mut b).unwrap(), "LU fallback expected");
        assert!((b[0] - 3.0).abs() < 1e-14 && (b[1] - 2.0).abs() < 1e-14);
    }

    #[test]
    fn non_symmetric_tangent_is_solved_by_lu() {
        let mut s = laplacian(4);
        s.symmetric = false;
        let k = s.slot(0, 1).unwrap();
        s.values[k] = 0.5;
        let x: Vec<f64> = (0..16).map(|i| 1.0 + i as f64).collect();
        let mut b = matvec(&s, &x);
        assert!(!s.solve(&mut b).unwrap());
        for i in 0..16 {
            assert!((b[i] - x[i]).abs() < 1e-11);
        }
    }

    #[test]
    #[ignore = "timing probe: cargo test -p nlvid-fem --release --lib solver_timing -- --ignored --nocapture"]
    fn solver_timing() {
        for m in [24, 48] {
            let mut s = laplacian(m);
            let mut b = vec![1.0; m * m];
            let t = std::time::Instant::now();
            for _ in 0..20 {
                b.fill(1.0);
                s.solve(&mut b).unwrap();
            }
            eprintln!(
                "n = {}: LDLT {:.3} ms per factorise+solve",
                m * m,
                t.elapsed().as_secs_f64() / 20.0 * 1e3
            );
            s.symmetric = false;
            let t = std::time::Instant::now();
            for _ in 0..20 {
                b.fill(1.0);
                s.solve(&mut b).unwrap();
            }
            eprintln!(
                "n = {}: LU {:.3} ms per factorise+solve",
                m * m,
                t.elapsed().as_secs_f64() / 20.0 * 1e3
            );
        }
    }
}
