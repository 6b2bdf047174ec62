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

use crate::ldlt::SupernodalLdlt;
use crate::{FemError, Result};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// Slot marking an entry that belongs to an eliminated (prescribed) dof.
pub(crate) const NO_SLOT: usize = usize::MAX;

/// Relative residual ‖K x − b‖∞ / (‖K‖∞ ‖x‖∞ + ‖b‖∞) above which an LDLᵀ
/// solution (no pivoting) is distrusted and the system is solved again by
/// LU with partial pivoting.
const LDLT_RESIDUAL_LIMIT: f64 = 1e-9;

/// The tangent matrix: pattern, values and reusable factorisation.
///
/// Symmetric mode (the default of the cell model) stores only the lower
/// triangle of the matrix with its equations renumbered once by the AMD
/// fill-reducing ordering, so the numeric LDLᵀ reads `values` directly
/// (faer's per-call permutation of K into the factor's ordering, ≈ 3 % of
/// the AFM run, is gone; the element loop scatters half the entries).
/// `slot(r, c)` names the stored entry that represents `K[r][c]` (for
/// `r`, `c` in the caller's numbering); [`SparseSystem::block_slots`]
/// returns it only once per symmetric pair. The LU fallback expands the
/// lower triangle into the full pattern. Non-symmetric mode stores the full
/// matrix in the caller's numbering.
pub(crate) struct SparseSystem {
    n: usize,
    /// Stored pattern: lower triangle in AMD numbering (symmetric) or the
    /// full matrix in caller numbering.
    symbolic: SymbolicSparseColMat<usize>,
    pub(crate) values: Vec<f64>,
    /// Full pattern (caller numbering) for LU.
    full: SymbolicSparseColMat<usize>,
    /// Symmetric mode: for every entry of `full`, its slot in `values`.
    full_from_stored: Vec<usize>,
    full_values: Vec<f64>,
    /// Symmetric mode: caller equation → stored (AMD) equation, and back.
    to_stored: Vec<usize>,
    from_stored: Vec<usize>,
    lu_symbolic: SymbolicLu<usize>,
    /// Symmetric mode: the numeric LDLᵀ on faer's supernodal structure.
    ldlt: Option<SupernodalLdlt>,
    rhs_copy: Vec<f64>,
    work: Vec<f64>,
    kx: Vec<f64>,
    knorm: Vec<f64>,
    symmetric: bool,
    /// `ldlt` holds the LDLᵀ factors of the last factorised tangent
    /// (false before the first one and after an LU fallback).
    factored: bool,
    /// The LU factors of the last factorised tangent, if LU did it.
    last_lu: Option<Lu<usize, f64>>,
}

impl std::fmt::Debug for SparseSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SparseSystem(n = {}, stored nnz = {}, nnz(L) = {}, symmetric = {})",
            self.n,
            self.values.len(),
            self.ldlt.as_ref().map_or(0, |f| f.factor_len()),
            self.symmetric
        )
    }
}

fn csc(n: usize, cols: &mut [Vec<usize>]) -> SymbolicSparseColMat<usize> {
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for col in cols.iter_mut() {
        col.sort_unstable();
        col.dedup();
        row_idx.extend_from_slice(col);
        col_ptr.push(row_idx.len());
    }
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

fn find(s: &SymbolicSparseColMat<usize>, row: usize, col: usize) -> Option<usize> {
    let s = s.as_ref();
    let start = s.col_ptr()[col];
    let end = s.col_ptr()[col + 1];
    s.row_idx()[start..end]
        .binary_search(&row)
        .ok()
        .map(|k| start + k)
}

/// faer's symbolic analysis, always supernodal: supernodes (dense-block
/// kernels) measured 2.5× faster than simplicial on the 2500-equation cell
/// model (docs/theory/fem.md), and [`SupernodalLdlt`] needs them.
fn supernodal_params() -> CholeskySymbolicParams<'static> {
    CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    }
}

impl SparseSystem {
    /// Builds the pattern from lists of coupled equations (each list is a
    /// dense block: every pair in it is a nonzero); `symmetric` selects
    /// LDLᵀ on the stored lower triangle (LU fallback) or LU on the full
    /// matrix.
    pub(crate) fn new(n: usize, blocks: &[Vec<usize>], symmetric: bool) -> Result<Self> {
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
        }
        let full = csc(n, &mut cols);
        let lu_symbolic = SymbolicLu::try_new(full.as_ref())
            .map_err(|e| FemError::Solver(format!("symbolic LU: {e:?}")))?;
        let params = supernodal_params();
        let (symbolic, ldlt, to_stored, from_stored, full_from_stored) = if symmetric {
            // The AMD ordering, once; then the lower triangle in that order.
            let amd = factorize_symbolic_cholesky(
                full.as_ref(),
                faer::Side::Lower,
                SymmetricOrdering::Amd,
                params,
            )
            .map_err(|e| FemError::Solver(format!("symbolic Cholesky: {e:?}")))?;
            let (from_stored, to_stored) = match amd.perm() {
                Some(p) => {
                    let (fwd, inv) = p.arrays();
                    (fwd.to_vec(), inv.to_vec())
                }
                None => ((0..n).collect(), (0..n).collect()),
            };
            let mut lower: Vec<Vec<usize>> = vec![Vec::new(); n];
            let mut upper: Vec<Vec<usize>> = vec![Vec::new(); n];
            let fs = full.as_ref();
            for c in 0..n {
                for &r in &fs.row_idx()[fs.col_ptr()[c]..fs.col_ptr()[c + 1]] {
                    let (pr, pc) = (to_stored[r], to_stored[c]);
                    if pr >= pc {
                        lower[pc].push(pr);
                        upper[pr].push(pc);
                    }
                }
            }
            let stored = csc(n, &mut lower);
            // faer's symbolic analysis without an ordering reads the upper
            // triangle; the numeric LDLᵀ then takes the lower one (`Side::Lower`).
            let chol = factorize_symbolic_cholesky(
                csc(n, &mut upper).as_ref(),
                faer::Side::Lower,
                SymmetricOrdering::Identity,
                params,
            )
            .map_err(|e| FemError::Solver(format!("symbolic Cholesky: {e:?}")))?;
            let mut map = Vec::with_capacity(fs.row_idx().len());
            for c in 0..n {
                for &r in &fs.row_idx()[fs.col_ptr()[c]..fs.col_ptr()[c + 1]] {
                    let (pr, pc) = (to_stored[r], to_stored[c]);
                    let k = find(&stored, pr.max(pc), pr.min(pc)).ok_or_else(|| {
                        FemError::Solver(format!("entry ({r}, {c}) missing from the pattern"))
                    })?;
                    map.push(k);
                }
            }
            let SymbolicCholeskyRaw::Supernodal(structure) = chol.raw() else {
                return Err(FemError::Solver(
                    "symbolic Cholesky: supernodal structure expected".into(),
                ));
            };
            let ldlt = SupernodalLdlt::new(structure, stored.as_ref())?;
            (stored, Some(ldlt), to_stored, from_stored, map)
        } else {
            (full.clone(), None, Vec::new(), Vec::new(), Vec::new())
        };
        let nnz = symbolic.as_ref().row_idx().len();
        let full_nnz = full.as_ref().row_idx().len();
        Ok(Self {
            n,
            symbolic,
            values: vec![0.0; nnz],
            full,
            full_from_stored,
            full_values: if symmetric {
                vec![0.0; full_nnz]
            } else {
                Vec::new()
            },
            to_stored,
            from_stored,
            lu_symbolic,
            ldlt,
            rhs_copy: vec![0.0; n],
            work: vec![0.0; n],
            kx: vec![0.0; n],
            knorm: vec![0.0; n],
            symmetric,
            factored: false,
            last_lu: None,
        })
    }

    /// Position in `values` of the stored entry that represents
    /// (row, col) (caller numbering; symmetric mode: the same slot for
    /// (row, col) and (col, row)).
    pub(crate) fn slot(&self, row: usize, col: usize) -> Result<usize> {
        let (r, c) = if self.symmetric {
            let (pr, pc) = (self.to_stored[row], self.to_stored[col]);
            (pr.max(pc), pr.min(pc))
        } else {
            (row, col)
        };
        find(&self.symbolic, r, c).ok_or_else(|| {
            FemError::Solver(format!("entry ({row}, {col}) missing from the pattern"))
        })
    }

    /// Slot table of a dense block of equations, row-major, for adding a
    /// block into the matrix: `NO_SLOT` where either equation is
    /// eliminated and, in symmetric mode, for the member of each symmetric
    /// pair that is not stored (so every stored entry is added once).
    pub(crate) fn block_slots(&self, eqs: &[usize], out: &mut Vec<usize>) -> Result<()> {
        out.clear();
        for &r in eqs {
            for &c in eqs {
                if r == NO_SLOT
                    || c == NO_SLOT
                    || (self.symmetric && self.to_stored[r] < self.to_stored[c])
                {
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

    /// Relative residual of `x` as a solution of `K x = b` on the stored
    /// matrix (module docs); symmetric mode: stored numbering, the lower
    /// triangle standing for both.
    fn relative_residual(&mut self, x: &[f64], b: &[f64]) -> f64 {
        let s = self.symbolic.as_ref();
        self.kx.fill(0.0);
        self.knorm.fill(0.0);
        for c in 0..self.n {
            for k in s.col_ptr()[c]..s.col_ptr()[c + 1] {
                let r = s.row_idx()[k];
                let v = self.values[k];
                self.kx[r] += v * x[c];
                self.knorm[r] += v.abs();
                if self.symmetric && r != c {
                    self.kx[c] += v * x[r];
                    self.knorm[c] += v.abs();
                }
            }
        }
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |m, y| m.max(y.abs()));
        let err = self
            .kx
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        let den = inf(&self.knorm) * inf(x) + inf(b);
        if den > 0.0 { err / den } else { err }
    }

    /// Solves `K x = rhs` in place with the factors (LDLᵀ or LU) of the
    /// last factorised tangent (no new factorisation; the current `values`
    /// are not read). false when there are none (before the first
    /// factorisation) or the solution is not finite (`rhs` then holds no
    /// solution).
    pub(crate) fn solve_with_last_factors(&mut self, rhs: &mut [f64]) -> bool {
        if let Some(lu) = &self.last_lu {
            let col = faer::ColMut::from_slice_mut(rhs);
            lu.solve_in_place(col.as_mat_mut());
            return rhs.iter().all(|x| x.is_finite());
        }
        let Some(ldlt) = self.ldlt.as_mut().filter(|_| self.factored) else {
            return false;
        };
        for (w, &i) in self.work.iter_mut().zip(&self.from_stored) {
            *w = rhs[i];
        }
        ldlt.solve_in_place(&mut self.work);
        if !self.work.iter().all(|v| v.is_finite()) {
            return false;
        }
        for (w, &i) in self.work.iter().zip(&self.from_stored) {
            rhs[i] = *w;
        }
        true
    }

    /// Factorises the current values and solves `K x = rhs` in place:
    /// LDLᵀ of the stored lower triangle (AMD numbering, symbolic analysis
    /// reused, no allocation) when the tangent is symmetric and the
    /// solution's residual is at round-off level; LU with partial pivoting
    /// otherwise. Ok(true) if LDLᵀ did it.
    pub(crate) fn solve(&mut self, rhs: &mut [f64]) -> Result<bool> {
        self.factored = false;
        self.last_lu = None;
        if let Some(ldlt) = &mut self.ldlt {
            for (w, &i) in self.work.iter_mut().zip(&self.from_stored) {
                *w = rhs[i];
            }
            self.rhs_copy.copy_from_slice(&self.work);
            if ldlt.factorize(&self.values) {
                ldlt.solve_in_place(&mut self.work);
                let x = std::mem::take(&mut self.work);
                let b = std::mem::take(&mut self.rhs_copy);
                let good = x.iter().all(|v| v.is_finite())
                    && self.relative_residual(&x, &b) <= LDLT_RESIDUAL_LIMIT;
                self.work = x;
                self.rhs_copy = b;
                if good {
                    for (w, &i) in self.work.iter().zip(&self.from_stored) {
                        rhs[i] = *w;
                    }
                    self.factored = true;
                    return Ok(true);
                }
            }
            for (v, &k) in self.full_values.iter_mut().zip(&self.full_from_stored) {
                *v = self.values[k];
            }
        }
        let values = if self.symmetric {
            &self.full_values
        } else {
            &self.values
        };
        let mat = SparseColMatRef::new(self.full.as_ref(), values);
        let lu = Lu::try_new_with_symbolic(self.lu_symbolic.clone(), mat)
            .map_err(|e| FemError::Solver(format!("numeric LU: {e:?}")))?;
        let col = faer::ColMut::from_slice_mut(rhs);
        lu.solve_in_place(col.as_mat_mut());
        if rhs.iter().all(|x| x.is_finite()) {
            self.last_lu = Some(lu);
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
        laplacian_mode(m, true)
    }

    fn laplacian_mode(m: usize, symmetric: bool) -> SparseSystem {
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
        let mut s = SparseSystem::new(m * m, &blocks, symmetric).unwrap();
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
    fn block_assembly_into_lower_amd_storage_matches_full_lu() {
        // Overlapping dense 4×4 blocks of a chain (like elements sharing
        // nodes), each block symmetric; assembled with `block_slots` into the
        // symmetric (lower triangle, AMD numbering) and the full storage. The
        // LDLᵀ solution of the first must equal the LU solution of the second.
        let n = 40;
        let blocks: Vec<Vec<usize>> = (0..n - 3)
            .step_by(2)
            .map(|k| vec![k + 3, k, k + 2, k + 1])
            .collect();
        let mut sym = SparseSystem::new(n, &blocks, true).unwrap();
        let mut full = SparseSystem::new(n, &blocks, false).unwrap();
        let mut slots = Vec::new();
        for (e, b) in blocks.iter().enumerate() {
            let kb = |i: usize, j: usize| {
                let x = (1 + e + i + j) as f64;
                if i == j { 10.0 + x } else { 1.0 / x }
            };
            for sys in [&mut sym, &mut full] {
                sys.block_slots(b, &mut slots).unwrap();
                for i in 0..4 {
                    for j in 0..4 {
                        let s = slots[4 * i + j];
                        if s != NO_SLOT {
                            sys.values[s] += kb(i, j);
                        }
                    }
                }
            }
        }
        assert!(sym.values.len() < full.values.len());
        let rhs: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin()).collect();
        let (mut a, mut b) = (rhs.clone(), rhs.clone());
        assert!(sym.solve(&mut a).unwrap(), "LDLᵀ expected");
        assert!(!full.solve(&mut b).unwrap(), "LU expected");
        for i in 0..n {
            assert!((a[i] - b[i]).abs() < 1e-12 * (1.0 + b[i].abs()), "{i}");
        }
        // And against the product with the full matrix.
        let kx = matvec(&full, &a);
        for i in 0..n {
            assert!((kx[i] - rhs[i]).abs() < 1e-12, "{i}");
        }
    }

    /// FE-like blocks (Q4 elements on an nx × ny node grid, two dofs per
    /// node), seeded values, a diagonal made indefinite on every 7th dof.
    fn fe_like_system(nx: usize, ny: usize) -> SparseSystem {
        fe_like_system_with(nx, ny, &[])
    }

    /// [`fe_like_system`] with one more dense block over the equations
    /// `dense` (like a fluid cavity coupling a capsule's wall).
    fn fe_like_system_with(nx: usize, ny: usize, dense: &[usize]) -> SparseSystem {
        let node = |i: usize, j: usize| j * nx + i;
        let mut blocks = vec![dense.to_vec()];
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let nodes = [
                    node(i, j),
                    node(i + 1, j),
                    node(i + 1, j + 1),
                    node(i, j + 1),
                ];
                blocks.push(nodes.iter().flat_map(|&p| [2 * p, 2 * p + 1]).collect());
            }
        }
        let n = 2 * nx * ny;
        let mut s = SparseSystem::new(n, &blocks, true).unwrap();
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        for v in s.values.iter_mut() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *v = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        }
        for c in 0..n {
            let k = s.slot(c, c).unwrap();
            s.values[k] += if c % 7 == 0 { -8.0 } else { 8.0 };
        }
        s
    }

    /// faer's own numeric LDLᵀ on the structure `new` makes (faer's
    /// symbolic factorisation of the stored pattern): the second
    /// implementation the tests and the timing probe compare against.
    struct FaerLdlt {
        chol: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
        values: Vec<f64>,
        stack: faer::dyn_stack::MemBuffer,
    }

    impl FaerLdlt {
        fn new(s: &SparseSystem) -> Self {
            use faer::Par;
            let stored = s.symbolic.as_ref();
            let mut upper: Vec<Vec<usize>> = vec![Vec::new(); s.n];
            for c in 0..s.n {
                for r in stored.row_idx_of_col(c) {
                    upper[r].push(c);
                }
            }
            let chol = factorize_symbolic_cholesky(
                csc(s.n, &mut upper).as_ref(),
                faer::Side::Lower,
                SymmetricOrdering::Identity,
                supernodal_params(),
            )
            .unwrap();
            let stack = faer::dyn_stack::MemBuffer::new(faer::dyn_stack::StackReq::any_of(&[
                chol.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()),
                chol.solve_in_place_scratch::<f64>(1, Par::Seq),
            ]));
            Self {
                values: vec![0.0; chol.len_val()],
                chol,
                stack,
            }
        }

        fn factorize(&mut self, s: &SparseSystem) {
            use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
            self.chol
                .factorize_numeric_ldlt(
                    &mut self.values,
                    SparseColMatRef::new(s.symbolic.as_ref(), &s.values),
                    faer::Side::Lower,
                    LdltRegularization::default(),
                    faer::Par::Seq,
                    faer::dyn_stack::MemStack::new(&mut self.stack),
                    Default::default(),
                )
                .unwrap();
        }

        fn solve(&mut self, x: &mut [f64]) {
            faer::sparse::linalg::cholesky::LdltRef::new(&self.chol, &self.values)
                .solve_in_place_with_conj(
                    faer::Conj::No,
                    faer::ColMut::from_slice_mut(x).as_mat_mut(),
                    faer::Par::Seq,
                    faer::dyn_stack::MemStack::new(&mut self.stack),
                );
        }
    }

    /// The numeric LDLᵀ of `crate::ldlt` against faer's own numeric
    /// factorisation on the same structure (a second implementation).
    #[test]
    fn supernodal_factors_and_solution_equal_faers() {
        let mut s = fe_like_system(14, 11);
        let n = s.n;
        let mut faer = FaerLdlt::new(&s);
        let SymbolicCholeskyRaw::Supernodal(structure) = faer.chol.raw() else {
            panic!("supernodal expected");
        };
        assert!(
            structure.n_supernodes() > 20,
            "{}",
            structure.n_supernodes()
        );
        faer.factorize(&s);

        let ours = s.ldlt.as_mut().unwrap();
        assert!(ours.factorize(&s.values));
        let scale = faer.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, (a, b)) in ours.faer_values().iter().zip(&faer.values).enumerate() {
            assert!((a - b).abs() <= 1e-12 * scale, "entry {k}: {a} vs {b}");
        }
        let rhs: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
        let mut x = rhs.clone();
        ours.solve_in_place(&mut x);
        let mut y = rhs.clone();
        faer.solve(&mut y);
        let ymax = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..n {
            assert!(
                (x[i] - y[i]).abs() <= 1e-11 * ymax,
                "{i}: {} vs {}",
                x[i],
                y[i]
            );
        }
    }

    /// Supernodes large enough for faer's dense kernels (here a dense
    /// coupling of 160 equations) give the same factors as faer's own
    /// numeric factorisation, next to the tiled small ones.
    #[test]
    fn large_supernodes_equal_faers() {
        let dense: Vec<usize> = (0..160).map(|k| 3 * k + 1).collect();
        let mut s = fe_like_system_with(20, 20, &dense);
        let mut faer = FaerLdlt::new(&s);
        faer.factorize(&s);
        let ours = s.ldlt.as_mut().unwrap();
        assert!(ours.large_supernodes() >= 1, "{ours:?}");
        assert!(ours.factorize(&s.values));
        let scale = faer.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, (a, b)) in ours.faer_values().iter().zip(&faer.values).enumerate() {
            assert!((a - b).abs() <= 1e-11 * scale, "entry {k}: {a} vs {b}");
        }
    }

    /// Side by side, in one process: faer's numeric LDLᵀ and solve against
    /// `crate::ldlt`'s on the same structure (fastest of many repetitions,
    /// alternated; FE-like matrices of the cell model's size).
    #[test]
    #[ignore = "timing probe: cargo test -p nlvid-fem --release --lib ldlt_against_faer_timing -- --ignored --nocapture"]
    fn ldlt_against_faer_timing() {
        use std::time::Instant;
        for (nx, ny) in [(20, 20), (31, 31), (45, 45)] {
            let mut s = fe_like_system(nx, ny);
            let mut faer = FaerLdlt::new(&s);
            let mut x = vec![1.0; s.n];
            let (mut faer_best, mut ours_best) = ([f64::INFINITY; 2], [f64::INFINITY; 2]);
            for _ in 0..200 {
                let t = Instant::now();
                faer.factorize(&s);
                let t1 = Instant::now();
                faer.solve(&mut x);
                let t2 = Instant::now();
                faer_best[0] = faer_best[0].min((t1 - t).as_secs_f64());
                faer_best[1] = faer_best[1].min((t2 - t1).as_secs_f64());
                let ours = s.ldlt.as_mut().unwrap();
                let t = Instant::now();
                assert!(ours.factorize(&s.values));
                let t1 = Instant::now();
                ours.solve_in_place(&mut x);
                let t2 = Instant::now();
                ours_best[0] = ours_best[0].min((t1 - t).as_secs_f64());
                ours_best[1] = ours_best[1].min((t2 - t1).as_secs_f64());
            }
            eprintln!(
                "n = {}: factorise {:.1} µs (faer {:.1} µs, ratio {:.3}); solve {:.1} µs (faer {:.1} µs, ratio {:.3})",
                s.n,
                ours_best[0] * 1e6,
                faer_best[0] * 1e6,
                ours_best[0] / faer_best[0],
                ours_best[1] * 1e6,
                faer_best[1] * 1e6,
                ours_best[1] / faer_best[1],
            );
        }
    }

    #[test]
    fn zero_pivot_falls_back_to_lu() {
        // [[0, 1], [1, 0]]: LDLᵀ without pivoting meets a zero pivot; LU
        // with partial pivoting solves it.
        let mut s = SparseSystem::new(2, &[vec![0, 1]], true).unwrap();
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
        let mut s = laplacian_mode(4, false);
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
            let mut s = laplacian_mode(m, false);
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
