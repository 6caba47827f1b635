//! KKT system of the interior-point Newton step (Wächter & Biegler 2006, eq. (13)):
//!
//! ```text
//! K(δ_w, δ_c) = [ W + Σ + δ_w I    Jᵀ    ]      W = ∇²ₓₓL (σ_f, y),  Σ = Z_L S_L⁻¹ + Z_U S_U⁻¹
//!               [ J               −δ_c I ]      J = ∇c(x)ᵀ
//! ```
//!
//! * [`KktPattern`]: the lower-triangle CSC pattern of `K`, built once from the Hessian and Jacobian
//!   triplet patterns, with scatter maps so that each iteration's assembly is one pass over the
//!   user values (duplicates are summed, as in Ipopt's triplet convention).
//! * [`KktSolver`]: the small factor/solve interface used by the IPM (symbolic analysis once,
//!   numeric refactorization per iteration, inertia of the factor).
//! * [`FaerLdlt`]: the implementation on faer 0.24's sparse LDLᵀ (AMD ordering, supernodal or
//!   simplicial by flop ratio). faer's LDLᵀ does not pivot, so the inertia is read from the signs of
//!   `D` (Sylvester's law of inertia; invariant under the symmetric AMD permutation) and the IPM does
//!   the δ_w/δ_c correction itself.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltParams, LdltRegularization};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};

use crate::error::OptimError;

/// Inertia of a symmetric matrix: numbers of positive, negative and zero eigenvalues.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Inertia {
    /// Number of positive eigenvalues.
    pub positive: usize,
    /// Number of negative eigenvalues.
    pub negative: usize,
    /// Number of zero eigenvalues (zero or non-finite pivots).
    pub zero: usize,
}

/// A symmetric sparse matrix in lower-triangle CSC form (rows sorted within each column).
#[derive(Debug, Clone)]
pub struct LowerCsc {
    /// Dimension.
    pub dim: usize,
    /// Column pointers (`dim + 1` entries).
    pub col_ptr: Vec<usize>,
    /// Row indices (each ≥ its column index, sorted within a column).
    pub row_idx: Vec<usize>,
    /// Values (same length as `row_idx`).
    pub values: Vec<f64>,
}

impl LowerCsc {
    /// `out = K x` for the symmetric matrix whose lower triangle is stored.
    pub fn sym_matvec(&self, x: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..self.dim {
            let xj = x[j];
            let mut acc = 0.0;
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                let v = self.values[p];
                out[i] += v * xj;
                if i != j {
                    acc += v * x[i];
                }
            }
            out[j] += acc;
        }
    }
}

/// Interface of a sparse symmetric indefinite solver for the KKT matrix.
///
/// Call order: [`analyse`](KktSolver::analyse) once per sparsity pattern, then any number of
/// [`factor`](KktSolver::factor) (same pattern, new values) each followed by any number of
/// [`solve`](KktSolver::solve).
pub trait KktSolver {
    /// Symbolic analysis (ordering, elimination tree, storage) of the lower-triangle pattern.
    fn analyse(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<(), OptimError>;
    /// Numeric factorization of the matrix with the analysed pattern and these values.
    ///
    /// Returns the inertia of the computed factor, or `None` when a pivot was exactly zero or
    /// non-finite (the matrix is treated as singular and the factor is unusable).
    fn factor(&mut self, values: &[f64]) -> Option<Inertia>;
    /// Solves `K x = rhs` in place with the last successful factorization.
    fn solve(&mut self, rhs: &mut [f64]);
}

/// faer 0.24 sparse LDLᵀ behind [`KktSolver`]: symbolic analysis (AMD) once, numeric
/// refactorization per call, one workspace buffer allocated at analysis time.
pub struct FaerLdlt {
    symbolic: Option<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    mem: Option<MemBuffer>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    factored: bool,
    /// Force the simplicial (`Some(false)`) or supernodal (`Some(true)`) variant; `None` = automatic.
    pub supernodal: Option<bool>,
    /// Static pivoting: pivots with |d| ≤ `pivot_epsilon` are replaced by `±pivot_delta`
    /// (absolute values; sign kept, zero → +; not relative to max|K_ij|, which the barrier
    /// terms Σ make as large as 1e10). Structurally zero diagonals (states
    /// without cost in collocation NLPs) otherwise stop the unpivoted LDLᵀ when AMD eliminates
    /// them first; the caller refines against the exact matrix. 0 disables (exact zero pivots
    /// then report a singular matrix).
    pub pivot_epsilon: f64,
    /// Replacement magnitude for tiny pivots (see `pivot_epsilon`).
    pub pivot_delta: f64,
}

impl std::fmt::Debug for FaerLdlt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaerLdlt")
            .field("dim", &self.col_ptr.len().saturating_sub(1))
            .field("nnz", &self.row_idx.len())
            .field("factor_nnz", &self.l_values.len())
            .field("supernodal", &self.is_supernodal())
            .finish()
    }
}

impl Default for FaerLdlt {
    fn default() -> Self {
        Self::new()
    }
}

impl FaerLdlt {
    /// A solver that picks simplicial/supernodal automatically (faer's flop-ratio rule).
    pub fn new() -> Self {
        Self {
            symbolic: None,
            l_values: Vec::new(),
            mem: None,
            col_ptr: Vec::new(),
            row_idx: Vec::new(),
            factored: false,
            supernodal: None,
            pivot_epsilon: 1e-14,
            pivot_delta: 1e-4,
        }
    }

    /// Whether the symbolic analysis chose the supernodal variant.
    pub fn is_supernodal(&self) -> bool {
        matches!(
            self.symbolic.as_ref().map(|s| s.raw()),
            Some(SymbolicCholeskyRaw::Supernodal(_))
        )
    }

    /// Number of stored entries of the factor `L` (fill-in measure).
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Counts signs of `D`. For the simplicial factor `D[k]` is the first stored entry of column k;
    /// for the supernodal factor it is the diagonal of each supernode's leading square block
    /// (column-major `nrows × ncols` block at `col_ptr_for_val[s]`).
    fn inertia(&self) -> Inertia {
        let mut inertia = Inertia::default();
        let mut count = |d: f64| {
            if d > 0.0 {
                inertia.positive += 1;
            } else if d < 0.0 {
                inertia.negative += 1;
            } else {
                inertia.zero += 1;
            }
        };
        let Some(sym) = self.symbolic.as_ref() else {
            return inertia;
        };
        match sym.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                for k in 0..s.nrows() {
                    count(self.l_values[cp[k]]);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let begin = s.supernode_begin();
                let end = s.supernode_end();
                let vp = s.col_ptr_for_val();
                for k in 0..s.n_supernodes() {
                    let ncols = end[k] - begin[k];
                    let block = &self.l_values[vp[k]..vp[k + 1]];
                    let nrows = block.len() / ncols.max(1);
                    for j in 0..ncols {
                        count(block[j * nrows + j]);
                    }
                }
            }
        }
        inertia
    }
}

impl KktSolver for FaerLdlt {
    fn analyse(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<(), OptimError> {
        // Same pattern as the last analysis (repeated solves of one NLP structure): keep the
        // symbolic factorization and the workspace.
        if self.symbolic.is_some() && self.col_ptr == col_ptr && self.row_idx == row_idx {
            self.factored = false;
            return Ok(());
        }
        self.col_ptr = col_ptr.to_vec();
        self.row_idx = row_idx.to_vec();
        let pattern =
            SymbolicSparseColMatRef::new_checked(dim, dim, &self.col_ptr, None, &self.row_idx);
        let threshold = match self.supernodal {
            None => SupernodalThreshold::AUTO,
            Some(true) => SupernodalThreshold::FORCE_SUPERNODAL,
            Some(false) => SupernodalThreshold::FORCE_SIMPLICIAL,
        };
        let sym = factorize_symbolic_cholesky(
            pattern,
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: threshold,
                ..Default::default()
            },
        )
        .map_err(|e| OptimError::Factorization(format!("symbolic analysis failed: {e:?}")))?;
        let params: Spec<LdltParams, f64> = Default::default();
        let req = StackReq::any_of(&[
            sym.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, params),
            sym.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        self.mem = Some(MemBuffer::try_new(req).map_err(|_| {
            OptimError::Factorization("out of memory for the KKT workspace".into())
        })?);
        self.l_values = vec![0.0; sym.len_val()];
        self.symbolic = Some(sym);
        self.factored = false;
        Ok(())
    }

    fn factor(&mut self, values: &[f64]) -> Option<Inertia> {
        self.factored = false;
        let sym = self.symbolic.as_ref()?;
        let mem = self.mem.as_mut()?;
        let n = sym.nrows();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            values,
        );
        let stack = MemStack::new(mem);
        let regularization = LdltRegularization {
            dynamic_regularization_signs: None,
            dynamic_regularization_delta: self.pivot_delta,
            dynamic_regularization_epsilon: self.pivot_epsilon,
        };
        let res = sym.factorize_numeric_ldlt(
            &mut self.l_values,
            a,
            Side::Lower,
            regularization,
            Par::Seq,
            stack,
            Default::default(),
        );
        if res.is_err() {
            return None;
        }
        let inertia = self.inertia();
        if inertia.zero > 0 {
            return None;
        }
        self.factored = true;
        Some(inertia)
    }

    fn solve(&mut self, rhs: &mut [f64]) {
        let (Some(sym), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return;
        };
        debug_assert!(self.factored);
        let n = rhs.len();
        let ldlt = LdltRef::<usize, f64>::new(sym, &self.l_values);
        let stack = MemStack::new(mem);
        ldlt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
    }
}

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
    pub fn new(n: usize, m: usize, hess: &[(usize, usize)], jac: &[(usize, usize)]) -> Self {
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
        Self {
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
        }
    }

    /// Writes `K` for the given Hessian/Jacobian values, primal diagonal `diag_x` (Σ + δ_w) and
    /// dual diagonal `diag_y` (−δ_c).
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
        for j in 0..self.n {
            self.mat.values[self.diag_dst[j]] += delta_w_change;
        }
        for i in 0..self.m {
            self.mat.values[self.diag_dst[self.n + i]] -= delta_c_change;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Dense inertia by Gaussian elimination with symmetric (diagonal) Bunch–Parlett-free
    /// eigen-free counting: Sylvester on a dense LDLᵀ with full symmetric pivoting by largest
    /// diagonal is not always possible, so use the Jacobi eigenvalue method (independent of faer).
    fn dense_eigs(a: &mut [Vec<f64>]) -> Vec<f64> {
        let n = a.len();
        for _sweep in 0..100 {
            let mut off = 0.0;
            for i in 0..n {
                for j in 0..n {
                    if i != j {
                        off += a[i][j] * a[i][j];
                    }
                }
            }
            if off < 1e-22 {
                break;
            }
            for p in 0..n {
                for q in p + 1..n {
                    if a[p][q].abs() < 1e-300 {
                        continue;
                    }
                    let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                    let t = if theta == 0.0 { 1.0 } else { t };
                    let c = 1.0 / (t * t + 1.0).sqrt();
                    let s = t * c;
                    for k in 0..n {
                        let akp = a[k][p];
                        let akq = a[k][q];
                        a[k][p] = c * akp - s * akq;
                        a[k][q] = s * akp + c * akq;
                    }
                    for k in 0..n {
                        let apk = a[p][k];
                        let aqk = a[q][k];
                        a[p][k] = c * apk - s * aqk;
                        a[q][k] = s * apk + c * aqk;
                    }
                }
            }
        }
        (0..n).map(|i| a[i][i]).collect()
    }

    fn check(
        n: usize,
        m: usize,
        hess: &[(usize, usize, f64)],
        jac: &[(usize, usize, f64)],
        sup: Option<bool>,
    ) {
        let hp: Vec<_> = hess.iter().map(|&(r, c, _)| (r, c)).collect();
        let jp: Vec<_> = jac.iter().map(|&(r, c, _)| (r, c)).collect();
        let hv: Vec<_> = hess.iter().map(|&(_, _, v)| v).collect();
        let jv: Vec<_> = jac.iter().map(|&(_, _, v)| v).collect();
        let mut pat = KktPattern::new(n, m, &hp, &jp);
        pat.assemble(&hv, &jv, &vec![0.0; n], -1e-9);
        let dim = n + m;
        let mut dense = vec![vec![0.0; dim]; dim];
        for j in 0..dim {
            for p in pat.mat.col_ptr[j]..pat.mat.col_ptr[j + 1] {
                let i = pat.mat.row_idx[p];
                dense[i][j] += pat.mat.values[p];
                if i != j {
                    dense[j][i] += pat.mat.values[p];
                }
            }
        }
        let eig = dense_eigs(&mut dense.clone());
        let expect = Inertia {
            positive: eig.iter().filter(|&&e| e > 0.0).count(),
            negative: eig.iter().filter(|&&e| e < 0.0).count(),
            zero: 0,
        };
        let mut s = FaerLdlt {
            supernodal: sup,
            ..Default::default()
        };
        s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        let inertia = s.factor(&pat.mat.values).expect("nonsingular");
        assert_eq!(inertia, expect, "supernodal={sup:?}");
        let b: Vec<f64> = (0..dim).map(|i| (i as f64 * 0.37).sin() + 0.1).collect();
        let mut x = b.clone();
        s.solve(&mut x);
        let mut r = vec![0.0; dim];
        // Unpivoted LDLᵀ on an indefinite matrix loses a few digits; two refinement steps
        // (as the IPM does) recover them.
        for _ in 0..2 {
            pat.mat.sym_matvec(&x, &mut r);
            let mut c: Vec<f64> = b.iter().zip(&r).map(|(b, r)| b - r).collect();
            s.solve(&mut c);
            x.iter_mut().zip(&c).for_each(|(x, c)| *x += c);
        }
        pat.mat.sym_matvec(&x, &mut r);
        let res = r
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(res < 1e-8, "residual {res}");
    }

    #[test]
    fn inertia_matches_dense_eigenvalues() {
        // H indefinite 4x4 (tridiagonal), 2 constraints; both factor variants.
        let hess = vec![
            (0, 0, 2.0),
            (1, 1, -1.0),
            (2, 2, 3.0),
            (3, 3, 0.5),
            (1, 0, 0.3),
            (2, 1, 0.7),
            (3, 2, -0.2),
            (3, 3, 0.1), // duplicate entry: summed
        ];
        let jac = vec![
            (0, 0, 1.0),
            (0, 1, 2.0),
            (1, 2, 1.0),
            (1, 3, -1.0),
            (1, 1, 0.5),
        ];
        for sup in [None, Some(true), Some(false)] {
            check(4, 2, &hess, &jac, sup);
        }
        // Larger banded system whose inertia changes with the diagonal shift.
        let n = 60;
        let m = 20;
        let mut hess = Vec::new();
        for i in 0..n {
            hess.push((
                i,
                i,
                if i % 7 == 0 {
                    -2.0
                } else {
                    4.0 + (i as f64).cos()
                },
            ));
            if i + 1 < n {
                hess.push((i + 1, i, 0.9));
            }
            if i + 5 < n {
                hess.push((i + 5, i, -0.4));
            }
        }
        let mut jac = Vec::new();
        for r in 0..m {
            for k in 0..4 {
                jac.push((
                    r,
                    (3 * r + k * 2) % n,
                    1.0 + 0.1 * k as f64 + 0.01 * r as f64,
                ));
            }
        }
        for sup in [Some(true), Some(false)] {
            check(n, m, &hess, &jac, sup);
        }
    }

    #[test]
    fn singular_matrix_is_reported() {
        // x-block zero and no constraint coupling on variable 1: exact zero pivot.
        let mut pat = KktPattern::new(2, 1, &[], &[(0, 0)]);
        pat.assemble(&[], &[1.0], &[0.0, 0.0], 0.0);
        let mut s = FaerLdlt {
            pivot_epsilon: 0.0,
            pivot_delta: 0.0,
            ..FaerLdlt::new()
        };
        s.analyse(3, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
        assert!(s.factor(&pat.mat.values).is_none());
    }

    /// Structurally zero primal diagonals (variables without curvature, like collocation states
    /// without cost): static pivoting keeps the factorization alive, the inertia stays (n, m)
    /// and iterative refinement recovers the exact solution.
    #[test]
    fn static_pivoting_with_zero_primal_diagonal() {
        // chain: x0 -(c0)- x1 -(c1)- x2, cost only on x2; n = 3, m = 2, H = diag(0, 0, 1)
        let hess = [(2, 2)];
        let jac = [(0, 0), (0, 1), (1, 1), (1, 2)];
        let mut pat = KktPattern::new(3, 2, &hess, &jac);
        pat.assemble(&[1.0], &[1.0, -1.0, 1.0, -1.0], &[0.0; 3], -1e-9);
        for sup in [Some(true), Some(false)] {
            let mut s = FaerLdlt {
                supernodal: sup,
                ..FaerLdlt::new()
            };
            s.analyse(5, &pat.mat.col_ptr, &pat.mat.row_idx).unwrap();
            // With pivoting disabled the zero pivot (if eliminated first) would stop LDLᵀ;
            // with it the factor exists and has the KKT inertia.
            let inertia = s.factor(&pat.mat.values).expect("factor");
            assert_eq!(
                inertia,
                Inertia {
                    positive: 3,
                    negative: 2,
                    zero: 0
                }
            );
            let b = [1.0, -2.0, 0.5, 0.3, -0.7];
            let mut x = b;
            s.solve(&mut x);
            let mut r = [0.0; 5];
            for _ in 0..5 {
                pat.mat.sym_matvec(&x, &mut r);
                let mut c: Vec<f64> = b.iter().zip(&r).map(|(b, r)| b - r).collect();
                s.solve(&mut c);
                for i in 0..5 {
                    x[i] += c[i];
                }
            }
            pat.mat.sym_matvec(&x, &mut r);
            let res = r
                .iter()
                .zip(&b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(res < 1e-12, "refined residual {res}");
        }
    }
}
