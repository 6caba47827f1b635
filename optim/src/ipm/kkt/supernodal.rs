//! Supernodal left-looking LDLᵀ of the permuted KKT matrix `P K Pᵀ = L D Lᵀ` on the
//! fundamental supernodes of faer's simplicial structure ([`BlockPlan`]): same ordering, same
//! `L` pattern (no relaxation zeros) and the same pivot rule as the simplicial backend, with
//! dense column-major blocks per supernode so that the updates are dense column operations.
//! Its rounding differs from the simplicial backend's; it is tested by reconstructing
//! `P K Pᵀ` from `L D Lᵀ` and against dense eigenvalue inertia.

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

use super::Inertia;
use super::simplicial::{axpy_scatter, scatter_sub};

/// The AMD permutation (`fwd`, `inv`) and the simplicial `L` structure (column pointers, row
/// indices) of faer's symbolic analysis, which the supernodal and multifrontal plans are built
/// on; `None` if faer chose a supernodal analysis or no permutation.
#[allow(clippy::type_complexity)]
pub(super) fn simplicial_structure(
    sym: &SymbolicCholesky<usize>,
) -> Option<(&[usize], &[usize], &[usize], &[usize])> {
    let SymbolicCholeskyRaw::Simplicial(s) = sym.raw() else {
        return None;
    };
    let (fwd, inv) = sym.perm()?.arrays();
    Some((fwd, inv, s.col_ptr(), s.row_idx()))
}

/// A 1 × 1 pivot `d` after static pivoting (`|d| ≤ eps` replaced by `±delta` when `delta > 0`;
/// whether it was replaced), counted into `inertia`; `None` for a zero or non-finite pivot.
pub(super) fn counted_pivot(
    d: f64,
    delta: f64,
    eps: f64,
    inertia: &mut Inertia,
) -> Option<(f64, bool)> {
    let replaced = delta > 0.0 && d.abs() <= eps;
    let d = if replaced {
        if d < 0.0 { -delta } else { delta }
    } else {
        d
    };
    if d == 0.0 || !d.is_finite() {
        return None;
    }
    if d > 0.0 {
        inertia.positive += 1;
    } else {
        inertia.negative += 1;
    }
    Some((d, replaced))
}

/// A 2 × 2 pivot `[a b; b c]` counted into `inertia` by its determinant (one eigenvalue of
/// each sign when negative, else both of the sign of its trace); its determinant, or `None`
/// for a singular or non-finite one.
pub(super) fn counted_pair(a: f64, b: f64, c: f64, inertia: &mut Inertia) -> Option<f64> {
    let det = a * c - b * b;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    if det < 0.0 {
        inertia.positive += 1;
        inertia.negative += 1;
    } else if a + c > 0.0 {
        inertia.positive += 2;
    } else {
        inertia.negative += 2;
    }
    Some(det)
}

/// The [`Elimination`] of a [`BlockPlan`]'s pivot fields (a macro, so that the borrow is of
/// those fields only and the blocks in `vals` stay writable beside it).
macro_rules! elimination {
    ($plan:expr) => {
        Elimination {
            d: &mut $plan.d,
            inv_d: &mut $plan.inv_d,
            e: &mut $plan.e,
            inv_e: &mut $plan.inv_e,
            pair: &$plan.pair,
            l: &mut $plan.l,
            l_col_ptr: &$plan.l_col_ptr,
            coef: &mut $plan.coef,
        }
    };
}

/// Left-looking supernodal LDLᵀ on the fundamental supernodes of faer's simplicial structure
/// (same AMD permutation, same `L` pattern, no explicit zeros): runs of columns with nested
/// structure (`parent(j) = j + 1`, `|L_j| = |L_{j+1}| + 1`) are stored as dense column-major
/// blocks, so the updates from a multi-column supernode are dense column operations followed by
/// one scatter per target column instead of one indirect scatter per entry and source column.
/// On the hp-Radau collocation KKTs about 80 % of the flops come from such supernodes (element
/// blocks of 9–18 columns and the final dense block). Pivots (`D`), static pivoting and the
/// inertia are as in the simplicial backend; only the summation order, hence the rounding, differs.
#[derive(Debug, Clone, Default)]
pub(super) struct BlockPlan {
    /// `perm_fwd[i]`: original index of permuted row i.
    pub(super) perm_fwd: Vec<usize>,
    /// `perm_inv[i]`: permuted index of original row i.
    pub(super) perm_inv: Vec<usize>,
    /// Columns of supernode s: `sn_begin[s]..sn_begin[s + 1]`.
    pub(super) sn_begin: Vec<usize>,
    /// Rows of supernode s (ascending, its own columns first):
    /// `sn_rows[sn_row_ptr[s]..sn_row_ptr[s + 1]]`.
    pub(super) sn_row_ptr: Vec<usize>,
    pub(super) sn_rows: Vec<u32>,
    /// Start of supernode s's column-major `nrows × ncols` block in `vals`.
    pub(super) sn_val_ptr: Vec<usize>,
    /// Updates into supernode s: `(d, p1, p2)` = descendant d whose rows
    /// `rows_d[p1..p2]` are columns of s (rows `rows_d[p1..]` receive the update).
    pub(super) upd_ptr: Vec<usize>,
    pub(super) upd: Vec<(u32, u32, u32)>,
    /// Position in `vals` of each entry of the caller's lower-triangle value array.
    pub(super) a_dst: Vec<usize>,
    /// Block values (`L` below the diagonal, pivots on it, unused upper triangles).
    pub(super) vals: Vec<f64>,
    /// Diagonal of `D` and, for 1 × 1 pivots, its reciprocals, permuted order. For a 2 × 2
    /// pivot on columns (j, j + 1): `d[j]`, `d[j + 1]` its diagonal, `e[j]` its off-diagonal,
    /// and `inv_d[j]`, `inv_e[j]`, `inv_d[j + 1]` the entries of its inverse.
    pub(super) d: Vec<f64>,
    pub(super) inv_d: Vec<f64>,
    pub(super) e: Vec<f64>,
    pub(super) inv_e: Vec<f64>,
    /// `pair[j]`: columns j and j + 1 are one 2 × 2 pivot (same supernode, parent(j) = j + 1).
    pub(super) pair: Vec<bool>,
    /// Whether supernode s holds a 2 × 2 pivot.
    pub(super) sn_pair: Vec<bool>,
    /// `L` copied into faer's simplicial layout (diagonal slot first, holding `D`) for the
    /// triangular solves: per column one contiguous run of the block; the column-by-column
    /// solve measured faster than a per-supernode one on these KKTs.
    pub(super) l_col_ptr: Vec<usize>,
    pub(super) l_row_idx: Vec<u32>,
    pub(super) l: Vec<f64>,
    // workspaces
    pub(super) map: Vec<u32>,
    pub(super) tmp: Vec<f64>,
    pub(super) wbuf: Vec<f64>,
    pub(super) rel: Vec<u32>,
    pub(super) coef: Vec<f64>,
    pub(super) x: Vec<f64>,
}

impl BlockPlan {
    /// Builds the supernode partition, block layout, update lists and value map from faer's
    /// simplicial symbolic analysis (`None` for a supernodal one or oversized indices).
    /// `pair_first[j]` (permuted index; may be empty) asks for a 2 × 2 pivot on columns j and
    /// j + 1; it is granted where `L[j + 1, j]` is structurally nonzero (parent(j) = j + 1),
    /// and the two columns then share one supernode whose rows are the union of theirs
    /// (explicit zeros in column j where `L_{j+1}` has rows that `L_j` lacks).
    pub(super) fn new(
        sym: &SymbolicCholesky<usize>,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        pair_first: &[bool],
    ) -> Option<Self> {
        let (fwd, inv, lp, lr) = simplicial_structure(sym)?;
        if *lp.last()? > u32::MAX as usize || dim >= u32::MAX as usize || dim == 0 {
            return None;
        }
        let cnt = |j: usize| lp[j + 1] - lp[j];
        // Fundamental supernodes: column j continues j − 1's supernode when parent(j − 1) = j
        // and |L_{j−1}| = |L_j| + 1; column j − 1's structure is then {j − 1} ∪ struct(j), so
        // a supernode [f, l) has rows {f, …, l − 1} ∪ struct(l − 1) and no explicit zeros.
        // A granted pair [j, j + 1] joins one supernode as well: parent(j) = j + 1 gives
        // struct(L_j) ⊆ {j} ∪ struct(L_{j+1}), so the supernode's rows still contain every
        // column's structure.
        let mut pair = vec![false; dim];
        let mut sn_begin = vec![0usize];
        for j in 0..dim - 1 {
            let parent_next = cnt(j) > 1 && lr[lp[j] + 1] == j + 1;
            let chained = parent_next && cnt(j) == cnt(j + 1) + 1;
            pair[j] = parent_next
                && pair_first.get(j).copied().unwrap_or(false)
                && (j == 0 || !pair[j - 1]);
            if !chained && !pair[j] {
                sn_begin.push(j + 1);
            }
        }
        sn_begin.push(dim);
        let ns = sn_begin.len() - 1;
        let mut col2sn = vec![0u32; dim];
        let mut sn_row_ptr = Vec::with_capacity(ns + 1);
        let mut sn_val_ptr = Vec::with_capacity(ns + 1);
        let mut sn_rows = Vec::new();
        sn_row_ptr.push(0);
        sn_val_ptr.push(0);
        for sn in 0..ns {
            let (f, l) = (sn_begin[sn], sn_begin[sn + 1]);
            col2sn[f..l].iter_mut().for_each(|c| *c = sn as u32);
            sn_rows.extend((f..l).map(|r| r as u32));
            sn_rows.extend(lr[lp[l - 1] + 1..lp[l]].iter().map(|&r| r as u32));
            sn_row_ptr.push(sn_rows.len());
            sn_val_ptr.push(sn_val_ptr[sn] + (sn_row_ptr[sn + 1] - sn_row_ptr[sn]) * (l - f));
        }
        // Update lists: descendant d updates every supernode owning one of its off-block rows.
        let mut pairs: Vec<(u32, u32, u32, u32)> = Vec::new();
        for d in 0..ns {
            let w = sn_begin[d + 1] - sn_begin[d];
            let rows = &sn_rows[sn_row_ptr[d]..sn_row_ptr[d + 1]];
            let mut p = w;
            while p < rows.len() {
                let t = col2sn[rows[p] as usize];
                let mut q = p + 1;
                while q < rows.len() && col2sn[rows[q] as usize] == t {
                    q += 1;
                }
                pairs.push((t, d as u32, p as u32, q as u32));
                p = q;
            }
        }
        pairs.sort_unstable();
        let mut upd_ptr = vec![0usize; ns + 1];
        for &(t, ..) in &pairs {
            upd_ptr[t as usize + 1] += 1;
        }
        for sn in 0..ns {
            upd_ptr[sn + 1] += upd_ptr[sn];
        }
        let upd: Vec<(u32, u32, u32)> = pairs.iter().map(|&(_, d, p, q)| (d, p, q)).collect();
        let sn_pair = (0..ns)
            .map(|sn| pair[sn_begin[sn]..sn_begin[sn + 1]].iter().any(|&p| p))
            .collect();
        // `L` in column layout for the solves: column j of supernode s holds the block rows
        // from j down (diagonal slot first).
        let mut l_col_ptr = Vec::with_capacity(dim + 1);
        let mut l_row_idx = Vec::new();
        l_col_ptr.push(0);
        for sn in 0..ns {
            let rows = &sn_rows[sn_row_ptr[sn]..sn_row_ptr[sn + 1]];
            for c in 0..sn_begin[sn + 1] - sn_begin[sn] {
                l_row_idx.extend_from_slice(&rows[c..]);
                l_col_ptr.push(l_row_idx.len());
            }
        }
        // Value map of the permuted lower triangle.
        let mut a_dst = Vec::with_capacity(row_idx.len());
        for j in 0..dim {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                let (pi, pj) = (inv[i], inv[j]);
                let (r, c) = if pi >= pj { (pi, pj) } else { (pj, pi) };
                let sn = col2sn[c] as usize;
                let rows = &sn_rows[sn_row_ptr[sn]..sn_row_ptr[sn + 1]];
                let pos = rows.binary_search(&(r as u32)).ok()?;
                a_dst.push(sn_val_ptr[sn] + (c - sn_begin[sn]) * rows.len() + pos);
            }
        }
        let max_rows = (0..ns)
            .map(|sn| sn_row_ptr[sn + 1] - sn_row_ptr[sn])
            .max()
            .unwrap_or(0);
        // The blocked kernel's `L D` factor of an update (target columns × descendant
        // columns) or of a panel (its columns × the columns before it).
        let (mut max_w, mut max_tmp) = (0, max_rows);
        for t in 0..ns {
            let w = sn_begin[t + 1] - sn_begin[t];
            max_w = max_w.max((PANEL + 1).min(w) * w);
            for &(d, p, q) in &upd[upd_ptr[t]..upd_ptr[t + 1]] {
                let (d, p, q) = (d as usize, p as usize, q as usize);
                max_w = max_w.max((q - p) * (sn_begin[d + 1] - sn_begin[d]));
                max_tmp = max_tmp.max((sn_row_ptr[d + 1] - sn_row_ptr[d] - p) * (q - p));
            }
        }
        Some(Self {
            perm_fwd: fwd.to_vec(),
            perm_inv: inv.to_vec(),
            vals: vec![0.0; sn_val_ptr[ns]],
            sn_begin,
            sn_row_ptr,
            sn_rows,
            sn_val_ptr,
            upd_ptr,
            upd,
            a_dst,
            d: vec![0.0; dim],
            inv_d: vec![0.0; dim],
            e: vec![0.0; dim],
            inv_e: vec![0.0; dim],
            pair,
            sn_pair,
            l: vec![0.0; l_col_ptr[dim]],
            l_col_ptr,
            l_row_idx,
            map: vec![0; dim],
            tmp: vec![0.0; max_tmp],
            rel: vec![0; max_rows],
            wbuf: vec![0.0; max_w],
            coef: vec![0.0; max_rows],
            x: vec![0.0; dim],
        })
    }

    /// The values of `K` scattered into the zeroed blocks.
    fn load(&mut self, values: &[f64]) {
        self.vals.iter_mut().for_each(|v| *v = 0.0);
        for (&dst, &v) in self.a_dst.iter().zip(values) {
            self.vals[dst] = v;
        }
    }

    /// Numeric LDLᵀ with dense kernels where they pay ([`factor_with`](Self::factor_with)
    /// `blocked`). Pivots with |d| ≤ `eps` become ±`delta` when `delta > 0`. Returns the
    /// inertia, or `None` on a zero or non-finite pivot.
    pub(super) fn factor(&mut self, values: &[f64], eps: f64, delta: f64) -> Option<Inertia> {
        self.factor_with(values, eps, delta, true)
    }

    /// Numeric LDLᵀ with column-by-column updates only (each target column receives a linear
    /// combination of a descendant's columns, four at a time; each diagonal block is factored
    /// left-looking column by column): the kernel before the dense products, kept as
    /// [`LdltBackend::SupernodalColumns`](super::LdltBackend::SupernodalColumns) for comparison.
    pub(super) fn factor_columns(
        &mut self,
        values: &[f64],
        eps: f64,
        delta: f64,
    ) -> Option<Inertia> {
        self.factor_with(values, eps, delta, false)
    }

    /// The numeric LDLᵀ. With `blocked`, a descendant's update of at least [`GEMM_MIN`]
    /// columns into at least [`GEMM_MIN`] columns of a supernode is one matrix product
    /// `L_d[rows] (L_d D_d)[cols]ᵀ` on 4 × 4 register tiles ([`gemm_sub`]), subtracted in place
    /// where the descendant's rows are consecutive rows of the target and scattered from a
    /// buffer otherwise, and a diagonal block of at least `2 PANEL` columns without 2 × 2
    /// pivots is factored by panels of [`PANEL`] columns (the block's earlier columns update a
    /// panel by one product, the panel's own columns are eliminated one by one); every other
    /// update is a linear combination per target column. The products perform the column
    /// kernel's operations in its order (groups of four source columns, then single ones, per
    /// descendant in the same order), so the factor is bit for bit the same either way: the
    /// blocked kernel changes the time, not the path.
    fn factor_with(
        &mut self,
        values: &[f64],
        eps: f64,
        delta: f64,
        blocked: bool,
    ) -> Option<Inertia> {
        let (eps, delta) = (eps.abs(), delta.abs());
        self.load(values);
        let ns = self.sn_begin.len() - 1;
        let mut inertia = Inertia::default();
        for sn in 0..ns {
            let (f, l) = (self.sn_begin[sn], self.sn_begin[sn + 1]);
            let w = l - f;
            let rows = &self.sn_rows[self.sn_row_ptr[sn]..self.sn_row_ptr[sn + 1]];
            let nr = rows.len();
            for (pos, &r) in rows.iter().enumerate() {
                self.map[r as usize] = pos as u32;
            }
            let (done, rest) = self.vals.split_at_mut(self.sn_val_ptr[sn]);
            let blk = &mut rest[..nr * w];
            for &(dd, p1, p2) in &self.upd[self.upd_ptr[sn]..self.upd_ptr[sn + 1]] {
                let dd = dd as usize;
                let (p1, p2) = (p1 as usize, p2 as usize);
                let (fd, ld) = (self.sn_begin[dd], self.sn_begin[dd + 1]);
                let wd = ld - fd;
                let rd = &self.sn_rows[self.sn_row_ptr[dd]..self.sn_row_ptr[dd + 1]];
                let nrd = rd.len();
                let bd = &done[self.sn_val_ptr[dd]..self.sn_val_ptr[dd] + nrd * wd];
                let dpiv = &self.d[fd..ld];
                // Rows rd[p1..] land on consecutive rows of the target block: subtract
                // in place without the row map.
                let first = self.map[rd[p1] as usize] as usize;
                let contiguous = self.map[rd[nrd - 1] as usize] as usize - first == nrd - 1 - p1;
                let nc = p2 - p1;
                if blocked && wd >= GEMM_MIN && nc >= GEMM_MIN {
                    // W = (L_d D_d) on the target's columns, k-major: w[k·nc + j]. Rows rd[p1..]
                    // are consecutive rows of the block and rd[p1..p2] its consecutive columns
                    // (the block's own columns are its first rows); entries above the target's
                    // diagonal land in the block's unused upper triangle.
                    let wbuf = &mut self.wbuf[..nc * wd];
                    for j in 0..nc {
                        let coef = &mut self.coef[..wd];
                        if self.sn_pair[dd] {
                            dl_t(
                                coef,
                                bd,
                                nrd,
                                p1 + j,
                                dpiv,
                                &self.e[fd..ld],
                                &self.pair[fd..ld],
                            );
                        } else {
                            for (k, cf) in coef.iter_mut().enumerate() {
                                *cf = bd[k * nrd + p1 + j] * dpiv[k];
                            }
                        }
                        for (k, &cf) in coef.iter().enumerate() {
                            wbuf[k * nc + j] = cf;
                        }
                    }
                    let m = nrd - p1;
                    if contiguous {
                        let c0 = rd[p1] as usize - f;
                        gemm_sub(
                            &mut blk[c0 * nr + first..],
                            nr,
                            &bd[p1..],
                            nrd,
                            m,
                            wbuf,
                            nc,
                            wd,
                        );
                        continue;
                    }
                    // Elsewhere the product goes to a buffer, scattered through the row map
                    // once per target column (lower part only).
                    let tmp = &mut self.tmp[..m * nc];
                    tmp.iter_mut().for_each(|t| *t = 0.0);
                    gemm_sub(tmp, m, &bd[p1..], nrd, m, wbuf, nc, wd);
                    let rel = &mut self.rel[..m];
                    for (x, &r) in rel.iter_mut().zip(&rd[p1..]) {
                        *x = self.map[r as usize];
                    }
                    for j in 0..nc {
                        let bcol = &mut blk[(rd[p1 + j] as usize - f) * nr..][..nr];
                        for (&i, &t) in rel[j..].iter().zip(&tmp[j * m + j..(j + 1) * m]) {
                            bcol[i as usize] += t;
                        }
                    }
                    continue;
                }
                for q in p1..p2 {
                    let c = rd[q] as usize - f;
                    let len = nrd - q;
                    let bcol = &mut blk[c * nr..(c + 1) * nr];
                    if wd == 1 {
                        let sc = bd[q] * dpiv[0];
                        if contiguous {
                            let start = first + (q - p1);
                            for (b, &v) in bcol[start..start + len].iter_mut().zip(&bd[q..]) {
                                *b -= v * sc;
                            }
                        } else {
                            scatter_sub(bcol, &rd[q..], &bd[q..], sc, |r| {
                                self.map[r as usize] as usize
                            });
                        }
                        continue;
                    }
                    let coef = &mut self.coef[..wd];
                    if self.sn_pair[dd] {
                        dl_t(coef, bd, nrd, q, dpiv, &self.e[fd..ld], &self.pair[fd..ld]);
                    } else {
                        for (k, cf) in coef.iter_mut().enumerate() {
                            *cf = bd[k * nrd + q] * dpiv[k];
                        }
                    }
                    if contiguous {
                        let start = first + (q - p1);
                        lincomb_sub(&mut bcol[start..start + len], bd, nrd, q, coef);
                    } else {
                        let out = &mut self.tmp[..len];
                        out.iter_mut().for_each(|o| *o = 0.0);
                        lincomb_sub(out, bd, nrd, q, coef);
                        scatter_sub(bcol, &rd[q..], out, -1.0, |r| self.map[r as usize] as usize);
                    }
                }
            }
            // Dense LDLᵀ of the block's own columns: left-looking column by column, or by
            // panels whose columns the earlier ones update by one product.
            let has_pair = self.sn_pair[sn];
            // Panels start at multiples of four columns, so that the product before a panel and
            // the columns' own combinations group the source columns as the column kernel
            // does; a supernode with a 2 × 2 pivot (which may straddle a panel) keeps that
            // kernel.
            let panel = if blocked && w >= 2 * PANEL && !has_pair {
                PANEL
            } else {
                w
            };
            let mut c0 = 0;
            while c0 < w {
                let c1 = (c0 + panel).min(w);
                if c0 > 0 {
                    let nc = c1 - c0;
                    let wbuf = &mut self.wbuf[..nc * c0];
                    for j in 0..nc {
                        let coef = &mut self.coef[..c0];
                        if has_pair {
                            let r = f..f + c0;
                            dl_t(
                                coef,
                                blk,
                                nr,
                                c0 + j,
                                &self.d[r.clone()],
                                &self.e[r.clone()],
                                &self.pair[r],
                            );
                        } else {
                            for (k, cf) in coef.iter_mut().enumerate() {
                                *cf = blk[k * nr + c0 + j] * self.d[f + k];
                            }
                        }
                        for (k, &cf) in coef.iter().enumerate() {
                            wbuf[k * nc + j] = cf;
                        }
                    }
                    let (left, right) = blk.split_at_mut(c0 * nr);
                    gemm_sub(&mut right[c0..], nr, &left[c0..], nr, nr - c0, wbuf, nc, c0);
                }
                let mut elim = elimination!(self);
                let mut c = c0;
                while c < c1 {
                    c = elim.column(blk, nr, f, c0, c, has_pair, eps, delta, &mut inertia)?;
                }
                c0 = c1;
            }
        }
        Some(inertia)
    }

    /// Solves `K x = rhs` in place with the last factorization (column-oriented forward
    /// solve, `D⁻¹`, row-oriented backward solve with four partial sums per row).
    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let x = &mut self.x;
        for i in 0..n {
            x[i] = rhs[self.perm_fwd[i]];
        }
        let (lp, li, l) = (&self.l_col_ptr, &self.l_row_idx, &self.l);
        for j in 0..n {
            let (a, b) = (lp[j] + 1, lp[j + 1]);
            let xj = x[j];
            axpy_scatter(x, &li[a..b], &l[a..b], xj);
        }
        if self.sn_pair.iter().any(|&p| p) {
            let mut j = 0;
            while j < n {
                if self.pair[j] {
                    let (u, v) = (x[j], x[j + 1]);
                    x[j] = u * self.inv_d[j] + v * self.inv_e[j];
                    x[j + 1] = u * self.inv_e[j] + v * self.inv_d[j + 1];
                    j += 2;
                } else {
                    x[j] *= self.inv_d[j];
                    j += 1;
                }
            }
            for j in (0..n).rev() {
                let (a, b) = (lp[j] + 1, lp[j + 1]);
                x[j] -= dot_gather4(&l[a..b], &li[a..b], x);
            }
        } else {
            for j in (0..n).rev() {
                let (a, b) = (lp[j] + 1, lp[j + 1]);
                x[j] = x[j] * self.inv_d[j] - dot_gather4(&l[a..b], &li[a..b], x);
            }
        }
        for i in 0..n {
            rhs[i] = x[self.perm_inv[i]];
        }
    }
}

/// The pivot state of a [`BlockPlan`] that eliminating one column (or 2 × 2 pair) writes:
/// `D`, its inverse, the pair marks and `L`'s solve copy.
struct Elimination<'a> {
    d: &'a mut [f64],
    inv_d: &'a mut [f64],
    e: &'a mut [f64],
    inv_e: &'a mut [f64],
    pair: &'a [bool],
    l: &'a mut [f64],
    l_col_ptr: &'a [usize],
    coef: &'a mut [f64],
}

impl Elimination<'_> {
    /// Eliminates column `c` (with `c + 1` when they are a 2 × 2 pair) of the supernode whose
    /// first column is `f` and whose `nr`-row block is `blk`: the updates from its columns
    /// `c0..c` (those before `c0` are already applied), the static pivoting, the pivot's count
    /// into `inertia`, `L`'s columns scaled by the pivot's inverse and copied for the solves.
    /// The next column to eliminate, or `None` on a zero or non-finite pivot.
    #[allow(clippy::too_many_arguments)]
    fn column(
        &mut self,
        blk: &mut [f64],
        nr: usize,
        f: usize,
        c0: usize,
        c: usize,
        has_pair: bool,
        eps: f64,
        delta: f64,
        inertia: &mut Inertia,
    ) -> Option<usize> {
        let two = self.pair[f + c];
        for t in c..c + 1 + usize::from(two) {
            let coef = &mut self.coef[..c - c0];
            let (left, right) = blk.split_at_mut(t * nr);
            let src = &left[c0 * nr..];
            if has_pair {
                let r = f + c0..f + c;
                dl_t(
                    coef,
                    src,
                    nr,
                    t,
                    &self.d[r.clone()],
                    &self.e[r.clone()],
                    &self.pair[r],
                );
            } else {
                for (k, cf) in coef.iter_mut().enumerate() {
                    *cf = src[k * nr + t] * self.d[f + c0 + k];
                }
            }
            lincomb_sub(&mut right[t..nr], src, nr, t, coef);
        }
        if !two {
            let col = &mut blk[c * nr + c..(c + 1) * nr];
            let (d, _) = counted_pivot(col[0], delta, eps, inertia)?;
            col[0] = d;
            let inv = d.recip();
            col[1..].iter_mut().for_each(|v| *v *= inv);
            self.d[f + c] = d;
            self.inv_d[f + c] = inv;
            self.e[f + c] = 0.0;
            self.l[self.l_col_ptr[f + c]..self.l_col_ptr[f + c + 1]].copy_from_slice(col);
            return Some(c + 1);
        }
        // 2 × 2 pivot B = [d1 a; a d2] on columns c, c + 1: L's two columns below it are
        // [A_c A_{c+1}] B⁻¹, and L[c + 1, c] = 0.
        let (cc, c1) = blk.split_at_mut((c + 1) * nr);
        let (col0, col1) = (&mut cc[c * nr + c..], &mut c1[c + 1..nr]);
        let (mut d1, mut a, mut d2) = (col0[0], col0[1], col1[0]);
        if a.abs() <= eps {
            a = 0.0;
            // Two 1 × 1 pivots: the static pivoting of each applies.
            for d in [&mut d1, &mut d2] {
                if delta > 0.0 && d.abs() <= eps {
                    *d = if *d < 0.0 { -delta } else { delta };
                }
            }
        }
        let det = counted_pair(d1, a, d2, inertia)?;
        let (i11, i12, i22) = (d2 / det, -a / det, d1 / det);
        for (x, y) in col0[2..].iter_mut().zip(col1[1..].iter_mut()) {
            let (u, v) = (*x, *y);
            *x = u * i11 + v * i12;
            *y = u * i12 + v * i22;
        }
        col0[0] = d1;
        col0[1] = 0.0;
        col1[0] = d2;
        let j = f + c;
        self.d[j] = d1;
        self.d[j + 1] = d2;
        self.e[j] = a;
        self.e[j + 1] = 0.0;
        self.inv_d[j] = i11;
        self.inv_d[j + 1] = i22;
        self.inv_e[j] = i12;
        self.l[self.l_col_ptr[j]..self.l_col_ptr[j + 1]].copy_from_slice(col0);
        self.l[self.l_col_ptr[j + 1]..self.l_col_ptr[j + 2]].copy_from_slice(col1);
        Some(c + 2)
    }
}

/// `coef[k] = (D Lᵀ)[k, q]` for the columns k of a block whose `D` has 2 × 2 pivots:
/// `L[q, k] d[k]`, plus `L[q, k + 1] e[k]` where (k, k + 1) is a pair and `L[q, k − 1] e[k − 1]`
/// where (k − 1, k) is one (`L[q, k]` = `blk[k·stride + q]`).
#[inline(always)]
fn dl_t(
    coef: &mut [f64],
    blk: &[f64],
    stride: usize,
    q: usize,
    d: &[f64],
    e: &[f64],
    pair: &[bool],
) {
    let w = coef.len();
    for k in 0..w {
        let mut v = blk[k * stride + q] * d[k];
        if pair[k] && k + 1 < w {
            v += blk[(k + 1) * stride + q] * e[k];
        }
        if k > 0 && pair[k - 1] {
            v += blk[(k - 1) * stride + q] * e[k - 1];
        }
        coef[k] = v;
    }
}

/// `out[i] -= Σ_k coef[k] · blk[k·stride + off + i]`: a dense multi-column update, four source
/// columns per pass over `out` (one load/store of `out` per four multiply-adds).
#[inline(always)]
fn lincomb_sub(out: &mut [f64], blk: &[f64], stride: usize, off: usize, coef: &[f64]) {
    let len = out.len();
    let col = |k: usize| &blk[k * stride + off..k * stride + off + len];
    let mut c4 = coef.chunks_exact(4);
    let mut k = 0;
    for c in &mut c4 {
        let (v0, v1, v2, v3) = (col(k), col(k + 1), col(k + 2), col(k + 3));
        for ((((o, &a), &b), &cc), &d) in out.iter_mut().zip(v0).zip(v1).zip(v2).zip(v3) {
            *o -= (c[0] * a + c[1] * b) + (c[2] * cc + c[3] * d);
        }
        k += 4;
    }
    for &c in c4.remainder() {
        for (o, &a) in out.iter_mut().zip(col(k)) {
            *o -= c * a;
        }
        k += 1;
    }
}

/// `Σ vals[p] x[rows[p]]` with four partial sums (breaks the add latency chain).
#[inline(always)]
fn dot_gather4(vals: &[f64], rows: &[u32], x: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let (v4, r4) = (vals.chunks_exact(4), rows.chunks_exact(4));
    let (vr, rr) = (v4.remainder(), r4.remainder());
    for (v, r) in v4.zip(r4) {
        s[0] += v[0] * x[r[0] as usize];
        s[1] += v[1] * x[r[1] as usize];
        s[2] += v[2] * x[r[2] as usize];
        s[3] += v[3] * x[r[3] as usize];
    }
    let mut tail = 0.0;
    for (v, &r) in vr.iter().zip(rr) {
        tail += v * x[r as usize];
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// Columns of a diagonal-block panel of the blocked kernel: the columns before the panel
/// update it by one dense matrix product, the panel's own columns are eliminated one by one.
const PANEL: usize = 16;

/// Fewest descendant columns and target columns for which the blocked kernel computes an
/// update as one matrix product (below it the per-column linear combination is as fast).
const GEMM_MIN: usize = 4;

/// `out[j·ld + i] −= Σ_k a[k·lda + i] · w[k·nc + j]` for `i < m`, `j < nc` (a product of the
/// `m × kd` column-major `a` and the transpose of the `nc × kd` k-major `w`), on 4 × 4 tiles
/// held in registers over the whole sum; tiles entirely above the diagonal (`i < j`) are
/// skipped, entries above it inside a diagonal tile are written too (the callers' blocks leave
/// their upper triangles unused).
#[allow(clippy::too_many_arguments)]
fn gemm_sub(
    out: &mut [f64],
    ld: usize,
    a: &[f64],
    lda: usize,
    m: usize,
    w: &[f64],
    nc: usize,
    kd: usize,
) {
    let mut j0 = 0;
    while j0 < nc {
        let cols = (nc - j0).min(4);
        let mut i0 = j0 - j0 % 4;
        while i0 < m {
            let rows = (m - i0).min(4);
            let t = Tile {
                out: &mut *out,
                ld,
                a,
                lda,
                w,
                nc,
                kd,
                i0,
                j0,
            };
            match (rows, cols) {
                (4, 4) => t.run::<4, 4>(),
                (4, 3) => t.run::<4, 3>(),
                (4, 2) => t.run::<4, 2>(),
                (4, 1) => t.run::<4, 1>(),
                (3, 4) => t.run::<3, 4>(),
                (3, 3) => t.run::<3, 3>(),
                (3, 2) => t.run::<3, 2>(),
                (3, 1) => t.run::<3, 1>(),
                (2, 4) => t.run::<2, 4>(),
                (2, 3) => t.run::<2, 3>(),
                (2, 2) => t.run::<2, 2>(),
                (2, 1) => t.run::<2, 1>(),
                (1, 4) => t.run::<1, 4>(),
                (1, 3) => t.run::<1, 3>(),
                (1, 2) => t.run::<1, 2>(),
                _ => t.run::<1, 1>(),
            }
            i0 += 4;
        }
        j0 += 4;
    }
}

/// One `R × C` tile of [`gemm_sub`] at rows `i0..`, columns `j0..`.
struct Tile<'a> {
    out: &'a mut [f64],
    ld: usize,
    a: &'a [f64],
    lda: usize,
    w: &'a [f64],
    nc: usize,
    kd: usize,
    i0: usize,
    j0: usize,
}

impl Tile<'_> {
    #[inline(always)]
    fn run<const R: usize, const C: usize>(self) {
        let mut acc = [[0.0f64; R]; C];
        for (c, col) in acc.iter_mut().enumerate() {
            col.copy_from_slice(&self.out[(self.j0 + c) * self.ld + self.i0..][..R]);
        }
        let a = |k: usize| -> &[f64] { &self.a[k * self.lda + self.i0..][..R] };
        let w = |k: usize| -> &[f64] { &self.w[k * self.nc + self.j0..][..C] };
        // The operations of `lincomb_sub`, in its order: per group of four source columns one
        // subtraction of `(w₀a₀ + w₁a₁) + (w₂a₂ + w₃a₃)`, then one per remaining column.
        let groups = self.kd / 4 * 4;
        for k in (0..groups).step_by(4) {
            let (a0, a1, a2, a3) = (a(k), a(k + 1), a(k + 2), a(k + 3));
            let (w0, w1, w2, w3) = (w(k), w(k + 1), w(k + 2), w(k + 3));
            for c in 0..C {
                for r in 0..R {
                    acc[c][r] -= (w0[c] * a0[r] + w1[c] * a1[r]) + (w2[c] * a2[r] + w3[c] * a3[r]);
                }
            }
        }
        for k in groups..self.kd {
            let (ak, wk) = (a(k), w(k));
            for c in 0..C {
                for r in 0..R {
                    acc[c][r] -= wk[c] * ak[r];
                }
            }
        }
        for (c, col) in acc.iter().enumerate() {
            self.out[(self.j0 + c) * self.ld + self.i0..][..R].copy_from_slice(col);
        }
    }
}
