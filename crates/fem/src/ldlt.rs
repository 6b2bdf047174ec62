//! Numeric supernodal LDLᵀ factorisation and solve on a fixed symbolic
//! structure: faer's supernodal analysis of the AMD-ordered tangent.
//!
//! Why our own numeric phase: the cell model's tangent (≈ 1900 equations,
//! ≈ 260 supernodes of 7 columns on average) is factorised hundreds of times
//! per run with one pattern, and faer's general numeric factorisation spends
//! about half of each call on work per supernode that depends only on the
//! pattern (docs/theory/fem.md, "Session 17 (ordering)": ≈ 15.8 k
//! instructions per supernode and factorisation). Here every such index —
//! where each stored entry of K lands in the factor, where each entry of a
//! supernode's update lands in its ancestor — is computed once when the
//! system is built ([`SupernodalLdlt::new`]), so a factorisation is the
//! dense arithmetic plus one indexed subtraction per update entry.
//!
//! The values are stored as faer stores them, except that each block is
//! zero-padded for the register tiles: supernode s owns a column-major
//! block of n_s columns — its own rows, padded to a multiple of 4, then its
//! m_s off-diagonal rows, padded to a multiple of 4 ([`Panel`]) — with D
//! on the block's diagonal and the unit lower factor L below it. The
//! algorithm is right-looking: once a supernode's block is factorised, its
//! Schur complement update L₂₁ D L₂₁ᵀ is subtracted from the ancestors'
//! blocks, so every supernode has received all its updates when its turn
//! comes.
//!
//! The dense work of a small supernode runs in 4 × 4 register tiles
//! ([`Panel`], [`tile_product`]) on its block in place (the padded layout
//! spares copying every block into a padded working panel and back, ≈ 2 %
//! of the thesis run in memmove); a large one ([`LARGE_BLOCK`], e.g. the 3D
//! capsule's) goes to faer's cache-blocked dense kernels, which win there
//! (docs/theory/fem.md "Session 18").
//!
//! No pivoting: a zero or non-finite pivot makes [`SupernodalLdlt::factorize`]
//! return false, and the caller solves by LU instead (crates/fem/src/sparse.rs).

use crate::{FemError, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{
    LdltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place;
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, MatMut, MatRef, Par};

/// One ancestor that receives part of a supernode's update: the source's
/// off-diagonal rows `first..end` are columns of `supernode`.
#[derive(Debug, Clone, Copy)]
struct UpdateTarget {
    supernode: usize,
    first: usize,
    end: usize,
    /// Start in [`SupernodalLdlt::row_in_target`] of the positions of the
    /// source's off-diagonal rows `first..m` within the target's block.
    rel_start: usize,
}

/// Numeric LDLᵀ factors on a fixed supernodal structure, with every
/// pattern-only index precomputed (module docs).
pub(crate) struct SupernodalLdlt {
    /// First column of each supernode, then n (length S + 1).
    begin: Vec<usize>,
    /// Off-diagonal rows of supernode s: `rows[row_ptr[s]..row_ptr[s + 1]]`.
    row_ptr: Vec<usize>,
    rows: Vec<usize>,
    /// Values of supernode s (its padded block, [`Panel`]):
    /// `values[val_ptr[s]..val_ptr[s + 1]]`.
    val_ptr: Vec<usize>,
    /// For each stored entry of the matrix, its position in `values`.
    entry_to_factor: Vec<usize>,
    /// Targets of supernode s: `targets[target_ptr[s]..target_ptr[s + 1]]`.
    target_ptr: Vec<usize>,
    targets: Vec<UpdateTarget>,
    /// Row positions, within their target's block, of update rows.
    row_in_target: Vec<usize>,
    /// The factors (padded blocks, module docs).
    values: Vec<f64>,
    /// Number of factor values in faer's unpadded layout.
    faer_len: usize,
    /// Scratch of one supernode: L₂₁ D (column-major, m rounded up to 4
    /// rows), the update's lower tiles; one column of a product (longest
    /// block), coefficients (4 × widest supernode).
    scaled: Vec<f64>,
    update: Vec<f64>,
    column: Vec<f64>,
    coefficients: Vec<f64>,
    /// faer's workspace for the dense LDLᵀ of large supernodes.
    stack: MemBuffer,
}

impl std::fmt::Debug for SupernodalLdlt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "SupernodalLdlt(n = {}, supernodes = {}, factor values = {})",
            self.begin.last().copied().unwrap_or(0),
            self.begin.len().saturating_sub(1),
            self.faer_len
        )
    }
}

impl SupernodalLdlt {
    /// Precomputes the scatter maps of the lower-triangular `pattern`
    /// (already in the factor's numbering) into the supernodal
    /// `structure` of its factor.
    ///
    /// # Errors
    /// An entry of the pattern, or of an update, that the structure does not
    /// hold (a structure that was not computed from this pattern).
    pub(crate) fn new(
        structure: &SymbolicSupernodalCholesky<usize>,
        pattern: SymbolicSparseColMatRef<'_, usize>,
    ) -> Result<Self> {
        let n = structure.nrows();
        let n_super = structure.n_supernodes();
        let mut begin = structure.supernode_begin().to_vec();
        begin.push(n);
        let mut row_ptr = Vec::with_capacity(n_super + 1);
        let mut rows = Vec::new();
        let mut val_ptr = Vec::with_capacity(n_super + 1);
        row_ptr.push(0);
        val_ptr.push(0);
        let mut supernode_of = vec![0; n];
        let mut faer_len = 0;
        for s in 0..n_super {
            rows.extend_from_slice(structure.supernode(s).pattern());
            row_ptr.push(rows.len());
            let ns = begin[s + 1] - begin[s];
            let m = row_ptr[s + 1] - row_ptr[s];
            val_ptr.push(val_ptr[s] + Panel::new(ns, m).rows * ns);
            faer_len += (ns + m) * ns;
            supernode_of[begin[s]..begin[s + 1]].fill(s);
        }
        if faer_len != structure.len_val() {
            return Err(FemError::Solver(
                "supernodal structure: value layout differs from faer's".into(),
            ));
        }
        let missing =
            |r: usize, c: usize| FemError::Solver(format!("factor structure lacks ({r}, {c})"));
        let panel = |t: usize| Panel::new(begin[t + 1] - begin[t], row_ptr[t + 1] - row_ptr[t]);
        // Position of row r in supernode t's (padded) block.
        let row_position = |t: usize, r: usize| -> Option<usize> {
            if (begin[t]..begin[t + 1]).contains(&r) {
                Some(r - begin[t])
            } else {
                rows[row_ptr[t]..row_ptr[t + 1]]
                    .binary_search(&r)
                    .ok()
                    .map(|k| panel(t).top + k)
            }
        };
        let leading = |t: usize| panel(t).rows;

        let mut entry_to_factor = Vec::with_capacity(pattern.row_idx().len());
        for c in 0..n {
            let t = supernode_of[c];
            for r in pattern.row_idx_of_col(c) {
                let pos = row_position(t, r)
                    .filter(|_| r >= c)
                    .ok_or_else(|| missing(r, c))?;
                entry_to_factor.push(val_ptr[t] + (c - begin[t]) * leading(t) + pos);
            }
        }

        let mut target_ptr = vec![0];
        let mut targets = Vec::new();
        let mut row_in_target = Vec::new();
        let (mut max_ld, mut max_ns, mut max_scaled, mut max_update) = (0, 0, 0, 0);
        for s in 0..n_super {
            let own = &rows[row_ptr[s]..row_ptr[s + 1]];
            let m = own.len();
            let ns = begin[s + 1] - begin[s];
            max_ld = max_ld.max(Panel::new(ns, m).rows);
            max_ns = max_ns.max(ns);
            max_scaled = max_scaled.max(m.next_multiple_of(4) * ns);
            max_update = max_update.max(m.next_multiple_of(4).pow(2));
            if is_large(ns, m) {
                max_scaled = max_scaled.max(m * ns);
            }
            let mut first = 0;
            while first < m {
                let t = supernode_of[own[first]];
                let end = first + own[first..].partition_point(|&r| r < begin[t + 1]);
                let rel_start = row_in_target.len();
                for &r in &own[first..] {
                    row_in_target.push(row_position(t, r).ok_or_else(|| missing(r, begin[t]))?);
                }
                targets.push(UpdateTarget {
                    supernode: t,
                    first,
                    end,
                    rel_start,
                });
                first = end;
            }
            target_ptr.push(targets.len());
        }
        Ok(Self {
            values: vec![0.0; val_ptr[n_super]],
            begin,
            row_ptr,
            rows,
            val_ptr,
            entry_to_factor,
            target_ptr,
            targets,
            row_in_target,
            faer_len,
            scaled: vec![0.0; max_scaled],
            update: vec![0.0; max_update],
            column: vec![0.0; max_ld],
            coefficients: vec![0.0; 4 * max_ns],
            stack: MemBuffer::new(cholesky_in_place_scratch::<f64>(
                max_ns,
                Par::Seq,
                Default::default(),
            )),
        })
    }

    /// Number of supernodes that go to faer's dense kernels
    /// ([`LARGE_BLOCK`]).
    #[cfg(test)]
    pub(crate) fn large_supernodes(&self) -> usize {
        (0..self.begin.len() - 1)
            .filter(|&s| {
                is_large(
                    self.begin[s + 1] - self.begin[s],
                    self.row_ptr[s + 1] - self.row_ptr[s],
                )
            })
            .count()
    }

    /// Number of factor values (nnz(L) with D on the diagonal, faer's count).
    pub(crate) fn factor_len(&self) -> usize {
        self.faer_len
    }

    /// The factor values in faer's unpadded supernodal layout (tests compare
    /// them with faer's own factorisation), entries above the diagonal zero.
    #[cfg(test)]
    pub(crate) fn faer_values(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.faer_len);
        for s in 0..self.begin.len() - 1 {
            let ns = self.begin[s + 1] - self.begin[s];
            let panel = Panel::new(ns, self.row_ptr[s + 1] - self.row_ptr[s]);
            let block = &self.values[self.val_ptr[s]..self.val_ptr[s + 1]];
            for (k, column) in block.chunks_exact(panel.rows).enumerate() {
                out.extend((0..ns).map(|i| if i < k { 0.0 } else { column[i] }));
                out.extend_from_slice(&column[panel.top..panel.top + panel.m]);
            }
        }
        out
    }

    /// Factorises the matrix whose stored entries (the pattern given to
    /// [`SupernodalLdlt::new`], in its order) are `matrix`. false on a zero
    /// or non-finite pivot (the factors are then not usable).
    pub(crate) fn factorize(&mut self, matrix: &[f64]) -> bool {
        debug_assert_eq!(matrix.len(), self.entry_to_factor.len());
        self.values.fill(0.0);
        for (&k, &v) in self.entry_to_factor.iter().zip(matrix) {
            self.values[k] = v;
        }
        pulp::Arch::new().dispatch(Factorize(self))
    }

    /// Solves L D Lᵀ x = b in place (`x` holds b on entry, in the factor's
    /// numbering) with the factors of the last successful
    /// [`SupernodalLdlt::factorize`].
    pub(crate) fn solve_in_place(&mut self, x: &mut [f64]) {
        pulp::Arch::new().dispatch(Solve { ldlt: self, x });
    }
}

/// [`SupernodalLdlt::factorize`]'s arithmetic as a `pulp::WithSimd`
/// operation, so its loops are compiled for the CPU's SIMD width (as the
/// element kernel, crates/fem/src/fbar.rs). Products and sums are never
/// fused and their order does not depend on that width, so the factors are
/// bitwise the same on every x86-64.
struct Factorize<'a>(&'a mut SupernodalLdlt);

impl pulp::WithSimd for Factorize<'_> {
    type Output = bool;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> bool {
        let f = self.0;
        for s in 0..f.begin.len() - 1 {
            let ns = f.begin[s + 1] - f.begin[s];
            let m = f.row_ptr[s + 1] - f.row_ptr[s];
            let (head, tail) = f.values.split_at_mut(f.val_ptr[s + 1]);
            let q = &mut head[f.val_ptr[s]..];
            let panel = Panel::new(ns, m);
            // The update W = L₂₁ D L₂₁ᵀ, column-major with leading dimension `ldw`.
            let ldw = if is_large(ns, m) {
                if !factorize_large(q, &panel, &mut f.stack) {
                    return false;
                }
                update_large(q, &panel, &mut f.scaled, &mut f.update);
                m
            } else {
                if !panel.factorize(q, &mut f.coefficients, &mut f.column) {
                    return false;
                }
                // Lower tiles of 4 × 4 (leading dimension m4).
                let m4 = panel.rows - panel.top;
                let scaled = &mut f.scaled[..m4 * ns];
                for k in 0..ns {
                    let d = q[k * panel.rows + k];
                    let l = &q[k * panel.rows + panel.top..(k + 1) * panel.rows];
                    for (w, &v) in scaled[k * m4..(k + 1) * m4].iter_mut().zip(l) {
                        *w = v * d;
                    }
                }
                let update = &mut f.update[..m4 * m4];
                for j0 in (0..m4).step_by(4) {
                    for i0 in (j0..m4).step_by(4) {
                        let tile = tile_product(q, panel.rows, scaled, m4, panel.top + i0, j0);
                        for (jj, column) in tile.iter().enumerate() {
                            update[(j0 + jj) * m4 + i0..][..4].copy_from_slice(column);
                        }
                    }
                }
                m4
            };
            if m == 0 {
                continue;
            }
            let offset = f.val_ptr[s + 1];
            let own = &f.rows[f.row_ptr[s]..f.row_ptr[s + 1]];
            for target in &f.targets[f.target_ptr[s]..f.target_ptr[s + 1]] {
                let t = target.supernode;
                let ld_t =
                    Panel::new(f.begin[t + 1] - f.begin[t], f.row_ptr[t + 1] - f.row_ptr[t]).rows;
                for j in target.first..target.end {
                    let base = f.val_ptr[t] + (own[j] - f.begin[t]) * ld_t - offset;
                    let rel = &f.row_in_target[target.rel_start + (j - target.first)..][..m - j];
                    for (&u, &p) in f.update[j * ldw + j..j * ldw + m].iter().zip(rel) {
                        tail[base + p] -= u;
                    }
                }
            }
        }
        true
    }
}

/// Dense work (multiply–adds) of a supernode's panel and update above which
/// faer's cache-blocked dense kernels beat the register tiles: the 3D
/// capsule's supernodes (up to 505 columns, 451 off-diagonal rows) ran
/// 1.4 × slower in tiles, the cell model's (≤ 72 columns) faster.
const LARGE_BLOCK: usize = 1 << 20;

/// Whether a supernode of `ns` columns and `m` off-diagonal rows goes to
/// faer's dense kernels ([`LARGE_BLOCK`]).
#[inline(always)]
fn is_large(ns: usize, m: usize) -> bool {
    ns * (ns + m) * (ns + m) >= LARGE_BLOCK
}

/// A large supernode's (padded) block factorised in place by faer's dense
/// LDLᵀ (the diagonal block) and a unit triangular solve (L₂₁), as faer's
/// own supernodal factorisation does. false on a zero or non-finite pivot.
fn factorize_large(block: &mut [f64], panel: &Panel, stack: &mut MemBuffer) -> bool {
    let (ns, m) = (panel.ns, panel.m);
    let ls = MatMut::from_column_major_slice_mut(&mut block[..panel.rows * ns], panel.rows, ns);
    let (diagonal, below) = ls.split_at_row_mut(panel.top);
    let mut top = diagonal.split_at_row_mut(ns).0;
    let mut bottom = below.split_at_row_mut(m).0;
    let factored = cholesky_in_place(
        top.as_mut(),
        LdltRegularization::default(),
        Par::Seq,
        MemStack::new(stack),
        Default::default(),
    );
    if factored.is_err() || (0..ns).any(|j| top[(j, j)] == 0.0 || !top[(j, j)].is_finite()) {
        return false;
    }
    for j in 0..ns {
        for i in 0..j {
            top[(i, j)] = 0.0;
        }
    }
    solve_unit_lower_triangular_in_place(top.as_ref(), bottom.as_mut().transpose_mut(), Par::Seq);
    for j in 0..ns {
        let inv = 1.0 / top[(j, j)];
        for i in 0..m {
            bottom[(i, j)] *= inv;
        }
    }
    true
}

/// A large supernode's update W = L₂₁ D L₂₁ᵀ (lower triangle, column-major
/// m × m) by faer's triangular matrix product.
fn update_large(block: &[f64], panel: &Panel, scaled: &mut [f64], update: &mut [f64]) {
    let (ns, m) = (panel.ns, panel.m);
    let ls = MatRef::from_column_major_slice(&block[..panel.rows * ns], panel.rows, ns);
    let (diagonal, below) = ls.split_at_row(panel.top);
    let top = diagonal.split_at_row(ns).0;
    let l21 = below.split_at_row(m).0;
    let mut s = MatMut::from_column_major_slice_mut(&mut scaled[..m * ns], m, ns);
    for k in 0..ns {
        let d = top[(k, k)];
        for i in 0..m {
            s[(i, k)] = l21[(i, k)] * d;
        }
    }
    triangular::matmul(
        MatMut::from_column_major_slice_mut(&mut update[..m * m], m, m),
        BlockStructure::TriangularLower,
        Accum::Replace,
        l21,
        BlockStructure::Rectangular,
        s.as_ref().transpose(),
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
}

/// The layout of one supernode's block of `ns` columns: zero-padded row
/// counts that are multiples of 4, so the tiles need no remainder loops:
/// rows `0..ns` the diagonal block, `top..top + m` the off-diagonal rows
/// (`top` = ns rounded up to 4), `rows` = top + m rounded up to 4. The
/// padding rows are zeroed with the block and stay zero through the
/// factorisation.
struct Panel {
    ns: usize,
    m: usize,
    top: usize,
    rows: usize,
}

impl Panel {
    #[inline(always)]
    fn new(ns: usize, m: usize) -> Self {
        let top = ns.next_multiple_of(4);
        Self {
            ns,
            m,
            top,
            rows: top + m.next_multiple_of(4),
        }
    }

    /// Dense LDLᵀ of the panel, blocked by 4 columns, left-looking: each
    /// block of columns less the earlier columns' contribution (4 × 4
    /// tiles), then its own columns one by one, each scaled by its pivot.
    /// Entries above the diagonal of the diagonal block are left as
    /// garbage (never read). false on a zero or non-finite pivot.
    #[inline(always)]
    fn factorize(&self, q: &mut [f64], coefficients: &mut [f64], column: &mut [f64]) -> bool {
        let (ns, lq) = (self.ns, self.rows);
        for k0 in (0..ns).step_by(4) {
            let k1 = (k0 + 4).min(ns);
            if k0 > 0 {
                // C[kk, j] = L[k0 + kk, j] d_j (4 × k0, column-major).
                let c = &mut coefficients[..4 * k0];
                for j in 0..k0 {
                    let d = q[j * lq + j];
                    for kk in 0..4 {
                        c[j * 4 + kk] = if k0 + kk < k1 {
                            q[j * lq + k0 + kk] * d
                        } else {
                            0.0
                        };
                    }
                }
                let (left, right) = q.split_at_mut(k0 * lq);
                for i0 in (k0..lq).step_by(4) {
                    let tile = tile_product(left, lq, c, 4, i0, 0);
                    for (kk, t) in tile.iter().enumerate().take(k1 - k0) {
                        for (u, &v) in right[kk * lq + i0..][..4].iter_mut().zip(t) {
                            *u -= v;
                        }
                    }
                }
            }
            for k in k0..k1 {
                let (left, right) = q.split_at_mut(k * lq);
                let col_k = &mut right[..lq];
                if k > k0 {
                    let c = &mut coefficients[..k - k0];
                    for (j, cj) in (k0..k).zip(c.iter_mut()) {
                        *cj = left[j * lq + k] * left[j * lq + j];
                    }
                    let t = &mut column[..lq - k0];
                    product(t, &left[k0 * lq..], lq, k0, c);
                    for (u, &v) in col_k[k0..].iter_mut().zip(t.iter()) {
                        *u -= v;
                    }
                }
                let d = col_k[k];
                if d == 0.0 || !d.is_finite() {
                    return false;
                }
                let inv = 1.0 / d;
                for u in &mut col_k[k + 1..] {
                    *u *= inv;
                }
            }
        }
        true
    }
}

/// One 4 × 4 tile of A Bᵀ: `tile[jj][ii] = Σ_k A[i0 + ii, k] ·
/// B[j0 + jj, k]`, A and B column-major with leading dimensions `lda`,
/// `ldb` and as many columns as both hold (their lengths are whole
/// columns): sixteen independent sums in four SIMD registers. (Columns by
/// `chunks_exact`, so the bounds checks are loop-invariant and hoisted.)
#[inline(always)]
fn tile_product(
    a: &[f64],
    lda: usize,
    b: &[f64],
    ldb: usize,
    i0: usize,
    j0: usize,
) -> [[f64; 4]; 4] {
    let mut tile = [[0.0; 4]; 4];
    for (ac, bc) in a.chunks_exact(lda).zip(b.chunks_exact(ldb)) {
        let av: &[f64; 4] = ac[i0..i0 + 4].try_into().expect("four rows");
        let bv: &[f64; 4] = bc[j0..j0 + 4].try_into().expect("four rows");
        for (column, &bj) in tile.iter_mut().zip(bv) {
            for (t, &ai) in column.iter_mut().zip(av) {
                *t += ai * bj;
            }
        }
    }
    tile
}

/// `out[i] = Σ_k A[row0 + i, k] · c[k]` for i < out.len(), A column-major
/// with leading dimension `lda` (whole columns; k over as many as both
/// `a` and `c` hold): sixteen rows at a time so four independent sums hide
/// the additions' latency, then four, then one.
#[inline(always)]
fn product(out: &mut [f64], a: &[f64], lda: usize, row0: usize, c: &[f64]) {
    let n = out.len();
    let rest = product_rows::<16>(out, a, lda, row0, c);
    let rest_start = row0 + n - rest.len();
    let rest = product_rows::<4>(rest, a, lda, rest_start, c);
    let rest_start = row0 + n - rest.len();
    product_rows::<1>(rest, a, lda, rest_start, c);
}

/// [`product`] on the leading whole blocks of `W` rows of `out`; returns
/// the rows left over.
#[inline(always)]
fn product_rows<'o, const W: usize>(
    out: &'o mut [f64],
    a: &[f64],
    lda: usize,
    row0: usize,
    c: &[f64],
) -> &'o mut [f64] {
    let mut blocks = out.chunks_exact_mut(W);
    let mut i = row0;
    for o in &mut blocks {
        let mut acc = [0.0; W];
        for (col, &ck) in a.chunks_exact(lda).zip(c) {
            let v: &[f64; W] = col[i..i + W].try_into().expect("W rows");
            for l in 0..W {
                acc[l] += v[l] * ck;
            }
        }
        o.copy_from_slice(&acc);
        i += W;
    }
    blocks.into_remainder()
}

/// [`SupernodalLdlt::solve_in_place`] as a `pulp::WithSimd` operation.
struct Solve<'a, 'b> {
    ldlt: &'a mut SupernodalLdlt,
    x: &'b mut [f64],
}

impl pulp::WithSimd for Solve<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self { ldlt: f, x } = self;
        let n_super = f.begin.len() - 1;
        // L y = b: the diagonal block, then the off-diagonal rows less
        // L₂₁ y_s.
        for s in 0..n_super {
            let (b, ns) = (f.begin[s], f.begin[s + 1] - f.begin[s]);
            let own = &f.rows[f.row_ptr[s]..f.row_ptr[s + 1]];
            let Panel { rows: ld, top, .. } = Panel::new(ns, own.len());
            let values = &f.values[f.val_ptr[s]..f.val_ptr[s + 1]];
            for k in 0..ns {
                let xk = x[b + k];
                for (xi, &l) in x[b + k + 1..b + ns]
                    .iter_mut()
                    .zip(&values[k * ld + k + 1..])
                {
                    *xi -= l * xk;
                }
            }
            if !own.is_empty() {
                let t = &mut f.column[..own.len()];
                product(t, values, ld, top, &x[b..b + ns]);
                for (&r, &v) in own.iter().zip(t.iter()) {
                    x[r] -= v;
                }
            }
        }
        // D z = y.
        for s in 0..n_super {
            let (b, ns) = (f.begin[s], f.begin[s + 1] - f.begin[s]);
            let ld = Panel::new(ns, f.row_ptr[s + 1] - f.row_ptr[s]).rows;
            let values = &f.values[f.val_ptr[s]..f.val_ptr[s + 1]];
            for k in 0..ns {
                x[b + k] /= values[k * ld + k];
            }
        }
        // Lᵀ x = z: the off-diagonal rows' part L₂₁ᵀ x, then the diagonal
        // block backwards.
        for s in (0..n_super).rev() {
            let (b, ns) = (f.begin[s], f.begin[s + 1] - f.begin[s]);
            let own = &f.rows[f.row_ptr[s]..f.row_ptr[s + 1]];
            let Panel {
                rows: ld, top, m, ..
            } = Panel::new(ns, own.len());
            let values = &f.values[f.val_ptr[s]..f.val_ptr[s + 1]];
            if !own.is_empty() {
                let g = &mut f.column[..own.len()];
                for (gi, &r) in g.iter_mut().zip(own) {
                    *gi = x[r];
                }
                for k in 0..ns {
                    x[b + k] -= dot(&values[k * ld + top..k * ld + top + m], g);
                }
            }
            for k in (0..ns).rev() {
                let col = &values[k * ld + k + 1..k * ld + ns];
                let mut sum = x[b + k];
                for (&l, &xi) in col.iter().zip(&x[b + k + 1..b + ns]) {
                    sum -= l * xi;
                }
                x[b + k] = sum;
            }
        }
    }
}

/// Σ a_i b_i in four interleaved partial sums (a fixed order, whatever the
/// SIMD width).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (a4.remainder(), b4.remainder());
    for (p, q) in a4.zip(b4) {
        for l in 0..4 {
            acc[l] += p[l] * q[l];
        }
    }
    let mut sum = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    for (p, q) in ra.iter().zip(rb) {
        sum += p * q;
    }
    sum
}
