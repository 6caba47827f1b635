//! Fill-reducing elimination order of the KKT matrix `K(δ_w, δ_c)` (Wächter & Biegler 2006,
//! eq. (13)) for an LDLᵀ with 1 × 1 pivots.
//!
//! AMD alone orders by degree and may eliminate a constraint row (index ≥ n) before every
//! primal variable it couples to; its pivot is then exactly `−δ_c`, and for the small static
//! δ_c the IPM uses, the update `Jᵢᵀ Jᵢ / δ_c` of the primal block swamps its curvature in
//! rounding, so the sign count of `D` no longer matches the inertia of `K`.
//! [`delay_constraint_rows`] post-processes the AMD order so that each constraint row is
//! eliminated right after the first of its primal neighbours: the row's pivot is then
//! `−δ_c − Σ a²/d` with `d` the neighbour's pivot, the Schur complement of a 2 × 2 block
//! `[d a; a −δ_c]` of one positive and one negative eigenvalue, and the `1/δ_c` growth is gone.

/// The order `fwd` (`fwd[k]` = index eliminated k-th) with every constraint row `i ≥ n` that
/// precedes all of its primal neighbours moved to right after the first of them (several rows
/// after one variable keep their relative order). Constraint rows without primal neighbours
/// stay where they are. `col_ptr`/`row_idx` is the lower-triangle pattern of `K`.
pub(super) fn delay_constraint_rows(
    fwd: &[usize],
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Vec<usize> {
    let dim = fwd.len();
    let mut pos = vec![0usize; dim];
    for (k, &v) in fwd.iter().enumerate() {
        pos[v] = k;
    }
    // First primal neighbour (in elimination order) of each constraint row: the Jacobian
    // entries are the rows ≥ n of the primal columns.
    let mut first = vec![usize::MAX; dim];
    for c in 0..n.min(dim) {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r >= n && (first[r] == usize::MAX || pos[c] < pos[first[r]]) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// On a chain `x0 – c0 – x1 – c1 – x2` ordered constraints first, each constraint row ends
    /// up right after its earliest-ordered primal neighbour and the result is a permutation.
    #[test]
    fn constraint_rows_follow_a_primal_neighbour() {
        // n = 3 primal, rows 3 (c0: x0, x1) and 4 (c1: x1, x2); lower-triangle CSC.
        let cols: Vec<Vec<usize>> = vec![vec![0, 3], vec![1, 3, 4], vec![2, 4], vec![3], vec![4]];
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for c in &cols {
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let fwd = [3, 4, 2, 1, 0];
        let out = delay_constraint_rows(&fwd, 3, &col_ptr, &row_idx);
        assert_eq!(out, vec![2, 4, 1, 3, 0]);
        let mut sorted = out.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vec![0, 1, 2, 3, 4]);
        // Already admissible orders are kept.
        let ok = [0, 3, 1, 4, 2];
        assert_eq!(
            delay_constraint_rows(&ok, 3, &col_ptr, &row_idx),
            ok.to_vec()
        );
    }
}
