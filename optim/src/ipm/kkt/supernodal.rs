//! Supernodal left-looking LDLᵀ of the permuted KKT matrix `P K Pᵀ = L D Lᵀ` on the
//! fundamental supernodes of faer's simplicial structure ([`BlockPlan`]): same ordering, same
//! `L` pattern (no relaxation zeros) and the same pivot rule as the simplicial backend, with
//! dense column-major blocks per supernode so that the updates are dense column operations.
//! Its rounding differs from the simplicial backend's; it is tested by reconstructing
//! `P K Pᵀ` from `L D Lᵀ` and against dense eigenvalue inertia. Where a descendant's rows
//! land in its target's block is computed once per pattern ([`BlockPlan::upd_rel`]), so a
//! scattered update reads one index per entry (decision record 0092). A descendant updates
//! several target columns at once (decision record 0093): a one-column descendant four
//! ([`rank1_scatter`]: each row's relative row and value read once for the four), a wider one
//! and a panel's finished columns two ([`lincomb_sub_stair`]: each chunk of source columns
//! read once for both sums), and two 1 × 1 pivots in a row of a block's own columns share
//! their sums' common chunks ([`factor_panel`]). Every entry still receives its column's
//! operations in their order, so the factor is the same bit for bit.
//!
//! Shared factorization (decision record 0090): the analysis marks the supernodes with work
//! enough for two threads ([`MIN_PARALLEL_WORK`]; on Legendre–Gauss KKTs the phases' dense
//! blocks). Their descendant updates are divided by target columns (balanced by multiply–adds
//! and the scatter's pass over each target column's rows, record 0091),
//! and their own columns are factored in panels of [`PANEL`] columns with look-ahead: while
//! the calling thread updates and factors the next panel, the helper thread subtracts the
//! finished panels from the later columns. Every entry receives the same operations in the
//! same order as in one left-looking pass (descendants in list order, then the block's own
//! columns in chunks of four from column 0), so the factor is the same bit for bit on one
//! thread or two.
//!
//! The small supernodes between the shared ones (decision record 0091): in each stretch of
//! them the analysis finds two consecutive ranges, the second depending on nothing in the
//! first ([`split_stretch`], balanced by an estimate of their time, [`SMALL_COSTS`]), and the
//! two threads factor one range each ([`BlockPlan::pairs`]), each on its own slices of the
//! arrays and reading the supernodes finished before the stretch. A supernode's operations do
//! not depend on which thread runs them, so this too gives the same bits. Each block is filled
//! with the matrix's entries just before it is factored, by the thread that factors it.
//!
//! The helper is the one worker of a pool of its own, woken once per factorization a little
//! ahead of the first shared work (a wake-up costs some 60 µs on a virtual machine) and
//! spinning between the halves it is handed until the last shared work is done. One
//! factorization at a time has the helper; a factorization on another thread meanwhile runs
//! alone.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

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
    /// Where update k's rows `rows_d[p1..]` land in its target's block (positions among the
    /// target's rows): `upd_rel[upd_rel_ptr[k]..upd_rel_ptr[k + 1]]`, so that the scatter
    /// reads one index per entry instead of the row and then a row map filled per target.
    pub(super) upd_rel_ptr: Vec<usize>,
    pub(super) upd_rel: Vec<u32>,
    /// The entries of the caller's lower-triangle value array in supernode s's block:
    /// `a_map[a_ptr[s]..a_ptr[s + 1]]` = (index in the value array, position in the block),
    /// by position. A block is filled from them just before it is factored, while it is
    /// about to be in cache anyway, by whichever thread factors it.
    pub(super) a_ptr: Vec<usize>,
    pub(super) a_map: Vec<(u32, u32)>,
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
    /// Per column of `L`, how many of its rows below the diagonal come first as one run of
    /// consecutive rows (its supernode's own columns, and the whole column near the root):
    /// the solves treat them as a slice of `x`.
    pub(super) l_head: Vec<u32>,
    /// First target column of supernode s's second half of the descendant updates when two
    /// threads share them (balanced by multiply–adds and the scatter's rows), 0 where they are
    /// not shared.
    pub(super) sn_split: Vec<u32>,
    /// Whether supernode s's own columns are factored in panels whose updates two threads
    /// share.
    pub(super) sn_panels: Vec<bool>,
    /// Whether any supernode is shared between two threads ([`BlockPlan::pairs`] exist only
    /// then).
    pub(super) parallel_work: bool,
    /// The supernode before which the second thread is put on watch: about
    /// [`WAKE_AHEAD_WORK`] of factoring before the first shared supernode, or the first
    /// pair's first supernode if that comes earlier (0 for a pair at the start).
    pub(super) wake_at: usize,
    /// Where the helper's watch ends: after the last shared supernode or the last pair's
    /// second range, whichever comes later.
    pub(super) after_shared: usize,
    /// Pairs of consecutive ranges of supernodes that two threads factor at once, in order:
    /// `(s, x, y)` = `s..x` and `x..y`, no supernode of the second depending on one of the
    /// first; each within a stretch between shared supernodes ([`split_stretch`]).
    pub(super) pairs: Vec<(usize, usize, usize)>,
    /// Pairs factored on two threads so far (for the tests: that a shared factorization
    /// took the pairs' path).
    #[cfg(test)]
    pub(super) pairs_run: usize,
    /// The workspaces of the calling thread and of the helper.
    pub(super) work: Work,
    pub(super) work2: Work,
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
        // Where each update's rows land in its target's block, once per pattern rather than
        // through a row map in every factorization.
        let mut upd_rel_ptr = Vec::with_capacity(upd.len() + 1);
        let mut upd_rel = Vec::new();
        upd_rel_ptr.push(0);
        let mut map = vec![0u32; dim];
        for sn in 0..ns {
            for (pos, &r) in sn_rows[sn_row_ptr[sn]..sn_row_ptr[sn + 1]]
                .iter()
                .enumerate()
            {
                map[r as usize] = pos as u32;
            }
            for &(d, p1, _) in &upd[upd_ptr[sn]..upd_ptr[sn + 1]] {
                let rd = &sn_rows[sn_row_ptr[d as usize]..sn_row_ptr[d as usize + 1]];
                upd_rel.extend(rd[p1 as usize..].iter().map(|&r| map[r as usize]));
                upd_rel_ptr.push(upd_rel.len());
            }
        }
        // Work per target column, to divide a large supernode's updates between two threads,
        // and the work of its own columns' LDLᵀ.
        let mut sn_split = vec![0u32; ns];
        let mut sn_panels = vec![false; ns];
        let mut sn_work = vec![0.0f64; ns];
        for sn in 0..ns {
            let (f, w) = (sn_begin[sn], sn_begin[sn + 1] - sn_begin[sn]);
            let nr = sn_row_ptr[sn + 1] - sn_row_ptr[sn];
            let own: f64 = (0..w).map(|t| (t * (nr - t)) as f64).sum();
            sn_panels[sn] = w >= 2 * PANEL && own >= MIN_PARALLEL_WORK;
            let mut col_work = vec![0.0f64; w];
            for &(dd, p1, p2) in &upd[upd_ptr[sn]..upd_ptr[sn + 1]] {
                let dd = dd as usize;
                let wd = sn_begin[dd + 1] - sn_begin[dd];
                let rd = &sn_rows[sn_row_ptr[dd]..sn_row_ptr[dd + 1]];
                // A target column's update: `wd` multiply–adds per row, and one pass over
                // its rows to subtract them (the scatter), which costs about as much as a
                // multiply–add (decision record 0091).
                for q in p1 as usize..p2 as usize {
                    col_work[rd[q] as usize - f] += ((rd.len() - q) * (wd + 1)) as f64;
                }
            }
            let total: f64 = col_work.iter().sum();
            sn_work[sn] = own + total;
            if total >= MIN_PARALLEL_WORK {
                let mut acc = 0.0;
                for (c, &cw) in col_work.iter().enumerate() {
                    acc += cw;
                    if 2.0 * acc >= total {
                        if c + 1 < w {
                            sn_split[sn] = (c + 1) as u32;
                        }
                        break;
                    }
                }
            }
        }
        let shared = |sn: &usize| sn_split[*sn] > 0 || sn_panels[*sn];
        let cost: Vec<f64> = (0..ns)
            .map(|sn| {
                let w = sn_begin[sn + 1] - sn_begin[sn];
                let nr = sn_row_ptr[sn + 1] - sn_row_ptr[sn];
                let updates = upd_ptr[sn + 1] - upd_ptr[sn];
                sn_work[sn]
                    + SMALL_COSTS[0] * updates as f64
                    + SMALL_COSTS[1] * w as f64
                    + SMALL_COSTS[2] * nr as f64
            })
            .collect();
        // The stretches of supernodes between the shared ones, each divided where it can be;
        // the first stretch's pair is where the helper is woken, so its second range starts
        // late by the wake-up. Only in plans with shared supernodes: a plan with pairs alone
        // would give up the speculative factorization (decision record 0036) for them, a
        // trade not measured.
        let parallel_work = (0..ns).any(|sn| shared(&sn));
        let mut pairs = Vec::new();
        if parallel_work {
            let mut s0 = 0;
            for s1 in (0..ns).filter(shared).chain([ns]) {
                let lead = if s0 == 0 { WAKE_LEAD } else { 0.0 };
                if let Some((x, y)) = split_stretch(&cost[s0..s1], s0, lead, &upd_ptr, &upd) {
                    pairs.push((s0, x, y));
                }
                s0 = s1 + 1;
            }
        }
        // The helper is on watch from a little before the first shared work to the end of
        // the last.
        let first_work = (0..ns)
            .find(shared)
            .into_iter()
            .chain(pairs.first().map(|p| p.0));
        let last_work = (0..ns).rev().find(shared).map(|sn| sn + 1);
        let after_shared = last_work
            .into_iter()
            .chain(pairs.last().map(|p| p.2))
            .max()
            .unwrap_or(ns);
        let mut wake_at = first_work.min().unwrap_or(ns);
        let mut ahead = 0.0;
        while wake_at > 0 && ahead < WAKE_AHEAD_WORK {
            wake_at -= 1;
            ahead += sn_work[wake_at];
        }
        let sn_pair = (0..ns)
            .map(|sn| pair[sn_begin[sn]..sn_begin[sn + 1]].iter().any(|&p| p))
            .collect();
        // `L` in column layout for the solves: column j of supernode s holds the block rows
        // from j down (diagonal slot first).
        let mut l_col_ptr = Vec::with_capacity(dim + 1);
        let mut l_row_idx = Vec::new();
        let mut l_head = Vec::with_capacity(dim);
        l_col_ptr.push(0);
        for sn in 0..ns {
            let rows = &sn_rows[sn_row_ptr[sn]..sn_row_ptr[sn + 1]];
            for c in 0..sn_begin[sn + 1] - sn_begin[sn] {
                l_row_idx.extend_from_slice(&rows[c..]);
                l_col_ptr.push(l_row_idx.len());
                let below = rows.get(c + 1..).unwrap_or(&[]);
                let run = below.windows(2).take_while(|p| p[1] == p[0] + 1).count();
                l_head.push((run + usize::from(!below.is_empty())) as u32);
            }
        }
        // Value map of the permuted lower triangle, per supernode in the order of its block
        // (a stable sort: of two values for one entry, the later wins, as in the caller's array).
        if row_idx.len() > u32::MAX as usize || sn_val_ptr[ns] > u32::MAX as usize {
            return None;
        }
        let mut a_entries: Vec<(u32, u32, u32)> = Vec::with_capacity(row_idx.len());
        for j in 0..dim {
            for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
                let (pi, pj) = (inv[i], inv[j]);
                let (r, c) = if pi >= pj { (pi, pj) } else { (pj, pi) };
                let sn = col2sn[c] as usize;
                let rows = &sn_rows[sn_row_ptr[sn]..sn_row_ptr[sn + 1]];
                let pos = rows.binary_search(&(r as u32)).ok()?;
                let at = (c - sn_begin[sn]) * rows.len() + pos;
                a_entries.push((sn as u32, at as u32, a_entries.len() as u32));
            }
        }
        a_entries.sort_by_key(|&(sn, at, _)| (sn, at));
        let mut a_ptr = vec![0usize; ns + 1];
        for &(sn, ..) in &a_entries {
            a_ptr[sn as usize + 1] += 1;
        }
        for sn in 0..ns {
            a_ptr[sn + 1] += a_ptr[sn];
        }
        let a_map = a_entries.iter().map(|&(_, at, v)| (v, at)).collect();
        let max_rows = (0..ns)
            .map(|sn| sn_row_ptr[sn + 1] - sn_row_ptr[sn])
            .max()
            .unwrap_or(0);
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
            upd_rel_ptr,
            upd_rel,
            a_ptr,
            a_map,
            d: vec![0.0; dim],
            inv_d: vec![0.0; dim],
            e: vec![0.0; dim],
            inv_e: vec![0.0; dim],
            pair,
            sn_pair,
            l: vec![0.0; l_col_ptr[dim]],
            l_col_ptr,
            l_row_idx,
            l_head,
            sn_split,
            sn_panels,
            parallel_work,
            wake_at,
            after_shared,
            pairs,
            #[cfg(test)]
            pairs_run: 0,
            work: Work::new(max_rows),
            work2: Work::new(max_rows),
            x: vec![0.0; dim],
        })
    }

    /// Whether the analysis found work to share between two threads (supernodes, and pairs
    /// of ranges between them), and the machine has a second core for it.
    pub(super) fn shares_work(&self) -> bool {
        self.parallel_work && factor_pool().is_some()
    }

    /// Numeric LDLᵀ; pivots with |d| ≤ `eps` become ±`delta` when `delta > 0`. Returns the
    /// inertia, or `None` on a zero or non-finite pivot. With `parallel`, the supernodes whose
    /// work the analysis divided ([`BlockPlan::sn_split`], [`BlockPlan::sn_panels`]) are
    /// shared with the worker of [`factor_pool`], each thread on its own columns, and the two
    /// ranges of each of [`BlockPlan::pairs`] are factored one on each thread: every entry
    /// receives the same operations in the same order as on one thread, so the factor is the
    /// same bit for bit either way.
    pub(super) fn factor(
        &mut self,
        values: &[f64],
        eps: f64,
        delta: f64,
        parallel: bool,
    ) -> Option<Inertia> {
        // One factorization at a time has the helper: another thread factoring meanwhile
        // (several solvers on threads of their own) factors alone, the same factor, rather
        // than queue its halves behind the first one's.
        let claim = (parallel && self.parallel_work)
            .then(factor_pool)
            .flatten()
            .and_then(|pool| HelperClaim::take().map(|claim| (pool, claim)));
        let Some((pool, _claim)) = claim else {
            return self.factor_with(values, eps, delta, None);
        };
        let helper = Helper {
            pool,
            stop: Arc::new(AtomicBool::new(false)),
        };
        self.factor_with(values, eps, delta, Some(&helper))
    }

    /// [`BlockPlan::factor`], sharing work with `helper`'s thread if given: the two ranges of
    /// each of [`BlockPlan::pairs`] factored at once, and the shared supernodes' halves.
    fn factor_with(
        &mut self,
        values: &[f64],
        eps: f64,
        delta: f64,
        helper: Option<&Helper>,
    ) -> Option<Inertia> {
        let (eps, delta) = (eps.abs(), delta.abs());
        let ns = self.sn_begin.len() - 1;
        let lay = Layout {
            sn_begin: &self.sn_begin,
            sn_rows: &self.sn_rows,
            sn_row_ptr: &self.sn_row_ptr,
            sn_val_ptr: &self.sn_val_ptr,
            upd_ptr: &self.upd_ptr,
            upd_rel_ptr: &self.upd_rel_ptr,
            upd_rel: &self.upd_rel,
            upd: &self.upd,
            pair: &self.pair,
            sn_pair: &self.sn_pair,
            sn_split: &self.sn_split,
            sn_panels: &self.sn_panels,
            l_col_ptr: &self.l_col_ptr,
            a_ptr: &self.a_ptr,
            a_map: &self.a_map,
            values,
            pivots: (eps, delta),
        };
        let mut inertia = Inertia::default();
        let mut pairs = self.pairs.iter().peekable();
        let mut sn = 0;
        while sn < ns {
            if sn == self.wake_at {
                helper.inspect(|h| h.wake());
            }
            if sn == self.after_shared {
                helper.inspect(|h| h.finish());
            }
            let pair = pairs.next_if(|p| p.0 == sn);
            if let Some((h, &(s, x, y))) = helper.zip(pair) {
                // Two independent ranges, each on its own slices of the arrays from its
                // first supernode on; both read the finished supernodes before `s`.
                let c = [self.sn_begin[s], self.sn_begin[x], self.sn_begin[y]];
                let v = [self.sn_val_ptr[s], self.sn_val_ptr[x], self.sn_val_ptr[y]];
                let lc = c.map(|c| self.l_col_ptr[c]);
                let (vals_0, vals_a, vals_b) = thirds(&mut self.vals, v);
                let (d_0, d_a, d_b) = thirds(&mut self.d, c);
                let (e_0, e_a, e_b) = thirds(&mut self.e, c);
                let (_, id_a, id_b) = thirds(&mut self.inv_d, c);
                let (_, ie_a, ie_b) = thirds(&mut self.inv_e, c);
                let (_, l_a, l_b) = thirds(&mut self.l, lc);
                let before = Finished {
                    vals: vals_0,
                    d: d_0,
                    e: e_0,
                };
                let parts_a = [vals_a, d_a, e_a, id_a, ie_a, l_a];
                let parts_b = [vals_b, d_b, e_b, id_b, ie_b, l_b];
                let at = |k: usize| (c[k], v[k], lc[k]);
                let mut a = Region::range(at(0), before, parts_a, &mut self.work);
                let mut b = Region::range(at(1), before, parts_b, &mut self.work2);
                let mut theirs = None;
                let mine = h.join(
                    || factor_range(&lay, &mut a, s..x),
                    || theirs = Some(factor_range(&lay, &mut b, x..y)),
                );
                let (mine, theirs) = (mine?, theirs.flatten()?);
                inertia.positive += mine.positive + theirs.positive;
                inertia.negative += mine.negative + theirs.negative;
                inertia.zero += mine.zero + theirs.zero;
                #[cfg(test)]
                {
                    self.pairs_run += 1;
                }
                sn = y;
                continue;
            }
            let arrays = [
                &mut self.vals[..],
                &mut self.d,
                &mut self.e,
                &mut self.inv_d,
                &mut self.inv_e,
                &mut self.l,
            ];
            let mut all = Region::range((0, 0, 0), Finished::default(), arrays, &mut self.work);
            all.second = Some(&mut self.work2);
            factor_supernode(&lay, &mut all, sn, helper, &mut inertia)?;
            sn += 1;
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
        let (lp, li, l, head) = (&self.l_col_ptr, &self.l_row_idx, &self.l, &self.l_head);
        for j in 0..n {
            let (a, b) = (lp[j] + 1, lp[j + 1]);
            let xj = x[j];
            let h = a + head[j] as usize;
            if h > a {
                axpy_scatter(x, &li[a..h], &l[a..h], xj);
            }
            axpy_scatter(x, &li[h..b], &l[h..b], xj);
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
                x[j] -= dot_gather4(&l[a..b], &li[a..b], head[j] as usize, x);
            }
        } else {
            for j in (0..n).rev() {
                let (a, b) = (lp[j] + 1, lp[j + 1]);
                x[j] = x[j] * self.inv_d[j] - dot_gather4(&l[a..b], &li[a..b], head[j] as usize, x);
            }
        }
        for i in 0..n {
            rhs[i] = x[self.perm_inv[i]];
        }
    }
}

/// `coef[i] = (D Lᵀ)[k, q]` for the columns k = a + i of a block whose `D` has 2 × 2 pivots
/// (`coef.len()` of them), where the columns before `lim` are finished: `L[q, k] d[k]`, plus
/// `L[q, k + 1] e[k]` where (k, k + 1) is a pair and k + 1 < `lim`, and `L[q, k − 1] e[k − 1]`
/// where (k − 1, k) is one (`L[q, k]` = `blk[k·stride + q]`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn dl_range(
    coef: &mut [f64],
    blk: &[f64],
    stride: usize,
    q: usize,
    d: &[f64],
    e: &[f64],
    pair: &[bool],
    a: usize,
    lim: usize,
) {
    for (i, cf) in coef.iter_mut().enumerate() {
        let k = a + i;
        let mut v = blk[k * stride + q] * d[k];
        if pair[k] && k + 1 < lim {
            v += blk[(k + 1) * stride + q] * e[k];
        }
        if k > 0 && pair[k - 1] {
            v += blk[(k - 1) * stride + q] * e[k - 1];
        }
        *cf = v;
    }
}

/// `out[i] -= Σ_k coef[k] · blk[k·stride + off + i]`: a dense multi-column update, four source
/// columns per pass over `out` (one load/store of `out` per four multiply-adds).
#[inline(always)]
pub(super) fn lincomb_sub(out: &mut [f64], blk: &[f64], stride: usize, off: usize, coef: &[f64]) {
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

/// [`lincomb_sub`] of `G` columns at once: `outs[j][i] -= Σ_k coefs[j][k] · blk[k·stride +
/// off + i]` (the `outs` of one length), each chunk of four source columns read once for the
/// `G` sums; every entry receives [`lincomb_sub`]'s operations in its order.
#[inline(always)]
fn lincomb_sub_tile<const G: usize>(
    outs: &mut [&mut [f64]; G],
    blk: &[f64],
    stride: usize,
    off: usize,
    coefs: [&[f64]; G],
) {
    let len = outs[0].len();
    let wd = coefs[0].len();
    let col = |k: usize| &blk[k * stride + off..k * stride + off + len];
    let mut k = 0;
    while k + 4 <= wd {
        let (v0, v1, v2, v3) = (col(k), col(k + 1), col(k + 2), col(k + 3));
        let c: [[f64; 4]; G] = std::array::from_fn(|j| {
            [
                coefs[j][k],
                coefs[j][k + 1],
                coefs[j][k + 2],
                coefs[j][k + 3],
            ]
        });
        for i in 0..len {
            let (a, b, cc, d) = (v0[i], v1[i], v2[i], v3[i]);
            for j in 0..G {
                outs[j][i] -= (c[j][0] * a + c[j][1] * b) + (c[j][2] * cc + c[j][3] * d);
            }
        }
        k += 4;
    }
    while k < wd {
        let v = col(k);
        let c: [f64; G] = std::array::from_fn(|j| coefs[j][k]);
        for i in 0..len {
            for j in 0..G {
                outs[j][i] -= c[j] * v[i];
            }
        }
        k += 1;
    }
}

/// `Σ vals[p] x[rows[p]]` with four partial sums (breaks the add latency chain): entry p
/// goes to sum p mod 4, the last `len mod 4` to a fifth. The first `head` rows are
/// consecutive ([`BlockPlan::l_head`]), so the chunks of four among them read a slice of `x`
/// instead of gathering: the same values in the same order, so the same bits.
#[inline(always)]
pub(super) fn dot_gather4(vals: &[f64], rows: &[u32], head: usize, x: &[f64]) -> f64 {
    let n4 = vals.len() - vals.len() % 4;
    let h4 = head.min(n4) / 4 * 4;
    let mut s = [0.0f64; 4];
    if h4 > 0 {
        let r0 = rows[0] as usize;
        for (v, y) in vals[..h4]
            .chunks_exact(4)
            .zip(x[r0..r0 + h4].chunks_exact(4))
        {
            s[0] += v[0] * y[0];
            s[1] += v[1] * y[1];
            s[2] += v[2] * y[2];
            s[3] += v[3] * y[3];
        }
    }
    for (v, r) in vals[h4..n4]
        .chunks_exact(4)
        .zip(rows[h4..n4].chunks_exact(4))
    {
        s[0] += v[0] * x[r[0] as usize];
        s[1] += v[1] * x[r[1] as usize];
        s[2] += v[2] * x[r[2] as usize];
        s[3] += v[3] * x[r[3] as usize];
    }
    let mut tail = 0.0;
    for (v, &r) in vals[n4..].iter().zip(&rows[n4..]) {
        tail += v * x[r as usize];
    }
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

/// Columns of a panel of a shared supernode's own LDLᵀ (a multiple of four, the lincomb's
/// chunk). Narrower panels leave less of the block to one thread, wider ones hand over
/// fewer times: 16 and 32 columns measured alike on the LG-30 KKT (decision record 0090),
/// and a supernode is factored in panels only from twice this width.
pub(super) const PANEL: usize = 16;

/// Target columns that a one-column descendant updates at once ([`rank1_scatter`]): 4 and 8
/// measured alike on the LG-30 KKT, 0.84 of the factor's time against one at a time
/// (decision record 0093).
const SCATTER_TILE: usize = 4;

/// Target columns that a wider descendant, or a panel's finished columns, update at once
/// ([`lincomb_sub_stair`]): with two, the sums' coefficients stay in the 16 registers of
/// baseline x86-64; four spilled them and measured slower (decision record 0093).
const LINCOMB_TILE: usize = 2;

/// Smallest work (multiply–adds) of a supernode's descendant updates, or of its own
/// columns' LDLᵀ, that the analysis splits between two threads: about 50 µs of factoring,
/// many times the cost of handing a half over to the other thread.
pub(super) const MIN_PARALLEL_WORK: f64 = 2e5;

/// What a supernode's factorization costs besides its multiply–adds, in multiply–adds: per
/// descendant update, per column and per row. Small supernodes cost mostly this: on the
/// LG-30 KKT the 2 092 supernodes before the shared ones took 0.74–0.80 ms for 7.2e5
/// multiply–adds, and a least-squares fit of their times (decision record 0091) gave 44 ns
/// per update, 83 ns per column and 0.9 ns per row against 0.33 ns per multiply–add.
/// [`BlockPlan::pairs`] balances its two ranges by this cost.
const SMALL_COSTS: [f64; 3] = [130.0, 250.0, 2.6];

/// How late, in [`SMALL_COSTS`]' units (about 20 µs), the helper starts the second range of a
/// pair when it is woken for that pair: on the LG-30 KKT it began 15–25 µs after the calling
/// thread began the first (decision record 0091).
const WAKE_LEAD: f64 = 6e4;

/// Multiply–adds (about 0.1–0.2 ms) of the supernodes factored before the first shared one
/// while the second thread wakes up: waking a sleeping thread takes some 60 µs on a virtual
/// machine, more than a shared update saves, so the thread is woken once, ahead, and then
/// watches for work until the factorization ends.
const WAKE_AHEAD_WORK: f64 = 4e5;

/// The second thread of a shared factorization ([`BlockPlan::factor`]): the calling thread
/// factors, and hands one half of each shared supernode's work, and the second range of each
/// pair, to the worker of [`factor_pool`], which watches for it ([`linger`]) from
/// [`Helper::wake`] until the last shared work is done (or the helper is dropped).
struct Helper {
    pool: &'static rayon::ThreadPool,
    stop: Arc<AtomicBool>,
}

impl Helper {
    /// Puts the worker on watch: waking a sleeping thread takes some 60 µs on a virtual
    /// machine, more than many shared updates save, so it is woken once per factorization,
    /// a little ahead ([`BlockPlan::wake_at`]).
    fn wake(&self) {
        let stop = Arc::clone(&self.stop);
        self.pool.spawn(move || linger(&stop));
    }

    /// Runs `mine` on the calling thread and `theirs` on the worker, and returns when both
    /// have ended; waits for the worker by spinning (for at most [`MAX_SPIN`]) rather than
    /// by sleeping, whose wake-up would cost more than the halves save.
    fn join<R>(&self, mine: impl FnOnce() -> R, theirs: impl FnOnce() + Send) -> R {
        let done = AtomicBool::new(false);
        self.pool.in_place_scope(|scope| {
            scope.spawn(|_| {
                theirs();
                done.store(true, Ordering::Release);
            });
            let r = mine();
            let start = Instant::now();
            while !done.load(Ordering::Acquire) && start.elapsed() < MAX_SPIN {
                std::hint::spin_loop();
            }
            r
        })
    }
}

impl Helper {
    /// Ends the worker's watch (after the last shared work).
    fn finish(&self) {
        self.stop.store(true, Ordering::Release);
    }
}

impl Drop for Helper {
    fn drop(&mut self) {
        self.finish();
    }
}

/// The right to the helper for one factorization (module docs): taken with a
/// compare-and-swap, returned when dropped.
struct HelperClaim;

static HELPER_TAKEN: AtomicBool = AtomicBool::new(false);

impl HelperClaim {
    /// The claim, or `None` while another factorization holds it.
    fn take() -> Option<Self> {
        HELPER_TAKEN
            .compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed)
            .ok()
            .map(|_| HelperClaim)
    }
}

impl Drop for HelperClaim {
    fn drop(&mut self) {
        HELPER_TAKEN.store(false, Ordering::Release);
    }
}

/// Longest the calling thread spins for the worker's half before it sleeps until it ends.
const MAX_SPIN: Duration = Duration::from_micros(200);

/// The worker's watch: runs the halves handed over as soon as they come, spinning in
/// between, until `stop`. A watch that the worker takes up while it still keeps another (the
/// next factorization's, begun before the last one's watch saw its end) returns at once:
/// watches nested inside one another could grow the worker's stack for as long as
/// factorizations kept following one another that closely; the halves are then run by the
/// worker's own loop.
fn linger(stop: &AtomicBool) {
    thread_local! {
        static WATCHING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    if WATCHING.with(|w| w.replace(true)) {
        return;
    }
    while !stop.load(Ordering::Acquire) {
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::hint::spin_loop();
        }
    }
    WATCHING.with(|w| w.set(false));
}

/// The thread that takes half of the shared supernodes of a [`BlockPlan`] (a pool of its
/// own, not rayon's global one, whose workers a parallel multi-start keeps busy); `None` on a
/// single core.
fn factor_pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: OnceLock<Option<rayon::ThreadPool>> = OnceLock::new();
    POOL.get_or_init(|| {
        if super::speculative::cores() < 2 {
            return None;
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .thread_name(|i| format!("kkt-factor-{i}"))
            .build()
            .ok()
    })
    .as_ref()
}

/// What the descendant updates of a supernode read: the finished supernodes' layout and
/// pivots, and where the target's updates land in its block.
struct Frozen<'a> {
    lay: &'a Layout<'a>,
    /// The target's first update in [`BlockPlan::upd`] (its relative rows are those of the
    /// updates from there on, [`BlockPlan::upd_rel`]).
    first_update: usize,
    /// The first column and block value of `d`, `e` and `done` (a [`Region`]'s `at`); the
    /// supernodes before them are in `before`.
    at: (usize, usize),
    before: Finished<'a>,
    d: &'a [f64],
    e: &'a [f64],
}

impl Frozen<'_> {
    /// Subtracts the updates `upd` of the finished supernodes (`done`) from the target
    /// columns `cols` (relative to the target's first column `f`) of a block with `nr` rows,
    /// whose columns `cols` are `blk`; descendants in the list's order, so that each entry's
    /// operations do not depend on how the columns are divided.
    #[allow(clippy::too_many_arguments)]
    fn update(
        &self,
        done: &[f64],
        upd: &[(u32, u32, u32)],
        f: usize,
        nr: usize,
        cols: Range<usize>,
        blk: &mut [f64],
        tmp: &mut [f64],
        coef: &mut [f64],
    ) {
        for (k, &(dd, p1, p2)) in upd.iter().enumerate() {
            let lay = self.lay;
            let u = self.first_update + k;
            let rel = &lay.upd_rel[lay.upd_rel_ptr[u]..lay.upd_rel_ptr[u + 1]];
            let dd = dd as usize;
            let (p1, p2) = (p1 as usize, p2 as usize);
            let (fd, ld) = (lay.sn_begin[dd], lay.sn_begin[dd + 1]);
            let wd = ld - fd;
            let rd = &lay.sn_rows[lay.sn_row_ptr[dd]..lay.sn_row_ptr[dd + 1]];
            let nrd = rd.len();
            let (col0, val0) = self.at;
            let (bd, dpiv, epiv) = if fd < col0 {
                let b = &self.before;
                let at = lay.sn_val_ptr[dd];
                (&b.vals[at..at + nrd * wd], &b.d[fd..ld], &b.e[fd..ld])
            } else {
                let at = lay.sn_val_ptr[dd] - val0;
                let c = fd - col0..ld - col0;
                (&done[at..at + nrd * wd], &self.d[c.clone()], &self.e[c])
            };
            // Rows rd[p1..] land on consecutive rows of the target block: subtract in place
            // without the relative rows.
            let first = rel[0] as usize;
            let contiguous = rel[nrd - 1 - p1] as usize - first == nrd - 1 - p1;
            let span = &rd[p1..p2];
            let qa = p1 + span.partition_point(|&r| (r as usize - f) < cols.start);
            let qb = p1 + span.partition_point(|&r| (r as usize - f) < cols.end);
            let mut q0 = qa;
            // (D Lᵀ)[k, q] of the descendant's columns k, for its row q.
            let fill_coef = |coef: &mut [f64], q: usize| {
                if lay.sn_pair[dd] {
                    dl_range(coef, bd, nrd, q, dpiv, epiv, &lay.pair[fd..ld], 0, wd);
                } else {
                    for (k, cf) in coef.iter_mut().enumerate() {
                        *cf = bd[k * nrd + q] * dpiv[k];
                    }
                }
            };
            if wd > 1 && !contiguous {
                // Target columns in pairs: each chunk of the descendant's columns is read once
                // for both sums, each summed in its own scratch column and then scattered.
                while q0 + LINCOMB_TILE <= qb {
                    let (cf, _) = coef.split_at_mut(LINCOMB_TILE * wd);
                    for (j, c) in cf.chunks_exact_mut(wd).enumerate() {
                        fill_coef(c, q0 + j);
                    }
                    let len0 = nrd - q0;
                    let mut scratch = tmp[..LINCOMB_TILE * len0].chunks_exact_mut(len0);
                    let mut outs: [&mut [f64]; LINCOMB_TILE] = std::array::from_fn(|j| {
                        let o = &mut scratch.next().unwrap_or_default()[j..];
                        o.iter_mut().for_each(|o| *o = 0.0);
                        o
                    });
                    lincomb_sub_stair(&mut outs, bd, nrd, q0, cf);
                    for (j, out) in outs.iter().enumerate() {
                        let c = rd[q0 + j] as usize - f - cols.start;
                        let bcol = &mut blk[c * nr..(c + 1) * nr];
                        scatter_sub(bcol, &rel[q0 + j - p1..], out, -1.0, |r| r as usize);
                    }
                    q0 += LINCOMB_TILE;
                }
            }
            if wd == 1 && !contiguous {
                // Target columns four (then two) at a time: each row's relative row and value
                // are read once for all of them.
                let (base, d0) = (f + cols.start, dpiv[0]);
                while q0 + SCATTER_TILE <= qb {
                    let (rows, rel) = (&rd[q0..], &rel[q0 - p1..]);
                    rank1_scatter::<SCATTER_TILE>(blk, nr, rows, base, rel, &bd[q0..], d0);
                    q0 += SCATTER_TILE;
                }
                if q0 + 2 <= qb {
                    let (rows, rel) = (&rd[q0..], &rel[q0 - p1..]);
                    rank1_scatter::<2>(blk, nr, rows, base, rel, &bd[q0..], d0);
                    q0 += 2;
                }
            }
            for q in q0..qb {
                let c = rd[q] as usize - f - cols.start;
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
                        scatter_sub(bcol, &rel[q - p1..], &bd[q..], sc, |r| r as usize);
                    }
                    continue;
                }
                let coef = &mut coef[..wd];
                fill_coef(coef, q);
                if contiguous {
                    let start = first + (q - p1);
                    lincomb_sub(&mut bcol[start..start + len], bd, nrd, q, coef);
                } else {
                    let out = &mut tmp[..len];
                    out.iter_mut().for_each(|o| *o = 0.0);
                    lincomb_sub(out, bd, nrd, q, coef);
                    scatter_sub(bcol, &rel[q - p1..], out, -1.0, |r| r as usize);
                }
            }
        }
    }
}

/// A one-column descendant's update of `G` consecutive target columns, whose rows start one
/// further down each: `blk[c[j]·nr + rel[i]] −= v[i] · (v[j] d)` for `i ≥ j`, where `c[j] =
/// rows[j] − base` is the target column of the descendant's row `j` (rows in increasing
/// order, blocks of `nr` rows). Each row's relative row and value are read once for the `G`
/// columns, and every entry receives the one multiply–subtract of [`scatter_sub`], so the bits
/// are those of `G` calls of it.
#[inline(always)]
pub(super) fn rank1_scatter<const G: usize>(
    blk: &mut [f64],
    nr: usize,
    rows: &[u32],
    base: usize,
    rel: &[u32],
    v: &[f64],
    d: f64,
) {
    let mut cols: [&mut [f64]; G] = std::array::from_fn(|_| Default::default());
    let mut rest = blk;
    let mut next = 0;
    for (col, &r) in cols.iter_mut().zip(rows) {
        let c = r as usize - base;
        let (_, r) = std::mem::take(&mut rest).split_at_mut((c - next) * nr);
        let (b, r) = r.split_at_mut(nr);
        *col = b;
        rest = r;
        next = c + 1;
    }
    let sc: [f64; G] = std::array::from_fn(|j| v[j] * d);
    // Both slices cut to one length up front: the loop below then compiles without a length
    // check per row (zipping the uncut slices measured 2–3 % slower on the LG-30 factor).
    let n = v.len().min(rel.len());
    // The triangle: rows 0..G − 1 of the first columns.
    for i in 0..G - 1 {
        let r = rel[i] as usize;
        for j in 0..=i {
            cols[j][r] -= v[i] * sc[j];
        }
    }
    for (&r, &x) in rel[G - 1..n].iter().zip(&v[G - 1..n]) {
        let r = r as usize;
        for j in 0..G {
            cols[j][r] -= x * sc[j];
        }
    }
}

/// [`lincomb_sub`] of `G` consecutive target columns whose rows start one further down each:
/// `outs[j][i] −= Σ_k coefs[j·wd + k] · blk[k·stride + off + j + i]` (`wd` = `coefs.len() /
/// G`), the rows of all `G` columns ([`lincomb_sub_tile`]) after the rows of the first ones
/// above them. Every entry receives [`lincomb_sub`]'s operations in its order, so the bits
/// are those of `G` calls of it.
#[inline(always)]
pub(super) fn lincomb_sub_stair<const G: usize>(
    outs: &mut [&mut [f64]; G],
    blk: &[f64],
    stride: usize,
    off: usize,
    coefs: &[f64],
) {
    let wd = coefs.len() / G;
    let coefs: [&[f64]; G] = std::array::from_fn(|j| &coefs[j * wd..(j + 1) * wd]);
    let mut common: [&mut [f64]; G] = std::array::from_fn(|_| Default::default());
    for (j, (c, out)) in common.iter_mut().zip(outs.iter_mut()).enumerate() {
        let (above, rest) = out.split_at_mut(G - 1 - j);
        lincomb_sub(above, blk, stride, off + j, coefs[j]);
        *c = rest;
    }
    lincomb_sub_tile(&mut common, blk, stride, off + G - 1, coefs);
}

/// The finished pivots of a supernode (from its first column), for a panel's update.
struct Pivots<'a> {
    d: &'a [f64],
    e: &'a [f64],
    pair: &'a [bool],
    has_pair: bool,
}

impl Pivots<'_> {
    /// Subtracts `Σ_{k ∈ ks} L[·, k] (D Lᵀ)[k, t]` from rows `t..nr` of the block's columns
    /// `t ∈ cols`, which are `out`; `left` holds the block's finished columns (from 0), `ks`
    /// starts at a multiple of four so that the chunks are those of one left-looking pass.
    fn panel_update(
        &self,
        left: &[f64],
        nr: usize,
        ks: Range<usize>,
        cols: Range<usize>,
        out: &mut [f64],
        coef: &mut [f64],
    ) {
        let nk = ks.len();
        let fill_coef = |coef: &mut [f64], t: usize| {
            if self.has_pair {
                let lim = if t > 0 && self.pair[t - 1] { t - 1 } else { t };
                dl_range(coef, left, nr, t, self.d, self.e, self.pair, ks.start, lim);
            } else {
                for (k, cf) in coef.iter_mut().enumerate() {
                    *cf = left[(ks.start + k) * nr + t] * self.d[ks.start + k];
                }
            }
        };
        let mut t0 = cols.start;
        // Columns in pairs: each chunk of the finished columns is read once for both.
        let from = &left[ks.start * nr..];
        while t0 + LINCOMB_TILE <= cols.end {
            let (cf, _) = coef.split_at_mut(LINCOMB_TILE * nk);
            for (j, c) in cf.chunks_exact_mut(nk).enumerate() {
                fill_coef(c, t0 + j);
            }
            let c = t0 - cols.start;
            let mut rest = &mut out[c * nr..(c + LINCOMB_TILE) * nr];
            let mut outs: [&mut [f64]; LINCOMB_TILE] = std::array::from_fn(|j| {
                let (col, r) = std::mem::take(&mut rest).split_at_mut(nr);
                rest = r;
                &mut col[t0 + j..]
            });
            lincomb_sub_stair(&mut outs, from, nr, t0, cf);
            t0 += LINCOMB_TILE;
        }
        let coef = &mut coef[..nk];
        for t in t0..cols.end {
            fill_coef(coef, t);
            let c = t - cols.start;
            lincomb_sub(
                &mut out[c * nr + t..(c + 1) * nr],
                &left[ks.start * nr..],
                nr,
                t,
                coef,
            );
        }
    }
}

/// What the factorization of a supernode's panel writes, from the panel's first column on:
/// its pivots (`D`, their inverses) and `L`'s columns in the solves' layout.
struct Own<'a> {
    d: &'a mut [f64],
    e: &'a mut [f64],
    inv_d: &'a mut [f64],
    inv_e: &'a mut [f64],
    pair: &'a [bool],
    l: &'a mut [f64],
    l_col_ptr: &'a [usize],
    /// The entry of `L`'s column layout that `l` starts at.
    l0: usize,
}

/// Left-looking LDLᵀ of the block's columns `cols` (`blk` holds the columns from
/// `cols.start` on, `nr` rows each), which have received every update but those of the
/// earlier columns of `cols`; 1 × 1 and 2 × 2 pivots as marked in `own.pair`, static
/// pivoting `(eps, delta)`, counted into `inertia`. `None` on a zero or non-finite pivot.
#[allow(clippy::too_many_arguments)]
fn factor_panel(
    blk: &mut [f64],
    nr: usize,
    cols: Range<usize>,
    has_pair: bool,
    own: &mut Own<'_>,
    coef: &mut [f64],
    (eps, delta): (f64, f64),
    inertia: &mut Inertia,
) -> Option<()> {
    let p = cols.start;
    let mut c = p;
    // `(D Lᵀ)[k, t]` of a block without 2 × 2 pivots, for its columns k from `from` on.
    let plain_coef = |coef: &mut [f64], blk: &[f64], d: &[f64], t: usize, from: usize| {
        for (k, cf) in coef.iter_mut().enumerate() {
            *cf = blk[(from + k) * nr + t] * d[from + k];
        }
    };
    // The panel's columns already subtracted from column c (by the pair of the column before).
    let mut done = 0;
    while c < cols.end {
        let cl = c - p;
        let two = own.pair[cl];
        // Two 1 × 1 pivots in a row (and at least one chunk): the chunks of four finished
        // columns that both sums share are read once for both; the next column's sum
        // continues after this column's pivot, with the chunk or the columns it finishes.
        let paired = !has_pair && !two && done == 0 && cl >= 4 && c + 1 < cols.end;
        let paired = (paired && !own.pair[cl + 1]).then(|| {
            let n4 = cl / 4 * 4;
            let (cf, _) = coef.split_at_mut(2 * n4);
            for (j, cfj) in cf.chunks_exact_mut(n4).enumerate() {
                plain_coef(cfj, blk, own.d, c + j, 0);
            }
            let (left, right) = blk.split_at_mut(cl * nr);
            let (col0, rest) = right.split_at_mut(nr);
            let mut outs = [&mut col0[c..], &mut rest[c + 1..nr]];
            lincomb_sub_stair(&mut outs, left, nr, c, cf);
            n4
        });
        let from = paired.unwrap_or(done);
        for t in c..c + 1 + usize::from(two) {
            let coef = &mut coef[..cl - from];
            if has_pair {
                dl_range(coef, blk, nr, t, own.d, own.e, own.pair, 0, cl);
            } else {
                plain_coef(coef, blk, own.d, t, from);
            }
            let (left, right) = blk.split_at_mut((t - p) * nr);
            lincomb_sub(&mut right[t..nr], &left[from * nr..], nr, t, coef);
        }
        done = paired.unwrap_or(0);
        if !two {
            let col = &mut blk[cl * nr + c..(cl + 1) * nr];
            let (d, _) = counted_pivot(col[0], delta, eps, inertia)?;
            col[0] = d;
            let inv = d.recip();
            col[1..].iter_mut().for_each(|v| *v *= inv);
            own.d[cl] = d;
            own.inv_d[cl] = inv;
            own.e[cl] = 0.0;
            own.l[own.l_col_ptr[cl] - own.l0..own.l_col_ptr[cl + 1] - own.l0].copy_from_slice(col);
            c += 1;
            continue;
        }
        // 2 × 2 pivot B = [d1 a; a d2] on columns c, c + 1: L's two columns below it are
        // [A_c A_{c+1}] B⁻¹, and L[c + 1, c] = 0.
        let (cc, c1) = blk.split_at_mut((cl + 1) * nr);
        let (col0, col1) = (&mut cc[cl * nr + c..], &mut c1[c + 1..nr]);
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
        own.d[cl] = d1;
        own.d[cl + 1] = d2;
        own.e[cl] = a;
        own.e[cl + 1] = 0.0;
        own.inv_d[cl] = i11;
        own.inv_d[cl + 1] = i22;
        own.inv_e[cl] = i12;
        let (l0, lp) = (own.l0, own.l_col_ptr);
        own.l[lp[cl] - l0..lp[cl + 1] - l0].copy_from_slice(col0);
        own.l[lp[cl + 1] - l0..lp[cl + 2] - l0].copy_from_slice(col1);
        c += 2;
    }
    Some(())
}

/// Where a look-ahead round divides the later columns `p..w` of a block with `nr` rows: the
/// first thread updates columns `p..mid` by the `k` finished columns and factors the next
/// panel `p..q`, the second updates `mid..w`; `mid ≥ q` balances the two by multiply–adds.
fn look_ahead_split(nr: usize, k: usize, p: usize, q: usize, w: usize) -> usize {
    let panel: usize = (p..q).map(|t| (t - p) * (nr - t)).sum();
    let rest: usize = (p..w).map(|t| k * (nr - t)).sum();
    let mut first = panel;
    for t in p..w {
        if t >= q && 2 * first >= panel + rest {
            return t;
        }
        first += k * (nr - t);
    }
    w
}

/// `a[..at[2]]` divided at `at[0]` and `at[1]`: the finished part before, and two ranges.
fn thirds(a: &mut [f64], at: [usize; 3]) -> (&[f64], &mut [f64], &mut [f64]) {
    let (finished, rest) = a[..at[2]].split_at_mut(at[0]);
    let (first, second) = rest.split_at_mut(at[1] - at[0]);
    (finished, first, second)
}

/// The finished supernodes before a [`Region`] (their block values and pivots, from the
/// first), which its supernodes read but do not write.
#[derive(Clone, Copy, Default)]
struct Finished<'a> {
    vals: &'a [f64],
    d: &'a [f64],
    e: &'a [f64],
}

/// The analysis's structure that every supernode's factorization reads, and the pivot rule
/// `(eps, delta)` of [`BlockPlan::factor`].
struct Layout<'a> {
    sn_begin: &'a [usize],
    sn_rows: &'a [u32],
    sn_row_ptr: &'a [usize],
    sn_val_ptr: &'a [usize],
    upd_ptr: &'a [usize],
    upd: &'a [(u32, u32, u32)],
    upd_rel_ptr: &'a [usize],
    upd_rel: &'a [u32],
    pair: &'a [bool],
    sn_pair: &'a [bool],
    sn_split: &'a [u32],
    sn_panels: &'a [bool],
    l_col_ptr: &'a [usize],
    a_ptr: &'a [usize],
    a_map: &'a [(u32, u32)],
    /// The matrix's values ([`BlockPlan::a_map`]).
    values: &'a [f64],
    pivots: (f64, f64),
}

impl Layout<'_> {
    /// Fills `part`, the positions `at..at + part.len()` of supernode `sn`'s block, with the
    /// matrix's entries there and zeros elsewhere.
    fn fill(&self, sn: usize, part: &mut [f64], at: usize) {
        part.iter_mut().for_each(|v| *v = 0.0);
        let entries = &self.a_map[self.a_ptr[sn]..self.a_ptr[sn + 1]];
        let lo = entries.partition_point(|&(_, p)| (p as usize) < at);
        for &(v, p) in &entries[lo..] {
            let Some(slot) = part.get_mut(p as usize - at) else {
                break;
            };
            *slot = self.values[v as usize];
        }
    }
}

/// A thread's scratch: a gathered update, the coefficients `D Lᵀ`.
#[derive(Debug, Clone, Default)]
pub(super) struct Work {
    tmp: Vec<f64>,
    coef: Vec<f64>,
}

impl Work {
    fn new(max_rows: usize) -> Self {
        Self {
            tmp: vec![0.0; LINCOMB_TILE * max_rows],
            coef: vec![0.0; LINCOMB_TILE * max_rows],
        }
    }
}

/// The arrays a range of consecutive supernodes writes, from the range's first supernode on:
/// `at` = (its first column, its first block value, its first entry of `L`'s column layout),
/// which the indices of the whole arrays are reduced by. A range reads only its own
/// supernodes and those `before` it, so two ranges that do not depend on each other are
/// factored at once.
struct Region<'a> {
    at: (usize, usize, usize),
    before: Finished<'a>,
    vals: &'a mut [f64],
    d: &'a mut [f64],
    e: &'a mut [f64],
    inv_d: &'a mut [f64],
    inv_e: &'a mut [f64],
    l: &'a mut [f64],
    work: &'a mut Work,
    /// The helper's scratch, for the shared supernodes' halves.
    second: Option<&'a mut Work>,
}

impl<'a> Region<'a> {
    /// A region without the helper's scratch: its `[vals, d, e, inv_d, inv_e, l]` from `at`
    /// on.
    fn range(
        at: (usize, usize, usize),
        before: Finished<'a>,
        [vals, d, e, inv_d, inv_e, l]: [&'a mut [f64]; 6],
        work: &'a mut Work,
    ) -> Self {
        Self {
            at,
            before,
            vals,
            d,
            e,
            inv_d,
            inv_e,
            l,
            work,
            second: None,
        }
    }
}

/// Factors the supernodes `sns` of `reg` on this thread alone; their inertia.
fn factor_range(lay: &Layout<'_>, reg: &mut Region<'_>, sns: Range<usize>) -> Option<Inertia> {
    let mut inertia = Inertia::default();
    for sn in sns {
        factor_supernode(lay, reg, sn, None, &mut inertia)?;
    }
    Some(inertia)
}

/// Factors supernode `sn` (every supernode it depends on finished in `reg`): its descendants'
/// updates, then its own columns; with `helper` and the region's second scratch, a shared
/// supernode's work is divided with the helper's thread. `None` on a zero or non-finite
/// pivot.
fn factor_supernode(
    lay: &Layout<'_>,
    reg: &mut Region<'_>,
    sn: usize,
    helper: Option<&Helper>,
    inertia: &mut Inertia,
) -> Option<()> {
    let (col0, val0, l0) = reg.at;
    let (f, l) = (lay.sn_begin[sn], lay.sn_begin[sn + 1]);
    let w = l - f;
    let rows = &lay.sn_rows[lay.sn_row_ptr[sn]..lay.sn_row_ptr[sn + 1]];
    let nr = rows.len();
    let Work { tmp, coef } = &mut *reg.work;
    let (done, rest) = reg.vals.split_at_mut(lay.sn_val_ptr[sn] - val0);
    let blk = &mut rest[..nr * w];
    let upd = &lay.upd[lay.upd_ptr[sn]..lay.upd_ptr[sn + 1]];
    let frozen = Frozen {
        lay,
        first_update: lay.upd_ptr[sn],
        at: (col0, val0),
        before: reg.before,
        d: &*reg.d,
        e: &*reg.e,
    };
    let mut helper = helper.zip(reg.second.as_deref_mut());
    let split = lay.sn_split[sn] as usize;
    match helper.as_mut() {
        Some((h, second)) if split > 0 => {
            let (a, b) = blk.split_at_mut(split * nr);
            let (tmp_b, coef_b) = (&mut second.tmp, &mut second.coef);
            h.join(
                || {
                    lay.fill(sn, a, 0);
                    frozen.update(done, upd, f, nr, 0..split, a, tmp, coef);
                },
                || {
                    lay.fill(sn, b, split * nr);
                    frozen.update(done, upd, f, nr, split..w, b, tmp_b, coef_b);
                },
            );
        }
        _ => {
            lay.fill(sn, blk, 0);
            frozen.update(done, upd, f, nr, 0..w, blk, tmp, coef);
        }
    }
    // Dense LDLᵀ of the block's own columns, left-looking. With panels, the columns are
    // factored panel by panel; while one thread factors the next panel, the other subtracts
    // the finished panels from the later columns (look-ahead). The panels end at multiples of
    // four, the lincomb's chunk, so that every entry sees the chunks of one left-looking pass.
    let has_pair = lay.sn_pair[sn];
    let mut panels = helper.filter(|_| lay.sn_panels[sn]);
    let pair = &lay.pair[f..l];
    let paneled = panels.is_some();
    let panel_end = |p0: usize| {
        if !paneled {
            return w;
        }
        let mut p1 = (p0 + PANEL).min(w);
        while p1 < w && pair[p1 - 1] {
            p1 = (p1 + 4).min(w);
        }
        p1
    };
    let mut p = panel_end(0);
    let mut own = Own {
        d: &mut reg.d[f - col0..l - col0],
        e: &mut reg.e[f - col0..l - col0],
        inv_d: &mut reg.inv_d[f - col0..l - col0],
        inv_e: &mut reg.inv_e[f - col0..l - col0],
        pair,
        l: &mut *reg.l,
        l_col_ptr: &lay.l_col_ptr[f..],
        l0,
    };
    factor_panel(blk, nr, 0..p, has_pair, &mut own, coef, lay.pivots, inertia)?;
    let mut a = 0;
    while let Some((helper, second)) = panels.as_mut().filter(|_| p < w) {
        let q = panel_end(p);
        let ks = a..p;
        let mid = look_ahead_split(nr, ks.len(), p, q, w);
        let (left, right) = blk.split_at_mut(p * nr);
        let (ra, rb) = right.split_at_mut((mid - p) * nr);
        let (d_done, d_new) = own.d.split_at_mut(p);
        let (e_done, e_new) = own.e.split_at_mut(p);
        let piv = Pivots {
            d: d_done,
            e: e_done,
            pair,
            has_pair,
        };
        let mut next = Own {
            d: d_new,
            e: e_new,
            inv_d: &mut own.inv_d[p..],
            inv_e: &mut own.inv_e[p..],
            pair: &pair[p..],
            l: &mut *own.l,
            l_col_ptr: &own.l_col_ptr[p..],
            l0,
        };
        let coef_a = &mut *coef;
        let coef_b = &mut second.coef;
        let inertia = &mut *inertia;
        let factored = helper.join(
            || {
                piv.panel_update(left, nr, ks.clone(), p..mid, ra, coef_a);
                factor_panel(
                    ra,
                    nr,
                    p..q,
                    has_pair,
                    &mut next,
                    coef_a,
                    lay.pivots,
                    inertia,
                )
            },
            || piv.panel_update(left, nr, ks.clone(), mid..w, rb, coef_b),
        );
        factored?;
        a = p;
        p = q;
    }
    Some(())
}

/// Where a stretch of supernodes `s..s + work.len()` (`work` their costs, [`SMALL_COSTS`];
/// the supernodes before `s` finished) holds two consecutive ranges `s..x` and `x..y` that
/// two threads can factor at once: no supernode of the second depends on one of the first,
/// directly or through others. Supernodes are numbered after their descendants, so one pass
/// in order finds each one's lowest dependency in the stretch, and for each `x` the second
/// range ends at the first supernode that depends below `x`. With the second range starting
/// `lead` late, the pair saves `min(second, first − lead)` of the two ranges' time on one
/// thread; the pair that saves the most, if it saves at least [`MIN_PARALLEL_WORK`].
fn split_stretch(
    work: &[f64],
    s: usize,
    lead: f64,
    upd_ptr: &[usize],
    upd: &[(u32, u32, u32)],
) -> Option<(usize, usize)> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let len = work.len();
    // Indices relative to `s`; dependencies before the stretch are finished.
    let mut lowest: Vec<usize> = (0..len).collect();
    for k in 0..len {
        for &(d, ..) in &upd[upd_ptr[s + k]..upd_ptr[s + k + 1]] {
            if let Some(d) = (d as usize).checked_sub(s) {
                lowest[k] = lowest[k].min(lowest[d]);
            }
        }
    }
    // by_lowest[j]: the supernodes whose lowest dependency is j (below x once x > j).
    let mut by_lowest = vec![Vec::new(); len];
    for k in 0..len {
        if lowest[k] < k {
            by_lowest[lowest[k]].push(k);
        }
    }
    let prefix: Vec<f64> = std::iter::once(0.0)
        .chain(work.iter().scan(0.0, |acc, &w| {
            *acc += w;
            Some(*acc)
        }))
        .collect();
    let mut below = BinaryHeap::new();
    let mut best: Option<(f64, usize, usize)> = None;
    for x in 1..len {
        below.extend(by_lowest[x - 1].iter().map(|&k| Reverse(k)));
        while below.peek().is_some_and(|&Reverse(k)| k < x) {
            below.pop();
        }
        let y = below.peek().map_or(len, |&Reverse(k)| k);
        let saved = (prefix[y] - prefix[x]).min(prefix[x] - lead);
        if saved >= MIN_PARALLEL_WORK && best.is_none_or(|(m, ..)| saved > m) {
            best = Some((saved, x, y));
        }
    }
    best.map(|(_, x, y)| (s + x, s + y))
}
