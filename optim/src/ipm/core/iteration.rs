//! The phases of one outer iteration of [`Core::run`] (W&B Algorithm A), each a method so that
//! `run` reads as the algorithm:
//!
//! * [`Core::analyse_kkt`]: the symbolic analysis of the KKT pattern (once per run), with the
//!   elimination order of `Settings::kkt_ordering`;
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
//! * [`Core::recover`]: what happens without an acceptable step: the adaptive rule's fallback
//!   to monotone μ, the acceptable-level stop, the restoration phase (W&B Sect. 3.3).

use std::time::Instant;

use super::barrier::MuRule;
use super::line_search::LsOutcome;
use super::step::StepResult;
use super::{Core, CoreStart, Ctx, norm_1, norm_inf};
use crate::error::OptimError;
use crate::ipm::kkt::{KktSolver, LdltBackend, LdltOptions, LdltOrdering, SparseLdlt};
use crate::ipm::settings::{ExtrapolationScope, KktOrdering};
use crate::ipm::solution::{IterationInfo, Status};

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
    alpha: f64,
    /// Dual step size when a soft restoration step fixed it; otherwise the fraction to the
    /// boundary decides.
    alpha_dual: Option<f64>,
    /// Line-search trials.
    trials: usize,
}

/// The outcome of the step-size phase.
pub(super) enum StepChoice {
    /// Take this step.
    Take(Taken),
    /// No acceptable step: recover ([`Core::recover`]).
    Recover,
    /// Stop with this status (tiny steps at the smallest μ).
    Stop(Status),
}

impl Core<'_> {
    /// Symbolic analysis of the KKT pattern, once per run, in the elimination order of
    /// `Settings::kkt_ordering`.
    pub(super) fn analyse_kkt(&mut self, ctx: &mut Ctx<'_, '_>) -> Result<(), OptimError> {
        let settings = ctx.settings;
        let t = Instant::now();
        self.check_pairs = matches!(
            settings.kkt_ordering,
            KktOrdering::AmdThenPivotPairs | KktOrdering::AmdCheckedByPivotPairs
        ) && self.m > 0;
        self.switched_to_pairs = false;
        self.other_solver = None;
        let ordering = match settings.kkt_ordering {
            KktOrdering::Amd
            | KktOrdering::AmdThenPivotPairs
            | KktOrdering::AmdCheckedByPivotPairs
            | KktOrdering::ThresholdPivoting => LdltOrdering::Amd,
            KktOrdering::AmdPivotPairs => LdltOrdering::AmdPivotPairs {
                constraint_rows_from: self.n,
            },
            KktOrdering::ConstraintsAfterVariables => {
                let mut bounded = vec![false; self.n];
                for &j in self.lo.iter().chain(&self.up) {
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
        let current = self.solver.options();
        let backend = match (settings.kkt_ordering, current.backend) {
            (KktOrdering::ThresholdPivoting, _) => LdltBackend::Multifrontal,
            (_, LdltBackend::Multifrontal) => LdltBackend::Auto,
            (_, backend) => backend,
        };
        let options = LdltOptions {
            backend,
            ordering,
            ..current.clone()
        };
        if options != *current {
            self.solver = SparseLdlt::with_options(options);
        }
        self.solver.analyse(
            self.n + self.m,
            &self.kkt.mat.col_ptr,
            &self.kkt.mat.row_idx,
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
        let mut x0 = std::mem::take(&mut self.x);
        self.push_into_bounds(&mut x0, start.bound_push, start.bound_frac);
        self.x = x0;
        self.update_slacks();
        if let Some(z) = &start.z_l {
            for (k, &j) in self.lo.iter().enumerate() {
                self.zl[k] = z[j].max(start.mult_floor);
            }
        }
        if let Some(z) = &start.z_u {
            for (k, &j) in self.up.iter().enumerate() {
                self.zu[k] = z[j].max(start.mult_floor);
            }
        }
        let (f, ok) = self.eval_fc(ctx, false);
        self.f = f;
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
            Some(y) => self.y.copy_from_slice(y),
            None => self.least_squares_y(ctx, settings),
        }
        let theta0 = norm_1(&self.c);
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
        last.objective = self.f / os;
        last.inf_pr = err.primal_inf;
        last.inf_du = err.dual_inf;
        (last.dual_infeasibility, _, last.complementarity) = self.unscaled(err);
        last.mu = self.mu;
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
        if self.restoration && self.prob.early_stop(&self.x) {
            return Some((Status::Solved, true));
        }
        if settings.print_level > 2 {
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
        let stage_iterations = mu_rule.stage_iterations(self.mu, ctx.iter);
        if !self.eval_hessian(ctx) {
            return Err(OptimError::NonFinite {
                iter: ctx.iter,
                what: "Hessian",
            });
        }
        self.compute_grad_phi();
        self.set_rhs(None);
        self.proximal = if self.mu > mu_rule.answer_mu
            && stage_iterations >= settings.proximal_after
            && !self.restoration
        {
            if settings.proximal_weight > 0.0 {
                ctx.counters.proximal_iterations += 1;
            }
            settings.proximal_weight * self.mu
        } else {
            0.0
        };
        Ok(matches!(
            self.compute_step(ctx, settings, true),
            StepResult::Ok
        ))
    }

    /// The step size along the direction just computed: the tiny-step rule (W&B Sect. 3.9),
    /// else the filter line search (extrapolating along negative curvature on the barrier
    /// problems the scope allows, decision record 0010), else a soft restoration step.
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
            .dx
            .iter()
            .zip(&self.x)
            .all(|(d, x)| d.abs() / (1.0 + x.abs()) < 10.0 * f64::EPSILON)
            && err.primal_inf <= settings.constr_viol_tol;
        if tiny {
            run.tiny_count += 1;
            if run.tiny_count >= 2 && self.mu <= mu_rule.floor {
                return StepChoice::Stop(Status::SearchDirectionTooSmall);
            }
            mu_rule.force_decrease = true;
            let amax = self.max_step_primal(&self.dx);
            for j in 0..self.n {
                self.x_t[j] = self.x[j] + amax * self.dx[j];
            }
            let (f_t, ok) = self.eval_fc(ctx, true);
            if !ok {
                return StepChoice::Recover;
            }
            self.f_t = f_t;
            return StepChoice::Take(Taken {
                alpha: amax,
                alpha_dual: None,
                trials: 1,
            });
        }
        run.tiny_count = 0;
        let extrapolate = settings.max_curvature_extrapolation > 1.0
            && (self.mu <= mu_rule.answer_mu
                || settings.extrapolation_scope == ExtrapolationScope::EveryBarrier);
        match self.line_search(ctx, settings, extrapolate) {
            LsOutcome::Accepted { alpha, trials } => {
                run.soft_count = 0;
                StepChoice::Take(Taken {
                    alpha,
                    alpha_dual: None,
                    trials,
                })
            }
            LsOutcome::Failed => {
                let e_mu = err.e(self.compl_mu(self.mu));
                match self.soft_restoration_step(ctx, settings, e_mu) {
                    Some(a) if run.soft_count < 10 => {
                        run.soft_count += 1;
                        StepChoice::Take(Taken {
                            alpha: a,
                            alpha_dual: Some(a),
                            trials: 0,
                        })
                    }
                    _ => StepChoice::Recover,
                }
            }
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
        std::mem::swap(&mut self.x, &mut self.x_t);
        std::mem::swap(&mut self.c, &mut self.c_t);
        self.f = self.f_t;
        // Slacks before the multipliers move: an underflowed slack takes μ / z with the z
        // the trial point was judged with (as Ipopt's trial slacks).
        self.update_slacks();
        // `y + dy` is the Newton estimate of the multipliers: a primal step extrapolated
        // beyond α = 1 along negative curvature does not extend it.
        for i in 0..self.m {
            self.y[i] += accepted_alpha.min(1.0) * self.dy[i];
        }
        for k in 0..self.zl.len() {
            self.zl[k] += alpha_z * self.dzl[k];
        }
        for k in 0..self.zu.len() {
            self.zu[k] += alpha_z * self.dzu[k];
        }
        let ks = settings.kappa_sigma;
        let mu = self.mu;
        for k in 0..self.zl.len() {
            let s = self.sl[k];
            self.zl[k] = self.zl[k].min(ks * mu / s).max(mu / (ks * s));
        }
        for k in 0..self.zu.len() {
            let s = self.su[k];
            self.zu[k] = self.zu[k].min(ks * mu / s).max(mu / (ks * s));
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
        last.step_norm = norm_inf(&self.dx) * accepted_alpha;
        last.delta_w = self.delta_w;
        last.alpha_du = alpha_z;
        last.alpha_pr = accepted_alpha;
        last.ls_trials = taken.trials;
        Ok(())
    }

    /// No acceptable step (`step_ok`: a direction existed but no step along it was
    /// acceptable). In order: the adaptive μ rule falls back to monotone mode; inside
    /// restoration (or with restoration off) the run fails; an iterate at the acceptable
    /// level stops as `Acceptable`; otherwise the restoration phase runs. `Some(status)` ends
    /// the run.
    pub(super) fn recover(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        step_ok: bool,
        e0: f64,
        pr_u: f64,
        mu_rule: &mut MuRule,
        run: &mut RunState,
    ) -> Result<Option<Status>, OptimError> {
        let settings = ctx.settings;
        if mu_rule.free_mode {
            mu_rule.free_mode = false;
            if let Some((avg, _)) = self.avg_compl() {
                self.mu = (0.8 * avg).max(mu_rule.floor);
                self.tau = settings.tau_min.max(1.0 - self.mu);
            }
            self.filter.clear();
            return Ok(None);
        }
        if self.restoration || !settings.restoration {
            return Ok(Some(if step_ok {
                Status::RestorationFailed
            } else {
                Status::ErrorInStepComputation
            }));
        }
        if e0 <= settings.acceptable_tol && pr_u <= settings.acceptable_constr_viol_tol {
            return Ok(Some(Status::Acceptable));
        }
        if let Some(status) = self.restoration_phase(ctx, settings)? {
            return Ok(Some(status));
        }
        let last = &mut run.last;
        last.restoration = false;
        last.step_norm = 0.0;
        last.alpha_du = 0.0;
        last.alpha_pr = 0.0;
        last.ls_trials = 0;
        last.delta_w = 0.0;
        Ok(None)
    }
}
