//! Fill-reducing elimination order of the KKT matrix `K(δ_w, δ_c)` (Wächter & Biegler 2006,
//! eq. (13)) for an LDLᵀ with 1 × 1 and 2 × 2 pivots.
//!
//! AMD alone orders by degree and may eliminate a constraint row (index ≥ n) before every
//! primal variable it couples to; its pivot is then exactly `−δ_c`, and for the small static
//! δ_c the IPM uses, the update `Jᵢᵀ Jᵢ / δ_c` of the primal block swamps its curvature in
//! rounding, so the sign count of `D` no longer matches the inertia of `K`.
//!
//! * [`paired_amd`]: each constraint row is paired with a primal neighbour of its own
//!   (bounded variables first: their pivot carries the barrier term Σ > 0), AMD orders the
//!   graph of pairs, and each pair is eliminated as (variable, row): the row's pivot is then
//!   the Schur complement `−δ_c − a²/d` of the 2 × 2 block `[d a; a −δ_c]`, which has one
//!   positive and one negative eigenvalue when d > 0, and no `1/δ_c` growth enters the factor.
//! * [`amd_pivot_pairs`]: AMD's own order, with each row that would have the bare pivot
//!   delayed to its parent in the elimination tree, a variable of its own, and eliminated
//!   with it as one 2 × 2 block pivot.
//! * [`delay_constraint_rows`]: the fallback for rows left unpaired: each is moved to right
//!   after the first of its primal neighbours in the order.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::{FaerError, SymbolicSparseColMatRef};

/// The order `fwd` (`fwd[k]` = index eliminated k-th) with every constraint row `i ≥ n` that
/// precedes all of its primal neighbours moved to right after the first of them (several rows
/// after one variable keep their relative order). Constraint rows without primal neighbours
/// stay where they are. `col_ptr`/`row_idx` is the lower-triangle pattern of `K`.
pub(super) fn delay_constraint_rows(
    fwd: &[usize],
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    preferred: &[bool],
) -> Vec<usize> {
    let dim = fwd.len();
    let mut pos = vec![0usize; dim];
    for (k, &v) in fwd.iter().enumerate() {
        pos[v] = k;
    }
    // First primal neighbour (in elimination order) of each constraint row: the Jacobian
    // entries are the rows ≥ n of the primal columns.
    let mut first = vec![usize::MAX; dim];
    let pref = |c: usize| preferred.get(c).copied().unwrap_or(false);
    for c in 0..n.min(dim) {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r >= n
                && (first[r] == usize::MAX
                    || (pref(c), std::cmp::Reverse(pos[c]))
                        > (pref(first[r]), std::cmp::Reverse(pos[first[r]])))
            {
                first[r] = c;
            }
        }
    }
    let mut after: Vec<Vec<usize>> = vec![Vec::new(); dim];
    let mut delayed = vec![false; dim];
    for &v in fwd {
        if v >= n && first[v] != usize::MAX && pos[v] < pos[first[v]] {
            after[first[v]].push(v);
            delayed[v] = true;
        }
    }
    let mut out = Vec::with_capacity(dim);
    for &v in fwd {
        if delayed[v] {
            continue;
        }
        out.push(v);
        out.extend_from_slice(&after[v]);
    }
    out
}

/// A fill-reducing order in which every constraint row that can be paired with a primal
/// neighbour of its own follows that neighbour directly: a greedy matching pairs each
/// constraint row with an unmatched primal neighbour (`preferred` ones first, e.g. bounded
/// variables whose pivot carries Σ > 0), AMD orders the graph in which each pair is one node,
/// and each pair is expanded as (variable, constraint row). Rows left unpaired are then
/// placed by [`delay_constraint_rows`]. `None` if faer's AMD fails.
pub(super) fn paired_amd(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    preferred: &[bool],
) -> Option<Vec<usize>> {
    let dim = col_ptr.len() - 1;
    let pref = |c: usize| preferred.get(c).copied().unwrap_or(false);
    // Primal neighbours of each constraint row.
    let mut nbr: Vec<Vec<usize>> = vec![Vec::new(); dim];
    for c in 0..n.min(dim) {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r >= n {
                nbr[r].push(c);
            }
        }
    }
    let mut mate = vec![usize::MAX; dim];
    for round in [true, false] {
        for r in n..dim {
            if mate[r] != usize::MAX {
                continue;
            }
            if let Some(&c) = nbr[r]
                .iter()
                .find(|&&c| mate[c] == usize::MAX && (pref(c) || !round))
            {
                mate[r] = c;
                mate[c] = r;
            }
        }
    }
    // Compressed graph: a pair is the node of its variable.
    let mut node = vec![usize::MAX; dim];
    let mut members: Vec<Vec<usize>> = Vec::new();
    for v in 0..dim {
        if v >= n && mate[v] != usize::MAX {
            continue;
        }
        node[v] = members.len();
        let mut m = vec![v];
        if v < n && mate[v] != usize::MAX {
            m.push(mate[v]);
        }
        members.push(m);
    }
    for r in n..dim {
        if mate[r] != usize::MAX {
            node[r] = node[mate[r]];
        }
    }
    let nc = members.len();
    let mut edges: Vec<(usize, usize)> = Vec::with_capacity(row_idx.len() + nc);
    for c in 0..dim {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            let (a, b) = (node[r], node[c]);
            edges.push((a.min(b), a.max(b)));
        }
    }
    for k in 0..nc {
        edges.push((k, k));
    }
    edges.sort_unstable();
    edges.dedup();
    // Lower-triangle CSC of the compressed graph (column = smaller index).
    let mut cp = vec![0usize; nc + 1];
    for &(c, _) in &edges {
        cp[c + 1] += 1;
    }
    for k in 0..nc {
        cp[k + 1] += cp[k];
    }
    let ri: Vec<usize> = edges.iter().map(|&(_, r)| r).collect();
    let pattern = SymbolicSparseColMatRef::new_checked(nc, nc, &cp, None, &ri);
    let (mut fwd, mut inv) = (vec![0usize; nc], vec![0usize; nc]);
    let mut mem =
        MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(nc, ri.len())).ok()?;
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .ok()?;
    let order: Vec<usize> = fwd
        .iter()
        .flat_map(|&k| members[k].iter().copied())
        .collect();
    Some(delay_constraint_rows(&order, n, col_ptr, row_idx, &[]))
}

/// AMD's order of the lower-triangle pattern `col_ptr`/`row_idx` (`fwd[k]` = index eliminated
/// k-th). `None` if faer's AMD fails.
pub(super) fn amd_order(col_ptr: &[usize], row_idx: &[usize]) -> Option<Vec<usize>> {
    amd_order_counted(col_ptr, row_idx).ok().map(|(fwd, _)| fwd)
}

/// [`amd_order`] with AMD's own count of the LDLᵀ's divisions and multiply–subtracts in that
/// order (`n_div + n_mult_subs_ldl`): what faer's symbolic analysis with its AMD ordering
/// compares against the fill to choose a supernodal factor (`FaerFactor::auto_supernodal`).
pub(super) fn amd_order_counted(
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<(Vec<usize>, f64), FaerError> {
    let dim = col_ptr.len() - 1;
    let pattern = SymbolicSparseColMatRef::new_checked(dim, dim, col_ptr, None, row_idx);
    let (mut fwd, mut inv) = (vec![0usize; dim], vec![0usize; dim]);
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
        dim,
        row_idx.len(),
    ))
    .map_err(|_| FaerError::OutOfMemory)?;
    let flops = amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )?;
    Ok((fwd, flops.n_div + flops.n_mult_subs_ldl))
}

/// AMD's order with 2 × 2 pivot pairs (MA57-style delayed pivots, resolved symbolically).
/// Walking AMD's order, the elimination is followed symbolically (elimination tree and, per
/// eliminated subtree, its boundary: the nodes not yet eliminated that are adjacent to it). A
/// constraint row `r ≥ n` whose row of `L` would contain no primal variable eliminated as a
/// 1 × 1 pivot would have the bare pivot `−δ_c` (or one of order δ_c where its variables went
/// into pairs with other rows). Such a row is delayed to the first primal variable `v` adjacent
/// to it (in the partly eliminated graph) that AMD eliminates later, its parent in the
/// elimination tree, and the two are eliminated together as one 2 × 2 block pivot
/// `[d a; a −δ_c]` (`a` the entry coupling them), whose determinant `−d δ_c − a²` is negative
/// whenever `d ≥ 0`: one positive and one negative eigenvalue whatever the size of `d`, and an
/// inverse with entries of order `1/|a|` rather than `1/δ_c`. Moving `v` forward to the row
/// instead eliminates a high-degree variable early and costs far more fill. Delayed rows still
/// waiting at the end follow as 1 × 1 pivots; a delayed row that meanwhile got a 1 × 1
/// variable in its row of `L` is placed before the next variable adjacent to it. Returns the
/// order and, per position `k`, whether positions `k`, `k + 1` form a pair (the row is in the
/// variable's structure, so `parent(k) = k + 1`). `amd`: AMD's order of this pattern where
/// it is known ([`amd_order`] otherwise). `None` if faer's AMD fails.
pub(super) fn amd_pivot_pairs(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    amd: Option<&[usize]>,
) -> Option<(Vec<usize>, Vec<bool>)> {
    let dim = col_ptr.len() - 1;
    let fwd = match amd {
        Some(fwd) => fwd.to_vec(),
        None => amd_order(col_ptr, row_idx)?,
    };
    let mut pos = vec![0usize; dim];
    for (k, &v) in fwd.iter().enumerate() {
        pos[v] = k;
    }
    // Full adjacency (both triangles, no diagonal).
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); dim];
    for c in 0..dim {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r != c {
                adj[c].push(r);
                adj[r].push(c);
            }
        }
    }
    let mut elim = Elimination::new(dim);
    let mut out = Vec::with_capacity(dim);
    let mut pair_first = Vec::with_capacity(dim);
    let mut in_pair = vec![false; dim];
    let mut pending = vec![false; dim];
    let mut n_pending = 0usize;
    // Whether row r's pivot would be bare: no 1 × 1 primal pivot in its row of L.
    let is_early = |elim: &mut Elimination, in_pair: &[bool], r: usize| {
        let (visited, _) = elim.row_structure(r, &adj);
        !visited.iter().any(|&j| j < n && !in_pair[j])
    };
    for &v in &fwd {
        if elim.placed[v] {
            continue;
        }
        if v >= n {
            let has_primal = adj[v].iter().any(|&c| c < n);
            if has_primal && is_early(&mut elim, &in_pair, v) {
                pending[v] = true;
                n_pending += 1;
            } else {
                elim.place(v, &adj);
                out.push(v);
                pair_first.push(false);
            }
            continue;
        }
        if n_pending > 0 {
            // Delayed rows adjacent to v, in AMD's order: the first still early pairs with v;
            // those no longer early go right before v as 1 × 1 pivots.
            let (_, roots) = elim.row_structure(v, &adj);
            let mut rows: Vec<usize> = adj[v]
                .iter()
                .chain(roots.iter().flat_map(|&rho| elim.boundary[rho].iter()))
                .copied()
                .filter(|&r| r >= n && pending[r])
                .collect();
            rows.sort_unstable_by_key(|&r| pos[r]);
            rows.dedup();
            let mut partner = None;
            for r in rows {
                if is_early(&mut elim, &in_pair, r) {
                    partner = Some(r);
                    break;
                }
                pending[r] = false;
                n_pending -= 1;
                elim.place(r, &adj);
                out.push(r);
                pair_first.push(false);
            }
            if let Some(r) = partner {
                pending[r] = false;
                n_pending -= 1;
                elim.place(v, &adj);
                elim.place(r, &adj);
                out.extend([v, r]);
                pair_first.extend([true, false]);
                in_pair[v] = true;
                in_pair[r] = true;
                continue;
            }
        }
        elim.place(v, &adj);
        out.push(v);
        pair_first.push(false);
    }
    for &r in &fwd {
        if pending[r] {
            elim.place(r, &adj);
            out.push(r);
            pair_first.push(false);
        }
    }
    Some((out, pair_first))
}

/// Symbolic elimination in a given order, one node at a time: elimination tree so far and the
/// boundary of each current subtree root (not yet eliminated nodes adjacent to the subtree).
struct Elimination {
    placed: Vec<bool>,
    parent: Vec<usize>,
    boundary: Vec<Vec<usize>>,
    mark: Vec<usize>,
    stamp: usize,
}

impl Elimination {
    fn new(dim: usize) -> Self {
        Self {
            placed: vec![false; dim],
            parent: vec![usize::MAX; dim],
            boundary: vec![Vec::new(); dim],
            mark: vec![usize::MAX; dim],
            stamp: 0,
        }
    }

    /// Row structure of `x` in `L` if it were eliminated next (eliminated nodes j with
    /// `L[x, j] ≠ 0`: the elimination-tree paths from its eliminated neighbours) and the
    /// current subtree roots those paths end in.
    fn row_structure(&mut self, x: usize, adj: &[Vec<usize>]) -> (Vec<usize>, Vec<usize>) {
        self.stamp += 1;
        let (mut visited, mut roots) = (Vec::new(), Vec::new());
        for &i in &adj[x] {
            let mut j = i;
            while self.placed[j] && self.mark[j] != self.stamp {
                self.mark[j] = self.stamp;
                visited.push(j);
                if self.parent[j] == usize::MAX {
                    roots.push(j);
                    break;
                }
                j = self.parent[j];
            }
        }
        (visited, roots)
    }

    /// Eliminates `x`: it becomes the parent of the subtree roots it touches, and its boundary
    /// is its own not yet eliminated neighbours plus theirs.
    fn place(&mut self, x: usize, adj: &[Vec<usize>]) {
        let (_, roots) = self.row_structure(x, adj);
        self.stamp += 1;
        let stamp = self.stamp;
        self.mark[x] = stamp;
        let mut b = Vec::new();
        for &w in &adj[x] {
            if !self.placed[w] && self.mark[w] != stamp {
                self.mark[w] = stamp;
                b.push(w);
            }
        }
        for rho in roots {
            self.parent[rho] = x;
            for w in std::mem::take(&mut self.boundary[rho]) {
                if !self.placed[w] && self.mark[w] != stamp {
                    self.mark[w] = stamp;
                    b.push(w);
                }
            }
        }
        self.boundary[x] = b;
        self.placed[x] = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lower-triangle CSC of the given columns.
    fn csc(cols: &[Vec<usize>]) -> (Vec<usize>, Vec<usize>) {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for c in cols {
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx)
    }

    /// On a chain `x0 – c0 – x1 – c1 – x2` ordered constraints first, each constraint row ends
    /// up right after its earliest-ordered primal neighbour and the result is a permutation.
    #[test]
    fn constraint_rows_follow_a_primal_neighbour() {
        // n = 3 primal, rows 3 (c0: x0, x1) and 4 (c1: x1, x2).
        let (col_ptr, row_idx) = csc(&[vec![0, 3], vec![1, 3, 4], vec![2, 4], vec![3], vec![4]]);
        let fwd = [3, 4, 2, 1, 0];
        let out = delay_constraint_rows(&fwd, 3, &col_ptr, &row_idx, &[]);
        assert_eq!(out, vec![2, 4, 1, 3, 0]);
        // Already admissible orders are kept.
        let ok = [0, 3, 1, 4, 2];
        assert_eq!(
            delay_constraint_rows(&ok, 3, &col_ptr, &row_idx, &[]),
            ok.to_vec()
        );
    }

    /// The paired order is a permutation in which every constraint row comes right after a
    /// primal neighbour of its own (distinct per row), a preferred one where available.
    #[test]
    fn paired_order_puts_each_row_after_its_own_variable() {
        // n = 4: rows 4 (x0, x1), 5 (x1, x2), 6 (x2, x3); x3 preferred.
        let (col_ptr, row_idx) = csc(&[
            vec![0, 1, 4],
            vec![1, 4, 5],
            vec![2, 5, 6],
            vec![3, 6],
            vec![4],
            vec![5],
            vec![6],
        ]);
        let preferred = [false, false, false, true];
        let out = paired_amd(4, &col_ptr, &row_idx, &preferred).unwrap();
        let mut sorted = out.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..7).collect::<Vec<_>>());
        let mut used = Vec::new();
        for (k, &v) in out.iter().enumerate() {
            if v >= 4 {
                let prev = out[k - 1];
                let cols = &row_idx[col_ptr[prev]..col_ptr[prev + 1]];
                assert!(prev < 4 && cols.contains(&v), "{out:?}");
                used.push(prev);
            }
        }
        used.sort_unstable();
        used.dedup();
        assert_eq!(used.len(), 3, "{out:?}");
        // Row 6 takes the preferred x3.
        let p6 = out.iter().position(|&v| v == 6).unwrap();
        assert_eq!(out[p6 - 1], 3, "{out:?}");
    }
}
