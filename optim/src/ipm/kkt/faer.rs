//! faer 0.24's sparse Cholesky machinery for the KKT matrix: the symbolic analysis (fill-reducing
//! ordering, elimination tree, structure of `L`, simplicial or supernodal) that every backend
//! starts from, and faer's own numeric LDLᵀ and triangular solves ([`FaerFactor`]).
//!
//! faer's LDLᵀ does not pivot; tiny pivots are replaced by `±δ` (static pivoting through
//! `LdltRegularization`), and the inertia is read from the signs of `D` (Sylvester's law of
//! inertia; invariant under the symmetric permutation).

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltParams, LdltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};

use super::Inertia;
use crate::error::{FactorizationError, OptimError};

/// faer's symbolic analysis of one lower-triangle pattern, its value storage for `L` (faer's
/// layout) and the workspace of its numeric factorization and solve.
pub(super) struct FaerFactor {
    /// Shared with the copies of [`FaerFactor::duplicate`] (read-only after the analysis).
    pub(super) symbolic: Arc<SymbolicCholesky<usize>>,
    pub(super) l_values: Vec<f64>,
    mem: MemBuffer,
    pub(super) col_ptr: Vec<usize>,
    pub(super) row_idx: Vec<usize>,
}

impl FaerFactor {
    /// Symbolic analysis of the pattern with faer's simplicial/supernodal `threshold`, in the
    /// order `custom` (`custom[k]` = index eliminated k-th) or, for `None`, faer's AMD.
    pub(super) fn analyse(
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        threshold: SupernodalThreshold,
        custom: Option<&[usize]>,
    ) -> Result<Self, OptimError> {
        let pattern = SymbolicSparseColMatRef::new_checked(dim, dim, col_ptr, None, row_idx);
        let symbolic_with = |ordering| {
            factorize_symbolic_cholesky(
                pattern,
                Side::Lower,
                ordering,
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: threshold,
                    ..Default::default()
                },
            )
            .map_err(|e| OptimError::from(FactorizationError::SymbolicAnalysis(e)))
        };
        let symbolic = match custom {
            Some(fwd) => {
                let mut inv = vec![0usize; dim];
                for (k, &v) in fwd.iter().enumerate() {
                    inv[v] = k;
                }
                symbolic_with(SymmetricOrdering::Custom(PermRef::new_checked(
                    fwd, &inv, dim,
                )))?
            }
            None => symbolic_with(SymmetricOrdering::Amd)?,
        };
        let params: Spec<LdltParams, f64> = Default::default();
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, params),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req)
            .map_err(|_| OptimError::from(FactorizationError::OutOfMemory))?;
        Ok(Self {
            l_values: vec![0.0; symbolic.len_val()],
            symbolic: Arc::new(symbolic),
            mem,
            col_ptr: col_ptr.to_vec(),
            row_idx: row_idx.to_vec(),
        })
    }

    /// A copy of the analysis with its own value storage and workspace (no factor): what
    /// [`FaerFactor::analyse`] of the same pattern and order returns, without the ordering
    /// work. `None` if the workspace cannot be allocated.
    pub(super) fn duplicate(&self) -> Option<Self> {
        let params: Spec<LdltParams, f64> = Default::default();
        let req = StackReq::any_of(&[
            self.symbolic
                .factorize_numeric_ldlt_scratch::<f64>(Par::Seq, params),
            self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        Some(Self {
            symbolic: Arc::clone(&self.symbolic),
            l_values: vec![0.0; self.l_values.len()],
            mem: MemBuffer::try_new(req).ok()?,
            col_ptr: self.col_ptr.clone(),
            row_idx: self.row_idx.clone(),
        })
    }

    /// Whether faer 0.24's symbolic analysis with `SupernodalThreshold::AUTO` would choose
    /// its supernodal variant in this analysis's order, decided on this (simplicial) analysis
    /// by faer's rule (`factorize_symbolic_cholesky`): more than [`AUTO_SUPERNODAL_RATIO`]
    /// operations per entry of `L`, the operations counted by AMD where the order is AMD's
    /// (`amd_flops`, from [`ordering::amd_order_counted`](super::ordering::amd_order_counted)),
    /// else `Σ_j (c_j + c_j (c_j + 1) / 2)` over the column counts `c_j` of `L` (diagonal
    /// included). Replicated so that one simplicial analysis serves both the choice and the
    /// kernel: with faer's own rule a supernodal choice had to be analysed a second time as
    /// simplicial (decision record 0094). A test checks it against faer's choice.
    pub(super) fn auto_supernodal(&self, amd_flops: Option<f64>) -> bool {
        let SymbolicCholeskyRaw::Simplicial(s) = self.symbolic.raw() else {
            return self.is_supernodal();
        };
        let cp = s.col_ptr();
        let counts = (0..s.nrows()).map(|k| (cp[k + 1] - cp[k]) as u128);
        let nnz: u128 = counts.clone().sum();
        let flops = amd_flops.unwrap_or_else(|| {
            let n_mult: u128 = counts.map(|c| c * (c + 1) / 2).sum();
            nnz as f64 + n_mult as f64
        });
        flops / nnz as f64 > SupernodalThreshold::AUTO.0 * AUTO_SUPERNODAL_RATIO
    }

    /// Whether the analysis chose the supernodal variant.
    pub(super) fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// `Σ_j (c_j + c_j²/2)` over the column counts `c_j` of `L` (for the supernodal factor the
    /// counts include the explicit zeros of relaxed supernodes).
    pub(super) fn flops(&self) -> f64 {
        let mut flops = 0.0;
        let mut add = |c: usize| {
            let c = c as f64;
            flops += c + 0.5 * c * c;
        };
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                for k in 0..s.nrows() {
                    add(cp[k + 1] - cp[k]);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let begin = s.supernode_begin();
                let end = s.supernode_end();
                let vp = s.col_ptr_for_val();
                for k in 0..s.n_supernodes() {
                    let ncols = end[k] - begin[k];
                    let nrows = (vp[k + 1] - vp[k]) / ncols.max(1);
                    for j in 0..ncols {
                        add(nrows - j);
                    }
                }
            }
        }
        flops
    }

    /// Counts signs of `D` in `l_values`. For the simplicial factor `D[k]` is the first stored
    /// entry of column k; for the supernodal factor it is the diagonal of each supernode's
    /// leading square block (column-major `nrows × ncols` block at `col_ptr_for_val[s]`).
    pub(super) fn inertia(&self) -> Inertia {
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
        match self.symbolic.raw() {
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

    /// faer's numeric LDLᵀ with static pivoting (|d| ≤ `eps` → ±`delta`); the inertia, or
    /// `None` on failure or a zero pivot.
    pub(super) fn factor(&mut self, values: &[f64], eps: f64, delta: f64) -> Option<Inertia> {
        let n = self.symbolic.nrows();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            values,
        );
        let stack = MemStack::new(&mut self.mem);
        let regularization = LdltRegularization {
            dynamic_regularization_signs: None,
            dynamic_regularization_delta: delta,
            dynamic_regularization_epsilon: eps,
        };
        let res = self.symbolic.factorize_numeric_ldlt(
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
        // Zero pivots are judged by the caller (`SparseLdlt::factor_numeric`), as for the
        // other kernels.
        Some(self.inertia())
    }

    /// faer's triangular solves with the last factor in `l_values`.
    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let ldlt = LdltRef::<usize, f64>::new(&self.symbolic, &self.l_values);
        let stack = MemStack::new(&mut self.mem);
        ldlt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
    }
}

/// faer 0.24's `CHOLESKY_SUPERNODAL_RATIO_FACTOR` (private there): operations per entry of `L`
/// above which `SupernodalThreshold::AUTO` chooses the supernodal factor.
pub(super) const AUTO_SUPERNODAL_RATIO: f64 = 40.0;
