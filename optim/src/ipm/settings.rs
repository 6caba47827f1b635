//! Solver settings. Names and defaults follow Ipopt's options (Wächter & Biegler 2006, "W&B",
//! Sect. 2–3 and Table 1) wherever an equivalent exists, except where a field's documentation
//! says otherwise: `max_hessian_perturbation` is 1e40 where Ipopt's is 1e20. [`Settings`] is
//! grouped by part of the algorithm (decision record 0019):
//!
//! * [`TerminationSettings`]: the termination test (W&B eq. (5), Sect. 2.1) and its limits;
//! * [`BarrierSettings`]: the μ update (W&B eq. (7)), τ (eq. (8)), the initial point (Sect.
//!   3.6), κ_Σ (eq. (16)), κ_d (Sect. 3.7), the slack safeguard and the proximal term;
//! * [`ScalingSettings`]: the internal scaling of f and c;
//! * [`LineSearchSettings`]: the filter line search (W&B eqs. (18)–(23), Sect. 2.3–2.4);
//! * [`LinearSolverSettings`]: the static δ_c, the pivot-pair checks, the speculative and the
//!   shared factorization on a second core and the iterative refinement of KKT solves;
//! * [`RecoverySettings`]: the inertia correction (W&B Algorithm IC, Sect. 3.1) and the
//!   restoration phase (Sect. 3.3);
//! * [`ExperimentalSettings`]: research switches no default path uses;
//! * [`OutputSettings`]: the log.

use serde::{Deserialize, Serialize};

use crate::error::OptimError;

/// Barrier-parameter update rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum MuStrategy {
    /// Fiacco–McCormick: solve each barrier problem to `E_μ ≤ κ_ε μ`, then
    /// `μ ← max(tol/10, min(κ_μ μ, μ^θ_μ))` (Wächter & Biegler eq. (7)).
    #[default]
    Monotone,
    /// LOQO rule `μ = σ · sᵀz / n_c` with `σ = 0.1 min(0.05 (1−ξ)/ξ, 2)³`, `ξ = min sᵢzᵢ / avg`,
    /// recomputed every iteration; safeguarded by falling back to monotone mode when the
    /// optimality error stops decreasing (Nocedal, Wächter & Waltz 2009, "free/fixed" modes).
    Adaptive,
}

/// How the objective and constraints are scaled internally.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ScalingMethod {
    /// No scaling.
    None,
    /// Ipopt's gradient-based scaling: each function is scaled so that its gradient at the
    /// initial point has ∞-norm ≤ `scaling_max_gradient` (constraint factors never exceed 1
    /// and are at least 1e-8; the objective factor has no lower limit). Unlike Ipopt, an
    /// objective whose gradient has ∞-norm below `scaling_min_gradient` (but above zero) is
    /// scaled up to ∞-norm `scaling_max_gradient`, so that the dual-infeasibility test,
    /// absolute in scaled units, does not stop a tiny objective before its optimum, and an
    /// objective `c · f` is scaled to the same internal objective for every factor `c` that
    /// puts its gradient outside `[scaling_min_gradient, scaling_max_gradient]`.
    #[default]
    GradientBased,
    /// Use [`Nlp::scaling`](crate::ipm::Nlp::scaling) (falls back to none if it returns `None`).
    User,
}

/// On which barrier problems the line search may extrapolate a full step along negative
/// curvature ([`LineSearchSettings::max_curvature_extrapolation`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ExtrapolationScope {
    /// Only on the barrier problems whose solutions are answers: μ at most the optimality
    /// tolerance (in the scaled units of the barrier rule's floor), so that complementarity
    /// no longer exceeds it. Earlier barrier problems are approximate stations on the way, and
    /// longer steps there move the solve across basins to other local optima (decision
    /// records 0010, 0011).
    #[default]
    #[serde(alias = "FinalBarrier")]
    Answers,
    /// On every barrier problem (the first version of 0010).
    EveryBarrier,
}

/// Elimination order of the KKT matrix's LDLᵀ factorization.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum KktOrdering {
    /// Approximate minimum degree (faer's AMD) alone, 1 × 1 pivots: constraint rows that AMD
    /// eliminates before their variables have the pivot −δ_c, whose 1/δ_c growth can hide the
    /// reduced Hessian's curvature in rounding.
    Amd,
    /// [`Amd`](KktOrdering::Amd) until an inertia correction: the first factorization of a
    /// Newton step that is rejected (wrong inertia, singular or inaccurate) is repeated with
    /// [`AmdPivotPairs`](KktOrdering::AmdPivotPairs) on the same matrix; if that one is
    /// accepted, the rejection was an artefact of the bare −δ_c pivots and the solve keeps the
    /// pivot pairs from then on; if not, the need for δ_w (or δ_c) is genuine and AMD stays.
    /// Solves whose AMD factorizations are never rejected cost what AMD costs; KKT matrices
    /// where AMD eliminates no constraint row bare never try the pairs.
    AmdThenPivotPairs,
    /// [`Amd`](KktOrdering::Amd), with the first rejected factorization of each Newton step
    /// checked by [`AmdPivotPairs`](KktOrdering::AmdPivotPairs) on the same matrix if its δ_w
    /// is at most `LinearSolverSettings::pivot_pairs_check_max_delta_w`: where the
    /// pairs accept what AMD rejected, the rejection is an artefact of the bare −δ_c pivots,
    /// and the static δ_c of the solve grows (`static_dual_regularization_growth`, up to
    /// `static_dual_regularization_max`), which shrinks their 1/δ_c growth; the order stays
    /// AMD. Once δ_c is at its maximum, no more checks. Solves whose AMD factorizations are
    /// never rejected cost what AMD costs and run bit for bit as with
    /// [`Amd`](KktOrdering::Amd).
    #[default]
    AmdCheckedByPivotPairs,
    /// AMD, except that each constraint row that AMD eliminates before all of its primal
    /// variables is delayed to the first of them and eliminated with it as one 2 × 2 block
    /// pivot, so that no constraint row has the bare pivot −δ_c and each such pair contributes
    /// (1, 1) to the inertia by construction (see [`crate::ipm::kkt`]). More fill than AMD,
    /// less than [`ConstraintsAfterVariables`](KktOrdering::ConstraintsAfterVariables).
    AmdPivotPairs,
    /// AMD on the graph of (variable, constraint row) pairs, each row eliminated right after a
    /// primal variable of its own (bounded ones preferred), so that no constraint row is
    /// eliminated with the bare pivot −δ_c (see [`crate::ipm::kkt`]). More fill than AMD.
    ConstraintsAfterVariables,
    /// AMD's order modified at factorization time: a multifrontal LDLᵀ with threshold
    /// Bunch–Kaufman 1 × 1 / 2 × 2 pivoting and delayed pivots
    /// ([`LdltBackend::Multifrontal`](crate::ipm::LdltBackend::Multifrontal)), so that the
    /// factor's growth is bounded and its inertia is the matrix's for any δ_c ≥ 0; no checks
    /// by pivot pairs (the static δ_c still grows on a factor that does not solve its own
    /// matrix after refinement).
    ThresholdPivoting,
}

/// Declares a group of [`Settings`] with each field's default written once, beside the field:
/// the macro emits the field (its doc ending in "Default: `…`." generated from the same
/// expression) and the `Default` impl, so the docs and `Default` cannot disagree. A field
/// written `name as "key"` is serialized as `key` (the flat name it had before the grouping).
macro_rules! settings {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $(
                $(#[doc = $doc:literal])*
                $field:ident $(as $key:literal)? : $ty:ty = $default:expr
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            $(
                $(#[doc = $doc])*
                #[doc = ""]
                #[doc = concat!("Default: `", stringify!($default), "`.")]
                $(#[serde(rename = $key)])?
                pub $field: $ty,
            )*
        }

        impl Default for $name {
            fn default() -> Self {
                Self {
                    $($field: $default,)*
                }
            }
        }

        impl $name {
            /// Each field's serialized name and its default as written in the source (the
            /// text the field's documentation shows), in declaration order.
            pub const DEFAULTS: &'static [(&'static str, &'static str)] =
                &[$((settings!(@key $field $($key)?), stringify!($default)),)*];
        }
    };
    (@key $field:ident) => { stringify!($field) };
    (@key $field:ident $key:literal) => { $key };
}

/// Settings of the interior-point solver, by part of the algorithm. All fields are public;
/// [`Settings::validate`] checks ranges. Serialized flat (each group's fields at the top
/// level, as before the grouping), so settings written by older versions read unchanged.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Termination tests and limits.
    #[serde(flatten)]
    pub termination: TerminationSettings,
    /// Barrier parameter, initial point, multiplier safeguards.
    #[serde(flatten)]
    pub barrier: BarrierSettings,
    /// Internal scaling of the problem.
    #[serde(flatten)]
    pub scaling: ScalingSettings,
    /// Filter line search.
    #[serde(flatten)]
    pub line_search: LineSearchSettings,
    /// KKT solve: regularization and refinement.
    #[serde(flatten)]
    pub linear_solver: LinearSolverSettings,
    /// Inertia correction and feasibility restoration.
    #[serde(flatten)]
    pub recovery: RecoverySettings,
    /// Research switches no default path uses (decision record 0019).
    #[serde(flatten)]
    pub experimental: ExperimentalSettings,
    /// Log output.
    #[serde(flatten)]
    pub output: OutputSettings,
}

impl Settings {
    /// Each group's name and its fields' [`DEFAULTS`](TerminationSettings::DEFAULTS)
    /// (serialized name, default as written in the source).
    pub const GROUPS: &'static [(&'static str, &'static [(&'static str, &'static str)])] = &[
        ("termination", TerminationSettings::DEFAULTS),
        ("barrier", BarrierSettings::DEFAULTS),
        ("scaling", ScalingSettings::DEFAULTS),
        ("line_search", LineSearchSettings::DEFAULTS),
        ("linear_solver", LinearSolverSettings::DEFAULTS),
        ("recovery", RecoverySettings::DEFAULTS),
        ("experimental", ExperimentalSettings::DEFAULTS),
        ("output", OutputSettings::DEFAULTS),
    ];
}

settings! {
/// When the solve stops: the optimality tolerances of the termination test (W&B Sect. 2.1, eq. (5)), the acceptable level, the iteration and time limits and the divergence tests.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TerminationSettings {
    /// Desired scaled optimality error `E_0`.
    tol: f64 = 1e-8,
    /// Unscaled constraint violation required for `Solved`.
    constr_viol_tol: f64 = 1e-4,
    /// Unscaled dual infeasibility required for `Solved`.
    dual_inf_tol: f64 = 1.0,
    /// Unscaled complementarity required for `Solved`.
    compl_inf_tol: f64 = 1e-4,
    /// "Acceptable" scaled optimality error.
    acceptable_tol: f64 = 1e-6,
    /// Consecutive acceptable iterations before stopping with `Acceptable` (0 disables this
    /// count; an iterate at the acceptable level that has no acceptable step still stops
    /// `Acceptable` instead of starting the restoration phase, see
    /// [`Status::Acceptable`](crate::ipm::Status::Acceptable)).
    acceptable_iter: usize = 15,
    /// Unscaled constraint violation for the acceptable level.
    acceptable_constr_viol_tol: f64 = 1e-2,
    /// Maximum number of iterations, restoration iterations included.
    max_iter: usize = 3000,
    /// Wall-clock limit in seconds.
    max_wall_time: f64 = 1e20,
    /// Stop with `DivergingIterates` if ‖x‖_∞ exceeds this.
    diverging_iterates_tol: f64 = 1e20,
    /// Stop with `Unbounded` if the scaled objective (after the objective scaling of
    /// `scaling`, so independent of the objective's units) drops below −this at a feasible
    /// iterate while a variable with a free or one-sided bound reaches a new largest magnitude
    /// (the collocation objectives of this project are O(1)–O(1e4)).
    unbounded_objective: f64 = 1e15,
    /// Scaling cap s_max of the optimality error.
    s_max: f64 = 100.0,
}
}

settings! {
/// The barrier problems and the initial point: the μ update (W&B eq. (7)), the fraction to the boundary, the push of the initial point into the bounds and the initial multipliers (W&B Sect. 3.6), the bound relaxation, the multiplier safeguard κ_Σ (W&B eq. (16)), the damping κ_d (W&B Sect. 3.7), the slack safeguard and the proximal term on stalled barrier problems (decision record 0011).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BarrierSettings {
    /// Barrier-parameter strategy.
    mu_strategy: MuStrategy = MuStrategy::Monotone,
    /// Initial barrier parameter.
    mu_init: f64 = 0.1,
    /// Smallest barrier parameter, multiplied by the objective scaling factor when that is
    /// below 1. The μ floor of a run is the larger of it and
    /// `min(tol, σ_f · compl_inf_tol) / (barrier_tol_factor + 1)`.
    mu_min: f64 = 1e-11,
    /// Linear decrease factor κ_μ.
    mu_linear_decrease: f64 = 0.2,
    /// Superlinear decrease power θ_μ.
    mu_superlinear_power: f64 = 1.5,
    /// Barrier subproblem tolerance factor κ_ε.
    barrier_tol_factor: f64 = 10.0,
    /// Minimum fraction-to-boundary parameter τ_min.
    tau_min: f64 = 0.99,
    /// Absolute push of the initial point into the bounds κ_1.
    bound_push: f64 = 1e-2,
    /// Relative push κ_2 (fraction of the bound interval).
    bound_frac: f64 = 1e-2,
    /// Initial value of the bound multipliers.
    bound_mult_init: f64 = 1.0,
    /// Relative relaxation of all bounds, `x_L ← x_L − r max(1, |x_L|)`.
    bound_relax_factor: f64 = 1e-8,
    /// Least-squares initial λ is discarded if its ∞-norm exceeds this.
    constr_mult_init_max: f64 = 1e3,
    /// Push of the primal point into the bounds for a warm start.
    warm_start_bound_push: f64 = 1e-3,
    /// Minimum value of warm-start bound multipliers.
    warm_start_mult_bound_push: f64 = 1e-3,
    /// Bound-multiplier safeguard κ_Σ.
    kappa_sigma: f64 = 1e10,
    /// Damping of one-sided bounded variables κ_d.
    kappa_d: f64 = 1e-5,
    /// Ipopt's `slack_move` (W&B end of Sect. 3.5): a slack to a bound that falls below `ε_mach ·
    /// min(1, μ)` (it has underflowed in the rounding of `x − x_L`) is replaced by `min(max(μ / z,
    /// ε_mach · min(1, μ)), s + slack_move · max(1, |x_L|))` and the bound moved to `x − s`, so
    /// that every slack stays positive and representable (the default, `ε_mach^{3/4}`, is about
    /// 1.8e-12; must be positive).
    slack_move: f64 = libm::pow(f64::EPSILON, 0.75),
    /// Weight κ_p of the primal proximal regularization δ_w ≥ κ_p μ on a stalled barrier
    /// problem that is not an answer (0 turns it off): one whose μ exceeds the
    /// optimality tolerance (its complementarity alone exceeds `tol`, in the scaled units of
    /// the barrier rule's floor) and that has taken [`proximal_after`](BarrierSettings::proximal_after)
    /// iterations without meeting its tolerance κ_ε μ. Along a flat direction of the reduced
    /// Hessian the Newton step is long (‖∇φ_μ‖ / λ_min), the constraints' linearization fails
    /// over it, and the solve wanders at one μ for hundreds of iterations (`periodic-cot`
    /// LG-40); a proximal term that vanishes with μ (regularized interior-point methods:
    /// Friedlander & Orban 2012; Armand, Benoist & Orban 2013) bounds that step by
    /// ‖∇φ_μ‖ / (κ_p μ). The barrier problems that decide the answer (μ ≤ tol) never carry
    /// it, so they keep Newton's fast local convergence (decision record 0011).
    proximal_weight: f64 = 0.1,
    /// Iterations on one barrier problem after which it counts as stalled and carries the
    /// proximal term of [`proximal_weight`](BarrierSettings::proximal_weight) (a barrier
    /// problem that Newton's method solves takes a few iterations; 0 puts the term on every
    /// barrier problem above the tolerance).
    proximal_after: usize = 60,
}
}

settings! {
/// How the objective and the constraints are scaled internally (Ipopt's gradient-based scaling).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ScalingSettings {
    /// Scaling method.
    method as "scaling": ScalingMethod = ScalingMethod::GradientBased,
    /// Target maximal gradient for gradient-based scaling.
    scaling_max_gradient: f64 = 100.0,
    /// Objective gradients (∞-norm at the initial point) below this are scaled up to
    /// `scaling_max_gradient` by gradient-based scaling: from a smaller gradient, the
    /// absolute `tol` would leave fewer than five orders of magnitude of decrease of the dual
    /// infeasibility (0 disables).
    scaling_min_gradient: f64 = 1e-3,
    /// Extra objective factor applied on top of the scaling method.
    obj_scaling_factor: f64 = 1.0,
}
}

settings! {
/// The filter line search (W&B Sect. 2.3–2.4, eqs. (18)–(23)): filter margins, switching and Armijo conditions, second-order corrections, backtracking, the extrapolation along negative curvature (decision record 0010) and the filter reset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LineSearchSettings {
    /// Filter margin γ_θ.
    gamma_theta: f64 = 1e-5,
    /// Filter margin γ_φ.
    gamma_phi: f64 = 1e-8,
    /// Switching-rule constant δ.
    switching_delta: f64 = 1.0,
    /// Switching exponent s_θ.
    s_theta: f64 = 1.1,
    /// Switching exponent s_φ.
    s_phi: f64 = 2.3,
    /// Armijo constant η_φ.
    eta_phi: f64 = 1e-8,
    /// Maximum second-order corrections per line search.
    max_soc: usize = 4,
    /// Required θ reduction between consecutive corrections κ_soc.
    kappa_soc: f64 = 0.99,
    /// Backtracking factor.
    alpha_red_factor: f64 = 0.5,
    /// Largest step size α of the extrapolation along negative curvature (1 turns
    /// it off): when the full step of an iteration whose inertia needed δ_w > 0 (above the floor
    /// of [`proximal_weight`](BarrierSettings::proximal_weight), where that acts) is accepted at
    /// the first trial and the Lagrangian's curvature `dxᵀ(W + Σ)dx` along it is negative, the
    /// quadratic model decreases without bound along the step, so α is doubled (2, 4, …,
    /// within the fraction-to-boundary rule) while the acceptance test gives the same verdict
    /// and φ_μ keeps decreasing (Moré & Sorensen 1979; Gould, Lucidi, Roma & Toint 2000).
    /// Without it, a solve in a descending valley of negative curvature crawls with steps of
    /// length ‖∇L‖/δ_w. Applies on the barrier problems chosen by
    /// [`extrapolation_scope`](ExperimentalSettings::extrapolation_scope), by default those whose μ is at
    /// most the tolerance (decision records 0010, 0011).
    max_curvature_extrapolation: f64 = 16.0,
    /// Ipopt's filter reset heuristic: the filter is cleared when, in this many consecutive
    /// iterations, the last trial point rejected before the accepted one had made sufficient
    /// progress over the current iterate and was dominated only by a filter entry.
    filter_reset_trigger: usize = 5,
    /// Filter resets per solve at most (0 disables the heuristic).
    max_filter_resets: usize = 5,
    /// Reject trial points whose barrier objective rises by more than this many orders of
    /// magnitude.
    obj_max_inc: f64 = 5.0,
}
}

settings! {
/// The KKT solve: the static dual regularization of the unpivoted LDLᵀ and its growth, and the iterative refinement with its accuracy tests (decision records 0008, 0009).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LinearSolverSettings {
    /// Static −δ_c always on the constraint block so that the unpivoted LDLᵀ never meets an exact
    /// zero dual pivot; the step is refined against the unregularized matrix.
    static_dual_regularization: f64 = 1e-9,
    /// Factor by which the static δ_c of a solve grows when a factor with the right inertia
    /// does not solve its own matrix accurately after refinement (growth of the unpivoted
    /// LDLᵀ ∝ 1/δ_c), in place of a larger δ_w; once per Newton step, kept for the rest of the
    /// solve.
    static_dual_regularization_growth: f64 = 30.0,
    /// Largest static δ_c that this growth may reach (a value at most
    /// `static_dual_regularization` disables the growth).
    static_dual_regularization_max: f64 = 3e-8,
    /// With [`KktOrdering::AmdCheckedByPivotPairs`]: largest δ_w of a rejected AMD factor that
    /// the pivot pairs re-factor to check. What the check detects is a rounding artefact of the
    /// bare −δ_c pivots, an error of order `ε ‖a‖² / δ_c` (≈ 1e-7 ‖a‖² at δ_c = 1e-9) in the
    /// reduced Hessian, which a larger δ_w outweighs; there a check only confirms the
    /// rejection, at 1.55 times an AMD factorization's cost. The largest δ_w at which a check
    /// was seen to accept is 1.3e-5 (decision record 0031).
    pivot_pairs_check_max_delta_w: f64 = 1e-3,
    /// Factor on a second core, while the inertia correction (W&B Algorithm IC) factors
    /// `K(δ_w, δ_c)`, the matrix it would factor next if this one were rejected (δ_w grown by
    /// κ_w⁺), and take that factor when the correction asks for exactly that matrix (decision
    /// record 0036). The path of a solve is bit for bit the same either way, on any number of
    /// cores; only the wall time changes. Used only where it can pay: at least two cores, one
    /// of them idle (the solve's thread has not been waiting for a core), a KKT factorization
    /// of at least [`MIN_SPECULATION_FLOPS`](crate::ipm::kkt::MIN_SPECULATION_FLOPS)
    /// multiply–adds, and a solve not running on a worker of a rayon pool that already uses
    /// every core (a parallel multi-start). On two idle cores a cold `periodic-qc` solve takes
    /// 15 % less wall time on LG-30 and 8 % less on Radau 3 × 10; where the cores are busy the
    /// idle-core test keeps the second thread from taking the solve's own core (decision
    /// record 0036). Off: every factor on the solve's thread.
    speculative_factorization: bool = true,
    /// Share the factorization of the widest supernodes (the dense blocks of Legendre–Gauss
    /// collocation: on LG-30 the last supernode holds 318 columns) with a second core, each
    /// thread on its own columns, and the small supernodes between them in pairs of ranges
    /// that do not depend on each other, one range per thread, so that the factor is the same
    /// bit for bit ([`LdltOptions::parallel`](crate::ipm::kkt::LdltOptions::parallel)). Used
    /// where the supernodal kernel finds such work, the solve runs on a thread of its own
    /// (not a worker of a rayon pool: a parallel multi-start's starts already keep every core
    /// busy) and the machine has two cores, and each factorization shares only while the
    /// second core is idle; there it replaces `speculative_factorization`, which would
    /// compete for the same core. A cold LG-30 `periodic-qc` solve takes about 0.8 of the
    /// speculative one's wall time (decision records 0090 and 0091). Off: every factor on the
    /// solve's thread (speculation as before).
    parallel_factorization: bool = true,
    /// Maximum iterative-refinement steps per solve (the default is Ipopt's
    /// `max_refinement_steps`); see `min_refinement_steps` and `refinement_contraction` for
    /// when refinement stops earlier. An unpivoted factor with pivot growth refines, but
    /// slowly: on the finest `periodic-cot-human` mesh the residual falls by 0.1–0.3 per step,
    /// and three steps left every step "inaccurate" (docs/decisions/0009-refinement-steps.md).
    max_refinement_steps: usize = 10,
    /// Refinement steps taken whatever their progress, unless `refinement_tol` is met (the default
    /// is the solver's former maximum). Further steps are taken only while the solution fails the
    /// accuracy test (1e-5), so every solve that three steps made accurate keeps its path bit for
    /// bit.
    min_refinement_steps: usize = 3,
    /// Beyond `min_refinement_steps`, a correction is kept only if it reduces the residual relative
    /// to ‖rhs‖ by at least this factor; otherwise it is undone and refinement stops (the default
    /// is LAPACK xGERFS's test). A contraction slower than that will not reach the accuracy test's
    /// 1e-5 within `max_refinement_steps` from where it stalled (e.g. the near-singular solves of
    /// `rotate-fast`, 0.99 per step).
    refinement_contraction: f64 = 0.5,
    /// Relative residual `‖K sol − rhs‖_∞ / ‖rhs‖_∞` at which refinement stops.
    refinement_tol: f64 = 1e-10,
    /// Normwise backward error `η = ‖K sol − rhs‖_∞ / (max|K_ij| ‖sol‖_∞ + ‖rhs‖_∞)` up to
    /// which a refined KKT solution that fails the relative-residual test above is still
    /// accepted, if its relative residual is at most [`LinearSolverSettings::backward_error_forcing`]
    /// (the default is about 45 ε; 0 disables). Such a solution solves exactly a matrix within η
    /// relative of `K`, as exactly as `K`'s own rounding allows: its large residual relative
    /// to `rhs` is the conditioning of a nearly flat direction of the barrier problem, where
    /// the exact Newton step is far longer than the right-hand side, not an inaccurate factor,
    /// and damping it by δ_w makes the solve creep along the valley until it stops
    /// `Acceptable` (fine `periodic-cot` meshes: 8 of 8 starts Solved with it on Radau 3 × 24,
    /// 1 of 8 without; docs/decisions/0008-one-kkt-regularization.md). It leaves every solve
    /// the relative test accepts unchanged.
    backward_error_tol: f64 = 1e-14,
    /// Largest relative residual `‖K sol − rhs‖_∞ / ‖rhs‖_∞` of a solution accepted on its
    /// backward error (the default is the forcing term of an inexact Newton method, Dembo,
    /// Eisenstat & Steihaug 1982): a step that leaves most of the linearized residual is
    /// dominated by its component along a nearly singular direction of `K`, however exact
    /// the solve, and makes little progress (`rotate-fast` Radau 30 crawled at 4 % per
    /// iteration on steps with 0.3–0.5).
    backward_error_forcing: f64 = 0.1,
}
}

settings! {
/// What the solver does when a step fails: the inertia correction δ_w, δ_c of a rejected KKT factor (W&B Sect. 3.1, Algorithm IC) and the feasibility restoration phase (W&B Sect. 3.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RecoverySettings {
    /// First trial δ_w of the inertia correction.
    first_hessian_perturbation: f64 = 1e-4,
    /// Smallest δ_w (positive and finite).
    min_hessian_perturbation: f64 = 1e-20,
    /// Largest δ_w before giving up on the step. Ipopt's is 1e20; this larger one lets the
    /// inertia correction go on for about 22 more factorizations (κ_w⁺ = 8) before the step
    /// is given up.
    max_hessian_perturbation: f64 = 1e40,
    /// δ_w decrease factor κ_w⁻.
    perturb_dec_fact: f64 = 1.0 / 3.0,
    /// δ_w increase factor κ_w⁺ (finite and > 1, so that δ_w reaches
    /// `max_hessian_perturbation`).
    perturb_inc_fact: f64 = 8.0,
    /// δ_w first increase factor κ̄_w⁺ (finite and > 1).
    perturb_inc_fact_first: f64 = 100.0,
    /// δ_c = δ̄_c μ^κ_c used for a singular Jacobian: δ̄_c.
    jacobian_regularization_value: f64 = 1e-8,
    /// κ_c.
    jacobian_regularization_exponent: f64 = 0.25,
    /// Enable the feasibility restoration phase.
    restoration: bool = true,
    /// Penalty ρ of the restoration problem.
    resto_penalty: f64 = 1000.0,
    /// Required infeasibility reduction κ_resto to leave restoration.
    resto_required_reduction: f64 = 0.9,
}
}

settings! {
/// Research switches that no default path uses: each alternative was measured and kept for comparison, and is described with its evidence in decision record 0019. Their defaults are the solver's ordinary behaviour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExperimentalSettings {
    /// Elimination order of the KKT factorization ([`KktOrdering`]).
    kkt_ordering: KktOrdering = KktOrdering::AmdCheckedByPivotPairs,
    /// Where the extrapolation along negative curvature acts ([`ExtrapolationScope`]).
    extrapolation_scope: ExtrapolationScope = ExtrapolationScope::Answers,
    /// Judge the accuracy of a refined KKT solution (accepted at 1e-5; below 1e-6 against the
    /// unregularized matrix, else the step of the regularized system) on Ipopt's residual ratio `‖K
    /// sol − rhs‖_∞ / (‖rhs‖_∞ + ‖sol‖_∞)` instead of `‖K sol − rhs‖_∞ / ‖rhs‖_∞`. Near a flat
    /// valley of the barrier problem (a tiny reduced-Hessian eigenvalue) the Newton step is orders
    /// of magnitude longer than the right-hand side, and a backward-stable solve leaves a residual
    /// of order `ε ‖K‖ ‖sol‖`: measured against `‖rhs‖` alone, the exact step is rejected as
    /// inaccurate and damped by δ_w, which limits every step to about `‖rhs‖ / δ_w`, and the solve
    /// creeps along the valley. Not the default because the undamped steps change the paths of the
    /// collocation solves, not always for the better (BENCHMARKS.md).
    residual_ratio_with_solution: bool = false,
    /// First trial δ_w of a step whose previous step grew δ_w beyond its own first trial:
    /// this factor times δ_w_last in place of κ_w⁻ δ_w_last (`None`: κ_w⁻, W&B Algorithm IC).
    /// A larger factor (1/2, or 1: the δ_w that worked last) rejects fewer first trials, 1.41
    /// and 1.49 factorizations per iteration against 1.53 on the seven problems' cold solves;
    /// not the default because the larger δ_w changes every path, and the changed paths end at
    /// better and worse local optima alike, in more or fewer iterations (decision record 0035).
    perturb_dec_fact_after_rejection: Option<f64> = None,
}
}

settings! {
/// What the solver prints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OutputSettings {
    /// 0 = silent, 1 = Ipopt-style iteration log and the final status on stdout, 2 = also
    /// restoration details, 3 and above = also each KKT factorization (δ_w, δ_c, inertia),
    /// refinement residuals, the parts of the optimality error and the recovery strategy that
    /// acted.
    print_level: u8 = 0,
}
}

impl Settings {
    /// Checks that every parameter is in its valid range.
    pub fn validate(&self) -> Result<(), OptimError> {
        // Every range check names the setting and says what it must be.
        let check = |name: &'static str, v: f64, ok: bool, expected: &str| {
            if ok {
                Ok(())
            } else {
                Err(OptimError::InvalidSetting {
                    name,
                    msg: format!("must be {expected}, got {v}"),
                })
            }
        };
        let pos = |name, v: f64| check(name, v, v > 0.0 && v.is_finite(), "positive and finite");
        let nonneg = |name, v: f64| check(name, v, v >= 0.0 && v.is_finite(), "finite and ≥ 0");
        let at_least_one =
            |name, v: f64, expected| check(name, v, v >= 1.0 && v.is_finite(), expected);
        let unit = |name, v: f64| check(name, v, v > 0.0 && v < 1.0, "in (0, 1)");
        pos("tol", self.termination.tol)?;
        pos("constr_viol_tol", self.termination.constr_viol_tol)?;
        pos("dual_inf_tol", self.termination.dual_inf_tol)?;
        pos("compl_inf_tol", self.termination.compl_inf_tol)?;
        pos("acceptable_tol", self.termination.acceptable_tol)?;
        pos(
            "acceptable_constr_viol_tol",
            self.termination.acceptable_constr_viol_tol,
        )?;
        pos("mu_init", self.barrier.mu_init)?;
        pos("mu_min", self.barrier.mu_min)?;
        unit("mu_linear_decrease", self.barrier.mu_linear_decrease)?;
        if !(self.barrier.mu_superlinear_power > 1.0 && self.barrier.mu_superlinear_power < 2.0) {
            return Err(OptimError::InvalidSetting {
                name: "mu_superlinear_power",
                msg: format!(
                    "must be in (1, 2), got {}",
                    self.barrier.mu_superlinear_power
                ),
            });
        }
        pos("barrier_tol_factor", self.barrier.barrier_tol_factor)?;
        unit("tau_min", self.barrier.tau_min)?;
        pos("bound_push", self.barrier.bound_push)?;
        if !(self.barrier.bound_frac > 0.0 && self.barrier.bound_frac <= 0.5) {
            return Err(OptimError::InvalidSetting {
                name: "bound_frac",
                msg: "must be in (0, 0.5]".into(),
            });
        }
        pos("bound_mult_init", self.barrier.bound_mult_init)?;
        if self.barrier.bound_relax_factor.is_nan() || self.barrier.bound_relax_factor < 0.0 {
            return Err(OptimError::InvalidSetting {
                name: "bound_relax_factor",
                msg: "must be ≥ 0".into(),
            });
        }
        pos("warm_start_bound_push", self.barrier.warm_start_bound_push)?;
        pos(
            "warm_start_mult_bound_push",
            self.barrier.warm_start_mult_bound_push,
        )?;
        pos("kappa_sigma", self.barrier.kappa_sigma)?;
        pos("slack_move", self.barrier.slack_move)?;
        pos("scaling_max_gradient", self.scaling.scaling_max_gradient)?;
        nonneg("scaling_min_gradient", self.scaling.scaling_min_gradient)?;
        pos("obj_scaling_factor", self.scaling.obj_scaling_factor)?;
        unit(
            "refinement_contraction",
            self.linear_solver.refinement_contraction,
        )?;
        pos("refinement_tol", self.linear_solver.refinement_tol)?;
        nonneg("backward_error_tol", self.linear_solver.backward_error_tol)?;
        if !(self.linear_solver.backward_error_forcing > 0.0
            && self.linear_solver.backward_error_forcing <= 1.0)
        {
            return Err(OptimError::InvalidSetting {
                name: "backward_error_forcing",
                msg: format!(
                    "must be in (0, 1], got {}",
                    self.linear_solver.backward_error_forcing
                ),
            });
        }
        nonneg(
            "static_dual_regularization",
            self.linear_solver.static_dual_regularization,
        )?;
        at_least_one(
            "static_dual_regularization_growth",
            self.linear_solver.static_dual_regularization_growth,
            "finite and ≥ 1",
        )?;
        nonneg(
            "static_dual_regularization_max",
            self.linear_solver.static_dual_regularization_max,
        )?;
        nonneg(
            "pivot_pairs_check_max_delta_w",
            self.linear_solver.pivot_pairs_check_max_delta_w,
        )?;
        pos(
            "first_hessian_perturbation",
            self.recovery.first_hessian_perturbation,
        )?;
        // With 0 a δ_w_last that has shrunk to 0 by κ_w⁻ would restart the correction at 0,
        // and δ_w would never grow.
        pos(
            "min_hessian_perturbation",
            self.recovery.min_hessian_perturbation,
        )?;
        pos(
            "max_hessian_perturbation",
            self.recovery.max_hessian_perturbation,
        )?;
        nonneg("proximal_weight", self.barrier.proximal_weight)?;
        unit("perturb_dec_fact", self.recovery.perturb_dec_fact)?;
        if let Some(v) = self.experimental.perturb_dec_fact_after_rejection {
            check(
                "perturb_dec_fact_after_rejection",
                v,
                v > 0.0 && v <= 1.0,
                "in (0, 1]",
            )?;
        }
        // A factor ≤ 1 never grows δ_w, and the inertia correction, which stops only when δ_w
        // exceeds `max_hessian_perturbation`, would factor the same matrix forever.
        let above_one = |name, v: f64| check(name, v, v > 1.0 && v.is_finite(), "finite and > 1");
        above_one("perturb_inc_fact", self.recovery.perturb_inc_fact)?;
        above_one(
            "perturb_inc_fact_first",
            self.recovery.perturb_inc_fact_first,
        )?;
        nonneg(
            "jacobian_regularization_value",
            self.recovery.jacobian_regularization_value,
        )?;
        nonneg(
            "jacobian_regularization_exponent",
            self.recovery.jacobian_regularization_exponent,
        )?;
        unit("gamma_theta", self.line_search.gamma_theta)?;
        unit("gamma_phi", self.line_search.gamma_phi)?;
        unit("eta_phi", self.line_search.eta_phi)?;
        unit("alpha_red_factor", self.line_search.alpha_red_factor)?;
        unit("kappa_soc", self.line_search.kappa_soc)?;
        at_least_one(
            "max_curvature_extrapolation",
            self.line_search.max_curvature_extrapolation,
            "finite and ≥ 1 (1 turns the extrapolation off)",
        )?;
        unit(
            "resto_required_reduction",
            self.recovery.resto_required_reduction,
        )?;
        pos("resto_penalty", self.recovery.resto_penalty)?;
        pos("s_max", self.termination.s_max)?;
        if self.termination.max_wall_time.is_nan() || self.termination.max_wall_time <= 0.0 {
            return Err(OptimError::InvalidSetting {
                name: "max_wall_time",
                msg: "must be positive".into(),
            });
        }
        Ok(())
    }
}
