//! The primal-dual barrier algorithm on the standard form (Wächter & Biegler 2006, "W&B"),
//! Algorithm A of W&B Sect. 2 with the refinements of Sect. 3:
//!
//! * [`Core::run`]: the outer loop: initial point (W&B Sect. 3.6), optimality error and
//!   termination ([`termination`]), barrier update ([`barrier`]), search direction with
//!   inertia correction ([`step`]; with the proximal term on a barrier problem above the
//!   tolerance that has stalled, decision record 0011), filter line search ([`line_search`];
//!   extrapolation along negative curvature on the barrier problems with μ ≤ tol, decision
//!   record 0010), slack safeguard for slacks that underflow (W&B end of Sect. 3.5,
//!   [`barrier`]), multiplier update with the
//!   κ_Σ safeguard (W&B eq. (16)), and feasibility restoration ([`restoration_phase`]);
//! * [`Ctx`], [`CoreStart`], [`CoreOutput`]: the shared per-solve state, the primal-dual
//!   starting point and the result, in internal variables (with the unscaled dual
//!   infeasibility and complementarity of the termination test at the final iterate).

mod barrier;
mod filter;
mod iteration;
mod line_search;
mod restoration_phase;
mod step;
mod termination;

use std::time::Instant;

use self::barrier::MuRule;
use self::filter::Filter;
use self::iteration::{RunState, StepChoice};
use self::termination::Verdict;
use super::kkt::{KktPattern, SparseLdlt};
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
    /// A previously analysed KKT solver to reuse (see [`super::Workspace`]).
    pub kkt_solver: std::cell::Cell<Option<SparseLdlt>>,
}

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

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}
fn norm_1(v: &[f64]) -> f64 {
    v.iter().map(|x| x.abs()).sum()
}
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(crate) struct Core<'p> {
    prob: &'p mut dyn StdProblem,
    n: usize,
    m: usize,
    xl: Vec<f64>,
    xu: Vec<f64>,
    lo: Vec<usize>,
    up: Vec<usize>,
    damp: Vec<f64>,
    // iterate
    x: Vec<f64>,
    y: Vec<f64>,
    zl: Vec<f64>,
    zu: Vec<f64>,
    f: f64,
    grad: Vec<f64>,
    /// The x at which `grad` and `jac` were last evaluated.
    derivs_x: Vec<f64>,
    c: Vec<f64>,
    jac: Vec<f64>,
    hess: Vec<f64>,
    jac_pat: Vec<(usize, usize)>,
    // derived
    sl: Vec<f64>,
    su: Vec<f64>,
    grad_phi: Vec<f64>,
    jty: Vec<f64>,
    // KKT
    kkt: KktPattern,
    solver: SparseLdlt,
    /// With [`KktOrdering::AmdThenPivotPairs`](super::settings::KktOrdering::AmdThenPivotPairs) before the switch: the solver with AMD and
    /// 2 × 2 pivot pairs, analysed when first needed, that re-factors a rejected AMD factor's
    /// matrix; after the switch: the AMD solver (handed back by [`Core::into_kkt_solver`]).
    other_solver: Option<SparseLdlt>,
    /// Rejected AMD factorizations are still to be checked with the pivot pairs (the switch
    /// has not happened and the pair order differs from AMD's).
    check_pairs: bool,
    /// The solve switched to the pivot pairs.
    switched_to_pairs: bool,
    /// Static dual regularization of this solve: `static_dual_regularization`, raised when a
    /// factor turns out unstable (see `step`).
    static_dc: f64,
    diag_x: Vec<f64>,
    delta_w_last: f64,
    /// Smallest δ_w of this iteration's KKT matrix: the proximal term κ_p μ of
    /// `Settings::proximal_weight` on a stalled barrier problem whose μ is above the
    /// tolerance, else 0. Read by the inertia correction (its starting δ_w) and by the
    /// extrapolation (which extends only steps whose inertia needed more than this floor).
    proximal: f64,
    /// The previous step's δ_w = 0 attempt failed: start from κ_w⁻ δ_w_last (saves one
    /// factorization per iteration on collocation KKTs whose states carry no curvature).
    skip_zero_trial: bool,
    delta_w: f64,
    delta_c: f64,
    delta_c_target: f64,
    rhs: Vec<f64>,
    sol: Vec<f64>,
    resid: Vec<f64>,
    corr: Vec<f64>,
    /// The KKT solution before the last refinement correction, which may be undone.
    sol_before: Vec<f64>,
    // step
    dx: Vec<f64>,
    dy: Vec<f64>,
    dzl: Vec<f64>,
    dzu: Vec<f64>,
    // trial
    x_t: Vec<f64>,
    c_t: Vec<f64>,
    f_t: f64,
    // barrier & filter
    mu: f64,
    tau: f64,
    /// The line search's filter, θ bounds and reset bookkeeping.
    filter: Filter,
    restoration: bool,
    kappa_d: f64,
    /// Ipopt's `slack_move` (see [`barrier`]).
    slack_move: f64,
    /// Largest |x_j| over the variables without a finite lower or upper bound, over all
    /// iterates so far (the unboundedness test).
    unboxed_max: std::cell::Cell<f64>,
}

impl<'p> Core<'p> {
    pub fn new(
        prob: &'p mut dyn StdProblem,
        settings: &Settings,
        start: &CoreStart,
    ) -> Result<Self, OptimError> {
        let n = prob.n();
        let m = prob.m();
        let mut xl = prob.x_lower().to_vec();
        let mut xu = prob.x_upper().to_vec();
        if start.relax_bounds && settings.bound_relax_factor > 0.0 {
            let r = settings.bound_relax_factor;
            for j in 0..n {
                if xl[j].is_finite() {
                    xl[j] -= r * xl[j].abs().max(1.0);
                }
                if xu[j].is_finite() {
                    xu[j] += r * xu[j].abs().max(1.0);
                }
            }
        }
        let lo: Vec<usize> = (0..n).filter(|&j| xl[j].is_finite()).collect();
        let up: Vec<usize> = (0..n).filter(|&j| xu[j].is_finite()).collect();
        let damp = (0..n)
            .map(|j| match (xl[j].is_finite(), xu[j].is_finite()) {
                (true, false) => 1.0,
                (false, true) => -1.0,
                _ => 0.0,
            })
            .collect();
        let jac_pat = prob.jac_pattern().to_vec();
        let hess_pat = prob.hess_pattern().to_vec();
        let kkt = KktPattern::new(n, m, &hess_pat, &jac_pat);
        let nlo = lo.len();
        let nup = up.len();
        Ok(Self {
            n,
            m,
            x: start.x.clone(),
            y: vec![0.0; m],
            zl: vec![settings.bound_mult_init; nlo],
            zu: vec![settings.bound_mult_init; nup],
            f: 0.0,
            grad: vec![0.0; n],
            derivs_x: Vec::new(),
            c: vec![0.0; m],
            jac: vec![0.0; jac_pat.len()],
            hess: vec![0.0; hess_pat.len()],
            jac_pat,
            sl: vec![0.0; nlo],
            su: vec![0.0; nup],
            grad_phi: vec![0.0; n],
            jty: vec![0.0; n],
            kkt,
            solver: start.kkt_solver.take().unwrap_or_default(),
            other_solver: None,
            check_pairs: false,
            switched_to_pairs: false,
            static_dc: settings.static_dual_regularization,
            diag_x: vec![0.0; n],
            delta_w_last: 0.0,
            skip_zero_trial: false,
            proximal: 0.0,
            delta_w: 0.0,
            delta_c: 0.0,
            delta_c_target: 0.0,
            rhs: vec![0.0; n + m],
            sol: vec![0.0; n + m],
            resid: vec![0.0; n + m],
            corr: vec![0.0; n + m],
            sol_before: vec![0.0; n + m],
            dx: vec![0.0; n],
            dy: vec![0.0; m],
            dzl: vec![0.0; nlo],
            dzu: vec![0.0; nup],
            x_t: vec![0.0; n],
            c_t: vec![0.0; m],
            f_t: 0.0,
            mu: start.mu,
            tau: settings.tau_min.max(1.0 - start.mu),
            filter: Filter::default(),
            restoration: start.restoration,
            kappa_d: settings.kappa_d,
            slack_move: settings.slack_move,
            unboxed_max: std::cell::Cell::new(f64::NEG_INFINITY),
            prob,
            xl,
            xu,
            lo,
            up,
            damp,
        })
    }

    // ---------- evaluations (timed) ----------

    fn eval_fc(&mut self, ctx: &mut Ctx<'_, '_>, trial: bool) -> (f64, bool) {
        let t = Instant::now();
        let (x, c) = if trial {
            (&self.x_t, &mut self.c_t)
        } else {
            (&self.x, &mut self.c)
        };
        let f = self.prob.eval_f(x);
        self.prob.eval_c(x, c);
        ctx.counters.objective_evals += 1;
        ctx.counters.constraint_evals += 1;
        ctx.timing.function_evals += t.elapsed();
        let ok = f.is_finite() && c.iter().all(|v| v.is_finite());
        (f, ok)
    }

    fn eval_derivs(&mut self, ctx: &mut Ctx<'_, '_>) -> bool {
        let t = Instant::now();
        self.prob.eval_grad(&self.x, &mut self.grad);
        self.prob.eval_jac(&self.x, &mut self.jac);
        ctx.timing.derivative_evals += t.elapsed();
        self.derivs_x.clone_from(&self.x);
        self.grad.iter().all(|v| v.is_finite()) && self.jac.iter().all(|v| v.is_finite())
    }

    fn eval_hessian(&mut self, ctx: &mut Ctx<'_, '_>) -> bool {
        let t = Instant::now();
        self.prob.eval_hess(&self.x, 1.0, &self.y, &mut self.hess);
        ctx.counters.hessian_evals += 1;
        ctx.timing.derivative_evals += t.elapsed();
        self.hess.iter().all(|v| v.is_finite())
    }

    // ---------- initialization ----------

    fn push_into_bounds(&self, x: &mut [f64], push: f64, frac: f64) {
        for j in 0..self.n {
            let (l, u) = (self.xl[j], self.xu[j]);
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
        if settings.print_level > 0 {
            println!(
                "iter    objective    inf_pr   inf_du lg(mu)  ||d||  lg(rg) alpha_du alpha_pr  ls"
            );
        }
    }

    fn log(&self, settings: &Settings, info: &IterationInfo) {
        if settings.print_level == 0 {
            return;
        }
        let rg = if info.delta_w > 0.0 {
            format!("{:5.1}", info.delta_w.log10())
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
            info.mu.log10(),
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
        if self.derivs_x != self.x {
            let saved = (
                self.c.clone(),
                self.grad.clone(),
                self.jac.clone(),
                self.derivs_x.clone(),
            );
            let (f, ok) = self.eval_fc(ctx, false);
            if ok && self.eval_derivs(ctx) {
                self.f = f;
            } else {
                (self.c, self.grad, self.jac, self.derivs_x) = saved;
            }
        }
        self.compute_jty();
        let err = self.errors(ctx.settings);
        let (dual_infeasibility, _, complementarity) = self.unscaled(&err);
        let mut zl = vec![0.0; self.n];
        let mut zu = vec![0.0; self.n];
        for (k, &j) in self.lo.iter().enumerate() {
            zl[j] = self.zl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            zu[j] = self.zu[k];
        }
        CoreOutput {
            dual_infeasibility,
            complementarity,
            status,
            x: self.x.clone(),
            y: self.y.clone(),
            z_l: zl,
            z_u: zu,
            mu: self.mu,
            early_stopped: early,
        }
    }

    /// Hands the (analysed) KKT solver back for reuse by a later solve.
    pub fn into_kkt_solver(self) -> SparseLdlt {
        // After a switch to the pivot pairs, the AMD solver is the one whose analysis the next
        // run (which starts with AMD again) can reuse.
        match (self.switched_to_pairs, self.other_solver) {
            (true, Some(amd)) => amd,
            _ => self.solver,
        }
    }

    /// Runs the algorithm from `start`: W&B's Algorithm A, one outer iteration per pass of
    /// the loop. Each phase is a method of its own (`iteration.rs`, `step.rs`,
    /// `line_search.rs`, `barrier.rs`, `termination.rs`, `restoration_phase.rs`).
    pub fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: &CoreStart,
    ) -> Result<CoreOutput, OptimError> {
        let settings = ctx.settings;
        self.analyse_kkt(ctx)?;
        self.initialize(ctx, start)?;
        let mut mu_rule = MuRule::new(settings, self.mu, self.prob.scales().0);
        let mut run = RunState::new(ctx.iter, self.restoration, self.mu);
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
            // Step size: tiny steps, filter line search, soft restoration (W&B Sect. 3.3–3.9).
            let step = if step_ok {
                self.find_step(ctx, &err, &mut mu_rule, &mut run)
            } else {
                StepChoice::Recover
            };
            match step {
                StepChoice::Take(taken) => self.accept_step(ctx, taken, &mut run)?,
                StepChoice::Stop(status) => return Ok(self.output(ctx, status, false)),
                // No acceptable step: the monotone fallback or the restoration phase.
                StepChoice::Recover => {
                    if let Some(status) =
                        self.recover(ctx, step_ok, e0, pr_u, &mut mu_rule, &mut run)?
                    {
                        return Ok(self.output(ctx, status, false));
                    }
                }
            }
        }
    }
}
