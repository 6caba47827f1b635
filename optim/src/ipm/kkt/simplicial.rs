//! Simplicial (up-looking) LDLᵀ of the permuted KKT matrix `P K Pᵀ = L D Lᵀ` on faer's
//! simplicial symbolic analysis, with the permuted pattern, a value gather map and the
//! elimination-tree reaches computed once per pattern ([`SimplicialPlan`]). Each
//! refactorization performs faer 0.24's operations in faer's order, so factor and solution are
//! bitwise those of `SymbolicCholesky::factorize_numeric_ldlt` (tested against it).

use faer::Side;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::utils::{permute_self_adjoint_scratch, permute_self_adjoint_to_unsorted};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};

/// The simplicial (up-looking) numeric LDLᵀ of faer 0.24 redone on data prepared once per
/// pattern: faer's `SymbolicCholesky::factorize_numeric_ldlt` permutes `K` into a fresh upper
/// triangle on every call and recomputes `1/d_j` for every entry of `L`; here the permuted
/// pattern and a value map are built at analysis time, so a refactorization is one gather plus
/// the elimination. The operations and their order are exactly faer's (same elimination-tree
/// reach order, same rounding), so factors and solutions are bitwise those of faer.
#[derive(Debug, Clone, Default)]
pub(super) struct SimplicialPlan {
    /// `perm_fwd[i]`: original index of permuted row i.
    perm_fwd: Vec<usize>,
    /// `perm_inv[i]`: permuted index of original row i.
    perm_inv: Vec<usize>,
    /// Upper triangle of `P K Pᵀ` (faer's unsorted layout): column pointers, rows, and the
    /// position of each entry in the caller's lower-triangle value array.
    a_col_ptr: Vec<usize>,
    a_row_idx: Vec<usize>,
    a_src: Vec<usize>,
    /// Row patterns of `L` in faer's elimination-tree reach order (faer's `ereach`, done once
    /// here instead of per factorization): for row k, `reach[reach_ptr[k]..reach_ptr[k+1]]`
    /// holds `[j, a, p]` with `a` the position of column j's first off-diagonal entry and `p`
    /// that of `L[k, j]` in the value array, so `a..p` is the part of column j already
    /// computed. `a` is `l_col_ptr[j] + 1`, kept here so that the walk reads one array instead
    /// of two; with the working arrays cut to the dimension in `factor`, the factorization is
    /// measurably faster (BENCHMARKS.md, "The simplicial kernel's column starts").
    reach_ptr: Vec<usize>,
    reach: Vec<[u32; 3]>,
    /// Structure of `L` (diagonal first, rows increasing within a column), 32-bit rows.
    l_col_ptr: Vec<usize>,
    l_row_idx: Vec<u32>,
    // workspaces
    a_val: Vec<f64>,
    x: Vec<f64>,
    inv_d: Vec<f64>,
    tmp: Vec<f64>,
}

impl SimplicialPlan {
    /// Prepares the plan from faer's symbolic analysis of the lower-triangle pattern.
    pub(super) fn new(
        sym: &SymbolicCholesky<usize>,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Option<Self> {
        let SymbolicCholeskyRaw::Simplicial(s) = sym.raw() else {
            return None;
        };
        let perm = sym.perm()?;
        let (fwd, inv) = perm.arrays();
        let nnz = row_idx.len();
        // Positions as values: permuting them gives the gather map (exact in f64).
        let pos: Vec<f64> = (0..nnz).map(|p| p as f64).collect();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(dim, dim, col_ptr, None, row_idx),
            &pos[..],
        );
        let mut new_val = vec![0.0; nnz];
        let mut new_col_ptr = vec![0usize; dim + 1];
        let mut new_row_idx = vec![0usize; nnz];
        let mut mem = MemBuffer::try_new(permute_self_adjoint_scratch::<usize>(dim)).ok()?;
        let permuted = permute_self_adjoint_to_unsorted(
            &mut new_val,
            &mut new_col_ptr,
            &mut new_row_idx,
            a,
            perm,
            Side::Lower,
            Side::Upper,
            MemStack::new(&mut mem),
        );
        let a_col_ptr = permuted.col_ptr().to_vec();
        let a_row_idx = permuted.row_idx().to_vec();
        let a_src: Vec<usize> = permuted.val().iter().map(|&v| v as usize).collect();
        let l_col_ptr = s.col_ptr().to_vec();
        let l_nnz = *l_col_ptr.last()?;
        if l_nnz > u32::MAX as usize || dim > u32::MAX as usize {
            return None;
        }
        let l_rows = s.row_idx();
        // Elimination tree read off L (first off-diagonal row of each column).
        let parent: Vec<usize> = (0..dim)
            .map(|j| {
                if l_col_ptr[j + 1] > l_col_ptr[j] + 1 {
                    l_rows[l_col_ptr[j] + 1]
                } else {
                    usize::MAX
                }
            })
            .collect();
        let mut visited = vec![usize::MAX; dim];
        let mut stack = vec![0usize; dim];
        let mut next: Vec<usize> = l_col_ptr[..dim].to_vec();
        let mut reach_ptr = Vec::with_capacity(dim + 1);
        let mut reach = Vec::with_capacity(l_nnz - dim);
        reach_ptr.push(0);
        for k in 0..dim {
            let mut top = dim;
            visited[k] = k;
            for &i0 in &a_row_idx[a_col_ptr[k]..a_col_ptr[k + 1]] {
                if i0 >= k {
                    continue;
                }
                let mut i = i0;
                let mut len = 0;
                while visited[i] != k {
                    stack[len] = i;
                    len += 1;
                    visited[i] = k;
                    i = parent[i];
                }
                stack.copy_within(..len, top - len);
                top -= len;
            }
            for &j in &stack[top..] {
                next[j] += 1;
                if l_rows.get(next[j]) != Some(&k) {
                    return None; // not faer's structure: use faer's own path
                }
                reach.push([j as u32, l_col_ptr[j] as u32 + 1, next[j] as u32]);
            }
            reach_ptr.push(reach.len());
        }
        Some(Self {
            perm_fwd: fwd.to_vec(),
            perm_inv: inv.to_vec(),
            a_val: vec![0.0; a_row_idx.len()],
            a_col_ptr,
            a_row_idx,
            a_src,
            reach_ptr,
            reach,
            l_row_idx: l_rows.iter().map(|&r| r as u32).collect(),
            l_col_ptr,
            x: vec![0.0; dim],
            inv_d: vec![0.0; dim],
            tmp: vec![0.0; dim],
        })
    }

    /// Numeric LDLᵀ into `l` (layout of `l_col_ptr`); pivots with |d| ≤ `eps` become ±`delta`
    /// when `delta > 0`. `false` on a zero or non-finite pivot.
    pub(super) fn factor(&mut self, values: &[f64], l: &mut [f64], eps: f64, delta: f64) -> bool {
        let n = self.x.len();
        for (dst, &src) in self.a_val.iter_mut().zip(&self.a_src) {
            *dst = values[src];
        }
        let (eps, delta) = (eps.abs(), delta.abs());
        let x = &mut self.x[..n];
        x.iter_mut().for_each(|v| *v = 0.0);
        let inv_d = &mut self.inv_d[..n];
        for k in 0..n {
            let (a0, a1) = (self.a_col_ptr[k], self.a_col_ptr[k + 1]);
            for (&i, &aik) in self.a_row_idx[a0..a1].iter().zip(&self.a_val[a0..a1]) {
                x[i] += aik;
            }
            let mut d = x[k];
            x[k] = 0.0;
            for &[j, a, row] in &self.reach[self.reach_ptr[k]..self.reach_ptr[k + 1]] {
                let (j, a, row) = (j as usize, a as usize, row as usize);
                let xj = std::mem::replace(&mut x[j], 0.0);
                let lkj = xj * inv_d[j];
                axpy_scatter(x, &self.l_row_idx[a..row], &l[a..row], xj);
                d -= lkj * xj;
                l[row] = lkj;
            }
            if delta > 0.0 && d.abs() <= eps {
                d = if d < 0.0 { -delta } else { delta };
            }
            if d == 0.0 || !d.is_finite() {
                return false;
            }
            l[self.l_col_ptr[k]] = d;
            inv_d[k] = d.recip();
        }
        true
    }

    /// Solves `K x = rhs` in place with the factor `l` (faer's permuted unit-lower solve, the
    /// D scaling fused into the transposed solve, and the inverse permutation).
    pub(super) fn solve(&mut self, l: &[f64], rhs: &mut [f64]) {
        let n = rhs.len();
        let x = &mut self.tmp;
        for i in 0..n {
            x[i] = rhs[self.perm_fwd[i]];
        }
        for j in 0..n {
            let (a, b) = (self.l_col_ptr[j] + 1, self.l_col_ptr[j + 1]);
            let xj = x[j];
            axpy_scatter(x, &self.l_row_idx[a..b], &l[a..b], xj);
        }
        for j in (0..n).rev() {
            let (a, b) = (self.l_col_ptr[j] + 1, self.l_col_ptr[j + 1]);
            let mut acc = 0.0;
            for (&i, &lij) in self.l_row_idx[a..b].iter().zip(&l[a..b]).rev() {
                acc += lij * x[i as usize];
            }
            x[j] = x[j] * l[a - 1].recip() - acc;
        }
        for i in 0..n {
            rhs[i] = x[self.perm_inv[i]];
        }
    }
}

/// `x[rows[p]] -= vals[p] * s` for all p (distinct rows), unrolled by four: the hot loop of
/// the factorization and the forward solve. Each entry of `x` is updated once, so the result
/// does not depend on the unrolling.
#[inline(always)]
pub(super) fn axpy_scatter(x: &mut [f64], rows: &[u32], vals: &[f64], s: f64) {
    // Rows are strictly increasing, so first + len − 1 = last means a contiguous run (the
    // dense fronts near the root of the elimination tree): the same element-wise operations
    // on a slice, which the compiler vectorizes.
    if let (Some(&first), Some(&last)) = (rows.first(), rows.last())
        && (last - first) as usize + 1 == rows.len()
    {
        let first = first as usize;
        for (xi, &v) in x[first..=last as usize].iter_mut().zip(vals) {
            *xi -= v * s;
        }
        return;
    }
    scatter_sub(x, rows, vals, s, |r| r as usize);
}

/// `dst[index(rows[p])] -= vals[p] * s` for all p (distinct targets), unrolled by four (four
/// independent loads before the stores): the scatter of the simplicial factorization and
/// forward solve (`index` = identity) and of the supernodal kernel's updates at their
/// relative rows. Each entry of `dst` is updated once, so the result does not depend on the
/// unrolling.
#[inline(always)]
pub(super) fn scatter_sub(
    dst: &mut [f64],
    rows: &[u32],
    vals: &[f64],
    s: f64,
    index: impl Fn(u32) -> usize,
) {
    let mut r4 = rows.chunks_exact(4);
    let mut v4 = vals.chunks_exact(4);
    for (r, v) in (&mut r4).zip(&mut v4) {
        let (a, b, c, d) = (index(r[0]), index(r[1]), index(r[2]), index(r[3]));
        let (xa, xb, xc, xd) = (
            dst[a] - v[0] * s,
            dst[b] - v[1] * s,
            dst[c] - v[2] * s,
            dst[d] - v[3] * s,
        );
        dst[a] = xa;
        dst[b] = xb;
        dst[c] = xc;
        dst[d] = xd;
    }
    for (&r, &v) in r4.remainder().iter().zip(v4.remainder()) {
        dst[index(r)] -= v * s;
    }
}
