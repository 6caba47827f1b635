//! The primal-dual barrier algorithm on the standard form (Wächter & Biegler 2006, "W&B"),
//! Algorithm A of W&B Sect. 2 with the refinements of Sect. 3:
//!
//! * [`Core::run`]: the outer loop: initial point (W&B Sect. 3.6), optimality error and
//!   termination ([`termination`]), barrier update ([`barrier`]), search direction with
//!   inertia correction ([`step`]; with the proximal term on a barrier problem above the
//!   tolerance that has stalled, decision record 0011), filter line search ([`line_search`],
//!   [`filter`]; extrapolation along negative curvature on the barrier problems with μ ≤ tol,
//!   decision record 0010), slack safeguard for slacks that underflow (W&B end of Sect. 3.5,
//!   [`barrier`]), multiplier update with the κ_Σ safeguard (W&B eq. (16)); each phase is a
//!   method of [`iteration`];
//! * without an acceptable step, the chain of [`recovery`] strategies: soft restoration,
//!   monotone fallback, give up, acceptable stop, feasibility restoration
//!   ([`restoration_phase`], W&B Sect. 3.3);
//! * [`Core`]'s state by part of the algorithm ([`parts`]): bounds, iterate, evaluations,
//!   trial point, direction, KKT system, regularization, barrier parameters, filter;
//! * [`Ctx`], [`CoreStart`], [`CoreOutput`]: the shared per-solve state, the primal-dual
//!   starting point and the result, in internal variables (with the unscaled dual
//!   infeasibility and complementarity of the termination test at the final iterate).

mod barrier;
mod filter;
mod iteration;
mod line_search;
mod parts;
mod recovery;
mod restoration_phase;
mod step;
mod termination;

use std::time::Instant;

use self::barrier::MuRule;
use self::filter::Filter;
use self::iteration::StepChoice;
use self::parts::{
    Barrier, Bounds, Direction, Evaluations, Iterate, KktSystem, Regularization, RunState,
    TrialPoint,
};
use self::recovery::{Failure, NoStep, Remedy};
use self::termination::Verdict;
use super::kkt::SparseLdlt;
use super::settings::Settings;
use super::solution::{Counters, IterationInfo, Status, Timing};
use super::stdform::StdProblem;
use crate::error::OptimError;

/// Shared state of one user-level solve (also seen by the restoration phase's inner solve).
pub(crate) struct Ctx<'c, 'b> {
    pub settings: &'c Settings,
    pub timing: Timing,
    pub counters: Counters,
    /// Global iteration counter (restoration iterations included).
    pub iter: usize,
    pub start: Instant,
    pub callback: Option<&'b mut dyn FnMut(&IterationInfo) -> bool>,
}

/// Primal-dual starting point in internal variables.
pub(crate) struct CoreStart {
    pub x: Vec<f64>,
    pub y: Option<Vec<f64>>,
    /// Full-length (n) bound multipliers.
    pub z_l: Option<Vec<f64>>,
    pub z_u: Option<Vec<f64>>,
    pub mu: f64,
    pub bound_push: f64,
    pub bound_frac: f64,
    pub mult_floor: f64,
    /// Relax the bounds by `bound_relax_factor` (false inside restoration: the bounds are already
    /// the outer problem's relaxed ones).
    pub relax_bounds: bool,
    pub restoration: bool,
    /// Previously analysed KKT solvers to reuse (see [`super::Workspace`]).
    pub solvers: std::cell::Cell<KeptSolvers>,
}

/// The analysed KKT solvers a run starts with and hands back ([`Core::into_kkt_solvers`]),
/// so that a later run on a pattern analysed before takes its analysis back (decision records
/// 0062 and 0072). A kept analysis is the one a new solver would make for the same pattern and
/// options, so what a run is given changes no result.
#[derive(Debug, Default)]
pub(crate) struct KeptSolvers {
    /// The solver a run starts with (AMD, its last pattern's and [`crate::ipm::kkt::KEPT_ANALYSES`]
    /// others' analyses).
    pub main: Option<SparseLdlt>,
    /// Solvers with 2 × 2 pivot pairs for the pivot-pair checks, one per set of options.
    pub pairs: Vec<SparseLdlt>,
    /// Those of the restoration phases' inner runs, whose patterns (the problem's with the
    /// elastic variables `p`, `n`) the outer run's solvers never see.
    pub restoration: Option<Box<KeptSolvers>>,
}

impl KeptSolvers {
    /// Symbolic analyses computed by these solvers and the restoration phases' ones.
    pub fn analyses(&self) -> usize {
        self.main.as_ref().map_or(0, SparseLdlt::analyses)
            + self.pairs.iter().map(SparseLdlt::analyses).sum::<usize>()
            + self.restoration.as_ref().map_or(0, |r| r.analyses())
    }
}

/// Solvers with 2 × 2 pivot pairs a run hands back for later runs ([`Core::into_kkt_solvers`]):
/// one per set of options, i.e. per number of variables, which a search's threads alternate
/// between a few of.
pub(crate) const KEPT_PAIRS_SOLVERS: usize = 4;

/// Result of a core run in internal variables.
pub(crate) struct CoreOutput {
    pub status: Status,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub z_l: Vec<f64>,
    pub z_u: Vec<f64>,
    pub mu: f64,
    pub early_stopped: bool,
    /// Unscaled complementarity `max |s z|` against the relaxed bounds (inequality slacks
    /// included), as the termination test measures it.
    pub complementarity: f64,
    /// Unscaled dual infeasibility `‖∇f + Jᵀy − z_L + z_U‖_∞ / σ_f` over the internal variables
    /// (inequality slacks included), as the termination test measures it.
    pub dual_infeasibility: f64,
}

/// `a.max(b)`, except that a NaN in either is the result: `f64::max` returns the other
/// operand, so a NaN entry would vanish from an error measure and a NaN iterate could pass the
/// termination tests. Without a NaN it is `a.max(b)` bit for bit.
fn max_or_nan(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// ‖v‖_∞, NaN if an entry is NaN ([`max_or_nan`]).
fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| max_or_nan(a, x.abs()))
}
fn norm_1(v: &[f64]) -> f64 {
    v.iter().map(|x| x.abs()).sum()
}
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The algorithm's state for one run, by part ([`parts`]): the problem and its bounds, the
/// iterate and its evaluations, the trial point, the direction, the KKT system with its
/// regularization, the barrier parameters and the filter.
pub(crate) struct Core<'p> {
    prob: &'p mut dyn StdProblem,
    n: usize,
    m: usize,
    bounds: Bounds,
    iterate: Iterate,
    evals: Evaluations,
    trial: TrialPoint,
    direction: Direction,
    kkt: KktSystem,
    reg: Regularization,
    barrier: Barrier,
    /// The line search's filter, θ bounds and reset bookkeeping.
    filter: Filter,
    /// This run is a restoration phase's inner solve.
    restoration: bool,
    /// Largest |x_j| over the variables without a finite lower or upper bound, over all
    /// iterates so far (the unboundedness test).
    unboxed_max: std::cell::Cell<f64>,
    /// A trial point of this run had a non-finite objective or constraint value.
    met_non_finite_trial: bool,
    /// Where the last restoration phase handed the run back, while `met_non_finite_trial`:
    /// the iteration and the bits of μ, x, y, z_L and z_U (`Core::restoration_repeats`).
    last_restoration_end: Option<(usize, Vec<u64>)>,
}

impl<'p> Core<'p> {
    /// The state at `start` before the first evaluation (the bounds relaxed unless
    /// `start.relax_bounds` is off, the bound multipliers at `bound_mult_init`).
    pub fn new(
        prob: &'p mut dyn StdProblem,
        settings: &Settings,
        start: &CoreStart,
    ) -> Result<Self, OptimError> {
        let n = prob.n();
        let m = prob.m();
        let relax = if start.relax_bounds {
            settings.barrier.bound_relax_factor
        } else {
            0.0
        };
        let bounds = Bounds::new(prob.x_lower().to_vec(), prob.x_upper().to_vec(), relax);
        let jac_pat = prob.jac_pattern().to_vec();
        let hess_pat = prob.hess_pattern().to_vec();
        let kkt = KktSystem::new(n, m, &hess_pat, &jac_pat, start.solvers.take())?;
        let nlo = bounds.lo.len();
        let nup = bounds.up.len();
        Ok(Self {
            n,
            m,
            iterate: Iterate {
                x: start.x.clone(),
                y: vec![0.0; m],
                zl: vec![settings.barrier.bound_mult_init; nlo],
                zu: vec![settings.barrier.bound_mult_init; nup],
                sl: vec![0.0; nlo],
                su: vec![0.0; nup],
            },
            evals: Evaluations {
                f: 0.0,
                c: vec![0.0; m],
                grad: vec![0.0; n],
                jac: vec![0.0; jac_pat.len()],
                hess: vec![0.0; hess_pat.len()],
                derivs_x: Vec::new(),
                jac_pat,
                grad_phi: vec![0.0; n],
                jty: vec![0.0; n],
            },
            trial: TrialPoint {
                x: vec![0.0; n],
                c: vec![0.0; m],
                f: 0.0,
            },
            direction: Direction {
                dx: vec![0.0; n],
                dy: vec![0.0; m],
                dzl: vec![0.0; nlo],
                dzu: vec![0.0; nup],
            },
            kkt,
            reg: Regularization::new(settings),
            barrier: Barrier {
                mu: start.mu,
                tau: settings.barrier.tau_min.max(1.0 - start.mu),
                kappa_d: settings.barrier.kappa_d,
                slack_move: settings.barrier.slack_move,
            },
            filter: Filter::default(),
            restoration: start.restoration,
            unboxed_max: std::cell::Cell::new(f64::NEG_INFINITY),
            met_non_finite_trial: false,
            last_restoration_end: None,
            prob,
            bounds,
        })
    }

    // ---------- evaluations (timed) ----------

    fn eval_fc(&mut self, ctx: &mut Ctx<'_, '_>, trial: bool) -> (f64, bool) {
        let t = Instant::now();
        let (x, c) = if trial {
            (&self.trial.x, &mut self.trial.c)
        } else {
            (&self.iterate.x, &mut self.evals.c)
        };
        let f = self.prob.eval_f(x);
        self.prob.eval_c(x, c);
        ctx.counters.objective_evals += 1;
        ctx.counters.constraint_evals += 1;
        ctx.timing.function_evals += t.elapsed();
        let ok = f.is_finite() && c.iter().all(|v| v.is_finite());
        if trial && !ok {
            self.met_non_finite_trial = true;
        }
        (f, ok)
    }

    fn eval_derivs(&mut self, ctx: &mut Ctx<'_, '_>) -> bool {
        let t = Instant::now();
        self.prob.eval_grad(&self.iterate.x, &mut self.evals.grad);
        self.prob.eval_jac(&self.iterate.x, &mut self.evals.jac);
        ctx.timing.derivative_evals += t.elapsed();
        self.evals.derivs_x.clone_from(&self.iterate.x);
        self.evals.grad.iter().all(|v| v.is_finite())
            && self.evals.jac.iter().all(|v| v.is_finite())
    }

    fn eval_hessian(&mut self, ctx: &mut Ctx<'_, '_>) -> bool {
        let t = Instant::now();
        self.prob
            .eval_hess(&self.iterate.x, 1.0, &self.iterate.y, &mut self.evals.hess);
        ctx.counters.hessian_evals += 1;
        ctx.timing.derivative_evals += t.elapsed();
        self.evals.hess.iter().all(|v| v.is_finite())
    }

    // ---------- initialization ----------

    fn push_into_bounds(&self, x: &mut [f64], push: f64, frac: f64) {
        for j in 0..self.n {
            let (l, u) = (self.bounds.xl[j], self.bounds.xu[j]);
            if l.is_finite() && u.is_finite() {
                let pl = (push * l.abs().max(1.0)).min(frac * (u - l));
                let pu = (push * u.abs().max(1.0)).min(frac * (u - l));
                if x[j] < l + pl || !x[j].is_finite() {
                    x[j] = l + pl;
                }
                if x[j] > u - pu {
                    x[j] = u - pu;
                }
                if x[j] <= l || x[j] >= u {
                    x[j] = 0.5 * (l + u);
                }
            } else if l.is_finite() {
                let pl = push * l.abs().max(1.0);
                if x[j] < l + pl || !x[j].is_finite() {
                    x[j] = l + pl;
                }
            } else if u.is_finite() {
                let pu = push * u.abs().max(1.0);
                if x[j] > u - pu || !x[j].is_finite() {
                    x[j] = u - pu;
                }
            } else if !x[j].is_finite() {
                x[j] = 0.0;
            }
        }
    }

    fn log_header(&self, settings: &Settings) {
        if settings.output.print_level > 0 {
            println!(
                "iter    objective    inf_pr   inf_du lg(mu)  ||d||  lg(rg) alpha_du alpha_pr  ls"
            );
        }
    }

    fn log(&self, settings: &Settings, info: &IterationInfo) {
        if settings.output.print_level == 0 {
            return;
        }
        let rg = if info.delta_w > 0.0 {
            format!("{:5.1}", libm::log10(info.delta_w))
        } else {
            "    -".to_string()
        };
        println!(
            "{:4}{} {:14.7e} {:8.2e} {:8.2e} {:5.1} {:8.2e} {} {:8.2e} {:8.2e} {:3}",
            info.iter,
            if info.restoration { "r" } else { " " },
            info.objective,
            info.inf_pr,
            info.inf_du,
            libm::log10(info.mu),
            info.step_norm,
            rg,
            info.alpha_du,
            info.alpha_pr,
            info.ls_trials
        );
    }

    /// The result at the current iterate. Its dual infeasibility and complementarity are the
    /// unscaled ones of the termination test ([`Core::unscaled`]) at this iterate, with the
    /// derivatives re-evaluated first if x moved since they were last evaluated (a restoration
    /// point); where they are not finite there, the last finite ones stand.
    fn output(&mut self, ctx: &mut Ctx<'_, '_>, status: Status, early: bool) -> CoreOutput {
        if self.evals.derivs_x != self.iterate.x {
            let saved = (
                self.evals.c.clone(),
                self.evals.grad.clone(),
                self.evals.jac.clone(),
                self.evals.derivs_x.clone(),
            );
            let (f, ok) = self.eval_fc(ctx, false);
            if ok && self.eval_derivs(ctx) {
                self.evals.f = f;
            } else {
                (
                    self.evals.c,
                    self.evals.grad,
                    self.evals.jac,
                    self.evals.derivs_x,
                ) = saved;
            }
        }
        self.compute_jty();
        let err = self.errors(ctx.settings);
        let (dual_infeasibility, _, complementarity) = self.unscaled(&err);
        let mut zl = vec![0.0; self.n];
        let mut zu = vec![0.0; self.n];
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            zl[j] = self.iterate.zl[k];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            zu[j] = self.iterate.zu[k];
        }
        CoreOutput {
            dual_infeasibility,
            complementarity,
            status,
            x: self.iterate.x.clone(),
            y: self.iterate.y.clone(),
            z_l: zl,
            z_u: zu,
            mu: self.barrier.mu,
            early_stopped: early,
        }
    }

    /// Hands the (analysed) KKT solvers back for reuse by a later solve: the one a run starts
    /// with, the ones with 2 × 2 pivot pairs (at most [`KEPT_PAIRS_SOLVERS`]) and those of its
    /// restoration phases.
    pub fn into_kkt_solvers(self) -> KeptSolvers {
        let mut kkt = self.kkt;
        // After a switch to the pivot pairs, the AMD solver is the one whose analysis the next
        // run (which starts with AMD again) can reuse.
        let (main, pairs) = match (kkt.switched_to_pairs, kkt.other_solver) {
            (true, Some(amd)) => (amd, Some(kkt.solver)),
            (_, other) => (kkt.solver, other),
        };
        kkt.spare_pairs.extend(pairs);
        let excess = kkt.spare_pairs.len().saturating_sub(KEPT_PAIRS_SOLVERS);
        kkt.spare_pairs.drain(..excess);
        KeptSolvers {
            main: Some(main),
            pairs: kkt.spare_pairs,
            restoration: kkt.restoration_solvers,
        }
    }

    /// Runs the algorithm from `start`: W&B's Algorithm A, one outer iteration per pass of
    /// the loop. Each phase is a method of its own (`iteration.rs`, `step.rs`,
    /// `line_search.rs`, `barrier.rs`, `termination.rs`); an iteration without a step goes to
    /// the chain of `recovery.rs` (which ends in `restoration_phase.rs`).
    pub fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: &CoreStart,
    ) -> Result<CoreOutput, OptimError> {
        let settings = ctx.settings;
        self.analyse_kkt(ctx)?;
        self.initialize(ctx, start)?;
        let mut mu_rule = MuRule::new(settings, self.barrier.mu, self.prob.scales().0);
        let mut run = RunState::new(ctx.iter, self.restoration, self.barrier.mu);
        loop {
            // Optimality error E_0 (W&B eq. (5)), log and callback, termination tests.
            self.compute_jty();
            let err = self.errors(settings);
            let e0 = err.e(err.compl0);
            if let Some((status, early)) = self.report(ctx, &err, e0, &mut run) {
                return Ok(self.output(ctx, status, early));
            }
            let pr_u = match self.termination(ctx, &err, e0, &mut run.acceptable_count) {
                Verdict::Continue { pr_u } => pr_u,
                Verdict::Stop(status) => return Ok(self.output(ctx, status, false)),
            };
            // Barrier parameter (W&B eq. (7), or the adaptive rule).
            self.update_mu(settings, &mut mu_rule, &err, e0);
            // Search direction: the KKT system with inertia correction (Algorithm IC).
            let step_ok = self.search_direction(ctx, &mut mu_rule)?;
            // Step size: tiny steps, filter line search (W&B Sect. 3.3–3.9).
            let step = if step_ok {
                self.find_step(ctx, &err, &mut mu_rule, &mut run)
            } else {
                StepChoice::Recover(NoStep::NoDirection)
            };
            let taken = match step {
                StepChoice::Take(taken) => taken,
                StepChoice::Stop(status) => return Ok(self.output(ctx, status, false)),
                // No acceptable step: the chain of recovery strategies (`recovery`).
                StepChoice::Recover(kind) => {
                    let mut failure = Failure {
                        kind,
                        err: &err,
                        e0,
                        pr_u,
                        mu_rule: &mut mu_rule,
                        run: &mut run,
                    };
                    match self.recover(ctx, &mut failure)? {
                        Remedy::Take(taken) => taken,
                        Remedy::Resume => continue,
                        Remedy::Stop(status) => return Ok(self.output(ctx, status, false)),
                    }
                }
            };
            self.accept_step(ctx, taken, &mut run)?;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::termination::Errors;
    use super::{max_or_nan, norm_inf};

    /// A NaN entry is the ∞-norm wherever it stands (`f64::max` would return the other
    /// operand and drop it), and so is a NaN part of the optimality error, which then passes
    /// no tolerance test; without a NaN both are the plain maximum.
    #[test]
    fn a_nan_is_never_dropped_from_an_error_measure() {
        assert!(norm_inf(&[f64::NAN]).is_nan());
        assert!(norm_inf(&[f64::NAN, 1.0]).is_nan());
        assert!(norm_inf(&[1.0, f64::NAN, -3.0]).is_nan());
        assert_eq!(norm_inf(&[1.0, -3.0, 2.0]), 3.0);
        assert_eq!(norm_inf(&[f64::NEG_INFINITY, 1.0]), f64::INFINITY);
        assert_eq!(norm_inf(&[]), 0.0);
        assert!(max_or_nan(f64::NAN, 2.0).is_nan() && max_or_nan(2.0, f64::NAN).is_nan());
        assert_eq!(max_or_nan(-1.0, 2.0), 2.0);
        let err = |dual_inf, primal_inf| Errors {
            dual_inf,
            primal_inf,
            compl0: 0.0,
            s_d: 1.0,
            s_c: 1.0,
        };
        assert!(err(f64::NAN, 0.0).e(0.0).is_nan());
        assert!(err(0.0, f64::NAN).e(0.0).is_nan());
        assert!(err(0.0, 0.0).e(f64::NAN).is_nan());
        // So it compares with no tolerance: `e0 <= tol` is false.
        assert!(err(f64::NAN, 0.0).e(0.0).partial_cmp(&1e-8).is_none());
        assert_eq!(err(1e-3, 2e-3).e(5e-4), 2e-3);
    }
}
