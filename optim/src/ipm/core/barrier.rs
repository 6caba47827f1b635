//! Barrier quantities of the primal-dual method (Wächter & Biegler 2006, "W&B"):
//!
//! * slacks `s_L = x − x_L`, `s_U = x_U − x` to the (relaxed) bounds, with Ipopt's safeguard
//!   for slacks that underflow (W&B end of Sect. 3.5, option `slack_move`): the slack becomes
//!   `μ / z` (within `slack_move` of the bound) and the bound moves to `x ∓ s`;
//! * the barrier objective `φ_μ(x) = f(x) − μ Σ ln s_L − μ Σ ln s_U + κ_d μ Σ (one-sided
//!   damping)` (W&B eq. (3), Sect. 3.7) and its gradient `∇φ_μ`;
//! * `Jᵀy` for the dual residual;
//! * the barrier-parameter update [`MuRule`]: monotone Fiacco–McCormick (W&B eq. (7):
//!   `μ ← max(μ_floor, min(κ_μ μ, μ^θ_μ))` once `E_μ ≤ κ_ε μ`) or the adaptive LOQO rule with
//!   its free/fixed safeguard (Nocedal, Wächter & Waltz 2009).

use super::Core;
use super::termination::Errors;
use crate::ipm::settings::{MuStrategy, Settings};

/// State of the barrier-parameter update across iterations of one run.
pub(super) struct MuRule {
    /// Smallest μ of this run (see [`MuRule::new`]), no larger than the initial μ.
    pub(super) floor: f64,
    /// The optimality tolerance in scaled units: barrier problems with a larger μ are not
    /// answers (their complementarity alone exceeds it) and carry the proximal term of
    /// `BarrierSettings::proximal_weight`.
    pub(super) answer_mu: f64,
    /// μ of the current barrier problem, and the iteration at which it was set.
    stage: (f64, usize),
    /// Adaptive μ in its free mode (LOQO rule each iteration).
    pub(super) free_mode: bool,
    /// Recent optimality errors of the free mode's sufficient-progress test.
    refs: Vec<f64>,
    /// Decrease μ at the next update even if the barrier problem is not solved (after a tiny
    /// step, W&B Sect. 3.9).
    pub(super) force_decrease: bool,
}

impl MuRule {
    /// The rule at the start of a run with initial barrier parameter `mu` on a problem whose
    /// objective is scaled by `obj_scale`. The floor comes from the tolerances in scaled
    /// units: `tol`, and `compl_inf_tol` on the unscaled complementarity, which is
    /// `obj_scale · compl_inf_tol` in scaled units (so a strongly down-scaled objective can
    /// still meet it); `mu_min` scales with the objective below 1.
    pub(super) fn new(settings: &Settings, mu: f64, obj_scale: f64) -> Self {
        let scaled_tol = settings
            .termination
            .tol
            .min(settings.termination.compl_inf_tol * obj_scale);
        Self {
            floor: (settings.barrier.mu_min * obj_scale.min(1.0))
                .max(scaled_tol / (settings.barrier.barrier_tol_factor + 1.0))
                .min(mu),
            answer_mu: scaled_tol,
            stage: (f64::NAN, 0),
            free_mode: settings.barrier.mu_strategy == MuStrategy::Adaptive,
            refs: Vec::new(),
            force_decrease: false,
        }
    }

    /// Iterations spent on the barrier problem of `mu` up to iteration `iter` (0 at the
    /// iteration where μ took this value; restoration iterations count too, being a sign of
    /// the same trouble).
    pub(super) fn stage_iterations(&mut self, mu: f64, iter: usize) -> usize {
        if mu != self.stage.0 {
            self.stage = (mu, iter);
        }
        iter.saturating_sub(self.stage.1)
    }
}

impl Core<'_> {
    /// Slacks below this have underflowed in the rounding of `x − x_L` (Ipopt:
    /// `ε_mach · min(1, μ)`, at least the smallest positive double).
    fn slack_floor(&self) -> f64 {
        let s = f64::EPSILON * self.barrier.mu.min(1.0);
        if s > 0.0 { s } else { f64::MIN_POSITIVE }
    }

    /// The slack used for the raw slack `raw` to a bound `bound` with multiplier `z`, given the
    /// floor `s_min` of [`Core::slack_floor`]: `raw` itself when it is at least `s_min`,
    /// otherwise Ipopt's safe slack `min(max(μ / z, s_min), max(raw, 0) + slack_move ·
    /// max(1, |bound|))` (W&B end of Sect. 3.5): the value the barrier problem asks for
    /// (`s z = μ`), moved by no more than `slack_move` relative to the bound.
    fn safe_slack(&self, raw: f64, bound: f64, z: f64, s_min: f64) -> f64 {
        if raw >= s_min {
            return raw;
        }
        (self.barrier.mu / z)
            .max(s_min)
            .min(raw.max(0.0) + self.barrier.slack_move * bound.abs().max(1.0))
    }

    /// Whether the raw slack `raw` to `bound` lies outside the bound by more than the safeguard
    /// may move it (or is NaN): a trial point there is infeasible, not a rounded slack.
    fn violates(&self, raw: f64, bound: f64) -> bool {
        raw.is_nan() || raw <= -self.barrier.slack_move * bound.abs().max(1.0)
    }

    /// Slacks `s_L = x − x_L`, `s_U = x_U − x` at the current iterate. A slack that has
    /// underflowed is replaced by its safe value ([`Core::safe_slack`], with the multipliers
    /// of the current iterate) and its bound moved to `x ∓ s`, as Ipopt does, so that the
    /// slack stays positive and `z = μ / s` finite however close x gets to its bound. Returns
    /// the number of bounds moved.
    pub(super) fn update_slacks(&mut self) -> usize {
        let s_min = self.slack_floor();
        let mut moved = 0;
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            let raw = self.iterate.x[j] - self.bounds.xl[j];
            let s = self.safe_slack(raw, self.bounds.xl[j], self.iterate.zl[k], s_min);
            if s != raw {
                self.bounds.xl[j] = self.iterate.x[j] - s;
                moved += 1;
            }
            self.iterate.sl[k] = s;
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            let raw = self.bounds.xu[j] - self.iterate.x[j];
            let s = self.safe_slack(raw, self.bounds.xu[j], self.iterate.zu[k], s_min);
            if s != raw {
                self.bounds.xu[j] = self.iterate.x[j] + s;
                moved += 1;
            }
            self.iterate.su[k] = s;
        }
        moved
    }

    /// φ_μ at `x` with objective value `f`, with the safe slacks of [`Core::safe_slack`] (the
    /// current multipliers); +∞ where a slack is beyond its bound by more than the safeguard's
    /// move ([`Core::violates`]).
    pub(super) fn barrier_value(&self, x: &[f64], f: f64) -> f64 {
        let mu = self.barrier.mu;
        let s_min = self.slack_floor();
        let mut phi = f;
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            let raw = x[j] - self.bounds.xl[j];
            if self.violates(raw, self.bounds.xl[j]) {
                return f64::INFINITY;
            }
            phi -=
                mu * libm::log(self.safe_slack(raw, self.bounds.xl[j], self.iterate.zl[k], s_min));
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            let raw = self.bounds.xu[j] - x[j];
            if self.violates(raw, self.bounds.xu[j]) {
                return f64::INFINITY;
            }
            phi -=
                mu * libm::log(self.safe_slack(raw, self.bounds.xu[j], self.iterate.zu[k], s_min));
        }
        let kd = self.barrier.kappa_d * mu;
        if kd > 0.0 {
            for j in 0..self.n {
                let d = self.bounds.damp[j];
                if d > 0.0 {
                    phi += kd * (x[j] - self.bounds.xl[j]);
                } else if d < 0.0 {
                    phi += kd * (self.bounds.xu[j] - x[j]);
                }
            }
        }
        phi
    }

    pub(super) fn compute_jty(&mut self) {
        self.evals.jty.iter_mut().for_each(|v| *v = 0.0);
        for (k, &(r, c)) in self.evals.jac_pat.iter().enumerate() {
            self.evals.jty[c] += self.evals.jac[k] * self.iterate.y[r];
        }
    }

    pub(super) fn compute_grad_phi(&mut self) {
        let mu = self.barrier.mu;
        let kd = self.barrier.kappa_d * mu;
        for j in 0..self.n {
            self.evals.grad_phi[j] = self.evals.grad[j] + kd * self.bounds.damp[j];
        }
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            self.evals.grad_phi[j] -= mu / self.iterate.sl[k];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            self.evals.grad_phi[j] += mu / self.iterate.su[k];
        }
    }

    /// Barrier-parameter update at an iterate with errors `err` and `E_0 = e0`; resets the
    /// filter and τ when μ changes.
    pub(super) fn update_mu(
        &mut self,
        settings: &Settings,
        rule: &mut MuRule,
        err: &Errors,
        e0: f64,
    ) {
        let old_mu = self.barrier.mu;
        if rule.free_mode {
            let ref_max = rule.refs.iter().fold(0.0f64, |a, &b| a.max(b));
            if !rule.refs.is_empty() && e0 > 0.9999 * ref_max {
                rule.free_mode = false;
                if let Some((avg, _)) = self.avg_compl() {
                    self.barrier.mu = (0.8 * avg).max(rule.floor);
                }
            } else {
                rule.refs.push(e0);
                if rule.refs.len() > 4 {
                    rule.refs.remove(0);
                }
                self.barrier.mu = match self.avg_compl() {
                    Some((avg, min)) => {
                        let xi = (min / avg).clamp(0.0, 1.0);
                        let sigma = 0.1 * (0.05 * (1.0 - xi) / xi.max(1e-300)).min(2.0).powi(3);
                        (sigma * avg).clamp(rule.floor, 1e5)
                    }
                    None => rule.floor,
                };
            }
        } else {
            if settings.barrier.mu_strategy == MuStrategy::Adaptive {
                let ref_min = rule.refs.iter().fold(f64::INFINITY, |a, &b| a.min(b));
                if e0 <= 0.9999 * ref_min {
                    rule.free_mode = true;
                    rule.refs.clear();
                    rule.refs.push(e0);
                }
            }
            loop {
                let e_mu = err.e(self.compl_mu(self.barrier.mu));
                if (e_mu <= settings.barrier.barrier_tol_factor * self.barrier.mu
                    || rule.force_decrease)
                    && self.barrier.mu > rule.floor
                {
                    rule.force_decrease = false;
                    let new_mu = (settings.barrier.mu_linear_decrease * self.barrier.mu)
                        .min(libm::pow(
                            self.barrier.mu,
                            settings.barrier.mu_superlinear_power,
                        ))
                        .max(rule.floor);
                    self.barrier.mu = new_mu;
                    self.barrier.tau = settings.barrier.tau_min.max(1.0 - self.barrier.mu);
                } else {
                    break;
                }
            }
            rule.force_decrease = false;
        }
        if self.barrier.mu != old_mu {
            self.barrier.tau = settings.barrier.tau_min.max(1.0 - self.barrier.mu);
            self.filter.clear();
        }
    }
}
