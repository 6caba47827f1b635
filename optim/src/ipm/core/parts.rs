//! The parts of the algorithm's state that [`Core`](super::Core) is made of, one struct per
//! concept of Wächter & Biegler 2006 ("W&B"), so that each method of the loop names the part
//! it works on:
//!
//! * [`Bounds`]: the (relaxed) variable bounds `x_L, x_U` of the standard form (W&B eq. (1)),
//!   the indices of the finite ones and the one-sided damping signs of W&B Sect. 3.7;
//! * [`Iterate`]: the primal-dual point `(x, y, z_L, z_U)` and its slacks `s_L, s_U` to the
//!   bounds (W&B Sect. 2);
//! * [`Evaluations`]: f, c and their derivatives at the iterate, and the derived `∇φ_μ`
//!   (W&B eq. (3)) and `Jᵀy`;
//! * [`TrialPoint`]: the trial point of the line search (W&B Sect. 2.3) and its f, c;
//! * [`Direction`]: the Newton direction `(dx, dy, dz_L, dz_U)` (W&B eqs. (11)–(12));
//! * [`KktSystem`]: the KKT matrix of W&B eq. (13), its LDLᵀ solvers and the solve's vectors;
//! * [`Regularization`]: the inertia correction's δ_w, δ_c (W&B Sect. 3.1, Algorithm IC) and
//!   what it carries from one step to the next;
//! * [`Barrier`]: μ, the fraction-to-the-boundary τ (W&B eq. (8)), κ_d and Ipopt's
//!   `slack_move`;
//! * [`RunState`], [`Taken`]: what the outer loop carries between iterations (acceptable,
//!   tiny-step and soft-restoration counts, the log record) and the step an iteration takes.

use super::KeptSolvers;
use crate::error::OptimError;
use crate::ipm::kkt::{KktPattern, SparseLdlt, Speculator};
use crate::ipm::settings::Settings;
use crate::ipm::solution::IterationInfo;

/// The (relaxed) bounds of the standard form and their index sets.
pub(super) struct Bounds {
    /// Lower bounds x_L (−∞ where absent), relaxed by `bound_relax_factor` outside restoration.
    pub xl: Vec<f64>,
    /// Upper bounds x_U (+∞ where absent).
    pub xu: Vec<f64>,
    /// Variables with a finite lower bound (the order of `z_L`, `s_L`).
    pub lo: Vec<usize>,
    /// Variables with a finite upper bound (the order of `z_U`, `s_U`).
    pub up: Vec<usize>,
    /// +1 for a variable bounded only below, −1 only above, 0 otherwise (W&B Sect. 3.7).
    pub damp: Vec<f64>,
}

impl Bounds {
    /// The problem's bounds, relaxed by `relax` (`x_L ← x_L − relax max(1, |x_L|)`, likewise
    /// up) when `relax > 0`.
    pub fn new(mut xl: Vec<f64>, mut xu: Vec<f64>, relax: f64) -> Self {
        if relax > 0.0 {
            for l in xl.iter_mut().filter(|l| l.is_finite()) {
                *l -= relax * l.abs().max(1.0);
            }
            for u in xu.iter_mut().filter(|u| u.is_finite()) {
                *u += relax * u.abs().max(1.0);
            }
        }
        let n = xl.len();
        let lo = (0..n).filter(|&j| xl[j].is_finite()).collect();
        let up = (0..n).filter(|&j| xu[j].is_finite()).collect();
        let damp = (0..n)
            .map(|j| match (xl[j].is_finite(), xu[j].is_finite()) {
                (true, false) => 1.0,
                (false, true) => -1.0,
                _ => 0.0,
            })
            .collect();
        Self {
            xl,
            xu,
            lo,
            up,
            damp,
        }
    }
}

/// The primal-dual iterate and its slacks.
pub(super) struct Iterate {
    /// Primal variables.
    pub x: Vec<f64>,
    /// Constraint multipliers.
    pub y: Vec<f64>,
    /// Lower-bound multipliers, one per entry of [`Bounds::lo`].
    pub zl: Vec<f64>,
    /// Upper-bound multipliers, one per entry of [`Bounds::up`].
    pub zu: Vec<f64>,
    /// Slacks `x − x_L` (with the underflow safeguard of `barrier`).
    pub sl: Vec<f64>,
    /// Slacks `x_U − x`.
    pub su: Vec<f64>,
}

/// Function values and derivatives at the iterate.
pub(super) struct Evaluations {
    /// Objective (scaled).
    pub f: f64,
    /// Constraints (scaled).
    pub c: Vec<f64>,
    /// Objective gradient.
    pub grad: Vec<f64>,
    /// Jacobian values in the order of `jac_pat`.
    pub jac: Vec<f64>,
    /// Lagrangian Hessian values (lower triangle) at `(x, y)`.
    pub hess: Vec<f64>,
    /// The x at which `grad` and `jac` were last evaluated.
    pub derivs_x: Vec<f64>,
    /// Jacobian pattern (row, column).
    pub jac_pat: Vec<(usize, usize)>,
    /// Gradient of the barrier objective `∇φ_μ` (W&B eq. (3), with the damping of Sect. 3.7).
    pub grad_phi: Vec<f64>,
    /// `Jᵀy`.
    pub jty: Vec<f64>,
}

/// The line search's trial point.
pub(super) struct TrialPoint {
    /// `x + α dx`.
    pub x: Vec<f64>,
    /// Constraints at `x`.
    pub c: Vec<f64>,
    /// Objective at `x`.
    pub f: f64,
}

/// The Newton direction.
pub(super) struct Direction {
    /// Primal direction.
    pub dx: Vec<f64>,
    /// Constraint-multiplier direction.
    pub dy: Vec<f64>,
    /// Lower-bound multiplier direction (W&B eq. (12)).
    pub dzl: Vec<f64>,
    /// Upper-bound multiplier direction.
    pub dzu: Vec<f64>,
}

/// The KKT system of W&B eq. (13): its matrix, the LDLᵀ solvers and the vectors of a solve.
pub(super) struct KktSystem {
    /// Pattern and values of `K(δ_w, δ_c)`.
    pub matrix: KktPattern,
    /// The factorization in use.
    pub solver: SparseLdlt,
    /// With [`KktOrdering::AmdThenPivotPairs`](crate::ipm::settings::KktOrdering::AmdThenPivotPairs)
    /// before the switch (or `AmdCheckedByPivotPairs`): the solver with AMD and 2 × 2 pivot
    /// pairs, analysed when first needed, that re-factors a rejected AMD factor's matrix;
    /// after the switch: the AMD solver (handed back by [`Core::into_kkt_solvers`](super::Core::into_kkt_solvers)).
    pub other_solver: Option<SparseLdlt>,
    /// Solvers with 2 × 2 pivot pairs of earlier runs (from the workspace), one of which
    /// becomes `other_solver` when its options are the ones a check needs.
    pub spare_pairs: Vec<SparseLdlt>,
    /// The solvers of this run's restoration phases, kept from one phase to the next and
    /// across runs (each phase's inner run starts with them and hands them back).
    pub restoration_solvers: Option<Box<KeptSolvers>>,
    /// Rejected AMD factorizations are still to be checked with the pivot pairs.
    pub check_pairs: bool,
    /// The solve switched to the pivot pairs.
    pub switched_to_pairs: bool,
    /// `Σ = Z_L S_L⁻¹ + Z_U S_U⁻¹` on the primal diagonal.
    pub diag_x: Vec<f64>,
    /// Right-hand side.
    pub rhs: Vec<f64>,
    /// Solution.
    pub sol: Vec<f64>,
    /// Residual of the refinement.
    pub resid: Vec<f64>,
    /// Refinement correction.
    pub corr: Vec<f64>,
    /// The KKT solution before the last refinement correction, which may be undone.
    pub sol_before: Vec<f64>,
    /// The second thread of `LinearSolverSettings::speculative_factorization`.
    pub speculation: Speculator,
    /// Whether this solve speculates (decided at its first factorization in a Newton step).
    pub speculate: Option<bool>,
}

impl KktSystem {
    /// The system of a problem with `n` variables, `m` constraints and these Hessian and
    /// Jacobian patterns, with the solvers a workspace `kept`: its main solver factors (a new
    /// one if it has none), its pivot-pair solvers serve the checks, and its restoration
    /// solvers the restoration phases.
    pub fn new(
        n: usize,
        m: usize,
        hess_pat: &[(usize, usize)],
        jac_pat: &[(usize, usize)],
        kept: KeptSolvers,
    ) -> Result<Self, OptimError> {
        Ok(Self {
            matrix: KktPattern::try_new(n, m, hess_pat, jac_pat)?,
            solver: kept.main.unwrap_or_default(),
            other_solver: None,
            spare_pairs: kept.pairs,
            restoration_solvers: kept.restoration,
            check_pairs: false,
            switched_to_pairs: false,
            diag_x: vec![0.0; n],
            rhs: vec![0.0; n + m],
            sol: vec![0.0; n + m],
            resid: vec![0.0; n + m],
            corr: vec![0.0; n + m],
            sol_before: vec![0.0; n + m],
            speculation: Speculator::new(),
            speculate: None,
        })
    }
}

/// The inertia correction's regularization (W&B Algorithm IC) and its memory across steps.
pub(super) struct Regularization {
    /// Static dual regularization of this solve: `static_dual_regularization`, raised when a
    /// factor turns out unstable (see `step`).
    pub static_dc: f64,
    /// The last nonzero δ_w of an accepted factorization.
    pub delta_w_last: f64,
    /// Smallest δ_w of this iteration's KKT matrix: the proximal term κ_p μ of
    /// `BarrierSettings::proximal_weight` on a stalled barrier problem whose μ is above the
    /// tolerance, else 0. Read by the inertia correction (its starting δ_w) and by the
    /// extrapolation (which extends only steps whose inertia needed more than this floor).
    pub proximal: f64,
    /// The previous step's δ_w = 0 attempt failed: start from κ_w⁻ δ_w_last (saves one
    /// factorization per iteration on collocation KKTs whose states carry no curvature).
    pub skip_zero_trial: bool,
    /// The last accepted step grew δ_w beyond its first trial: its next step's first trial
    /// is `ExperimentalSettings::perturb_dec_fact_after_rejection` δ_w_last.
    pub grew_from_first_trial: bool,
    /// δ_w of the current matrix.
    pub delta_w: f64,
    /// δ_c of the current matrix.
    pub delta_c: f64,
    /// δ_c of the matrix that refinement targets (0: the unregularized system).
    pub delta_c_target: f64,
}

impl Regularization {
    /// No regularization yet; the static δ_c of the settings.
    pub fn new(settings: &Settings) -> Self {
        Self {
            static_dc: settings.linear_solver.static_dual_regularization,
            delta_w_last: 0.0,
            proximal: 0.0,
            skip_zero_trial: false,
            grew_from_first_trial: false,
            delta_w: 0.0,
            delta_c: 0.0,
            delta_c_target: 0.0,
        }
    }
}

/// The barrier problem's parameters.
pub(super) struct Barrier {
    /// Barrier parameter μ.
    pub mu: f64,
    /// Fraction-to-the-boundary parameter τ = max(τ_min, 1 − μ) (W&B eq. (8)).
    pub tau: f64,
    /// Damping of one-sided bounded variables κ_d (W&B Sect. 3.7).
    pub kappa_d: f64,
    /// Ipopt's `slack_move` (see `barrier`).
    pub slack_move: f64,
}

/// What the outer loop carries from one iteration to the next besides the iterate.
pub(super) struct RunState {
    /// Consecutive iterates at the acceptable level (termination).
    pub acceptable_count: usize,
    /// The last log line / callback record.
    pub last: IterationInfo,
    /// Consecutive tiny steps (W&B Sect. 3.9).
    pub tiny_count: usize,
    /// Consecutive soft restoration steps.
    pub soft_count: usize,
    /// Log lines printed (a header every ten).
    pub lines: usize,
}

impl RunState {
    /// The state before the first iteration.
    pub fn new(iter: usize, restoration: bool, mu: f64) -> Self {
        Self {
            acceptable_count: 0,
            last: IterationInfo {
                iter,
                restoration,
                objective: 0.0,
                inf_pr: 0.0,
                inf_du: 0.0,
                dual_infeasibility: 0.0,
                complementarity: 0.0,
                mu,
                step_norm: 0.0,
                delta_w: 0.0,
                alpha_du: 0.0,
                alpha_pr: 0.0,
                ls_trials: 0,
            },
            tiny_count: 0,
            soft_count: 0,
            lines: 0,
        }
    }
}

/// A step the iteration takes: the trial point `x_t` (evaluated) at primal step `alpha`.
pub(super) struct Taken {
    /// Primal step size (above 1 after an extrapolation along negative curvature).
    pub alpha: f64,
    /// Dual step size when a soft restoration step fixed it; otherwise the fraction to the
    /// boundary decides.
    pub alpha_dual: Option<f64>,
    /// Line-search trials.
    pub trials: usize,
}
