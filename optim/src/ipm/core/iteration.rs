//! The phases of one outer iteration of [`Core::run`] (W&B Algorithm A), each a method so that
//! `run` reads as the algorithm:
//!
//! * [`Core::analyse_kkt`]: the symbolic analysis of the KKT pattern (once per run), with the
//!   elimination order of `ExperimentalSettings::kkt_ordering`;
//! * [`Core::initialize`]: the initial point pushed into the bounds, the bound multipliers,
//!   the first evaluations and the least-squares constraint multipliers (W&B Sect. 3.6), and
//!   the filter's θ_max, θ_min (W&B Sect. 3.3);
//! * [`Core::report`]: the iteration log line, the user callback and the restoration phase's
//!   early stop;
//! * [`Core::search_direction`]: the Hessian, the barrier gradient and the right-hand side,
//!   the proximal term on a stalled barrier problem (decision record 0011), then the KKT
//!   solve with inertia correction (`step`);
//! * [`Core::find_step`]: the step size: the tiny-step rule (W&B Sect. 3.9), the filter line
//!   search with extrapolation along negative curvature (decision record 0010), soft
//!   restoration;
//! * [`Core::accept_step`]: the new iterate, multipliers with the κ_Σ safeguard (W&B eq. (16));
//!
//! Without an acceptable step, the chain of recovery strategies of `recovery` decides
//! ([`Core::recover`]).

use std::time::Instant;

use super::barrier::MuRule;
use super::line_search::LsOutcome;
use super::parts::{RunState, Taken};
use super::recovery::NoStep;
use super::step::StepResult;
use super::{Core, CoreStart, Ctx, norm_1, norm_inf};
use crate::error::OptimError;
use crate::ipm::kkt::{KktSolver, LdltBackend, LdltOptions, LdltOrdering, SparseLdlt};
use crate::ipm::settings::{ExtrapolationScope, KktOrdering};
use crate::ipm::solution::Status;

/// The outcome of the step-size phase.
pub(super) enum StepChoice {
    /// Take this step.
    Take(Taken),
    /// No acceptable step: the recovery chain decides ([`Core::recover`]).
    Recover(NoStep),
    /// Stop with this status (tiny steps at the smallest μ).
    Stop(Status),
}

impl Core<'_> {
    /// Symbolic analysis of the KKT pattern, once per run, in the elimination order of
    /// `ExperimentalSettings::kkt_ordering`.
    pub(super) fn analyse_kkt(&mut self, ctx: &mut Ctx<'_, '_>) -> Result<(), OptimError> {
        let settings = ctx.settings;
        let t = Instant::now();
        self.kkt.check_pairs = matches!(
            settings.experimental.kkt_ordering,
            KktOrdering::AmdThenPivotPairs | KktOrdering::AmdCheckedByPivotPairs
        ) && self.m > 0;
        self.kkt.switched_to_pairs = false;
        self.kkt.other_solver = None;
        let ordering = match settings.experimental.kkt_ordering {
            KktOrdering::Amd
            | KktOrdering::AmdThenPivotPairs
            | KktOrdering::AmdCheckedByPivotPairs
            | KktOrdering::ThresholdPivoting => LdltOrdering::Amd,
            KktOrdering::AmdPivotPairs => LdltOrdering::AmdPivotPairs {
                constraint_rows_from: self.n,
            },
            KktOrdering::ConstraintsAfterVariables => {
                let mut bounded = vec![false; self.n];
                for &j in self.bounds.lo.iter().chain(&self.bounds.up) {
                    bounded[j] = true;
                }
                LdltOrdering::PairedAmd {
                    constraint_rows_from: self.n,
                    preferred_primal: bounded,
                }
            }
        };
        // A solver handed in by a workspace keeps its analysis when its options are the
        // ones this run needs (its backend is kept unless the ordering dictates one).
        let current = self.kkt.solver.options();
        let backend = match (settings.experimental.kkt_ordering, current.backend) {
            (KktOrdering::ThresholdPivoting, _) => LdltBackend::Multifrontal,
            (_, LdltBackend::Multifrontal) => LdltBackend::Auto,
            (_, backend) => backend,
        };
        let options = LdltOptions {
            backend,
            ordering,
            parallel: settings.linear_solver.parallel_factorization,
            ..current.clone()
        };
        if options != *current {
            self.kkt.solver = SparseLdlt::with_options(options);
        }
        self.kkt.solver.analyse(
            self.n + self.m,
            &self.kkt.matrix.mat.col_ptr,
            &self.kkt.matrix.mat.row_idx,
        )?;
        ctx.timing.factorization += t.elapsed();
        Ok(())
    }

    /// The initial point (W&B Sect. 3.6): x pushed into the bounds, slacks, bound multipliers
    /// from the start (at least `mult_floor`), f, c and their derivatives, the constraint
    /// multipliers (given or least squares) and the filter's θ bounds (W&B Sect. 3.3).
    pub(super) fn initialize(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: &CoreStart,
    ) -> Result<(), OptimError> {
        let settings = ctx.settings;
        let mut x0 = std::mem::take(&mut self.iterate.x);
        self.push_into_bounds(&mut x0, start.bound_push, start.bound_frac);
        self.iterate.x = x0;
        self.update_slacks();
        if let Some(z) = &start.z_l {
            for (k, &j) in self.bounds.lo.iter().enumerate() {
                self.iterate.zl[k] = z[j].max(start.mult_floor);
            }
        }
        if let Some(z) = &start.z_u {
            for (k, &j) in self.bounds.up.iter().enumerate() {
                self.iterate.zu[k] = z[j].max(start.mult_floor);
            }
        }
        let (f, ok) = self.eval_fc(ctx, false);
        self.evals.f = f;
        if !ok {
            return Err(OptimError::NonFinite {
                iter: ctx.iter,
                what: "objective or constraints at the initial point",
            });
        }
        if !self.eval_derivs(ctx) {
            return Err(OptimError::NonFinite {
                iter: ctx.iter,
                what: "gradient or Jacobian at the initial point",
            });
        }
        match &start.y {
            Some(y) => self.iterate.y.copy_from_slice(y),
            None => self.least_squares_y(ctx, settings),
        }
        let theta0 = norm_1(&self.evals.c);
        self.filter.set_bounds(theta0);
        Ok(())
    }

    /// Logs the iterate and calls the user's callback; `Some((status, early))` ends the run
    /// (the callback asked to stop, or the restoration phase reached its goal).
    pub(super) fn report(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        err: &super::termination::Errors,
        e0: f64,
        run: &mut RunState,
    ) -> Option<(Status, bool)> {
        let settings = ctx.settings;
        let (os, _) = self.prob.scales();
        let last = &mut run.last;
        last.iter = ctx.iter;
        last.objective = self.evals.f / os;
        last.inf_pr = err.primal_inf;
        last.inf_du = err.dual_inf;
        (last.dual_infeasibility, _, last.complementarity) = self.unscaled(err);
        last.mu = self.barrier.mu;
        if run.lines.is_multiple_of(10) {
            self.log_header(settings);
        }
        run.lines += 1;
        self.log(settings, &run.last);
        if let Some(cb) = ctx.callback.as_mut()
            && !cb(&run.last)
        {
            return Some((Status::UserStop, false));
        }
        if self.restoration && self.prob.early_stop(&self.iterate.x) {
            return Some((Status::Solved, true));
        }
        if settings.output.print_level > 2 {
            let (du_u, pr_u, co_u) = self.unscaled(err);
            println!(
                "    E0 {e0:.2e}: dual {:.2e} (s_d {:.2e}), primal {:.2e}, compl {:.2e} (s_c {:.2e}); unscaled dual {du_u:.2e}, primal {pr_u:.2e}, compl {co_u:.2e}; acceptable {}",
                err.dual_inf / err.s_d,
                err.s_d,
                err.primal_inf,
                err.compl0 / err.s_c,
                err.s_c,
                run.acceptable_count,
            );
        }
        None
    }

    /// The Newton direction of the barrier problem: Hessian, ∇φ_μ, right-hand side, the
    /// proximal floor of δ_w on a stalled barrier problem above the tolerance (decision record
    /// 0011), and the KKT solve with inertia correction. `Ok(false)`: no usable direction.
    pub(super) fn search_direction(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        mu_rule: &mut MuRule,
    ) -> Result<bool, OptimError> {
        let settings = ctx.settings;
        let stage_iterations = mu_rule.stage_iterations(self.barrier.mu, ctx.iter);
        if !self.eval_hessian(ctx) {
            return Err(OptimError::NonFinite {
                iter: ctx.iter,
                what: "Hessian",
            });
        }
        self.compute_grad_phi();
        self.set_rhs(None);
        self.reg.proximal = if self.barrier.mu > mu_rule.answer_mu
            && stage_iterations >= settings.barrier.proximal_after
            && !self.restoration
        {
            if settings.barrier.proximal_weight > 0.0 {
                ctx.counters.proximal_iterations += 1;
            }
            settings.barrier.proximal_weight * self.barrier.mu
        } else {
            0.0
        };
        Ok(matches!(
            self.compute_step(ctx, settings, true)?,
            StepResult::Ok
        ))
    }

    /// The step size along the direction just computed: the tiny-step rule (W&B Sect. 3.9),
    /// else the filter line search (extrapolating along negative curvature on the barrier
    /// problems the scope allows, decision record 0010).
    pub(super) fn find_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        err: &super::termination::Errors,
        mu_rule: &mut MuRule,
        run: &mut RunState,
    ) -> StepChoice {
        let settings = ctx.settings;
        self.unpack_step();
        let tiny = self
            .direction
            .dx
            .iter()
            .zip(&self.iterate.x)
            .all(|(d, x)| d.abs() / (1.0 + x.abs()) < 10.0 * f64::EPSILON)
            && err.primal_inf <= settings.termination.constr_viol_tol;
        if tiny {
            run.tiny_count += 1;
            if run.tiny_count >= 2 && self.barrier.mu <= mu_rule.floor {
                return StepChoice::Stop(Status::SearchDirectionTooSmall);
            }
            mu_rule.force_decrease = true;
            let amax = self.max_step_primal(&self.direction.dx);
            for j in 0..self.n {
                self.trial.x[j] = self.iterate.x[j] + amax * self.direction.dx[j];
            }
            let (f_t, ok) = self.eval_fc(ctx, true);
            if !ok {
                return StepChoice::Recover(NoStep::TrialNotEvaluable);
            }
            self.trial.f = f_t;
            return StepChoice::Take(Taken {
                alpha: amax,
                alpha_dual: None,
                trials: 1,
            });
        }
        run.tiny_count = 0;
        let extrapolate = settings.line_search.max_curvature_extrapolation > 1.0
            && (self.barrier.mu <= mu_rule.answer_mu
                || settings.experimental.extrapolation_scope == ExtrapolationScope::EveryBarrier);
        match self.line_search(ctx, settings, extrapolate) {
            LsOutcome::Accepted { alpha, trials } => {
                run.soft_count = 0;
                StepChoice::Take(Taken {
                    alpha,
                    alpha_dual: None,
                    trials,
                })
            }
            LsOutcome::Failed => StepChoice::Recover(NoStep::LineSearchFailed),
        }
    }

    /// Moves to the trial point: x, c, f, slacks, then the multipliers (y by the primal step
    /// capped at 1, z by the dual step) with the κ_Σ safeguard (W&B eq. (16)); evaluates the
    /// derivatives and counts the iteration.
    pub(super) fn accept_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        taken: Taken,
        run: &mut RunState,
    ) -> Result<(), OptimError> {
        let settings = ctx.settings;
        let accepted_alpha = taken.alpha;
        let alpha_z = taken.alpha_dual.unwrap_or_else(|| self.max_step_dual());
        std::mem::swap(&mut self.iterate.x, &mut self.trial.x);
        std::mem::swap(&mut self.evals.c, &mut self.trial.c);
        self.evals.f = self.trial.f;
        // Slacks before the multipliers move: an underflowed slack takes μ / z with the z
        // the trial point was judged with (as Ipopt's trial slacks).
        self.update_slacks();
        // `y + dy` is the Newton estimate of the multipliers: a primal step extrapolated
        // beyond α = 1 along negative curvature does not extend it.
        for i in 0..self.m {
            self.iterate.y[i] += accepted_alpha.min(1.0) * self.direction.dy[i];
        }
        for k in 0..self.iterate.zl.len() {
            self.iterate.zl[k] += alpha_z * self.direction.dzl[k];
        }
        for k in 0..self.iterate.zu.len() {
            self.iterate.zu[k] += alpha_z * self.direction.dzu[k];
        }
        let ks = settings.barrier.kappa_sigma;
        let mu = self.barrier.mu;
        for k in 0..self.iterate.zl.len() {
            let s = self.iterate.sl[k];
            self.iterate.zl[k] = self.iterate.zl[k].min(ks * mu / s).max(mu / (ks * s));
        }
        for k in 0..self.iterate.zu.len() {
            let s = self.iterate.su[k];
            self.iterate.zu[k] = self.iterate.zu[k].min(ks * mu / s).max(mu / (ks * s));
        }
        if !self.eval_derivs(ctx) {
            return Err(OptimError::NonFinite {
                iter: ctx.iter,
                what: "gradient or Jacobian",
            });
        }
        ctx.iter += 1;
        if self.restoration {
            ctx.counters.restoration_iterations += 1;
        }
        let last = &mut run.last;
        last.step_norm = norm_inf(&self.direction.dx) * accepted_alpha;
        last.delta_w = self.reg.delta_w;
        last.alpha_du = alpha_z;
        last.alpha_pr = accepted_alpha;
        last.ls_trials = taken.trials;
        Ok(())
    }
}
