//! The solver's recovery mechanisms (Wächter & Biegler 2006, "W&B") as chains of strategies
//! behind one trait, [`Recovery`]: each strategy looks at a failure and either passes it on or
//! acts; [`first_remedy`] tries a chain in order until one acts. Two chains, one per level at
//! which the algorithm can fail:
//!
//! **A rejected KKT factor** ([`Rejection`], [`KKT_CHAIN`], run by `Core::compute_step` in
//! `step`; W&B Sect. 3.1, Algorithm IC, with the checks of decision record 0002):
//!
//! 1. [`PivotPairsCheck`]: the same matrix re-factored once per step with 2 × 2 (variable,
//!    constraint row) pivots tells an artefact of AMD's bare −δ_c pivots from a genuine need
//!    for δ_w (with `AmdThenPivotPairs` its factor is the step); with
//!    `AmdCheckedByPivotPairs` only where the rejected δ_w is at most
//!    `LinearSolverSettings::pivot_pairs_check_max_delta_w`;
//! 2. [`RaiseStaticDualRegularization`]: an artefact, or a factor with the right inertia that
//!    does not solve its own matrix, raises the static δ_c of the solve;
//! 3. [`JacobianRegularization`]: a singular matrix gets `δ_c = δ̄_c μ^κ_c`;
//! 4. [`HessianPerturbation`]: δ_w grows (first δ_w⁰ or κ_w⁻ δ_w_last, then by κ̄_w⁺ or κ_w⁺)
//!    up to its maximum, where the step fails.
//!
//! **No acceptable step** ([`Failure`], [`CHAIN`], run by [`Core::recover`] from `Core::run`):
//!
//! 1. [`SoftRestoration`]: after a failed filter line search near feasibility, Ipopt's
//!    primal-dual step that reduces the barrier optimality error `E_μ` (at most ten in a row);
//! 2. [`MonotoneFallback`]: the adaptive μ rule falls back to monotone mode (Nocedal, Wächter
//!    & Waltz 2009) and clears the filter;
//! 3. [`GiveUp`]: inside a restoration phase, or with `RecoverySettings::restoration` off, the run
//!    fails;
//! 4. [`AcceptableStop`]: an iterate at the acceptable level stops as `Acceptable`;
//! 5. [`RestorationPhase`]: the feasibility restoration phase (W&B Sect. 3.3,
//!    `restoration_phase`).
//!

use std::time::Instant;

use super::barrier::MuRule;
use super::parts::{Regularization, RunState, Taken};
use super::termination::Errors;
use super::{Core, Ctx};
use crate::error::OptimError;
use crate::ipm::settings::{KktOrdering, RecoverySettings};
use crate::ipm::solution::Status;

/// A strategy's answer: pass the failure on, or act.
pub(super) enum Outcome<A> {
    /// Not applicable here (or a change made that a later strategy completes).
    Pass,
    /// Acted: the caller does this.
    Act(A),
}

/// One recovery mechanism for failures of type `F`, answering with actions of type `A`.
pub(super) trait Recovery<F, A> {
    /// Short name (logs, docs).
    fn name(&self) -> &'static str;
    /// Acts on `failure`, or passes it on.
    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut F,
    ) -> Result<Outcome<A>, OptimError>;
}

/// Tries `chain` in order on `failure`; the first strategy that acts decides (its name and
/// action); `None` when every one passed.
pub(super) fn first_remedy<F, A, R: Recovery<F, A> + ?Sized>(
    chain: &[&R],
    core: &mut Core<'_>,
    ctx: &mut Ctx<'_, '_>,
    failure: &mut F,
) -> Result<Option<(&'static str, A)>, OptimError> {
    for strategy in chain {
        if let Outcome::Act(action) = strategy.attempt(core, ctx, failure)? {
            return Ok(Some((strategy.name(), action)));
        }
    }
    Ok(None)
}

// ---------- a rejected KKT factor ----------

/// What the inertia correction remembers within one Newton step.
#[derive(Default)]
pub(super) struct StepMemory {
    /// The pivot pairs have checked a rejected factor of this step.
    pub pairs_checked: bool,
    /// The static δ_c was raised in this step.
    pub raised_c: bool,
    /// The Jacobian regularization δ_c is on.
    pub singular_handled: bool,
}

/// A factorization of `K(δ_w, δ_c)` that the step cannot use.
pub(super) struct Rejection<'m> {
    /// No usable factor, or one that cannot solve its own matrix.
    pub singular: bool,
    /// The factor has the right inertia but its refined solution is inaccurate.
    pub inaccurate: bool,
    /// The pivot pairs accepted the matrix that AMD's factor rejected.
    pub artefact: bool,
    /// The (1,1) block carries the Hessian (δ_w bookkeeping applies).
    pub use_hessian: bool,
    /// δ_w and δ_c of the rejected matrix.
    pub old_w: f64,
    /// See `old_w`.
    pub old_c: f64,
    /// The step's memory.
    pub memory: &'m mut StepMemory,
}

/// What the inertia correction does next.
#[derive(Debug, PartialEq, Eq)]
pub(super) enum KktAction {
    /// Factor the corrected matrix.
    Refactor,
    /// The current factor's solution is the step.
    Solved,
    /// δ_w beyond its maximum: no step.
    GiveUp,
}

/// The inertia correction, in the order it is tried.
pub(super) const KKT_CHAIN: [&dyn for<'m> Recovery<Rejection<'m>, KktAction>; 4] = [
    &PivotPairsCheck,
    &RaiseStaticDualRegularization,
    &JacobianRegularization,
    &HessianPerturbation,
];

/// Re-factors a rejected AMD factor's matrix with 2 × 2 pivot pairs, once per step
/// (`Core::try_pivot_pairs`; with `AmdCheckedByPivotPairs` only at a δ_w up to
/// `LinearSolverSettings::pivot_pairs_check_max_delta_w`): where the pairs accept it, the
/// rejection was an artefact of AMD's bare −δ_c pivots. `AmdThenPivotPairs` takes the pairs'
/// step and keeps their order, `AmdCheckedByPivotPairs` passes the artefact on to
/// [`RaiseStaticDualRegularization`].
pub(super) struct PivotPairsCheck;

impl<'m> Recovery<Rejection<'m>, KktAction> for PivotPairsCheck {
    fn name(&self) -> &'static str {
        "pivot pairs check"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        r: &mut Rejection<'m>,
    ) -> Result<Outcome<KktAction>, OptimError> {
        if !core.kkt.check_pairs || r.memory.pairs_checked {
            return Ok(Outcome::Pass);
        }
        r.memory.pairs_checked = true;
        let switch = ctx.settings.experimental.kkt_ordering == KktOrdering::AmdThenPivotPairs;
        // A δ_w this large outweighs the bare pivots' rounding: the check would only confirm
        // the rejection (`LinearSolverSettings::pivot_pairs_check_max_delta_w`). Within a step
        // δ_w only grows, so the step is not checked later either, as before.
        if !switch && r.old_w > ctx.settings.linear_solver.pivot_pairs_check_max_delta_w {
            return Ok(Outcome::Pass);
        }
        if core.try_pivot_pairs(ctx, ctx.settings, switch) {
            if switch {
                return Ok(Outcome::Act(KktAction::Solved));
            }
            r.artefact = true;
        }
        Ok(Outcome::Pass)
    }
}

/// A factor with the right inertia that does not solve its own matrix to 1e-5 after
/// refinement has grown like 1/δ_c, and so have the bare pivots of an AMD factor that the
/// pairs showed to be spurious: a larger static δ_c for the rest of the solve (refinement still
/// targets the unregularized system) rather than a larger δ_w, which would damp every later
/// step. Once per step, up to `static_dual_regularization_max`.
pub(super) struct RaiseStaticDualRegularization;

impl<'m> Recovery<Rejection<'m>, KktAction> for RaiseStaticDualRegularization {
    fn name(&self) -> &'static str {
        "raise the static δ_c"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        r: &mut Rejection<'m>,
    ) -> Result<Outcome<KktAction>, OptimError> {
        if !((r.inaccurate || r.artefact) && core.m > 0 && !r.memory.raised_c) {
            return Ok(Outcome::Pass);
        }
        let ls = &ctx.settings.linear_solver;
        let raised = (core.reg.delta_c * ls.static_dual_regularization_growth)
            .min(ls.static_dual_regularization_max);
        if raised <= core.reg.delta_c {
            if ctx.settings.experimental.kkt_ordering == KktOrdering::AmdCheckedByPivotPairs {
                // δ_c at its largest: the checks have nothing more to decide.
                core.kkt.check_pairs = false;
            }
            return Ok(Outcome::Pass);
        }
        r.memory.raised_c = true;
        ctx.counters.dual_regularization_raised_at = Some(ctx.iter);
        if ctx.settings.output.print_level > 0 {
            println!(
                "KKT: {}: static δ_c {:.1e} → {raised:.1e} from iteration {}",
                if r.artefact {
                    "AMD's factor rejected where the pivot pairs' is right"
                } else {
                    "factor with the right inertia but inaccurate"
                },
                core.reg.delta_c,
                ctx.iter
            );
        }
        let old_c = core.reg.delta_c;
        core.reg.static_dc = core.reg.static_dc.max(raised);
        core.reg.delta_c = raised;
        core.reg.delta_c_target = core.reg.delta_c_target.min(raised);
        let t = Instant::now();
        core.kkt.matrix.shift_diagonal(0.0, raised - old_c);
        ctx.timing.kkt_assembly += t.elapsed();
        Ok(Outcome::Act(KktAction::Refactor))
    }
}

/// A singular matrix (no usable factor, or an inaccurate one) gets the Jacobian
/// regularization `δ_c = max(δ̄_c μ^κ_c, static δ_c)`, once per step (W&B Algorithm IC,
/// step IC-2). From here on the rejection is genuine: a step whose δ_w = 0 trial failed starts
/// the next step from κ_w⁻ δ_w_last.
pub(super) struct JacobianRegularization;

impl<'m> Recovery<Rejection<'m>, KktAction> for JacobianRegularization {
    fn name(&self) -> &'static str {
        "Jacobian regularization"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        r: &mut Rejection<'m>,
    ) -> Result<Outcome<KktAction>, OptimError> {
        if core.reg.delta_w == 0.0 && r.use_hessian {
            core.reg.skip_zero_trial = true;
        }
        if !(r.singular && !r.memory.singular_handled && core.m > 0) {
            return Ok(Outcome::Pass);
        }
        r.memory.singular_handled = true;
        let rec = &ctx.settings.recovery;
        let dc = rec.jacobian_regularization_value
            * libm::pow(core.barrier.mu, rec.jacobian_regularization_exponent);
        core.reg.delta_c = dc.max(core.reg.static_dc);
        core.reg.delta_c_target = core.reg.delta_c;
        // δ_c unchanged (μ small enough that δ̄_c μ^κ_c ≤ the static δ_c): the matrix and the
        // factor are the ones just rejected, so go straight to δ_w; with δ_w > 0 already, δ_w
        // grows too and both shifts go into one matrix.
        if r.old_w == 0.0 && core.reg.delta_c != r.old_c {
            let t = Instant::now();
            core.kkt
                .matrix
                .shift_diagonal(0.0, core.reg.delta_c - r.old_c);
            ctx.timing.kkt_assembly += t.elapsed();
            return Ok(Outcome::Act(KktAction::Refactor));
        }
        Ok(Outcome::Pass)
    }
}

/// δ_w grows (W&B Algorithm IC, steps IC-3 to IC-6): the first trial is δ_w⁰ or κ_w⁻
/// δ_w_last, then δ_w is multiplied by κ̄_w⁺ (no earlier δ_w) or κ_w⁺; beyond
/// `max_hessian_perturbation` the step fails. The last link: it always acts.
pub(super) struct HessianPerturbation;

impl<'m> Recovery<Rejection<'m>, KktAction> for HessianPerturbation {
    fn name(&self) -> &'static str {
        "Hessian perturbation"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        r: &mut Rejection<'m>,
    ) -> Result<Outcome<KktAction>, OptimError> {
        let rec = &ctx.settings.recovery;
        core.reg.delta_w = next_delta_w(&core.reg, rec);
        if core.reg.delta_w > rec.max_hessian_perturbation {
            return Ok(Outcome::Act(KktAction::GiveUp));
        }
        let t = Instant::now();
        core.kkt
            .matrix
            .shift_diagonal(core.reg.delta_w - r.old_w, core.reg.delta_c - r.old_c);
        ctx.timing.kkt_assembly += t.elapsed();
        Ok(Outcome::Act(KktAction::Refactor))
    }
}

/// The δ_w that [`HessianPerturbation`] gives the matrix after a rejection of the current one
/// (beyond `max_hessian_perturbation`: no step). Also the prediction of the speculative
/// factorization (`Core::factor_trial`), so both are this one rule.
pub(super) fn next_delta_w(reg: &Regularization, rec: &RecoverySettings) -> f64 {
    if reg.delta_w == 0.0 {
        if reg.delta_w_last == 0.0 {
            rec.first_hessian_perturbation
        } else {
            (rec.perturb_dec_fact * reg.delta_w_last).max(rec.min_hessian_perturbation)
        }
    } else if reg.delta_w_last == 0.0 {
        reg.delta_w * rec.perturb_inc_fact_first
    } else {
        reg.delta_w * rec.perturb_inc_fact
    }
}

// ---------- no acceptable step ----------

/// Why the iteration has no step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NoStep {
    /// The KKT system gave no usable direction (δ_w beyond its maximum).
    NoDirection,
    /// The trial point of a tiny step (W&B Sect. 3.9) is not evaluable.
    TrialNotEvaluable,
    /// The filter line search found no acceptable step size.
    LineSearchFailed,
}

/// An iteration without a step, with the loop state a strategy may change.
pub(super) struct Failure<'a> {
    /// What failed.
    pub kind: NoStep,
    /// The current iterate's optimality errors (W&B eq. (5)).
    pub err: &'a Errors,
    /// Scaled optimality error `E_0`.
    pub e0: f64,
    /// Unscaled primal infeasibility.
    pub pr_u: f64,
    /// The barrier-parameter rule.
    pub mu_rule: &'a mut MuRule,
    /// The loop's own state (counters, log record).
    pub run: &'a mut RunState,
}

/// What the iteration does instead of its step.
pub(super) enum Remedy {
    /// Take this step.
    Take(Taken),
    /// The state changed (barrier rule, filter, iterate): go on with the next iteration.
    Resume,
    /// Stop the run with this status.
    Stop(Status),
}

/// The step-level chain, in the order it is tried.
pub(super) const CHAIN: [&dyn for<'a> Recovery<Failure<'a>, Remedy>; 5] = [
    &SoftRestoration,
    &MonotoneFallback,
    &GiveUp,
    &AcceptableStop,
    &RestorationPhase,
];

/// Ipopt's soft restoration step (`Core::soft_restoration_step`), after a failed line search.
pub(super) struct SoftRestoration;

impl<'a> Recovery<Failure<'a>, Remedy> for SoftRestoration {
    fn name(&self) -> &'static str {
        "soft restoration"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'a>,
    ) -> Result<Outcome<Remedy>, OptimError> {
        if failure.kind != NoStep::LineSearchFailed {
            return Ok(Outcome::Pass);
        }
        let e_mu = failure.err.e(core.compl_mu(core.barrier.mu));
        // The trial is evaluated (and counted) even past the limit of ten in a row.
        match core.soft_restoration_step(ctx, ctx.settings, e_mu) {
            Some(alpha) if failure.run.soft_count < 10 => {
                failure.run.soft_count += 1;
                Ok(Outcome::Act(Remedy::Take(Taken {
                    alpha,
                    alpha_dual: Some(alpha),
                    trials: 0,
                })))
            }
            _ => Ok(Outcome::Pass),
        }
    }
}

/// The adaptive μ rule's fallback to monotone mode: μ from the average complementarity, the
/// filter cleared.
pub(super) struct MonotoneFallback;

impl<'a> Recovery<Failure<'a>, Remedy> for MonotoneFallback {
    fn name(&self) -> &'static str {
        "monotone fallback"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'a>,
    ) -> Result<Outcome<Remedy>, OptimError> {
        let rule = &mut *failure.mu_rule;
        if !rule.free_mode {
            return Ok(Outcome::Pass);
        }
        rule.free_mode = false;
        if let Some((avg, _)) = core.avg_compl() {
            core.barrier.mu = (0.8 * avg).max(rule.floor);
            core.barrier.tau = ctx.settings.barrier.tau_min.max(1.0 - core.barrier.mu);
        }
        core.filter.clear();
        Ok(Outcome::Act(Remedy::Resume))
    }
}

/// No restoration to fall back on: inside a restoration phase, or with it switched off.
pub(super) struct GiveUp;

impl<'a> Recovery<Failure<'a>, Remedy> for GiveUp {
    fn name(&self) -> &'static str {
        "give up"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'a>,
    ) -> Result<Outcome<Remedy>, OptimError> {
        if !core.restoration && ctx.settings.recovery.restoration {
            return Ok(Outcome::Pass);
        }
        Ok(Outcome::Act(Remedy::Stop(
            if failure.kind == NoStep::NoDirection {
                Status::ErrorInStepComputation
            } else {
                Status::RestorationFailed
            },
        )))
    }
}

/// An iterate at the acceptable level (`acceptable_tol`, `acceptable_constr_viol_tol`) is the
/// answer rather than a restoration phase's start.
pub(super) struct AcceptableStop;

impl<'a> Recovery<Failure<'a>, Remedy> for AcceptableStop {
    fn name(&self) -> &'static str {
        "acceptable stop"
    }

    fn attempt(
        &self,
        _core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'a>,
    ) -> Result<Outcome<Remedy>, OptimError> {
        let t = &ctx.settings.termination;
        if failure.e0 <= t.acceptable_tol && failure.pr_u <= t.acceptable_constr_viol_tol {
            Ok(Outcome::Act(Remedy::Stop(Status::Acceptable)))
        } else {
            Ok(Outcome::Pass)
        }
    }
}

/// The feasibility restoration phase (W&B Sect. 3.3); the last link, it always acts.
pub(super) struct RestorationPhase;

impl<'a> Recovery<Failure<'a>, Remedy> for RestorationPhase {
    fn name(&self) -> &'static str {
        "restoration phase"
    }

    fn attempt(
        &self,
        core: &mut Core<'_>,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'a>,
    ) -> Result<Outcome<Remedy>, OptimError> {
        if let Some(status) = core.restoration_phase(ctx, ctx.settings)? {
            return Ok(Outcome::Act(Remedy::Stop(status)));
        }
        // The next log line is the outer iteration's, with no step of its own yet.
        let last = &mut failure.run.last;
        last.restoration = false;
        last.step_norm = 0.0;
        last.alpha_du = 0.0;
        last.alpha_pr = 0.0;
        last.ls_trials = 0;
        last.delta_w = 0.0;
        Ok(Outcome::Act(Remedy::Resume))
    }
}

impl Core<'_> {
    /// Runs the step-level [`CHAIN`] on `failure` up to the first strategy that acts.
    pub(super) fn recover(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        failure: &mut Failure<'_>,
    ) -> Result<Remedy, OptimError> {
        match first_remedy(&CHAIN, self, ctx, failure)? {
            Some((name, remedy)) => {
                if ctx.settings.output.print_level > 2 {
                    println!("    recovery: {name}");
                }
                Ok(remedy)
            }
            // The restoration phase never passes.
            None => Ok(Remedy::Stop(Status::RestorationFailed)),
        }
    }
}
