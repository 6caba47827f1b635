//! The KKT matrix `K(δ_w, δ_c)` of Wächter & Biegler 2006, eq. (13), as a lower-triangle CSC
//! pattern built once from the Hessian and Jacobian triplet patterns, with scatter maps so
//! that each iteration's assembly is one pass over the user values (duplicates are summed, as
//! in Ipopt's triplet convention). Rows/columns `0..n` are the primal variables, `n..n+m` the
//! equality constraints.

use super::LowerCsc;
use crate::error::OptimError;

/// Lower-triangle pattern of `K` plus scatter maps from the user triplets.
#[derive(Debug, Clone)]
pub struct KktPattern {
    /// Number of primal variables (x block).
    pub n: usize,
    /// Number of equality constraints (y block).
    pub m: usize,
    /// The matrix storage (`values` is rewritten by [`assemble`](KktPattern::assemble)).
    pub mat: LowerCsc,
    hess_dst: Vec<usize>,
    jac_dst: Vec<usize>,
    diag_dst: Vec<usize>,
}

impl KktPattern {
    /// Builds the pattern from the Hessian lower-triangle triplets `(row ≥ col)` over the `n`
    /// primal variables and the Jacobian triplets `(constraint row, variable col)`.
    ///
    /// # Panics
    ///
    /// If a triplet is out of range or a Hessian triplet lies above the diagonal;
    /// [`KktPattern::try_new`] returns that as an error instead.
    pub fn new(n: usize, m: usize, hess: &[(usize, usize)], jac: &[(usize, usize)]) -> Self {
        match Self::try_new(n, m, hess, jac) {
            Ok(pattern) => pattern,
            Err(e) => panic!("KktPattern::new: {e}"),
        }
    }

    /// [`KktPattern::new`], or [`OptimError::InvalidPattern`] for the first Hessian triplet
    /// out of `0..n` or above the diagonal, or Jacobian triplet out of `0..m × 0..n`.
    pub fn try_new(
        n: usize,
        m: usize,
        hess: &[(usize, usize)],
        jac: &[(usize, usize)],
    ) -> Result<Self, OptimError> {
        let invalid = |what, index, (row, col): (usize, usize)| OptimError::InvalidPattern {
            what,
            index,
            row,
            col,
        };
        if let Some(k) = hess.iter().position(|&(r, c)| r >= n || c > r) {
            return Err(invalid("hessian", k, hess[k]));
        }
        if let Some(k) = jac.iter().position(|&(r, c)| r >= m || c >= n) {
            return Err(invalid("jacobian", k, jac[k]));
        }
        let dim = n + m;
        // (row, col) keys of every contribution, diagonal first so it always exists.
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); dim];
        for (j, c) in cols.iter_mut().enumerate() {
            c.push(j);
        }
        for &(r, c) in hess {
            cols[c].push(r);
        }
        for &(r, c) in jac {
            cols[c].push(n + r);
        }
        let mut col_ptr = Vec::with_capacity(dim + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for c in cols.iter_mut() {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let find = |r: usize, c: usize| -> usize {
            let s = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            col_ptr[c] + s.binary_search(&r).unwrap_or(0)
        };
        let hess_dst = hess.iter().map(|&(r, c)| find(r, c)).collect();
        let jac_dst = jac.iter().map(|&(r, c)| find(n + r, c)).collect();
        let diag_dst = (0..dim).map(|j| find(j, j)).collect();
        let nnz = row_idx.len();
        Ok(Self {
            n,
            m,
            mat: LowerCsc {
                dim,
                col_ptr,
                row_idx,
                values: vec![0.0; nnz],
            },
            hess_dst,
            jac_dst,
            diag_dst,
        })
    }

    /// Writes `K` for the given Hessian/Jacobian values, primal diagonal `diag_x` (Σ + δ_w) and
    /// dual diagonal `diag_y` (−δ_c).
    ///
    /// # Panics
    ///
    /// If `hess` or `jac` has fewer values than the pattern's triplets, or `diag_x` fewer than
    /// `n`.
    pub fn assemble(&mut self, hess: &[f64], jac: &[f64], diag_x: &[f64], diag_y: f64) {
        let v = &mut self.mat.values;
        v.iter_mut().for_each(|e| *e = 0.0);
        for (k, &d) in self.hess_dst.iter().enumerate() {
            v[d] += hess[k];
        }
        for (k, &d) in self.jac_dst.iter().enumerate() {
            v[d] += jac[k];
        }
        for j in 0..self.n {
            v[self.diag_dst[j]] += diag_x[j];
        }
        for i in 0..self.m {
            v[self.diag_dst[self.n + i]] += diag_y;
        }
    }

    /// Adds `delta` to every primal diagonal entry and `-delta_c_change` to every dual one
    /// (used by the inertia-correction loop without a full reassembly).
    pub fn shift_diagonal(&mut self, delta_w_change: f64, delta_c_change: f64) {
        shift(
            &mut self.mat.values,
            &self.diag_dst,
            self.n,
            delta_w_change,
            delta_c_change,
        );
    }

    /// Writes into `out` the values [`shift_diagonal`](KktPattern::shift_diagonal) would leave
    /// (bit for bit: the same operations), without changing the matrix.
    pub fn shifted_values(&self, delta_w_change: f64, delta_c_change: f64, out: &mut Vec<f64>) {
        out.clear();
        out.extend_from_slice(&self.mat.values);
        shift(out, &self.diag_dst, self.n, delta_w_change, delta_c_change);
    }
}

/// Adds `delta_w_change` to the primal diagonal entries (`diag_dst[..n]`) of `values` and
/// `-delta_c_change` to the dual ones.
fn shift(values: &mut [f64], diag_dst: &[usize], n: usize, dw: f64, dc: f64) {
    for &d in &diag_dst[..n] {
        values[d] += dw;
    }
    for &d in &diag_dst[n..] {
        values[d] -= dc;
    }
}
