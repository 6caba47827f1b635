//! KKT system of the interior-point Newton step (Wächter & Biegler 2006, eq. (13)):
//!
//! ```text
//! K(δ_w, δ_c) = [ W + Σ + δ_w I    Jᵀ    ]      W = ∇²ₓₓL (σ_f, y),  Σ = Z_L S_L⁻¹ + Z_U S_U⁻¹
//!               [ J               −δ_c I ]      J = ∇c(x)ᵀ
//! ```
//!
//! The IPM needs `K`'s inertia (W&B Sect. 3.1, Algorithm IC: the step is a descent direction
//! when `K` has exactly n positive and m negative eigenvalues) and solves with it.
//!
//! * [`pattern`]: [`KktPattern`], the lower-triangle CSC pattern of `K` and its assembly.
//! * [`KktSolver`]: the factor/solve interface the IPM uses, in typed phases: symbolic
//!   analysis once per pattern (a [`SparseLdlt`] keeps the analyses of its last
//!   [`KEPT_ANALYSES`] other patterns too; one AMD ordering and one symbolic factorization,
//!   which the pivot pairs' analysis of the same pattern starts from through
//!   [`SparseLdlt::analyse_in_amd_order`], decision record 0094), numeric refactorization
//!   per iteration returning the inertia of the factor or a [`FactorizationFailure`] that
//!   says why there is none, solves that refuse without a current factor.
//! * [`LdltOptions`]: what a [`SparseLdlt`] is (backend, [`LdltOrdering`], static pivoting,
//!   pivot threshold, amalgamation), fixed at construction, so an analysis can never belong
//!   to other options than the solver's; defaults as constants (`DEFAULT_*`).
//! * [`SparseLdlt`]: the implementation, an LDLᵀ `P K Pᵀ = L D Lᵀ` with a fill-reducing
//!   symmetric permutation `P` from faer 0.24's AMD, and `D` with 1 × 1 pivots and, where the
//!   order asks for them, 2 × 2 pivots on (variable, constraint row) pairs; the inertia is
//!   the sign count of the 1 × 1 pivots plus (1, 1) for each 2 × 2 pivot of negative
//!   determinant (Sylvester's law of inertia). Tiny 1 × 1 pivots are replaced by
//!   `±pivot_delta` (static pivoting); the IPM refines each solve against the exact matrix.
//!   The numeric factorization is one of the [`LdltBackend`]s:
//!   * `simplicial`: faer's up-looking simplicial algorithm on data prepared once per pattern,
//!     bitwise faer's factor and solution (1 × 1 pivots only);
//!   * `supernodal`: a left-looking supernodal LDLᵀ on the fundamental supernodes of the same
//!     simplicial structure (dense element blocks of Legendre–Gauss KKTs), with 2 × 2 pivots;
//!     with [`LdltOptions::parallel`] its widest supernodes are shared with a second thread,
//!     each thread on its own columns, and the small supernodes between them are divided
//!     into pairs of independent ranges, one per thread: the same factor bit for bit
//!     (decision records 0090 and 0091);
//!   * `faer`: faer's own numeric factorization and solve (reference and fallback);
//!   * `multifrontal`: a multifrontal LDLᵀ with threshold Bunch–Kaufman pivoting (1 × 1 and
//!     2 × 2 pivots among each front's fully summed columns, MA57's test with threshold
//!     `pivot_threshold`) and delayed pivots: a pivot that fails the test is passed to the
//!     parent front, so the order is AMD's (or the pairs' order below) modified numerically,
//!     every entry of `L` is bounded by `1/u` outside the root front, and the sign count is
//!     the inertia of `K` for any δ_c ≥ 0 (no bare −δ_c pivot and no pair with
//!     `det ≈ −Σ δ_c` can pass the test). Supernodes are amalgamated (`amalgamation`).
//! * [`Speculator`] (`speculative`): a second thread that factors, with a
//!   [`SparseLdlt::duplicate`] of the solver, the matrix the inertia correction would factor
//!   next, so that a rejected trial's successor is ready when it is asked for (bit for bit the
//!   factor the solver would compute; decision record 0036). It gives way where the
//!   factorization itself is shared ([`SparseLdlt::shares_factorization`]).
//! * `ordering`: the elimination order. With plain AMD a constraint row eliminated before all
//!   of its primal variables has the pivot exactly `−δ_c`, and for a small δ_c the update
//!   `Jᵢᵀ Jᵢ / δ_c` swamps the reduced Hessian's curvature in rounding, so the sign count no
//!   longer matches the inertia of `K`. With `constraint_rows_from` set, either such a row is
//!   delayed to the first of its variables in AMD's order and eliminated with it in one 2 × 2
//!   pivot `[d a; a −δ_c]` (`pivot_pairs`; determinant `−d δ_c − a² < 0` for `d ≥ 0`, inverse
//!   entries of order `1/|a|`), or AMD orders the graph of (variable, row) pairs and each row
//!   follows its variable (1 × 1 pivots). Both cost more fill than AMD alone.

mod faer;
mod multifrontal;
mod ordering;
pub mod pattern;
mod simplicial;
mod speculative;
mod supernodal;
#[cfg(test)]
mod tests;

use ::faer::sparse::linalg::SupernodalThreshold;

use self::faer::FaerFactor;
use self::multifrontal::MultifrontalPlan;
pub use self::pattern::KktPattern;
use self::simplicial::SimplicialPlan;
use self::speculative::CoreWatch;
pub use self::speculative::{MIN_SPECULATION_FLOPS, Speculator};
use self::supernodal::BlockPlan;
use crate::error::{FactorizationError, OptimError};

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

/// Why a numeric factorization produced no usable factor (data, so a caller can tell a
/// singular matrix from a misuse).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FactorizationFailure {
    /// No symbolic analysis yet: [`KktSolver::analyse`] must come first.
    NotAnalysed,
    /// The values hold a non-finite entry (at this index of the pattern's values).
    NonFiniteValue {
        /// Index into the values array.
        index: usize,
    },
    /// A pivot was exactly zero or non-finite and could not be replaced (static pivoting off,
    /// or a 2 × 2 pivot block that is singular): the matrix is singular to working precision.
    SingularPivot,
    /// The factor exists but has this many zero pivots, so its inertia has zero eigenvalues
    /// and it cannot be solved with.
    ZeroPivots {
        /// Number of zero pivots.
        count: usize,
    },
    /// The values array does not have one entry per entry of the analysed pattern.
    ValueCount {
        /// Entries of the analysed pattern.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// The right-hand side of a solve does not have one entry per row of the matrix.
    RhsLength {
        /// Rows of the analysed matrix.
        expected: usize,
        /// Entries given.
        got: usize,
    },
}

impl std::fmt::Display for FactorizationFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotAnalysed => write!(f, "no symbolic analysis before the factorization"),
            Self::NonFiniteValue { index } => write!(f, "non-finite matrix entry at value {index}"),
            Self::SingularPivot => write!(f, "a zero or non-finite pivot (singular matrix)"),
            Self::ZeroPivots { count } => write!(f, "{count} zero pivots"),
            Self::ValueCount { expected, got } => {
                write!(f, "{got} matrix values for a pattern of {expected} entries")
            }
            Self::RhsLength { expected, got } => {
                write!(f, "a right-hand side of {got} entries for {expected} rows")
            }
        }
    }
}

/// Interface of a sparse symmetric indefinite solver for the KKT matrix, in three typed phases.
///
/// Call order: [`analyse`](KktSolver::analyse) once per sparsity pattern (the symbolic
/// phase: ordering, elimination tree, storage), then any number of
/// [`factor`](KktSolver::factor) (same pattern, new values: the numeric phase), each
/// followed by any number of [`solve`](KktSolver::solve).
pub trait KktSolver {
    /// Symbolic analysis (ordering, elimination tree, storage) of the lower-triangle pattern
    /// of dimension `dim` ([`LowerCsc`]: `dim + 1` column pointers rising from 0 to the
    /// number of row indices, rows strictly increasing within a column, none above the
    /// diagonal or beyond `dim`). A malformed pattern is an error
    /// ([`OptimError::DimensionMismatch`], [`OptimError::InvalidColumnPointers`] or
    /// [`OptimError::InvalidPattern`]), as is a failed analysis
    /// ([`OptimError::Factorization`]).
    fn analyse(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<(), OptimError>;
    /// Numeric factorization of the matrix with the analysed pattern and these values: the
    /// inertia of the computed factor, or why there is no usable factor.
    fn factor(&mut self, values: &[f64]) -> Result<Inertia, FactorizationFailure>;
    /// Solves `K x = rhs` in place with the last factorization; fails (leaving `rhs` as it
    /// was) when that factorization failed or none was made, or when `rhs` does not have one
    /// entry per row.
    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), FactorizationFailure>;
}

/// The elimination order of a [`SparseLdlt`] (module docs, "ordering").
#[derive(Debug, Clone, PartialEq, Default)]
pub enum LdltOrdering {
    /// faer's AMD on the whole KKT pattern.
    #[default]
    Amd,
    /// AMD on the graph of (variable, constraint row) pairs, each constraint row eliminated
    /// right after a primal neighbour (1 × 1 pivots). With
    /// [`LdltBackend::Multifrontal`] the kernel starts from the order of
    /// [`AmdPivotPairs`](LdltOrdering::AmdPivotPairs) instead and pivots numerically.
    PairedAmd {
        /// Index of the first constraint row (the primal dimension n).
        constraint_rows_from: usize,
        /// Primal variables preferred as the variable a row follows (e.g. those with a bound,
        /// whose pivot carries the barrier term Σ > 0); empty: none preferred.
        preferred_primal: Vec<bool>,
    },
    /// AMD's order, except that each constraint row AMD places before all its primal
    /// neighbours is delayed to the first of them and eliminated with it in a 2 × 2 pivot
    /// (supernodal kernel).
    AmdPivotPairs {
        /// Index of the first constraint row (the primal dimension n).
        constraint_rows_from: usize,
    },
}

impl LdltOrdering {
    /// The first constraint row, for the orders that pair rows with variables.
    pub fn constraint_rows_from(&self) -> Option<usize> {
        match self {
            Self::Amd => None,
            Self::PairedAmd {
                constraint_rows_from,
                ..
            }
            | Self::AmdPivotPairs {
                constraint_rows_from,
            } => Some(*constraint_rows_from),
        }
    }
}

/// Default of [`LdltOptions::pivot_epsilon`].
pub const DEFAULT_PIVOT_EPSILON: f64 = 1e-14;
/// Default of [`LdltOptions::pivot_delta`].
pub const DEFAULT_PIVOT_DELTA: f64 = 1e-4;
/// Default of [`LdltOptions::pivot_threshold`] (IPOPT's `ma57_pivtol`).
pub const DEFAULT_PIVOT_THRESHOLD: f64 = 1e-8;
/// Default of [`LdltOptions::amalgamation`].
pub const DEFAULT_AMALGAMATION: usize = 16;

/// What a [`SparseLdlt`] is: fixed when it is made ([`SparseLdlt::with_options`]), so a
/// symbolic analysis always belongs to the options it was made with.
#[derive(Debug, Clone, PartialEq)]
pub struct LdltOptions {
    /// Numeric algorithm (default: [`LdltBackend::Auto`]).
    pub backend: LdltBackend,
    /// Elimination order (default: [`LdltOrdering::Amd`]).
    pub ordering: LdltOrdering,
    /// Static pivoting: pivots with |d| ≤ `pivot_epsilon` are replaced by `±pivot_delta`
    /// (absolute values; sign kept, zero → +; not relative to max|K_ij|, which the barrier
    /// terms Σ make as large as 1e10). Structurally zero diagonals (states without cost in
    /// collocation NLPs) otherwise stop the unpivoted LDLᵀ when the ordering eliminates them
    /// first; the caller refines against the exact matrix. 0 disables (exact zero pivots then
    /// report a singular matrix). Default [`DEFAULT_PIVOT_EPSILON`].
    pub pivot_epsilon: f64,
    /// Replacement magnitude for tiny pivots (see `pivot_epsilon`). Default
    /// [`DEFAULT_PIVOT_DELTA`].
    pub pivot_delta: f64,
    /// Threshold `u` of the pivot test of [`LdltBackend::Multifrontal`] (a 1 × 1 pivot must be
    /// at least `u` times the largest other entry of its column; 2 × 2 pivots alike), clamped
    /// to (0, 0.5]; default [`DEFAULT_PIVOT_THRESHOLD`] (MA57's own 0.01 and 1e-4 delay so many
    /// pivots of the collocation KKTs that the fill triples, BENCHMARKS.md). With it a −δ_c
    /// pivot of δ_c = 1e-9 fails beside entries above 0.1, and a (variable, row) pair with
    /// `|B⁻¹| ≈ Σ/(Σ δ_c + a²)` fails for Σ = 1e10 beside entries above 0.1 as well; larger
    /// growth than that is left to iterative refinement.
    pub pivot_threshold: f64,
    /// Amalgamation of [`LdltBackend::Multifrontal`]: a supernode and its parent are merged
    /// into one front while both have fewer than this many columns (MA57's `nemin`; 1: the
    /// fundamental supernodes only). Default [`DEFAULT_AMALGAMATION`].
    pub amalgamation: usize,
    /// Share the factorization of the supernodal kernel's widest supernodes (the dense
    /// blocks of Legendre–Gauss collocation), and of pairs of independent ranges of the
    /// small supernodes between them (decision record 0091), with a second thread, when the
    /// solver runs on a thread of its own (not a worker of a rayon pool, whose other workers
    /// keep the cores busy) and the machine has two cores: the same factor bit for bit
    /// ([`SparseLdlt::shares_factorization`], decision record 0090). Default `true`.
    pub parallel: bool,
}

impl Default for LdltOptions {
    fn default() -> Self {
        Self {
            backend: LdltBackend::Auto,
            ordering: LdltOrdering::Amd,
            pivot_epsilon: DEFAULT_PIVOT_EPSILON,
            pivot_delta: DEFAULT_PIVOT_DELTA,
            pivot_threshold: DEFAULT_PIVOT_THRESHOLD,
            amalgamation: DEFAULT_AMALGAMATION,
            parallel: true,
        }
    }
}

/// Numeric LDLᵀ algorithm of a [`SparseLdlt`]. All backends use the same ordering, pivot rule
/// and inertia count; they differ in speed and rounding only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LdltBackend {
    /// [`Supernodal`](LdltBackend::Supernodal) where faer's flop-ratio rule would choose its
    /// supernodal factor (dense Legendre–Gauss blocks), [`Simplicial`](LdltBackend::Simplicial)
    /// elsewhere (the sparser hp-Radau KKTs).
    #[default]
    Auto,
    /// Up-looking simplicial LDLᵀ on data prepared once per pattern; bitwise faer's simplicial
    /// factor and solution.
    Simplicial,
    /// Left-looking supernodal LDLᵀ on the fundamental supernodes of the simplicial structure
    /// (no relaxation zeros); different rounding from the simplicial backend.
    Supernodal,
    /// faer's own simplicial numeric factorization and solve.
    FaerSimplicial,
    /// faer's own supernodal numeric factorization and solve.
    FaerSupernodal,
    /// Multifrontal LDLᵀ on the fundamental supernodes of the simplicial structure with
    /// threshold Bunch–Kaufman 1 × 1 / 2 × 2 pivoting among each front's fully summed columns
    /// and delayed pivots (`multifrontal`): the order is AMD's, modified at factorization time
    /// wherever a pivot fails the test [`LdltOptions::pivot_threshold`]; bounded growth and the
    /// inertia of the matrix for any δ_c ≥ 0. With `constraint_rows_from` set it starts from
    /// the order of `pivot_pairs` (AMD with each row AMD would eliminate bare delayed to a
    /// variable of its own), which leaves far fewer pivots to delay numerically.
    Multifrontal,
}

/// The numeric kernel chosen at analysis time.
#[derive(Clone)]
enum Kernel {
    Faer,
    Simplicial(Box<SimplicialPlan>),
    Supernodal(Box<BlockPlan>),
    Multifrontal(Box<MultifrontalPlan>),
}

/// Sparse LDLᵀ of the KKT matrix behind [`KktSolver`] (module docs): its [`LdltOptions`]
/// fixed at construction, the symbolic analysis once per pattern, a numeric refactorization
/// per call with the chosen [`LdltBackend`], workspaces allocated at analysis time.
pub struct SparseLdlt {
    options: LdltOptions,
    has_pairs: bool,
    faer: Option<FaerFactor>,
    kernel: Kernel,
    /// The last numeric factorization's outcome: a solve needs `Ok`.
    last: Result<Inertia, FactorizationFailure>,
    /// Analyses of earlier patterns, most recent last (at most [`KEPT_ANALYSES`]): a thread
    /// that alternates between a few KKT patterns (a search's coarse and full meshes, a solve
    /// with a bound held and one without) analyses each once.
    kept: Vec<Analysis>,
    /// Symbolic analyses computed (not taken from `kept` or the current one).
    analyses: usize,
    /// Whether this solver's thread waits for a core: a shared factorization needs the
    /// second core idle (decision record 0090).
    cores: CoreWatch,
}

/// Earlier patterns' analyses a [`SparseLdlt`] keeps besides its current one: a search's
/// threads alternate between about ten KKT patterns (with and without 2 × 2 pivot pairs), and
/// a `periodic-qc` search analysed about 1 350 times without them (decision record 0062).
pub const KEPT_ANALYSES: usize = 8;

/// One symbolic analysis of a [`SparseLdlt`]: the ordering and structure (`faer`) and the
/// kernel's plan, as [`KktSolver::analyse`] makes them for one pattern.
struct Analysis {
    has_pairs: bool,
    faer: FaerFactor,
    kernel: Kernel,
}

impl std::fmt::Debug for SparseLdlt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLdlt")
            .field("options", &self.options)
            .field(
                "dim",
                &self.faer.as_ref().map_or(0, |a| a.col_ptr.len() - 1),
            )
            .field("nnz", &self.faer.as_ref().map_or(0, |a| a.row_idx.len()))
            .field("factor_nnz", &self.factor_nnz())
            .field("supernodal", &self.is_supernodal())
            .finish()
    }
}

impl Default for SparseLdlt {
    fn default() -> Self {
        Self::new()
    }
}

impl SparseLdlt {
    /// A solver with the default [`LdltOptions`].
    pub fn new() -> Self {
        Self::with_options(LdltOptions::default())
    }

    /// A solver with the given backend and the other options at their defaults.
    pub fn with_backend(backend: LdltBackend) -> Self {
        Self::with_options(LdltOptions {
            backend,
            ..LdltOptions::default()
        })
    }

    /// A solver with these options (fixed for its life).
    pub fn with_options(options: LdltOptions) -> Self {
        Self {
            options,
            has_pairs: false,
            faer: None,
            kernel: Kernel::Faer,
            last: Err(FactorizationFailure::NotAnalysed),
            kept: Vec::new(),
            analyses: 0,
            cores: CoreWatch::default(),
        }
    }

    /// A second solver with these options and this symbolic analysis (ordering, structure,
    /// kernel plan) and no factor yet, so that two matrices of the pattern can be factored at
    /// once ([`Speculator`]); each factor is the one this solver would compute. `None` before
    /// an analysis or if a workspace cannot be allocated.
    pub fn duplicate(&self) -> Option<Self> {
        let faer = self.faer.as_ref()?.duplicate()?;
        Some(Self {
            options: self.options.clone(),
            has_pairs: self.has_pairs,
            faer: Some(faer),
            kernel: self.kernel.clone(),
            last: Err(FactorizationFailure::NotAnalysed),
            kept: Vec::new(),
            analyses: 0,
            cores: CoreWatch::default(),
        })
    }

    /// Whether [`KktSolver::factor`] may share the factorization with a second thread: the
    /// option [`LdltOptions::parallel`], a calling thread that is no rayon worker, two cores,
    /// and a supernodal kernel whose analysis found supernodes wide enough to share
    /// (`supernodal::MIN_PARALLEL_WORK` multiply–adds). It then shares only while the
    /// second core is idle: the calling thread has not been waiting for a core (the
    /// speculation's run-queue test, `MAX_RUN_QUEUE_WAIT`) and no other thread is ready to
    /// run (`/proc/loadavg`). Under load a shared factorization waits for a helper that gets
    /// no core: with two busy loops beside it a cold LG-30 solve took 1.8–2.7 s shared
    /// against 1.2 s alone (decision record 0090). The factor is the same either way.
    pub fn shares_factorization(&self) -> bool {
        self.may_share() && matches!(&self.kernel, Kernel::Supernodal(b) if b.shares_work())
    }

    fn may_share(&self) -> bool {
        self.options.parallel && rayon::current_thread_index().is_none()
    }

    /// [`KktSolver::factor`] on the calling thread alone (a supernodal kernel's large
    /// supernodes are not shared with a second thread); the same factor bit for bit.
    pub fn factor_on_one_thread(
        &mut self,
        values: &[f64],
    ) -> Result<Inertia, FactorizationFailure> {
        self.last = self.factor_numeric(values, false);
        self.last
    }

    /// Symbolic analyses this solver has computed; a pattern analysed before (the current one
    /// or one of the [`KEPT_ANALYSES`] kept) is not counted again.
    pub fn analyses(&self) -> usize {
        self.analyses
    }

    /// Moves the current analysis (if any) to the kept ones, dropping the oldest beyond
    /// [`KEPT_ANALYSES`].
    fn keep_current(&mut self) {
        if let Some(faer) = self.faer.take() {
            let kernel = std::mem::replace(&mut self.kernel, Kernel::Faer);
            self.kept.push(Analysis {
                has_pairs: self.has_pairs,
                faer,
                kernel,
            });
            if self.kept.len() > KEPT_ANALYSES {
                self.kept.remove(0);
            }
        }
        self.has_pairs = false;
    }

    /// The options the solver was made with.
    pub fn options(&self) -> &LdltOptions {
        &self.options
    }

    /// Whether faer's symbolic analysis is the supernodal one (only with
    /// [`LdltBackend::FaerSupernodal`]).
    pub fn is_supernodal(&self) -> bool {
        self.faer.as_ref().is_some_and(FaerFactor::is_supernodal)
    }

    /// Whether the analysed order has at least one 2 × 2 (variable, constraint row) pivot,
    /// i.e. plain AMD would eliminate some constraint row with the bare pivot −δ_c.
    pub fn has_pivot_pairs(&self) -> bool {
        self.has_pairs
    }

    /// Number of stored entries of faer's factor `L` (fill-in measure); for
    /// [`LdltBackend::Multifrontal`] the entries below the diagonal of the last factorization
    /// (delayed pivots included).
    pub fn factor_nnz(&self) -> usize {
        if let Kernel::Multifrontal(mf) = &self.kernel {
            return mf.factor_nnz();
        }
        self.faer.as_ref().map_or(0, |a| a.l_values.len())
    }

    /// With [`LdltBackend::Multifrontal`]: the pivots of the last factorization passed from a
    /// front to its parent (counted per front passed), its 2 × 2 pivot blocks and the pivots
    /// replaced by `±pivot_delta`; zeros for the other backends.
    pub fn pivot_statistics(&self) -> (usize, usize, usize) {
        match &self.kernel {
            Kernel::Multifrontal(mf) => (mf.delayed, mf.piv.two_by_two, mf.piv.static_pivots),
            _ => (0, 0, 0),
        }
    }

    /// Floating-point work of one numeric factorization, `Σ_j (c_j + c_j²/2)` over the column
    /// counts `c_j` of `L` (0 before the analysis). For faer's supernodal factor the counts
    /// include the explicit zeros of relaxed supernodes.
    pub fn factor_flops(&self) -> f64 {
        if let Kernel::Multifrontal(mf) = &self.kernel {
            return mf.factor_flops();
        }
        self.faer.as_ref().map_or(0.0, FaerFactor::flops)
    }
}

impl KktSolver for SparseLdlt {
    fn analyse(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<(), OptimError> {
        self.analyse_with(dim, col_ptr, row_idx, None)
    }

    fn factor(&mut self, values: &[f64]) -> Result<Inertia, FactorizationFailure> {
        // The run-queue test only where the kernel would share (it reads a /proc file).
        let share =
            self.shares_factorization() && self.cores.idle_core() && CoreWatch::machine_idle();
        self.last = self.factor_numeric(values, share);
        self.last
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), FactorizationFailure> {
        self.last?;
        let faer = self
            .faer
            .as_mut()
            .ok_or(FactorizationFailure::NotAnalysed)?;
        // The kernels take the length of `rhs` for the dimension.
        let dim = faer.col_ptr.len() - 1;
        if rhs.len() != dim {
            return Err(FactorizationFailure::RhsLength {
                expected: dim,
                got: rhs.len(),
            });
        }
        match &mut self.kernel {
            Kernel::Supernodal(block) => block.solve(rhs),
            Kernel::Multifrontal(mf) => mf.solve(rhs),
            Kernel::Simplicial(plan) => plan.solve(&faer.l_values, rhs),
            Kernel::Faer => faer.solve(rhs),
        }
        Ok(())
    }
}

impl SparseLdlt {
    /// The order of this solver's analysis when it is AMD's ([`LdltOrdering::Amd`]): what
    /// [`SparseLdlt::analyse_in_amd_order`] of another solver on the same pattern can start
    /// from instead of ordering again.
    pub fn amd_order(&self) -> Option<&[usize]> {
        if self.options.ordering != LdltOrdering::Amd {
            return None;
        }
        let perm = self.faer.as_ref()?.symbolic.perm()?;
        Some(perm.arrays().0)
    }

    /// [`KktSolver::analyse`] with AMD's order of this pattern where it is known (`amd`, from
    /// [`SparseLdlt::amd_order`] of a solver that analysed the same pattern): the orderings
    /// that start from AMD's (the pivot pairs') take it instead of ordering again, the larger
    /// part of their analysis (decision record 0094). The analysis is the one
    /// [`KktSolver::analyse`] makes; `None`, or anything but a permutation of `0..dim`, orders
    /// anew.
    pub fn analyse_in_amd_order(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        amd: Option<&[usize]>,
    ) -> Result<(), OptimError> {
        self.analyse_with(
            dim,
            col_ptr,
            row_idx,
            amd.filter(|a| is_permutation(a, dim)),
        )
    }

    fn analyse_with(
        &mut self,
        dim: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        amd: Option<&[usize]>,
    ) -> Result<(), OptimError> {
        self.last = Err(FactorizationFailure::NotAnalysed);
        // A pattern analysed before is well formed, but only for its own dimension.
        let same_dim = col_ptr.len().checked_sub(1) == Some(dim);
        // Same pattern as the last analysis (repeated solves of one NLP structure): keep the
        // symbolic factorization and the workspace (the options cannot have changed).
        if let Some(a) = &self.faer
            && same_dim
            && a.col_ptr == col_ptr
            && a.row_idx == row_idx
        {
            return Ok(());
        }
        // A pattern analysed before: its analysis is the one a new analysis would make (same
        // pattern, same options, and the ordering depends on nothing else), and its kernel's
        // workspaces are overwritten by every factorization.
        if let Some(k) = self
            .kept
            .iter()
            .position(|a| same_dim && a.faer.col_ptr == col_ptr && a.faer.row_idx == row_idx)
        {
            let found = self.kept.remove(k);
            self.keep_current();
            self.has_pairs = found.has_pairs;
            self.faer = Some(found.faer);
            self.kernel = found.kernel;
            return Ok(());
        }
        self.keep_current();
        check_lower_csc(dim, col_ptr, row_idx)?;
        self.analyses += 1;
        let opts = &self.options;
        // The elimination order: faer's AMD, AMD with 2 × 2 (variable, row) pivot pairs, or
        // AMD on the graph of pairs (module docs).
        let multifrontal = opts.backend == LdltBackend::Multifrontal;
        let (custom, pair_first) = match &opts.ordering {
            // The multifrontal kernel starts from the pairs' order (rows AMD would eliminate
            // bare already follow a variable of their own, so few pivots need delaying) and
            // chooses its pivots numerically; the pair marks are not used.
            order if multifrontal && order.constraint_rows_from().is_some() => (
                order
                    .constraint_rows_from()
                    .and_then(|n| ordering::amd_pivot_pairs(n, col_ptr, row_idx, amd))
                    .map(|(fwd, _)| fwd),
                Vec::new(),
            ),
            LdltOrdering::AmdPivotPairs {
                constraint_rows_from: n,
            } => match ordering::amd_pivot_pairs(*n, col_ptr, row_idx, amd) {
                Some((fwd, pairs)) => (Some(fwd), pairs),
                None => (None, Vec::new()),
            },
            LdltOrdering::PairedAmd {
                constraint_rows_from: n,
                preferred_primal,
            } => (
                ordering::paired_amd(*n, col_ptr, row_idx, preferred_primal),
                Vec::new(),
            ),
            LdltOrdering::Amd => (None, Vec::new()),
        };
        let has_pairs = pair_first.iter().any(|&p| p);
        self.has_pairs = has_pairs;
        // `Auto` decides by faer's own rule on the simplicial analysis that its kernels are
        // built on (`FaerFactor::auto_supernodal`), with AMD run here where the order is AMD's, so
        // that one ordering and one symbolic analysis serve both.
        let (custom, amd_flops) = match (opts.backend, custom) {
            (LdltBackend::Auto, None) => {
                let (fwd, flops) = ordering::amd_order_counted(col_ptr, row_idx)
                    .map_err(|e| OptimError::from(FactorizationError::SymbolicAnalysis(e)))?;
                (Some(fwd), Some(flops))
            }
            (_, custom) => (custom, None),
        };
        let faer = FaerFactor::analyse(
            dim,
            col_ptr,
            row_idx,
            match opts.backend {
                LdltBackend::FaerSupernodal => SupernodalThreshold::FORCE_SUPERNODAL,
                _ => SupernodalThreshold::FORCE_SIMPLICIAL,
            },
            custom.as_deref(),
        )?;
        if multifrontal {
            let plan = MultifrontalPlan::new(
                &faer.symbolic,
                dim,
                col_ptr,
                row_idx,
                opts.pivot_threshold.clamp(f64::MIN_POSITIVE, 0.5),
                opts.amalgamation.max(1),
            )
            .ok_or(OptimError::Factorization(FactorizationError::TooLarge))?;
            self.kernel = Kernel::Multifrontal(Box::new(plan));
            self.faer = Some(faer);
            return Ok(());
        }
        let supernodal = match opts.backend {
            LdltBackend::Supernodal => true,
            // Where faer's flop rule would pick its supernodal factor (dense LG blocks), the
            // supernodal kernel on the simplicial structure replaces it (same factor speed
            // there, no relaxation fill, faster solves). 2 × 2 pivots exist in the supernodal
            // kernel only.
            LdltBackend::Auto => has_pairs || faer.auto_supernodal(amd_flops),
            _ => false,
        };
        let block = if supernodal {
            BlockPlan::new(&faer.symbolic, dim, col_ptr, row_idx, &pair_first)
        } else {
            None
        };
        let plan = match (&block, opts.backend) {
            (None, LdltBackend::FaerSimplicial | LdltBackend::FaerSupernodal) => None,
            (None, _) => SimplicialPlan::new(&faer.symbolic, dim, col_ptr, row_idx),
            (Some(_), _) => None,
        };
        self.kernel = match (block, plan) {
            (Some(b), _) => Kernel::Supernodal(Box::new(b)),
            (None, Some(p)) => Kernel::Simplicial(Box::new(p)),
            (None, None) => Kernel::Faer,
        };
        self.faer = Some(faer);
        Ok(())
    }
}

/// Whether `order` holds each of `0..dim` once (an elimination order faer accepts).
fn is_permutation(order: &[usize], dim: usize) -> bool {
    let mut seen = vec![false; dim];
    order.len() == dim
        && order
            .iter()
            .all(|&k| k < dim && !std::mem::replace(&mut seen[k], true))
}

/// Checks that `col_ptr`/`row_idx` are a lower-triangle CSC pattern of dimension `dim` with
/// rows strictly increasing within each column ([`LowerCsc`]): faer's analysis asserts it and
/// the kernels index by it, so a malformed pattern from a caller is an error, not a panic.
fn check_lower_csc(dim: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<(), OptimError> {
    if col_ptr.len().checked_sub(1) != Some(dim) {
        return Err(OptimError::DimensionMismatch {
            what: "KKT column pointers",
            expected: dim.saturating_add(1),
            found: col_ptr.len(),
        });
    }
    let entries = row_idx.len();
    let rises = |k: usize| match k {
        0 => col_ptr[0] == 0,
        _ => col_ptr[k - 1] <= col_ptr[k] && col_ptr[k] <= entries,
    };
    if let Some(index) = (0..=dim)
        .find(|&k| !rises(k))
        .or((col_ptr[dim] != entries).then_some(dim))
    {
        return Err(OptimError::InvalidColumnPointers {
            index,
            value: col_ptr[index],
            entries,
        });
    }
    for j in 0..dim {
        let start = col_ptr[j];
        for (p, &row) in row_idx.iter().enumerate().take(col_ptr[j + 1]).skip(start) {
            // Rows rise from the diagonal (or below it) and stay below `dim`; the previous
            // row, already checked, is below `dim`, so `+ 1` cannot overflow.
            let lowest = if p == start { j } else { row_idx[p - 1] + 1 };
            if row < lowest || row >= dim {
                return Err(OptimError::InvalidPattern {
                    what: "kkt",
                    index: p,
                    row,
                    col: j,
                });
            }
        }
    }
    Ok(())
}

impl SparseLdlt {
    /// The numeric phase behind [`KktSolver::factor`].
    fn factor_numeric(
        &mut self,
        values: &[f64],
        parallel: bool,
    ) -> Result<Inertia, FactorizationFailure> {
        let faer = self
            .faer
            .as_mut()
            .ok_or(FactorizationFailure::NotAnalysed)?;
        if values.len() != faer.row_idx.len() {
            return Err(FactorizationFailure::ValueCount {
                expected: faer.row_idx.len(),
                got: values.len(),
            });
        }
        let (eps, delta) = (self.options.pivot_epsilon, self.options.pivot_delta);
        // A non-finite entry makes a non-finite pivot, which every kernel reports (as a failure
        // or a zero pivot); only then are the values searched for it, off the per-iteration
        // path, so that the failure names the entry rather than a pivot.
        let failure =
            |otherwise: FactorizationFailure| match values.iter().position(|v| !v.is_finite()) {
                Some(index) => FactorizationFailure::NonFiniteValue { index },
                None => otherwise,
            };
        let singular = || failure(FactorizationFailure::SingularPivot);
        let inertia = match &mut self.kernel {
            Kernel::Supernodal(block) => block
                .factor(values, eps, delta, parallel)
                .ok_or_else(singular)?,
            Kernel::Multifrontal(mf) => mf.factor(values, eps, delta).ok_or_else(singular)?,
            Kernel::Simplicial(plan) => {
                if !plan.factor(values, &mut faer.l_values, eps, delta) {
                    return Err(singular());
                }
                faer.inertia()
            }
            Kernel::Faer => faer.factor(values, eps, delta).ok_or_else(singular)?,
        };
        if inertia.zero > 0 {
            return Err(failure(FactorizationFailure::ZeroPivots {
                count: inertia.zero,
            }));
        }
        Ok(inertia)
    }
}
