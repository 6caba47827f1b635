//! Result types of a solve: termination status, primal-dual solution, statistics and the
//! per-iteration record passed to the log and the user callback.

use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Why the solver stopped. Only `Solved` and `Acceptable` carry a (locally) optimal point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Status {
    /// Scaled optimality error ≤ `tol` and the unscaled tolerances hold.
    Solved,
    /// The acceptable level (`acceptable_tol`, `acceptable_constr_viol_tol`) held at
    /// `acceptable_iter` consecutive iterates, or at an iterate of the main run (not a
    /// restoration phase's) that had no acceptable step, where the restoration phase would
    /// have started: the latter also with `acceptable_iter = 0`, but never with the
    /// restoration phase switched off (`RecoverySettings::restoration`).
    Acceptable,
    /// `max_iter` reached.
    MaxIterations,
    /// `max_wall_time` reached.
    MaxTime,
    /// The restoration phase converged to a stationary point of the infeasibility: the
    /// constraints are (locally) infeasible.
    LocallyInfeasible,
    /// The Newton step became negligible relative to x without meeting the tolerances.
    SearchDirectionTooSmall,
    /// ‖x‖_∞ exceeded `diverging_iterates_tol` (typically an unbounded problem).
    DivergingIterates,
    /// The scaled objective dropped below −`unbounded_objective` at a feasible point while a
    /// variable without a finite lower or upper bound grew.
    Unbounded,
    /// No acceptable step and no recovery: the restoration phase ended without a point from
    /// which the main run can go on (its own run failed, or the point it reached is not
    /// evaluable or not strictly inside the bounds) and without showing the constraints
    /// infeasible; or, with the restoration phase switched off, the line search found no
    /// acceptable step size or the trial point of a tiny step was not evaluable (then no
    /// restoration phase ran). Also where a restoration phase hands the run back exactly where
    /// the previous one did, with no iteration in between, in a run that met a trial point
    /// that was not evaluable: the run would repeat the same failed step and phase forever.
    RestorationFailed,
    /// No usable Newton step: the inertia correction grew δ_w beyond
    /// `max_hessian_perturbation`. Reported only with the restoration phase switched off
    /// (`RecoverySettings::restoration`); with it on, such an iteration stops `Acceptable` at
    /// the acceptable level or starts the restoration phase, whose failure is
    /// `RestorationFailed`.
    ErrorInStepComputation,
    /// The callback asked to stop.
    UserStop,
}

impl Status {
    /// `Solved` or `Acceptable`.
    pub fn is_success(self) -> bool {
        matches!(self, Status::Solved | Status::Acceptable)
    }
}

/// Wall-clock time spent in each part of the algorithm (exclusive of each other).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Whole solve.
    pub total: Duration,
    /// Objective and constraint evaluations (those at line-search trial points included),
    /// and the evaluation of f, g, ∇f and the Jacobian at the returned point that gives the
    /// [`Solution`]'s objective, constraint violation and fixed variables' multipliers.
    pub function_evals: Duration,
    /// Gradient, Jacobian and Hessian evaluations.
    pub derivative_evals: Duration,
    /// Building the KKT matrix and right-hand sides.
    pub kkt_assembly: Duration,
    /// Symbolic analysis and numeric factorizations (all inertia-correction attempts).
    pub factorization: Duration,
    /// Triangular solves and iterative refinement.
    pub solve: Duration,
    /// Line-search bookkeeping (filter, step sizes), excluding its function evaluations.
    pub line_search: Duration,
    /// Factorizations on the second thread of `LinearSolverSettings::speculative_factorization`
    /// (that thread's time, used or not): concurrent with the parts above, so not part of
    /// `total`.
    #[serde(default)]
    pub speculative_factorization: Duration,
}

/// Counters of a solve.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    /// Objective evaluations.
    pub objective_evals: usize,
    /// Constraint evaluations.
    pub constraint_evals: usize,
    /// Hessian evaluations.
    pub hessian_evals: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Factorizations (among `factorizations`) of a KKT matrix whose factor gave no step: wrong
    /// inertia, no factor, or an inaccurate solution; each is followed by another (the inertia
    /// correction, W&B Algorithm IC). Pivot-pair checks are counted apart.
    #[serde(default)]
    pub rejected_factorizations: usize,
    /// Factorizations (among `factorizations`) with 2 × 2 pivot pairs that check a rejected
    /// AMD factor ([`KktOrdering::AmdCheckedByPivotPairs`](crate::ipm::KktOrdering::AmdCheckedByPivotPairs)).
    #[serde(default)]
    pub pivot_pair_checks: usize,
    /// Iterations spent in the restoration phase (included in `iterations`).
    pub restoration_iterations: usize,
    /// Second-order corrections that were accepted.
    pub soc_accepted: usize,
    /// Full steps along negative curvature extended beyond α = 1
    /// (`LineSearchSettings::max_curvature_extrapolation`).
    #[serde(default)]
    pub extrapolations: usize,
    /// Iterations whose KKT matrix carried the proximal term of a stalled barrier problem
    /// (`BarrierSettings::proximal_weight`).
    #[serde(default)]
    pub proximal_iterations: usize,
    /// Iteration at which the KKT factorization switched from AMD to AMD with 2 × 2 pivot
    /// pairs ([`KktOrdering::AmdThenPivotPairs`](crate::ipm::KktOrdering::AmdThenPivotPairs));
    /// `None`: no switch.
    #[serde(default)]
    pub pivot_pairs_from: Option<usize>,
    /// Iteration at which the static dual regularization δ_c of the solve last grew (a factor
    /// with the right inertia was inaccurate, or the pivot pairs showed an AMD rejection to be
    /// spurious); `None`: it kept `LinearSolverSettings::static_dual_regularization`.
    #[serde(default)]
    pub dual_regularization_raised_at: Option<usize>,
    /// Filter resets of the filter reset heuristic (`LineSearchSettings::filter_reset_trigger`).
    #[serde(default)]
    pub filter_resets: usize,
    /// KKT solutions that failed the relative-residual test and were accepted on their normwise
    /// backward error (`LinearSolverSettings::backward_error_tol`).
    #[serde(default)]
    pub backward_error_accepts: usize,
    /// Iterative-refinement corrections computed for KKT solutions, over all solves, the ones
    /// undone for too slow a contraction included (`LinearSolverSettings::max_refinement_steps` bounds them
    /// per solve).
    #[serde(default)]
    pub refinement_steps: usize,
}

/// Result of a solve (unscaled, in the user's variables).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Solution {
    /// Termination status.
    pub status: Status,
    /// Final primal point (length n), projected onto the original variable bounds.
    pub x: Vec<f64>,
    /// Constraint multipliers λ (length m), Lagrangian `f + λᵀg`.
    pub lambda: Vec<f64>,
    /// Lower-bound multipliers z_L ≥ 0 (length n, zero for variables without a lower bound).
    pub z_l: Vec<f64>,
    /// Upper-bound multipliers z_U ≥ 0 (length n).
    pub z_u: Vec<f64>,
    /// Objective f(x).
    pub objective: f64,
    /// Iterations (restoration included).
    pub iterations: usize,
    /// Max violation of the variable and constraint bounds at `x`, unscaled; NaN if g(x) is
    /// not finite there (`x` is the final iterate projected onto the bounds, which the
    /// iterates, inside the relaxed bounds, may not have met).
    pub constraint_violation: f64,
    /// ‖∇f + Jᵀλ − z_L + z_U‖_∞ at the final iterate (the rows of the inequality slacks
    /// included), unscaled: exactly the value the termination test compares with
    /// `dual_inf_tol` (so a `Solved` run reports at most `dual_inf_tol`).
    pub dual_infeasibility: f64,
    /// Max complementarity |(x − x_L) z_L|, |(x_U − x) z_U| at the final iterate (including
    /// constraint slacks), unscaled, with the bounds relaxed by `bound_relax_factor` (and
    /// moved by the `slack_move` safeguard) as the termination test uses them: exactly the
    /// value it compares with `compl_inf_tol` (so a `Solved` run reports at most
    /// `compl_inf_tol`).
    pub complementarity: f64,
    /// Final barrier parameter μ of the internal problem, i.e. in the units of the scaled
    /// objective (`ScalingSettings`: σ_f f); unlike the other values it is not unscaled.
    pub mu: f64,
    /// Time breakdown.
    pub timing: Timing,
    /// Counters.
    pub counters: Counters,
}

/// What happened in one iteration (the columns of the Ipopt-style log).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IterationInfo {
    /// Iteration number (0 = initial point).
    pub iter: usize,
    /// True for iterations of the restoration phase.
    pub restoration: bool,
    /// Unscaled objective (for restoration iterations: the restoration objective).
    pub objective: f64,
    /// Max constraint violation ‖c‖_∞ of the internal (scaled) problem.
    pub inf_pr: f64,
    /// Scaled dual infeasibility ‖∇L‖_∞.
    pub inf_du: f64,
    /// Unscaled dual infeasibility, as the termination test compares it with `dual_inf_tol`
    /// (see [`Solution::dual_infeasibility`]).
    #[serde(default)]
    pub dual_infeasibility: f64,
    /// Unscaled complementarity, as the termination test compares it with `compl_inf_tol`
    /// (see [`Solution::complementarity`]).
    #[serde(default)]
    pub complementarity: f64,
    /// Barrier parameter μ.
    pub mu: f64,
    /// ‖Δx‖_∞ of the step taken to reach this iterate.
    pub step_norm: f64,
    /// Hessian regularization δ_w used for that step (0 = none).
    pub delta_w: f64,
    /// Dual step size.
    pub alpha_du: f64,
    /// Primal step size.
    pub alpha_pr: f64,
    /// Line-search trials.
    pub ls_trials: usize,
}

/// A primal-dual starting point (user variables; multipliers as returned in [`Solution`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WarmStart {
    /// Primal point (length n).
    pub x: Vec<f64>,
    /// Constraint multipliers (length m).
    pub lambda: Vec<f64>,
    /// Lower-bound multipliers (length n).
    pub z_l: Vec<f64>,
    /// Upper-bound multipliers (length n).
    pub z_u: Vec<f64>,
}

impl From<&Solution> for WarmStart {
    fn from(s: &Solution) -> Self {
        Self {
            x: s.x.clone(),
            lambda: s.lambda.clone(),
            z_l: s.z_l.clone(),
            z_u: s.z_u.clone(),
        }
    }
}
