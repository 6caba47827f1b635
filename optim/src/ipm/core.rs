//! The primal-dual barrier algorithm on the standard form (Wächter & Biegler 2006, "W&B"):
//!
//! * barrier problem `min φ_μ(x) = f(x) − μ Σ ln(x − x_L) − μ Σ ln(x_U − x) + κ_d μ (one-sided
//!   damping)` s.t. `c(x) = 0` (W&B eq. (3), Sect. 3.7);
//! * Newton step on the primal-dual equations with `z_L, z_U` eliminated (W&B eq. (11)–(13)),
//!   inertia correction δ_w, δ_c (W&B Sect. 3.1, Algorithm IC);
//! * fraction-to-boundary `τ = max(τ_min, 1 − μ)` (W&B eq. (15)) and bound-multiplier safeguard
//!   κ_Σ (W&B eq. (16));
//! * filter line search on `(θ = ‖c‖₁, φ_μ)` with switching rule, Armijo, second-order
//!   correction (W&B Sect. 2.3–2.4, eq. (18)–(27));
//! * feasibility restoration (W&B Sect. 3.3) via [`super::restoration`];
//! * scaled optimality error `E_μ` (W&B eq. (5)) with monotone (W&B eq. (7)) or adaptive μ.

use std::time::Instant;

use super::kkt::{FaerLdlt, KktPattern, KktSolver};
use super::restoration::{OuterInfo, RestorationProblem};
use super::settings::{MuStrategy, Settings};
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
    pub kkt_solver: std::cell::Cell<Option<FaerLdlt>>,
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

/// Optimality errors at the current iterate.
#[derive(Clone, Copy, Debug, Default)]
struct Errors {
    dual_inf: f64,
    primal_inf: f64,
    /// ‖S z‖_∞ (μ = 0)
    compl0: f64,
    s_d: f64,
    s_c: f64,
}

impl Errors {
    fn e(&self, compl: f64) -> f64 {
        (self.dual_inf / self.s_d)
            .max(self.primal_inf)
            .max(compl / self.s_c)
    }
}

/// Step-computation result.
enum StepResult {
    Ok,
    Failed,
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
    solver: FaerLdlt,
    diag_x: Vec<f64>,
    delta_w_last: f64,
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
    filter: Vec<(f64, f64)>,
    theta_max: f64,
    theta_min: f64,
    restoration: bool,
    kappa_d: f64,
}

enum LsOutcome {
    Accepted { alpha: f64, trials: usize },
    Failed,
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
            diag_x: vec![0.0; n],
            delta_w_last: 0.0,
            skip_zero_trial: false,
            delta_w: 0.0,
            delta_c: 0.0,
            delta_c_target: 0.0,
            rhs: vec![0.0; n + m],
            sol: vec![0.0; n + m],
            resid: vec![0.0; n + m],
            corr: vec![0.0; n + m],
            dx: vec![0.0; n],
            dy: vec![0.0; m],
            dzl: vec![0.0; nlo],
            dzu: vec![0.0; nup],
            x_t: vec![0.0; n],
            c_t: vec![0.0; m],
            f_t: 0.0,
            mu: start.mu,
            tau: settings.tau_min.max(1.0 - start.mu),
            filter: Vec::new(),
            theta_max: 0.0,
            theta_min: 0.0,
            restoration: start.restoration,
            kappa_d: settings.kappa_d,
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
        self.grad.iter().all(|v| v.is_finite()) && self.jac.iter().all(|v| v.is_finite())
    }

    fn eval_hessian(&mut self, ctx: &mut Ctx<'_, '_>) -> bool {
        let t = Instant::now();
        self.prob.eval_hess(&self.x, 1.0, &self.y, &mut self.hess);
        ctx.counters.hessian_evals += 1;
        ctx.timing.derivative_evals += t.elapsed();
        self.hess.iter().all(|v| v.is_finite())
    }

    // ---------- barrier quantities ----------

    fn slacks_of(&self, x: &[f64], sl: &mut [f64], su: &mut [f64]) {
        for (k, &j) in self.lo.iter().enumerate() {
            sl[k] = x[j] - self.xl[j];
        }
        for (k, &j) in self.up.iter().enumerate() {
            su[k] = self.xu[j] - x[j];
        }
    }

    fn update_slacks(&mut self) {
        let (mut sl, mut su) = (std::mem::take(&mut self.sl), std::mem::take(&mut self.su));
        self.slacks_of(&self.x, &mut sl, &mut su);
        self.sl = sl;
        self.su = su;
    }

    /// φ_μ at `x` with objective value `f`; +∞ outside the (relaxed) bounds.
    fn barrier_value(&self, x: &[f64], f: f64) -> f64 {
        let mu = self.mu;
        let mut phi = f;
        for &j in &self.lo {
            let s = x[j] - self.xl[j];
            if s <= 0.0 {
                return f64::INFINITY;
            }
            phi -= mu * s.ln();
        }
        for &j in &self.up {
            let s = self.xu[j] - x[j];
            if s <= 0.0 {
                return f64::INFINITY;
            }
            phi -= mu * s.ln();
        }
        let kd = self.kappa_d * mu;
        if kd > 0.0 {
            for j in 0..self.n {
                let d = self.damp[j];
                if d > 0.0 {
                    phi += kd * (x[j] - self.xl[j]);
                } else if d < 0.0 {
                    phi += kd * (self.xu[j] - x[j]);
                }
            }
        }
        phi
    }

    fn compute_jty(&mut self) {
        self.jty.iter_mut().for_each(|v| *v = 0.0);
        for (k, &(r, c)) in self.jac_pat.iter().enumerate() {
            self.jty[c] += self.jac[k] * self.y[r];
        }
    }

    fn compute_grad_phi(&mut self) {
        let mu = self.mu;
        let kd = self.kappa_d * mu;
        for j in 0..self.n {
            self.grad_phi[j] = self.grad[j] + kd * self.damp[j];
        }
        for (k, &j) in self.lo.iter().enumerate() {
            self.grad_phi[j] -= mu / self.sl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            self.grad_phi[j] += mu / self.su[k];
        }
    }

    fn errors(&self, settings: &Settings) -> Errors {
        let mut rd = self.grad.clone();
        for j in 0..self.n {
            rd[j] += self.jty[j];
        }
        for (k, &j) in self.lo.iter().enumerate() {
            rd[j] -= self.zl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            rd[j] += self.zu[k];
        }
        let compl0 = self
            .sl
            .iter()
            .zip(&self.zl)
            .chain(self.su.iter().zip(&self.zu))
            .fold(0.0f64, |a, (s, z)| a.max((s * z).abs()));
        let nz = self.lo.len() + self.up.len();
        let zsum = norm_1(&self.zl) + norm_1(&self.zu);
        let smax = settings.s_max;
        let s_d = (smax.max((norm_1(&self.y) + zsum) / ((self.m + self.n) as f64).max(1.0))) / smax;
        let s_c = if nz > 0 {
            smax.max(zsum / nz as f64) / smax
        } else {
            1.0
        };
        Errors {
            dual_inf: norm_inf(&rd),
            primal_inf: norm_inf(&self.c),
            compl0,
            s_d,
            s_c,
        }
    }

    fn compl_mu(&self, mu: f64) -> f64 {
        self.sl
            .iter()
            .zip(&self.zl)
            .chain(self.su.iter().zip(&self.zu))
            .fold(0.0f64, |a, (s, z)| a.max((s * z - mu).abs()))
    }

    fn avg_compl(&self) -> Option<(f64, f64)> {
        let nz = self.lo.len() + self.up.len();
        if nz == 0 {
            return None;
        }
        let mut sum = 0.0;
        let mut min = f64::INFINITY;
        for (s, z) in self
            .sl
            .iter()
            .zip(&self.zl)
            .chain(self.su.iter().zip(&self.zu))
        {
            sum += s * z;
            min = min.min(s * z);
        }
        Some((sum / nz as f64, min))
    }

    /// Unscaled (dual, primal, complementarity) for the `Solved` test.
    fn unscaled(&self, e: &Errors) -> (f64, f64, f64) {
        let (os, cs) = self.prob.scales();
        let primal = match cs {
            Some(cs) => self
                .c
                .iter()
                .zip(cs)
                .fold(0.0f64, |a, (c, s)| a.max((c / s).abs())),
            None => e.primal_inf,
        };
        (e.dual_inf / os, primal, e.compl0 / os)
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

    // ---------- linear algebra ----------

    fn factor_current(&mut self, ctx: &mut Ctx<'_, '_>) -> Option<super::kkt::Inertia> {
        let t = Instant::now();
        let r = self.solver.factor(&self.kkt.mat.values);
        ctx.counters.factorizations += 1;
        ctx.timing.factorization += t.elapsed();
        r
    }

    /// Solves `K sol = rhs` with refinement against `K(δ_w, δ_c_target)`; returns the final
    /// relative residual.
    fn solve_refined(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) -> f64 {
        let t = Instant::now();
        let nm = self.n + self.m;
        self.sol.copy_from_slice(&self.rhs);
        self.solver.solve(&mut self.sol);
        let bnorm = norm_inf(&self.rhs).max(1e-300);
        let mut best = f64::INFINITY;
        for target in [self.delta_c_target, self.delta_c] {
            let shift = self.delta_c - target;
            for step in 0..=settings.max_refinement_steps {
                self.kkt.mat.sym_matvec(&self.sol, &mut self.resid);
                for i in 0..nm {
                    let extra = if i >= self.n {
                        shift * self.sol[i]
                    } else {
                        0.0
                    };
                    self.resid[i] = self.rhs[i] - self.resid[i] - extra;
                }
                let rn = norm_inf(&self.resid) / bnorm;
                if !rn.is_finite() {
                    best = f64::INFINITY;
                    break;
                }
                best = rn;
                if rn <= settings.refinement_tol || step == settings.max_refinement_steps {
                    break;
                }
                self.corr.copy_from_slice(&self.resid);
                self.solver.solve(&mut self.corr);
                for i in 0..nm {
                    self.sol[i] += self.corr[i];
                }
            }
            if best <= 1e-6 || shift == 0.0 {
                break;
            }
            // Refinement against the unregularized matrix did not converge (rank-deficient J):
            // accept the step of the regularized system instead.
            self.sol.copy_from_slice(&self.rhs);
            self.solver.solve(&mut self.sol);
        }
        ctx.timing.solve += t.elapsed();
        best
    }

    /// Assembles and factors `K`, correcting the inertia (W&B Algorithm IC), then solves for the
    /// Newton step of the current right-hand side.
    fn compute_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        use_hessian: bool,
    ) -> StepResult {
        let t = Instant::now();
        for j in 0..self.n {
            self.diag_x[j] = 0.0;
        }
        for (k, &j) in self.lo.iter().enumerate() {
            self.diag_x[j] += self.zl[k] / self.sl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            self.diag_x[j] += self.zu[k] / self.su[k];
        }
        let static_c = if self.m > 0 {
            settings.static_dual_regularization
        } else {
            0.0
        };
        self.delta_c = static_c;
        self.delta_c_target = 0.0;
        self.delta_w = 0.0;
        if use_hessian {
            self.kkt
                .assemble(&self.hess, &self.jac, &self.diag_x, -self.delta_c);
        } else {
            let zeros = vec![0.0; self.hess.len()];
            self.kkt
                .assemble(&zeros, &self.jac, &self.diag_x, -self.delta_c);
        }
        let first_w = settings.perturb_dec_fact * self.delta_w_last;
        if use_hessian && self.skip_zero_trial && first_w >= 1e-12 {
            self.delta_w = first_w.max(settings.min_hessian_perturbation);
            self.kkt.shift_diagonal(self.delta_w, 0.0);
        }
        ctx.timing.kkt_assembly += t.elapsed();
        let mut singular_handled = false;
        loop {
            let mut inertia = self.factor_current(ctx);
            let good = match inertia {
                Some(i) => i.positive == self.n && i.negative == self.m,
                None => false,
            };
            if settings.print_level > 2 {
                println!(
                    "    KKT: delta_w {:.2e} delta_c {:.2e} inertia {:?} (want {}+, {}-)",
                    self.delta_w, self.delta_c, inertia, self.n, self.m
                );
            }
            if good {
                let res = self.solve_refined(ctx, settings);
                if settings.print_level > 2 {
                    println!("    KKT: relative residual after refinement {res:.2e}");
                }
                if res <= 1e-5 {
                    if self.delta_w == 0.0 && use_hessian {
                        self.skip_zero_trial = false;
                    }
                    if self.delta_w > 0.0 {
                        self.delta_w_last = self.delta_w;
                    }
                    return StepResult::Ok;
                }
                // Right inertia but refinement cannot reach the exact system: the matrix is
                // (numerically) singular and static pivoting hid it.
                inertia = None;
            }
            // Wrong inertia, singular, or inaccurate: perturb.
            if self.delta_w == 0.0 && use_hessian {
                self.skip_zero_trial = true;
            }
            let old_w = self.delta_w;
            let old_c = self.delta_c;
            if inertia.is_none() && !singular_handled && self.m > 0 {
                singular_handled = true;
                let dc = settings.jacobian_regularization_value
                    * self.mu.powf(settings.jacobian_regularization_exponent);
                self.delta_c = dc.max(static_c);
                self.delta_c_target = self.delta_c;
                // δ_c unchanged (μ small enough that δ̄_c μ^κ_c ≤ the static δ_c): the matrix
                // and the factor are the ones just rejected, so go straight to δ_w.
                if old_w == 0.0 && self.delta_c != old_c {
                    let t = Instant::now();
                    self.kkt.shift_diagonal(0.0, self.delta_c - old_c);
                    ctx.timing.kkt_assembly += t.elapsed();
                    continue;
                }
            }
            if self.delta_w == 0.0 {
                self.delta_w = if self.delta_w_last == 0.0 {
                    settings.first_hessian_perturbation
                } else {
                    (settings.perturb_dec_fact * self.delta_w_last)
                        .max(settings.min_hessian_perturbation)
                };
            } else if self.delta_w_last == 0.0 {
                self.delta_w *= settings.perturb_inc_fact_first;
            } else {
                self.delta_w *= settings.perturb_inc_fact;
            }
            if self.delta_w > settings.max_hessian_perturbation {
                return StepResult::Failed;
            }
            let t = Instant::now();
            self.kkt
                .shift_diagonal(self.delta_w - old_w, self.delta_c - old_c);
            ctx.timing.kkt_assembly += t.elapsed();
        }
    }

    /// Fills `rhs` with the Newton right-hand side `−(∇φ + Jᵀy, c_rhs)`.
    fn set_rhs(&mut self, c_rhs: Option<&[f64]>) {
        for j in 0..self.n {
            self.rhs[j] = -(self.grad_phi[j] + self.jty[j]);
        }
        let c = c_rhs.unwrap_or(&self.c);
        for i in 0..self.m {
            self.rhs[self.n + i] = -c[i];
        }
    }

    /// Unpacks `sol` into (dx, dy) and recovers (dz_L, dz_U) (W&B eq. (12)).
    fn unpack_step(&mut self) {
        self.dx.copy_from_slice(&self.sol[..self.n]);
        self.dy.copy_from_slice(&self.sol[self.n..]);
        let mu = self.mu;
        for (k, &j) in self.lo.iter().enumerate() {
            self.dzl[k] = mu / self.sl[k] - self.zl[k] - self.zl[k] / self.sl[k] * self.dx[j];
        }
        for (k, &j) in self.up.iter().enumerate() {
            self.dzu[k] = mu / self.su[k] - self.zu[k] + self.zu[k] / self.su[k] * self.dx[j];
        }
    }

    fn max_step_primal(&self, dx: &[f64]) -> f64 {
        let tau = self.tau;
        let mut a: f64 = 1.0;
        for (k, &j) in self.lo.iter().enumerate() {
            if dx[j] < 0.0 {
                a = a.min(-tau * self.sl[k] / dx[j]);
            }
        }
        for (k, &j) in self.up.iter().enumerate() {
            if dx[j] > 0.0 {
                a = a.min(tau * self.su[k] / dx[j]);
            }
        }
        a
    }

    fn max_step_dual(&self) -> f64 {
        let tau = self.tau;
        let mut a: f64 = 1.0;
        for (z, dz) in self
            .zl
            .iter()
            .zip(&self.dzl)
            .chain(self.zu.iter().zip(&self.dzu))
        {
            if *dz < 0.0 {
                a = a.min(-tau * z / dz);
            }
        }
        a
    }

    fn filter_acceptable(&self, theta: f64, phi: f64) -> bool {
        self.filter.iter().all(|&(ft, fp)| theta < ft || phi < fp)
    }

    fn augment_filter(&mut self, theta: f64, phi: f64, settings: &Settings) {
        let t = (1.0 - settings.gamma_theta) * theta;
        let p = phi - settings.gamma_phi * theta;
        self.filter.retain(|&(ft, fp)| !(ft >= t && fp >= p));
        self.filter.push((t, p));
    }

    /// Acceptance test of a trial point (W&B eq. (18)–(21)). Returns (accepted, f-type).
    fn acceptable(
        &self,
        settings: &Settings,
        theta: f64,
        phi: f64,
        gphi_dx: f64,
        alpha: f64,
        theta_t: f64,
        phi_t: f64,
    ) -> (bool, bool) {
        if !phi_t.is_finite() || !theta_t.is_finite() || theta_t > self.theta_max {
            return (false, false);
        }
        if phi_t > phi {
            let inc = (phi_t - phi).log10();
            if inc > settings.obj_max_inc + phi.abs().log10().max(1.0) {
                return (false, false);
            }
        }
        if !self.filter_acceptable(theta_t, phi_t) {
            return (false, false);
        }
        let switching = gphi_dx < 0.0
            && alpha * (-gphi_dx).powf(settings.s_phi)
                > settings.switching_delta * theta.powf(settings.s_theta);
        let eps = 10.0 * f64::EPSILON * phi.abs().max(1.0);
        if theta <= self.theta_min && switching {
            let armijo = phi_t - phi - eps <= settings.eta_phi * alpha * gphi_dx;
            return (armijo, true);
        }
        let ok = theta_t <= (1.0 - settings.gamma_theta) * theta
            || phi_t - eps <= phi - settings.gamma_phi * theta;
        (ok, false)
    }

    fn alpha_min(&self, settings: &Settings, theta: f64, gphi_dx: f64) -> f64 {
        let g = settings.gamma_theta;
        let a = if gphi_dx < 0.0 {
            let b = g.min(settings.gamma_phi * theta / (-gphi_dx));
            if theta <= self.theta_min {
                b.min(
                    settings.switching_delta * theta.powf(settings.s_theta)
                        / (-gphi_dx).powf(settings.s_phi),
                )
            } else {
                b
            }
        } else {
            g
        };
        0.05 * a
    }

    /// Backtracking filter line search with second-order correction (W&B Sect. 2.3, A-5.x).
    fn line_search(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) -> LsOutcome {
        let t0 = Instant::now();
        let fe0 = ctx.timing.function_evals;
        let theta = norm_1(&self.c);
        let phi = self.barrier_value(&self.x, self.f);
        let gphi_dx = dot(&self.grad_phi, &self.dx);
        let alpha_max = self.max_step_primal(&self.dx);
        let amin = self.alpha_min(settings, theta, gphi_dx);
        let mut alpha = alpha_max;
        let mut trials = 0;
        let outcome = loop {
            if alpha < amin || trials > 60 {
                break LsOutcome::Failed;
            }
            trials += 1;
            for j in 0..self.n {
                self.x_t[j] = self.x[j] + alpha * self.dx[j];
            }
            let (f_t, ok) = self.eval_fc(ctx, true);
            if ok {
                let theta_t = norm_1(&self.c_t);
                let phi_t = self.barrier_value(&self.x_t, f_t);
                let (acc, ftype) =
                    self.acceptable(settings, theta, phi, gphi_dx, alpha, theta_t, phi_t);
                if acc {
                    if !ftype {
                        self.augment_filter(theta, phi, settings);
                    }
                    self.f_t = f_t;
                    break LsOutcome::Accepted { alpha, trials };
                }
                if trials == 1
                    && theta_t >= theta
                    && settings.max_soc > 0
                    && self.m > 0
                    && let Some(a) = self.second_order_correction(ctx, settings, alpha, theta, phi)
                {
                    break LsOutcome::Accepted { alpha: a, trials };
                }
            }
            alpha *= settings.alpha_red_factor;
        };
        let fe = ctx.timing.function_evals - fe0;
        ctx.timing.line_search += t0.elapsed().saturating_sub(fe);
        outcome
    }

    /// Second-order corrections (W&B Sect. 2.4). On success `x_t, c_t, f_t` hold the accepted
    /// point and `dx, dy, dz` the corrected step (taken with the returned α).
    fn second_order_correction(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        alpha: f64,
        theta: f64,
        phi: f64,
    ) -> Option<f64> {
        let mut c_soc: Vec<f64> = self
            .c
            .iter()
            .zip(&self.c_t)
            .map(|(c, ct)| alpha * c + ct)
            .collect();
        let mut theta_old = theta;
        let saved = (
            self.dx.clone(),
            self.dy.clone(),
            self.dzl.clone(),
            self.dzu.clone(),
        );
        for _ in 0..settings.max_soc {
            self.set_rhs(Some(&c_soc));
            self.solve_refined(ctx, settings);
            self.unpack_step();
            let a_soc = self.max_step_primal(&self.dx);
            for j in 0..self.n {
                self.x_t[j] = self.x[j] + a_soc * self.dx[j];
            }
            let (f_t, ok) = self.eval_fc(ctx, true);
            if !ok {
                break;
            }
            let theta_t = norm_1(&self.c_t);
            let phi_t = self.barrier_value(&self.x_t, f_t);
            let gphi_dx = dot(&self.grad_phi, &self.dx);
            let (acc, ftype) =
                self.acceptable(settings, theta, phi, gphi_dx, a_soc, theta_t, phi_t);
            if acc {
                if !ftype {
                    self.augment_filter(theta, phi, settings);
                }
                self.f_t = f_t;
                ctx.counters.soc_accepted += 1;
                return Some(a_soc);
            }
            if theta_t > settings.kappa_soc * theta_old {
                break;
            }
            theta_old = theta_t;
            for i in 0..self.m {
                c_soc[i] = a_soc * c_soc[i] + self.c_t[i];
            }
        }
        self.dx = saved.0;
        self.dy = saved.1;
        self.dzl = saved.2;
        self.dzu = saved.3;
        self.set_rhs(None);
        None
    }

    /// Least-squares constraint multipliers: `[I Jᵀ; J 0] [w; y] = −[∇f − z_L + z_U; 0]`.
    fn least_squares_y(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) {
        if self.m == 0 {
            return;
        }
        let t = Instant::now();
        let ones = vec![1.0; self.n];
        let zeros = vec![0.0; self.hess.len()];
        self.kkt.assemble(
            &zeros,
            &self.jac,
            &ones,
            -settings.static_dual_regularization,
        );
        ctx.timing.kkt_assembly += t.elapsed();
        self.delta_c = settings.static_dual_regularization;
        self.delta_c_target = 0.0;
        let inertia = self.factor_current(ctx);
        let ok = matches!(inertia, Some(i) if i.positive == self.n && i.negative == self.m);
        if !ok {
            self.y.iter_mut().for_each(|v| *v = 0.0);
            return;
        }
        for j in 0..self.n {
            self.rhs[j] = -self.grad[j];
        }
        for (k, &j) in self.lo.iter().enumerate() {
            self.rhs[j] += self.zl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            self.rhs[j] -= self.zu[k];
        }
        for i in 0..self.m {
            self.rhs[self.n + i] = 0.0;
        }
        self.solve_refined(ctx, settings);
        let ys = &self.sol[self.n..];
        if norm_inf(ys) <= settings.constr_mult_init_max && ys.iter().all(|v| v.is_finite()) {
            self.y.copy_from_slice(ys);
        } else {
            self.y.iter_mut().for_each(|v| *v = 0.0);
        }
    }

    fn reset_filter(&mut self) {
        self.filter.clear();
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

    fn output(&self, status: Status, early: bool) -> CoreOutput {
        let mut zl = vec![0.0; self.n];
        let mut zu = vec![0.0; self.n];
        for (k, &j) in self.lo.iter().enumerate() {
            zl[j] = self.zl[k];
        }
        for (k, &j) in self.up.iter().enumerate() {
            zu[j] = self.zu[k];
        }
        CoreOutput {
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
    pub fn into_kkt_solver(self) -> FaerLdlt {
        self.solver
    }

    /// Runs the algorithm from `start`.
    pub fn run(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        start: &CoreStart,
    ) -> Result<CoreOutput, OptimError> {
        let settings = ctx.settings;
        // Symbolic analysis once per run.
        {
            let t = Instant::now();
            self.solver.analyse(
                self.n + self.m,
                &self.kkt.mat.col_ptr,
                &self.kkt.mat.row_idx,
            )?;
            ctx.timing.factorization += t.elapsed();
        }
        // Initial point (W&B Sect. 3.6).
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
        self.theta_max = 1e4 * theta0.max(1.0);
        self.theta_min = 1e-4 * theta0.max(1.0);
        let mu_floor = settings
            .mu_min
            .max(settings.tol / (settings.barrier_tol_factor + 1.0))
            .min(self.mu);
        let mut acceptable_count = 0usize;
        let mut last = IterationInfo {
            iter: ctx.iter,
            restoration: self.restoration,
            objective: 0.0,
            inf_pr: 0.0,
            inf_du: 0.0,
            mu: self.mu,
            step_norm: 0.0,
            delta_w: 0.0,
            alpha_du: 0.0,
            alpha_pr: 0.0,
            ls_trials: 0,
        };
        let mut free_mode = settings.mu_strategy == MuStrategy::Adaptive;
        let mut refs: Vec<f64> = Vec::new();
        let mut force_mu_decrease = false;
        let mut tiny_count = 0usize;
        let mut soft_count = 0usize;
        let mut lines = 0usize;
        loop {
            self.compute_jty();
            let err = self.errors(settings);
            let e0 = err.e(err.compl0);
            // log + callback
            let (os, _) = self.prob.scales();
            last.iter = ctx.iter;
            last.objective = self.f / os;
            last.inf_pr = err.primal_inf;
            last.inf_du = err.dual_inf;
            last.mu = self.mu;
            if lines.is_multiple_of(10) {
                self.log_header(settings);
            }
            lines += 1;
            self.log(settings, &last);
            if let Some(cb) = ctx.callback.as_mut()
                && !cb(&last)
            {
                return Ok(self.output(Status::UserStop, false));
            }
            if self.restoration && self.prob.early_stop(&self.x) {
                return Ok(self.output(Status::Solved, true));
            }
            // termination tests
            let (du_u, pr_u, co_u) = self.unscaled(&err);
            if e0 <= settings.tol
                && du_u <= settings.dual_inf_tol
                && pr_u <= settings.constr_viol_tol
                && co_u <= settings.compl_inf_tol
            {
                return Ok(self.output(Status::Solved, false));
            }
            if settings.acceptable_iter > 0
                && e0 <= settings.acceptable_tol
                && pr_u <= settings.acceptable_constr_viol_tol
            {
                acceptable_count += 1;
                if acceptable_count >= settings.acceptable_iter {
                    return Ok(self.output(Status::Acceptable, false));
                }
            } else {
                acceptable_count = 0;
            }
            if !self.restoration
                && pr_u <= settings.constr_viol_tol
                && self.f / os < -settings.unbounded_objective
            {
                return Ok(self.output(Status::Unbounded, false));
            }
            if norm_inf(&self.x) > settings.diverging_iterates_tol {
                return Ok(self.output(Status::DivergingIterates, false));
            }
            if ctx.iter >= settings.max_iter {
                return Ok(self.output(Status::MaxIterations, false));
            }
            if ctx.start.elapsed().as_secs_f64() > settings.max_wall_time {
                return Ok(self.output(Status::MaxTime, false));
            }
            // barrier parameter update
            let old_mu = self.mu;
            if free_mode {
                let ref_max = refs.iter().fold(0.0f64, |a, &b| a.max(b));
                if !refs.is_empty() && e0 > 0.9999 * ref_max {
                    free_mode = false;
                    if let Some((avg, _)) = self.avg_compl() {
                        self.mu = (0.8 * avg).max(mu_floor);
                    }
                } else {
                    refs.push(e0);
                    if refs.len() > 4 {
                        refs.remove(0);
                    }
                    self.mu = match self.avg_compl() {
                        Some((avg, min)) => {
                            let xi = (min / avg).clamp(0.0, 1.0);
                            let sigma = 0.1 * (0.05 * (1.0 - xi) / xi.max(1e-300)).min(2.0).powi(3);
                            (sigma * avg).clamp(mu_floor, 1e5)
                        }
                        None => mu_floor,
                    };
                }
            } else {
                if settings.mu_strategy == MuStrategy::Adaptive {
                    let ref_min = refs.iter().fold(f64::INFINITY, |a, &b| a.min(b));
                    if e0 <= 0.9999 * ref_min {
                        free_mode = true;
                        refs.clear();
                        refs.push(e0);
                    }
                }
                loop {
                    let e_mu = err.e(self.compl_mu(self.mu));
                    if (e_mu <= settings.barrier_tol_factor * self.mu || force_mu_decrease)
                        && self.mu > mu_floor
                    {
                        force_mu_decrease = false;
                        let new_mu = (settings.mu_linear_decrease * self.mu)
                            .min(self.mu.powf(settings.mu_superlinear_power))
                            .max(mu_floor);
                        self.mu = new_mu;
                        self.tau = settings.tau_min.max(1.0 - self.mu);
                    } else {
                        break;
                    }
                }
                force_mu_decrease = false;
            }
            if self.mu != old_mu {
                self.tau = settings.tau_min.max(1.0 - self.mu);
                self.reset_filter();
            }
            // search direction
            if !self.eval_hessian(ctx) {
                return Err(OptimError::NonFinite {
                    iter: ctx.iter,
                    what: "Hessian",
                });
            }
            self.compute_grad_phi();
            self.set_rhs(None);
            let step_ok = matches!(self.compute_step(ctx, settings, true), StepResult::Ok);
            let mut restore = false;
            let mut alpha_dual: Option<f64> = None;
            let mut accepted_alpha = 0.0;
            let mut trials = 0;
            if step_ok {
                self.unpack_step();
                // tiny step (W&B Sect. 3.9)
                let tiny = self
                    .dx
                    .iter()
                    .zip(&self.x)
                    .all(|(d, x)| d.abs() / (1.0 + x.abs()) < 10.0 * f64::EPSILON)
                    && err.primal_inf <= settings.constr_viol_tol;
                if tiny {
                    tiny_count += 1;
                    if tiny_count >= 2 && self.mu <= mu_floor {
                        return Ok(self.output(Status::SearchDirectionTooSmall, false));
                    }
                    force_mu_decrease = true;
                    let amax = self.max_step_primal(&self.dx);
                    for j in 0..self.n {
                        self.x_t[j] = self.x[j] + amax * self.dx[j];
                    }
                    let (f_t, ok) = self.eval_fc(ctx, true);
                    if ok {
                        self.f_t = f_t;
                        accepted_alpha = amax;
                        trials = 1;
                    } else {
                        restore = true;
                    }
                } else {
                    tiny_count = 0;
                    match self.line_search(ctx, settings) {
                        LsOutcome::Accepted { alpha, trials: tr } => {
                            accepted_alpha = alpha;
                            trials = tr;
                            soft_count = 0;
                        }
                        LsOutcome::Failed => {
                            let e_mu = err.e(self.compl_mu(self.mu));
                            match self.soft_restoration_step(ctx, settings, e_mu) {
                                Some(a) if soft_count < 10 => {
                                    accepted_alpha = a;
                                    alpha_dual = Some(a);
                                    soft_count += 1;
                                }
                                _ => restore = true,
                            }
                        }
                    }
                }
            } else {
                restore = true;
            }
            if restore {
                if free_mode {
                    // Adaptive μ: fall back to the monotone (fixed) mode before restoration.
                    free_mode = false;
                    if let Some((avg, _)) = self.avg_compl() {
                        self.mu = (0.8 * avg).max(mu_floor);
                        self.tau = settings.tau_min.max(1.0 - self.mu);
                    }
                    self.reset_filter();
                    continue;
                }
                if self.restoration || !settings.restoration {
                    let st = if step_ok {
                        Status::RestorationFailed
                    } else {
                        Status::ErrorInStepComputation
                    };
                    return Ok(self.output(st, false));
                }
                if e0 <= settings.acceptable_tol && pr_u <= settings.acceptable_constr_viol_tol {
                    return Ok(self.output(Status::Acceptable, false));
                }
                match self.restoration_phase(ctx, settings)? {
                    None => {}
                    Some(st) => return Ok(self.output(st, false)),
                }
                last.restoration = false;
                last.step_norm = 0.0;
                last.alpha_du = 0.0;
                last.alpha_pr = 0.0;
                last.ls_trials = 0;
                last.delta_w = 0.0;
                continue;
            }
            // accept the step
            let alpha_z = alpha_dual.unwrap_or_else(|| self.max_step_dual());
            std::mem::swap(&mut self.x, &mut self.x_t);
            std::mem::swap(&mut self.c, &mut self.c_t);
            self.f = self.f_t;
            for i in 0..self.m {
                self.y[i] += accepted_alpha * self.dy[i];
            }
            for k in 0..self.zl.len() {
                self.zl[k] += alpha_z * self.dzl[k];
            }
            for k in 0..self.zu.len() {
                self.zu[k] += alpha_z * self.dzu[k];
            }
            self.update_slacks();
            // κ_Σ safeguard (W&B eq. (16))
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
            last.step_norm = norm_inf(&self.dx) * accepted_alpha;
            last.delta_w = self.delta_w;
            last.alpha_du = alpha_z;
            last.alpha_pr = accepted_alpha;
            last.ls_trials = trials;
        }
    }

    /// Ipopt's "soft restoration" step: when the filter line search fails, try the primal-dual
    /// step with the common step size `α = min(α_max^pr, α_max^du)` and accept it if it reduces
    /// the barrier optimality error `E_μ` by the factor 0.9999 (avoids the full restoration
    /// phase at nearly feasible points of degenerate problems). On success `x_t, c_t, f_t` hold
    /// the trial point and α is returned.
    fn soft_restoration_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        e_mu_current: f64,
    ) -> Option<f64> {
        // Only at nearly feasible points (θ ≤ θ_min), where the full restoration phase cannot
        // make progress on θ and would move x far from the current iterate.
        if self.restoration || norm_1(&self.c) > self.theta_min {
            return None;
        }
        let a = self.max_step_primal(&self.dx).min(self.max_step_dual());
        for j in 0..self.n {
            self.x_t[j] = self.x[j] + a * self.dx[j];
        }
        let (f_t, ok) = self.eval_fc(ctx, true);
        if !ok {
            return None;
        }
        let t = Instant::now();
        let mut grad = vec![0.0; self.n];
        let mut jac = vec![0.0; self.jac.len()];
        self.prob.eval_grad(&self.x_t, &mut grad);
        self.prob.eval_jac(&self.x_t, &mut jac);
        ctx.timing.derivative_evals += t.elapsed();
        let y: Vec<f64> = (0..self.m).map(|i| self.y[i] + a * self.dy[i]).collect();
        let zl: Vec<f64> = (0..self.zl.len())
            .map(|k| self.zl[k] + a * self.dzl[k])
            .collect();
        let zu: Vec<f64> = (0..self.zu.len())
            .map(|k| self.zu[k] + a * self.dzu[k])
            .collect();
        let mut rd = grad;
        for (k, &(r, c)) in self.jac_pat.iter().enumerate() {
            rd[c] += jac[k] * y[r];
        }
        let mut compl = 0.0f64;
        for (k, &j) in self.lo.iter().enumerate() {
            rd[j] -= zl[k];
            compl = compl.max(((self.x_t[j] - self.xl[j]) * zl[k] - self.mu).abs());
        }
        for (k, &j) in self.up.iter().enumerate() {
            rd[j] += zu[k];
            compl = compl.max(((self.xu[j] - self.x_t[j]) * zu[k] - self.mu).abs());
        }
        let nz = self.lo.len() + self.up.len();
        let zsum = norm_1(&zl) + norm_1(&zu);
        let smax = settings.s_max;
        let s_d = smax.max((norm_1(&y) + zsum) / ((self.m + self.n) as f64).max(1.0)) / smax;
        let s_c = if nz > 0 {
            smax.max(zsum / nz as f64) / smax
        } else {
            1.0
        };
        let e = (norm_inf(&rd) / s_d)
            .max(norm_inf(&self.c_t))
            .max(compl / s_c);
        if e.is_finite() && e <= 0.9999 * e_mu_current && norm_1(&self.c_t) <= self.theta_max {
            self.f_t = f_t;
            Some(a)
        } else {
            None
        }
    }

    /// Feasibility restoration (W&B Sect. 3.3): minimise `ρ‖p + n‖₁ + ζ/2 ‖D_R (x − x_R)‖²`
    /// s.t. `c(x) − p + n = 0` with the same IPM, stopping as soon as the outer filter accepts.
    /// Returns `Some(status)` when the outer solve must stop.
    fn restoration_phase(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
    ) -> Result<Option<Status>, OptimError> {
        let theta = norm_1(&self.c);
        let phi = self.barrier_value(&self.x, self.f);
        self.augment_filter(theta, phi, settings);
        let outer = OuterInfo {
            xl: self.xl.clone(),
            xu: self.xu.clone(),
            lo: self.lo.clone(),
            up: self.up.clone(),
            damp: self.damp.clone(),
            kappa_d: self.kappa_d,
            mu: self.mu,
            filter: self.filter.clone(),
            theta_ref: theta,
            kappa_resto: settings.resto_required_reduction,
            tol: settings.tol,
        };
        let mu_r = self.mu.max(norm_inf(&self.c));
        let rho = settings.resto_penalty;
        let n0 = self.n;
        let m = self.m;
        let mut w = self.x.clone();
        let mut p = vec![0.0; m];
        let mut nn = vec![0.0; m];
        for i in 0..m {
            let ci = self.c[i];
            let a = (mu_r - rho * ci) / (2.0 * rho);
            nn[i] = a + (a * a + mu_r * ci / (2.0 * rho)).sqrt();
            p[i] = ci + nn[i];
        }
        w.extend_from_slice(&p);
        w.extend_from_slice(&nn);
        let mut zl = vec![0.0; n0 + 2 * m];
        let mut zu = vec![0.0; n0 + 2 * m];
        for (k, &j) in self.lo.iter().enumerate() {
            zl[j] = self.zl[k].min(rho);
        }
        for (k, &j) in self.up.iter().enumerate() {
            zu[j] = self.zu[k].min(rho);
        }
        for i in 0..m {
            zl[n0 + i] = mu_r / p[i];
            zl[n0 + m + i] = mu_r / nn[i];
        }
        let x_ref = self.x.clone();
        let start = CoreStart {
            x: w,
            y: Some(vec![0.0; m]),
            z_l: Some(zl),
            z_u: Some(zu),
            mu: mu_r,
            bound_push: 1e-12,
            bound_frac: 1e-12,
            mult_floor: 1e-12,
            relax_bounds: false,
            restoration: true,
            kkt_solver: std::cell::Cell::new(None),
        };
        if settings.print_level > 1 {
            println!("  entering restoration phase (theta = {theta:.3e}, mu_R = {mu_r:.3e})");
        }
        let out = {
            let mut rp =
                RestorationProblem::new(&mut *self.prob, x_ref, rho, self.mu.sqrt(), outer);
            let mut inner = Core::new(&mut rp, settings, &start)?;
            inner.delta_w_last = self.delta_w_last;
            inner.run(ctx, &start)?
        };
        let x_new = out.x[..n0].to_vec();
        let finish = |me: &mut Self, ctx: &mut Ctx<'_, '_>| -> Result<bool, OptimError> {
            me.x.copy_from_slice(&x_new);
            me.update_slacks();
            if me.sl.iter().chain(&me.su).any(|&s| s <= 0.0) {
                return Ok(false);
            }
            let (f, ok) = me.eval_fc(ctx, false);
            if !ok {
                return Ok(false);
            }
            me.f = f;
            if !me.eval_derivs(ctx) {
                return Err(OptimError::NonFinite {
                    iter: ctx.iter,
                    what: "gradient or Jacobian after restoration",
                });
            }
            for (k, &j) in me.lo.iter().enumerate() {
                me.zl[k] = out.z_l[j];
            }
            for (k, &j) in me.up.iter().enumerate() {
                me.zu[k] = out.z_u[j];
            }
            let zmax = norm_inf(&me.zl).max(norm_inf(&me.zu));
            if zmax > 1e3 {
                me.zl.iter_mut().for_each(|z| *z = 1.0);
                me.zu.iter_mut().for_each(|z| *z = 1.0);
            }
            me.least_squares_y(ctx, settings);
            Ok(true)
        };
        if out.early_stopped {
            if finish(self, ctx)? {
                return Ok(None);
            }
            return Ok(Some(Status::RestorationFailed));
        }
        match out.status {
            Status::Solved | Status::Acceptable => {
                // Converged restoration problem without reaching an acceptable outer point.
                let x_in = out.x[..n0].to_vec();
                let mut c = vec![0.0; m];
                self.prob.eval_c(&x_in, &mut c);
                let (_, cs) = self.prob.scales();
                let viol = match cs {
                    Some(cs) => c
                        .iter()
                        .zip(cs)
                        .fold(0.0f64, |a, (c, s)| a.max((c / s).abs())),
                    None => norm_inf(&c),
                };
                if viol > settings.constr_viol_tol {
                    self.x.copy_from_slice(&x_in);
                    self.c.copy_from_slice(&c);
                    self.update_slacks();
                    return Ok(Some(Status::LocallyInfeasible));
                }
                if finish(self, ctx)? {
                    self.reset_filter();
                    return Ok(None);
                }
                Ok(Some(Status::RestorationFailed))
            }
            Status::MaxIterations | Status::MaxTime | Status::UserStop => Ok(Some(out.status)),
            _ => Ok(Some(Status::RestorationFailed)),
        }
    }
}
