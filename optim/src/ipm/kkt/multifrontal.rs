//! Multifrontal LDLᵀ of the KKT matrix with threshold Bunch–Kaufman pivoting and delayed pivots
//! (Duff & Reid 1983; the 1 × 1 / 2 × 2 threshold test of MA57, Duff 2004): `Q K Qᵀ = L D Lᵀ`
//! with `D` block diagonal (1 × 1 and 2 × 2 blocks) and `Q` the fill-reducing order modified
//! at factorization time.
//!
//! * Symbolic ([`MultifrontalPlan::new`]): faer's AMD order and simplicial structure of `L`,
//!   the fundamental supernodes of that structure (as in the supernodal kernel), amalgamated
//!   with their parents while both have fewer than `nemin` columns (MA57's rule), and their
//!   assembly tree; each supernode's front holds its own columns and the rows of its
//!   structure.
//! * Numeric ([`MultifrontalPlan::factor`]): per supernode, children before parents, a dense
//!   front is assembled from the original entries of its columns, the contribution blocks of
//!   its children and the rows/columns its children could not eliminate (delayed pivots). Its
//!   fully summed columns (own and delayed) are eliminated with 1 × 1 pivots `a_jj` passing
//!   `|a_jj| ≥ u max_{i≠j} |a_ij|` or 2 × 2 pivots `B` on fully summed (j, r) passing
//!   `|B⁻¹| [γ_j; γ_r] ≤ [1/u; 1/u]` (γ the largest off-block entry of each column, over the
//!   whole front). What fails is passed to the parent front; in a root front everything is
//!   eliminated (Bunch–Kaufman partial pivoting with α = (1 + √17)/8 where the threshold test
//!   finds nothing, and static pivoting `±pivot_delta` for a pivot below `pivot_epsilon`).
//!   Every entry of `L` is thus bounded by `1/u` (threshold pivots) or by the Bunch–Kaufman
//!   growth bound, whatever δ_c: a constraint row with the pivot −δ_c and coupling entries of
//!   order one fails the test and waits until a variable of its own can form a 2 × 2 pivot
//!   with it, or until the variables already eliminated have made its pivot large; a pair
//!   whose variable carries a barrier term Σ ≫ 1 (`B⁻¹` holding Σ/(Σ δ_c + a²)) fails it as
//!   well.
//! * Inertia: signs of the 1 × 1 pivots plus, for each 2 × 2 block, (1, 1) when its determinant
//!   is negative and two of the sign of its diagonal otherwise (Sylvester's law of inertia).
//! * Solve ([`MultifrontalPlan::solve`]): forward substitution front by front with the stored
//!   panels of `L`, the block-diagonal `D⁻¹`, backward substitution in reverse, all in the
//!   original indexing (each front stores the original indices of its rows).

use faer::sparse::linalg::cholesky::SymbolicCholesky;

use super::Inertia;
use super::supernodal::{counted_pair, counted_pivot, simplicial_structure};

const NONE: usize = usize::MAX;

/// Bunch–Kaufman's α = (1 + √17)/8, minimising the element growth bound of partial pivoting.
const BK_ALPHA: f64 = 0.640_388_203_202_208_4;

/// Symbolic analysis, numeric factor and workspaces of the multifrontal LDLᵀ (module docs).
#[derive(Debug, Clone, Default)]
pub(super) struct MultifrontalPlan {
    /// `perm_fwd[i]`: original index of permuted index i (AMD order).
    perm_fwd: Vec<usize>,
    /// Columns of (amalgamated) supernode s, ascending permuted indices:
    /// `sn_cols[sn_col_ptr[s]..sn_col_ptr[s + 1]]`.
    sn_col_ptr: Vec<usize>,
    sn_cols: Vec<u32>,
    /// Rows of supernode s below its own columns (permuted indices, ascending):
    /// `sn_rows[sn_row_ptr[s]..sn_row_ptr[s + 1]]`.
    sn_row_ptr: Vec<usize>,
    sn_rows: Vec<u32>,
    /// Assembly tree: parent supernode (`NONE` for a root) and children lists.
    sn_parent: Vec<usize>,
    child_ptr: Vec<usize>,
    children: Vec<u32>,
    /// Original entries of the permuted lower triangle by supernode of their column:
    /// `(row, col, position in the caller's value array)`, permuted indices.
    a_ptr: Vec<usize>,
    a_ent: Vec<(u32, u32, u32)>,
    /// Threshold `u` of the pivot test (0 < u ≤ 0.5; smaller: fewer delays, more growth).
    pub(super) threshold: f64,
    // Numeric factor, per supernode s (valid after a successful `factor`):
    /// Original indices of the front rows after pivoting (eliminated ones first):
    /// `f_rows[f_row_ptr[s]..f_row_ptr[s + 1]]`.
    f_row_ptr: Vec<usize>,
    f_rows: Vec<u32>,
    /// Number of pivots eliminated in front s.
    f_nelim: Vec<usize>,
    /// Start of front s's column-major `nf × nelim` panel of `L` in `l_vals` (rows in the
    /// order of `f_rows`; column c holds `L` below its pivot from row c + 1 on).
    f_l_ptr: Vec<usize>,
    l_vals: Vec<f64>,
    /// The pivots of the last factorization, in elimination order.
    pub(super) piv: Pivots,
    /// Contribution block left by front s for its parent: rows (permuted indices; the first
    /// `cb_ndelay[s]` are its delayed, fully summed ones) and the column-major lower triangle.
    cb_rows: Vec<Vec<u32>>,
    cb_vals: Vec<Vec<f64>>,
    cb_ndelay: Vec<usize>,
    /// Pivots passed to a parent front in the last factorization (summed over fronts).
    pub(super) delayed: usize,
    // workspaces
    map: Vec<u32>,
    front: Vec<f64>,
    frows: Vec<u32>,
    w: Vec<f64>,
    x: Vec<f64>,
}

/// The block-diagonal `D` of a factorization, in elimination order, and its statistics.
#[derive(Debug, Clone, Default)]
pub(super) struct Pivots {
    /// 0 = 1 × 1, 1 = first and 2 = second column of a 2 × 2 block.
    kind: Vec<u8>,
    /// `[1/d, 0, 0]`, or at the first column of a 2 × 2 block its inverse `[i11, i12, i22]`.
    inv: Vec<[f64; 3]>,
    /// Diagonal of `D`, and at the first column of a 2 × 2 block its off-diagonal entry.
    pub(super) d: Vec<f64>,
    pub(super) e: Vec<f64>,
    /// Number of 2 × 2 blocks.
    pub(super) two_by_two: usize,
    /// Pivots replaced by `±pivot_delta` (static pivoting in a root front).
    pub(super) static_pivots: usize,
}

impl Pivots {
    fn clear(&mut self) {
        self.kind.clear();
        self.inv.clear();
        self.d.clear();
        self.e.clear();
        self.two_by_two = 0;
        self.static_pivots = 0;
    }

    fn push(&mut self, kind: u8, inv: [f64; 3], d: f64, e: f64) {
        self.kind.push(kind);
        self.inv.push(inv);
        self.d.push(d);
        self.e.push(e);
    }
}

/// A pivot chosen in a front: a 1 × 1 at position j, or a 2 × 2 on positions (j, r).
#[derive(Debug, Clone, Copy)]
enum Choice {
    One(usize),
    Two(usize, usize),
}

impl MultifrontalPlan {
    /// Builds the supernodes, assembly tree and entry lists from faer's simplicial symbolic
    /// analysis of the lower-triangle pattern (`None` for a supernodal analysis or oversized
    /// indices).
    pub(super) fn new(
        sym: &SymbolicCholesky<usize>,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        threshold: f64,
        nemin: usize,
    ) -> Option<Self> {
        let (fwd, inv, lp, lr) = simplicial_structure(sym)?;
        if dim == 0 || dim >= u32::MAX as usize || row_idx.len() >= u32::MAX as usize {
            return None;
        }
        let cnt = |j: usize| lp[j + 1] - lp[j];
        // Fundamental supernodes: column j continues j − 1's when parent(j − 1) = j and
        // |L_{j−1}| = |L_j| + 1 (nested structures, no explicit zeros in the front).
        let mut sn_begin = vec![0usize];
        for j in 0..dim - 1 {
            let chained = cnt(j) > 1 && lr[lp[j] + 1] == j + 1 && cnt(j) == cnt(j + 1) + 1;
            if !chained {
                sn_begin.push(j + 1);
            }
        }
        sn_begin.push(dim);
        let nfund = sn_begin.len() - 1;
        let mut fund_of = vec![0usize; dim];
        let mut fund_parent = vec![NONE; nfund];
        for sn in 0..nfund {
            let (f, l) = (sn_begin[sn], sn_begin[sn + 1]);
            fund_of[f..l].iter_mut().for_each(|c| *c = sn);
        }
        for sn in 0..nfund {
            let l = sn_begin[sn + 1];
            if cnt(l - 1) > 1 {
                fund_parent[sn] = fund_of[lr[lp[l - 1] + 1]];
            }
        }
        // Amalgamation (MA57's rule): a supernode and its parent are merged while both have
        // fewer than `nemin` columns. The merged front is the parent's (a child's rows lie in
        // its parent's columns and rows), with the child's columns as further fully summed
        // ones: explicit zeros, but larger dense blocks and more candidates for 2 × 2 pivots.
        let mut rep: Vec<usize> = (0..nfund).collect();
        let mut ncols: Vec<usize> = (0..nfund).map(|s| sn_begin[s + 1] - sn_begin[s]).collect();
        for sn in 0..nfund {
            let p = fund_parent[sn];
            if p != NONE && ncols[sn] < nemin && ncols[p] < nemin {
                ncols[p] += ncols[sn];
                rep[sn] = p;
            }
        }
        // Representatives: follow merges upwards (parents have larger indices).
        for sn in (0..nfund).rev() {
            let p = rep[sn];
            if p != sn {
                rep[sn] = rep[p];
            }
        }
        let mut new_id = vec![NONE; nfund];
        let mut ns = 0;
        for sn in 0..nfund {
            if rep[sn] == sn {
                new_id[sn] = ns;
                ns += 1;
            }
        }
        let mut col2sn = vec![0usize; dim];
        for (j, c) in col2sn.iter_mut().enumerate() {
            *c = new_id[rep[fund_of[j]]];
        }
        let mut sn_col_ptr = vec![0usize; ns + 1];
        for &c in &col2sn {
            sn_col_ptr[c + 1] += 1;
        }
        for sn in 0..ns {
            sn_col_ptr[sn + 1] += sn_col_ptr[sn];
        }
        let mut sn_cols = vec![0u32; dim];
        let mut next = sn_col_ptr.clone();
        for (j, &c) in col2sn.iter().enumerate() {
            sn_cols[next[c]] = j as u32;
            next[c] += 1;
        }
        let mut sn_row_ptr = vec![0usize];
        let mut sn_rows = Vec::new();
        let mut sn_parent = vec![NONE; ns];
        for sn in 0..nfund {
            if rep[sn] != sn {
                continue;
            }
            let l = sn_begin[sn + 1];
            sn_rows.extend(lr[lp[l - 1] + 1..lp[l]].iter().map(|&r| r as u32));
            sn_row_ptr.push(sn_rows.len());
            if fund_parent[sn] != NONE {
                sn_parent[new_id[sn]] = new_id[rep[fund_parent[sn]]];
            }
        }
        let mut child_ptr = vec![0usize; ns + 1];
        for &p in &sn_parent {
            if p != NONE {
                child_ptr[p + 1] += 1;
            }
        }
        for sn in 0..ns {
            child_ptr[sn + 1] += child_ptr[sn];
        }
        let mut next = child_ptr.clone();
        let mut children = vec![0u32; child_ptr[ns]];
        for (sn, &p) in sn_parent.iter().enumerate() {
            if p != NONE {
                children[next[p]] = sn as u32;
                next[p] += 1;
            }
        }
        // Original entries by the supernode of their (permuted) column.
        let mut a_ptr = vec![0usize; ns + 1];
        let mut ent = Vec::with_capacity(row_idx.len());
        for j in 0..dim {
            for (p, &i) in row_idx
                .iter()
                .enumerate()
                .take(col_ptr[j + 1])
                .skip(col_ptr[j])
            {
                let (pi, pj) = (inv[i], inv[j]);
                let (r, c) = if pi >= pj { (pi, pj) } else { (pj, pi) };
                let sn = col2sn[c];
                a_ptr[sn + 1] += 1;
                ent.push((sn, (r as u32, c as u32, p as u32)));
            }
        }
        for sn in 0..ns {
            a_ptr[sn + 1] += a_ptr[sn];
        }
        let mut a_ent = vec![(0u32, 0u32, 0u32); ent.len()];
        let mut next = a_ptr.clone();
        for (sn, e) in ent {
            a_ent[next[sn]] = e;
            next[sn] += 1;
        }
        Some(Self {
            perm_fwd: fwd.to_vec(),
            sn_col_ptr,
            sn_cols,
            sn_row_ptr,
            sn_rows,
            sn_parent,
            child_ptr,
            children,
            a_ptr,
            a_ent,
            threshold,
            f_row_ptr: vec![0; ns + 1],
            f_rows: Vec::new(),
            f_nelim: vec![0; ns],
            f_l_ptr: vec![0; ns + 1],
            l_vals: Vec::new(),
            piv: Pivots::default(),
            cb_rows: vec![Vec::new(); ns],
            cb_vals: vec![Vec::new(); ns],
            cb_ndelay: vec![0; ns],
            delayed: 0,
            map: vec![0; dim],
            front: Vec::new(),
            frows: Vec::new(),
            w: Vec::new(),
            x: vec![0.0; dim],
        })
    }

    /// Number of supernodes (fronts).
    pub(super) fn n_fronts(&self) -> usize {
        self.sn_col_ptr.len() - 1
    }

    /// Stored entries of `L` below the diagonal in the last factorization.
    pub(super) fn factor_nnz(&self) -> usize {
        (0..self.n_fronts())
            .map(|s| {
                let nf = self.f_row_ptr[s + 1] - self.f_row_ptr[s];
                let k = self.f_nelim[s];
                (0..k).map(|c| nf - c - 1).sum::<usize>()
            })
            .sum()
    }

    /// `Σ_c (n_c + n_c²/2)` over the eliminated columns c with `n_c` entries of `L` below
    /// the pivot, in the last factorization.
    pub(super) fn factor_flops(&self) -> f64 {
        let mut flops = 0.0;
        for s in 0..self.n_fronts() {
            let nf = self.f_row_ptr[s + 1] - self.f_row_ptr[s];
            for c in 0..self.f_nelim[s] {
                let n = (nf - c) as f64;
                flops += n + 0.5 * n * n;
            }
        }
        flops
    }

    /// The last factorization as dense matrices for tests: the elimination order `q` (original
    /// indices), `L` (unit lower triangular in that order) and the block-diagonal `D`.
    #[cfg(test)]
    pub(super) fn dense_factor(&self) -> (Vec<usize>, Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let dim = self.perm_fwd.len();
        let mut q = Vec::with_capacity(dim);
        let mut pos = vec![0usize; dim];
        for s in 0..self.n_fronts() {
            let rows = &self.f_rows[self.f_row_ptr[s]..self.f_row_ptr[s + 1]];
            for &r in &rows[..self.f_nelim[s]] {
                pos[r as usize] = q.len();
                q.push(r as usize);
            }
        }
        let mut l = vec![vec![0.0; dim]; dim];
        let mut d = vec![vec![0.0; dim]; dim];
        let mut g = 0;
        for s in 0..self.n_fronts() {
            let rows = &self.f_rows[self.f_row_ptr[s]..self.f_row_ptr[s + 1]];
            let nf = rows.len();
            let panel = &self.l_vals[self.f_l_ptr[s]..self.f_l_ptr[s + 1]];
            for c in 0..self.f_nelim[s] {
                let k = pos[rows[c] as usize];
                l[k][k] = 1.0;
                for i in c + 1..nf {
                    l[pos[rows[i] as usize]][k] = panel[c * nf + i];
                }
                d[k][k] = self.piv.d[g];
                if self.piv.kind[g] == 1 {
                    d[k + 1][k] = self.piv.e[g];
                    d[k][k + 1] = self.piv.e[g];
                }
                g += 1;
            }
        }
        (q, l, d)
    }

    /// Numeric factorization of the matrix with these values (the caller's lower-triangle
    /// array); pivots below `eps` in a root front become `±delta` when `delta > 0`. Returns the
    /// inertia, or `None` on a zero or non-finite pivot.
    pub(super) fn factor(&mut self, values: &[f64], eps: f64, delta: f64) -> Option<Inertia> {
        let (eps, delta) = (eps.abs(), delta.abs());
        let u = self.threshold;
        let ns = self.n_fronts();
        let mut inertia = Inertia::default();
        self.f_rows.clear();
        self.l_vals.clear();
        self.piv.clear();
        self.delayed = 0;
        for s in 0..ns {
            // Front rows: children's delayed rows, own columns (fully summed), then the rows
            // of the supernode's structure.
            let mut frows = std::mem::take(&mut self.frows);
            frows.clear();
            for &c in &self.children[self.child_ptr[s]..self.child_ptr[s + 1]] {
                let c = c as usize;
                frows.extend_from_slice(&self.cb_rows[c][..self.cb_ndelay[c]]);
            }
            frows.extend_from_slice(&self.sn_cols[self.sn_col_ptr[s]..self.sn_col_ptr[s + 1]]);
            let nfs = frows.len();
            frows.extend_from_slice(&self.sn_rows[self.sn_row_ptr[s]..self.sn_row_ptr[s + 1]]);
            let nf = frows.len();
            for (p, &r) in frows.iter().enumerate() {
                self.map[r as usize] = p as u32;
            }
            // Only the lower triangle is ever read (the strict upper one of the stored panel
            // columns included in the solve's slices is skipped).
            let mut front = std::mem::take(&mut self.front);
            if front.len() < nf * nf {
                front.resize(nf * nf, 0.0);
            }
            for j in 0..nf {
                front[j * nf + j..(j + 1) * nf].fill(0.0);
            }
            for &(r, c, src) in &self.a_ent[self.a_ptr[s]..self.a_ptr[s + 1]] {
                let (pr, pc) = (self.map[r as usize] as usize, self.map[c as usize] as usize);
                let (i, j) = if pr >= pc { (pr, pc) } else { (pc, pr) };
                front[j * nf + i] += values[src as usize];
            }
            // Extend-add of the children's contribution blocks.
            for &c in &self.children[self.child_ptr[s]..self.child_ptr[s + 1]] {
                let c = c as usize;
                let rows = std::mem::take(&mut self.cb_rows[c]);
                let vals = std::mem::take(&mut self.cb_vals[c]);
                let n = rows.len();
                for jj in 0..n {
                    let pj = self.map[rows[jj] as usize] as usize;
                    let col = &vals[jj * n..(jj + 1) * n];
                    for ii in jj..n {
                        let pi = self.map[rows[ii] as usize] as usize;
                        let (i, j) = if pi >= pj { (pi, pj) } else { (pj, pi) };
                        front[j * nf + i] += col[ii];
                    }
                }
                self.cb_rows[c] = rows;
                self.cb_vals[c] = vals;
                self.cb_rows[c].clear();
            }
            let root = self.sn_parent[s] == NONE;
            // Every entry of `w` that is read was written by its pivot first.
            if self.w.len() < nf * nfs {
                self.w.resize(nf * nfs, 0.0);
            }
            let k = eliminate(
                &mut front[..nf * nf],
                &mut self.w[..nf * nfs],
                nf,
                nfs,
                &mut frows,
                root,
                u,
                eps,
                delta,
                &mut self.piv,
                &mut inertia,
            )?;
            self.delayed += nfs - k;
            // Store the front's rows (original indices) and panel of L.
            self.f_row_ptr[s] = self.f_rows.len();
            self.f_rows
                .extend(frows.iter().map(|&r| self.perm_fwd[r as usize] as u32));
            self.f_row_ptr[s + 1] = self.f_rows.len();
            self.f_nelim[s] = k;
            self.f_l_ptr[s] = self.l_vals.len();
            self.l_vals.extend_from_slice(&front[..k * nf]);
            self.f_l_ptr[s + 1] = self.l_vals.len();
            // Contribution block: the Schur complement on the rows not eliminated.
            let ncb = nf - k;
            let cbv = &mut self.cb_vals[s];
            cbv.clear();
            cbv.resize(ncb * ncb, 0.0);
            for j in 0..ncb {
                cbv[j * ncb + j..(j + 1) * ncb]
                    .copy_from_slice(&front[(k + j) * nf + k + j..(k + j + 1) * nf]);
            }
            self.cb_rows[s].clear();
            self.cb_rows[s].extend_from_slice(&frows[k..]);
            self.cb_ndelay[s] = nfs - k;
            self.front = front;
            self.frows = frows;
        }
        Some(inertia)
    }

    /// Solves `K x = rhs` in place with the last factorization.
    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let ns = self.n_fronts();
        let x = &mut self.x;
        x.copy_from_slice(rhs);
        for s in 0..ns {
            let rows = &self.f_rows[self.f_row_ptr[s]..self.f_row_ptr[s + 1]];
            let nf = rows.len();
            let panel = &self.l_vals[self.f_l_ptr[s]..self.f_l_ptr[s + 1]];
            for c in 0..self.f_nelim[s] {
                let xc = x[rows[c] as usize];
                if xc != 0.0 {
                    for (&r, &l) in rows[c + 1..]
                        .iter()
                        .zip(&panel[c * nf + c + 1..(c + 1) * nf])
                    {
                        x[r as usize] -= l * xc;
                    }
                }
            }
        }
        let mut g = 0;
        for s in 0..ns {
            let rows = &self.f_rows[self.f_row_ptr[s]..self.f_row_ptr[s + 1]];
            let mut c = 0;
            while c < self.f_nelim[s] {
                let inv = self.piv.inv[g];
                if self.piv.kind[g] == 1 {
                    let (a, b) = (rows[c] as usize, rows[c + 1] as usize);
                    let (xa, xb) = (x[a], x[b]);
                    x[a] = inv[0] * xa + inv[1] * xb;
                    x[b] = inv[1] * xa + inv[2] * xb;
                    c += 2;
                    g += 2;
                } else {
                    x[rows[c] as usize] *= inv[0];
                    c += 1;
                    g += 1;
                }
            }
        }
        for s in (0..ns).rev() {
            let rows = &self.f_rows[self.f_row_ptr[s]..self.f_row_ptr[s + 1]];
            let nf = rows.len();
            let panel = &self.l_vals[self.f_l_ptr[s]..self.f_l_ptr[s + 1]];
            for c in (0..self.f_nelim[s]).rev() {
                let mut acc = 0.0;
                for (&r, &l) in rows[c + 1..]
                    .iter()
                    .zip(&panel[c * nf + c + 1..(c + 1) * nf])
                {
                    acc += l * x[r as usize];
                }
                x[rows[c] as usize] -= acc;
            }
        }
        rhs.copy_from_slice(x);
    }
}

/// `|F[i, j]|` of the symmetric front stored as a column-major lower triangle.
#[inline(always)]
fn at(f: &[f64], nf: usize, i: usize, j: usize) -> f64 {
    if i >= j { f[j * nf + i] } else { f[i * nf + j] }
}

/// Largest `|F[i, j]|` over the uneliminated rows `i ≥ k`, `i ∉ {j, skip}`, and the fully
/// summed row `i < nfs` (other than j and skip) where it is largest.
fn col_max(f: &[f64], nf: usize, nfs: usize, k: usize, j: usize, skip: usize) -> (f64, usize) {
    let (mut g, mut best, mut arg) = (0.0f64, 0.0f64, NONE);
    for i in k..j {
        if i != skip {
            let v = f[i * nf + j].abs();
            g = g.max(v);
            if v > best {
                best = v;
                arg = i;
            }
        }
    }
    let col = &f[j * nf..(j + 1) * nf];
    for (i, &v) in col.iter().enumerate().skip(j + 1) {
        if i != skip {
            let v = v.abs();
            g = g.max(v);
            if i < nfs && v > best {
                best = v;
                arg = i;
            }
        }
    }
    (g, arg)
}

/// Symmetric interchange of positions p < q of the front (lower-triangle storage), the rows of
/// the already eliminated columns included.
fn swap_sym(f: &mut [f64], nf: usize, rows: &mut [u32], p: usize, q: usize) {
    if p == q {
        return;
    }
    let (p, q) = (p.min(q), p.max(q));
    rows.swap(p, q);
    for j in 0..p {
        f.swap(j * nf + p, j * nf + q);
    }
    f.swap(p * nf + p, q * nf + q);
    for j in p + 1..q {
        f.swap(p * nf + j, j * nf + q);
    }
    for i in q + 1..nf {
        f.swap(p * nf + i, q * nf + i);
    }
}

/// The threshold test on the fully summed columns `k..nfs`: the first candidate j that passes
/// as a 1 × 1 pivot, or whose largest fully summed partner r passes as a 1 × 1 or forms a 2 × 2
/// pivot with it that passes (module docs). `None` if none does.
fn threshold_search(
    f: &[f64],
    nf: usize,
    nfs: usize,
    k: usize,
    u: f64,
    eps: f64,
) -> Option<Choice> {
    for j in k..nfs {
        let ajj = f[j * nf + j];
        let (gj, r) = col_max(f, nf, nfs, k, j, NONE);
        if ajj.abs() > eps && ajj.abs() >= u * gj {
            return Some(Choice::One(j));
        }
        if r == NONE {
            continue;
        }
        let arr = f[r * nf + r];
        let (gr, _) = col_max(f, nf, nfs, k, r, NONE);
        if arr.abs() > eps && arr.abs() >= u * gr {
            return Some(Choice::One(r));
        }
        let ajr = at(f, nf, j, r);
        let det = ajj * arr - ajr * ajr;
        if det == 0.0 || !det.is_finite() || det.abs() <= eps * eps {
            continue;
        }
        let (gj2, _) = col_max(f, nf, nfs, k, j, r);
        let (gr2, _) = col_max(f, nf, nfs, k, r, j);
        let lim = det.abs() / u;
        if arr.abs() * gj2 + ajr.abs() * gr2 <= lim && ajr.abs() * gj2 + ajj.abs() * gr2 <= lim {
            return Some(Choice::Two(j, r));
        }
    }
    None
}

/// Bunch–Kaufman partial pivoting on column k (root fronts, where every row is fully summed
/// and the threshold test found nothing): always a pivot with bounded growth, or a zero column.
fn bunch_kaufman(f: &[f64], nf: usize, k: usize) -> Choice {
    let akk = f[k * nf + k].abs();
    let (g1, r) = col_max(f, nf, nf, k, k, NONE);
    if g1 == 0.0 || akk >= BK_ALPHA * g1 {
        return Choice::One(k);
    }
    let (gr, _) = col_max(f, nf, nf, k, r, NONE);
    if akk * gr >= BK_ALPHA * g1 * g1 {
        Choice::One(k)
    } else if f[r * nf + r].abs() >= BK_ALPHA * gr {
        Choice::One(r)
    } else {
        Choice::Two(k, r)
    }
}

/// Eliminates the fully summed columns `0..nfs` of the dense front `f` (`nf × nf`,
/// column-major lower triangle, rows `rows`) as far as the threshold test allows (all of them
/// in a `root` front), with 1 × 1 / 2 × 2 pivots brought to the leading positions by symmetric
/// interchanges; then applies the eliminated pivots to the trailing block `nfs..nf` once
/// (`w` holds `L D`, `nf × nfs`). Returns the number of eliminated columns, or `None` on a
/// zero or non-finite pivot.
#[allow(clippy::too_many_arguments)]
fn eliminate(
    f: &mut [f64],
    w: &mut [f64],
    nf: usize,
    nfs: usize,
    rows: &mut [u32],
    root: bool,
    u: f64,
    eps: f64,
    delta: f64,
    piv: &mut Pivots,
    inertia: &mut Inertia,
) -> Option<usize> {
    let mut k = 0;
    while k < nfs {
        let choice = match threshold_search(f, nf, nfs, k, u, eps) {
            Some(c) => c,
            None if root => bunch_kaufman(f, nf, k),
            None => break,
        };
        match choice {
            Choice::One(j) => {
                swap_sym(f, nf, rows, k, j);
                let (d, replaced) = counted_pivot(f[k * nf + k], delta, eps, inertia)?;
                piv.static_pivots += usize::from(replaced);
                f[k * nf + k] = d;
                let inv = d.recip();
                let (head, tail) = f.split_at_mut((k + 1) * nf);
                let lk = &mut head[k * nf..];
                let wk = &mut w[k * nf..(k + 1) * nf];
                wk[k + 1..].copy_from_slice(&lk[k + 1..]);
                lk[k + 1..].iter_mut().for_each(|v| *v *= inv);
                // Rank-1 update of the remaining fully summed columns (all their rows).
                for j in k + 1..nfs {
                    let wj = wk[j];
                    if wj != 0.0 {
                        let col = &mut tail[(j - k - 1) * nf + j..(j - k) * nf];
                        for (x, &l) in col.iter_mut().zip(&lk[j..nf]) {
                            *x -= l * wj;
                        }
                    }
                }
                piv.push(0, [inv, 0.0, 0.0], d, 0.0);
                k += 1;
            }
            Choice::Two(j, r) => {
                // Bring j to k and r to k + 1 (r may sit at k, then j's old place).
                swap_sym(f, nf, rows, k, j);
                let r = if r == k { j } else { r };
                swap_sym(f, nf, rows, k + 1, r);
                let (a, b, c) = (f[k * nf + k], f[k * nf + k + 1], f[(k + 1) * nf + k + 1]);
                let det = counted_pair(a, b, c, inertia)?;
                let (i11, i12, i22) = (c / det, -b / det, a / det);
                let (head, tail) = f.split_at_mut((k + 2) * nf);
                let (c0, c1) = head[k * nf..].split_at_mut(nf);
                let (w0, w1) = w[k * nf..(k + 2) * nf].split_at_mut(nf);
                for i in k + 2..nf {
                    let (p, q) = (c0[i], c1[i]);
                    w0[i] = p;
                    w1[i] = q;
                    c0[i] = p * i11 + q * i12;
                    c1[i] = p * i12 + q * i22;
                }
                c0[k + 1] = 0.0;
                for jj in k + 2..nfs {
                    let (wa, wb) = (w0[jj], w1[jj]);
                    if wa != 0.0 || wb != 0.0 {
                        let col = &mut tail[(jj - k - 2) * nf + jj..(jj - k - 1) * nf];
                        for ((x, &la), &lb) in col.iter_mut().zip(&c0[jj..nf]).zip(&c1[jj..nf]) {
                            *x -= la * wa + lb * wb;
                        }
                    }
                }
                piv.two_by_two += 1;
                piv.push(1, [i11, i12, i22], a, b);
                piv.push(2, [0.0; 3], c, 0.0);
                k += 2;
            }
        }
    }
    // Deferred update of the trailing (not fully summed) block by all pivots of this front.
    if k > 0 {
        let (head, tail) = f.split_at_mut(nfs * nf);
        for j in nfs..nf {
            let col = &mut tail[(j - nfs) * nf + j..(j - nfs + 1) * nf];
            let lcol = |c: usize| &head[c * nf + j..(c + 1) * nf];
            // Four pivots per pass over the target column (one load and store of it per four
            // multiply-adds).
            let mut c = 0;
            while c + 4 <= k {
                let wv = [
                    w[c * nf + j],
                    w[(c + 1) * nf + j],
                    w[(c + 2) * nf + j],
                    w[(c + 3) * nf + j],
                ];
                let (l0, l1, l2, l3) = (lcol(c), lcol(c + 1), lcol(c + 2), lcol(c + 3));
                for (i, x) in col.iter_mut().enumerate() {
                    *x -= (l0[i] * wv[0] + l1[i] * wv[1]) + (l2[i] * wv[2] + l3[i] * wv[3]);
                }
                c += 4;
            }
            for c in c..k {
                let wj = w[c * nf + j];
                if wj != 0.0 {
                    for (x, &l) in col.iter_mut().zip(lcol(c)) {
                        *x -= l * wj;
                    }
                }
            }
        }
    }
    Some(k)
}
