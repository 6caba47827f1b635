//! Step acceptance (Wächter & Biegler 2006, "W&B"):
//!
//! * fraction-to-boundary step sizes with `τ = max(τ_min, 1 − μ)` (W&B eq. (15));
//! * the filter on `(θ = ‖c‖₁, φ_μ)` with the switching condition and Armijo test
//!   (W&B eq. (18)–(21)), the minimal step `α_min` (W&B eq. (23)) and backtracking
//!   (W&B Sect. 2.3);
//! * second-order corrections (W&B Sect. 2.4);
//! * extrapolation of a full step along negative curvature (α doubled while the acceptance
//!   test holds and φ_μ decreases; [`Core::extrapolate`], by default only on the barrier
//!   problems with μ ≤ tol; decision records 0010, 0011);
//! * Ipopt's filter reset heuristic (`Filter::note_accept`, in `filter`);
//! * Ipopt's "soft restoration" step when the line search fails near feasibility.

use std::time::Instant;

use super::{Core, Ctx, dot, max_or_nan, norm_1, norm_inf};
use crate::ipm::settings::Settings;

/// What a trial point is judged against (W&B eq. (18)–(21)): the current iterate's filter
/// measures θ = ‖c‖₁ and φ_μ, and the slope ∇φ_μᵀdx of the barrier objective along the step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Base {
    pub(super) theta: f64,
    pub(super) phi: f64,
    pub(super) gphi_dx: f64,
}

/// Result of the backtracking line search.
pub(super) enum LsOutcome {
    Accepted { alpha: f64, trials: usize },
    Failed,
}

/// The verdict of the acceptance test on a trial point ([`Core::acceptable`]).
#[derive(Clone, Copy, PartialEq, Debug)]
pub(super) enum Trial {
    /// Sufficient progress and not dominated by the filter; `f_type` when the switching
    /// condition held and the Armijo condition decided (no filter augmentation, W&B ).
    Accepted { f_type: bool },
    /// Sufficient progress over the current iterate, but dominated by a filter entry (Ipopt's
    /// `last_rejection_due_to_filter_`, counted by the filter reset).
    BlockedByFilter,
    /// Not enough progress, or not evaluable.
    Rejected,
}

impl Core<'_> {
    pub(super) fn max_step_primal(&self, dx: &[f64]) -> f64 {
        self.max_step_primal_upto(dx, 1.0)
    }

    /// The fraction-to-boundary step size (W&B eq. (15)) capped at `cap` instead of 1.
    pub(super) fn max_step_primal_upto(&self, dx: &[f64], cap: f64) -> f64 {
        let tau = self.barrier.tau;
        let mut a: f64 = cap;
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            if dx[j] < 0.0 {
                a = a.min(-tau * self.iterate.sl[k] / dx[j]);
            }
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            if dx[j] > 0.0 {
                a = a.min(tau * self.iterate.su[k] / dx[j]);
            }
        }
        a
    }

    pub(super) fn max_step_dual(&self) -> f64 {
        let tau = self.barrier.tau;
        let mut a: f64 = 1.0;
        for (z, dz) in self
            .iterate
            .zl
            .iter()
            .zip(&self.direction.dzl)
            .chain(self.iterate.zu.iter().zip(&self.direction.dzu))
        {
            if *dz < 0.0 {
                a = a.min(-tau * z / dz);
            }
        }
        a
    }

    /// Acceptance test of a trial point (W&B eq. (18)–(21)).
    pub(super) fn acceptable(
        &self,
        settings: &Settings,
        base: Base,
        alpha: f64,
        theta_t: f64,
        phi_t: f64,
    ) -> Trial {
        let Base {
            theta,
            phi,
            gphi_dx,
        } = base;
        if !phi_t.is_finite() || !theta_t.is_finite() || theta_t > self.filter.theta_max {
            return Trial::Rejected;
        }
        if phi_t > phi {
            let inc = libm::log10(phi_t - phi);
            if inc > settings.line_search.obj_max_inc + libm::log10(phi.abs()).max(1.0) {
                return Trial::Rejected;
            }
        }
        let switching = gphi_dx < 0.0
            && alpha * libm::pow(-gphi_dx, settings.line_search.s_phi)
                > settings.line_search.switching_delta
                    * libm::pow(theta, settings.line_search.s_theta);
        let eps = 10.0 * f64::EPSILON * phi.abs().max(1.0);
        let (progress, ftype) = if theta <= self.filter.theta_min && switching {
            (
                phi_t - phi - eps <= settings.line_search.eta_phi * alpha * gphi_dx,
                true,
            )
        } else {
            let ok = theta_t <= (1.0 - settings.line_search.gamma_theta) * theta
                || phi_t - eps <= phi - settings.line_search.gamma_phi * theta;
            (ok, false)
        };
        if !progress {
            return Trial::Rejected;
        }
        if !self.filter.acceptable(theta_t, phi_t) {
            return Trial::BlockedByFilter;
        }
        Trial::Accepted { f_type: ftype }
    }

    /// Acts on the verdict of [`Core::acceptable`] for a trial point judged against `base`:
    /// an accepted point counts for the filter reset and augments the filter with the
    /// iterate's measures unless f-type; a rejected one records whether the filter alone
    /// blocked it. Returns whether the point was accepted.
    fn take_verdict(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        verdict: Trial,
        base: Base,
    ) -> bool {
        match verdict {
            Trial::Accepted { f_type } => {
                if self.filter.note_accept(settings) {
                    ctx.counters.filter_resets += 1;
                }
                if !f_type {
                    self.filter.augment(base.theta, base.phi, settings);
                }
                true
            }
            Trial::BlockedByFilter | Trial::Rejected => {
                self.filter
                    .note_rejection(verdict == Trial::BlockedByFilter);
                false
            }
        }
    }

    /// Sets the trial point `x_t = x + α dx` and evaluates it: `(f, θ, φ_μ)` at `x_t` (with
    /// `c_t` filled), or `None` where the functions are not finite there.
    fn trial_point(&mut self, ctx: &mut Ctx<'_, '_>, alpha: f64) -> Option<(f64, f64, f64)> {
        for j in 0..self.n {
            self.trial.x[j] = self.iterate.x[j] + alpha * self.direction.dx[j];
        }
        let (f_t, ok) = self.eval_fc(ctx, true);
        ok.then(|| {
            (
                f_t,
                norm_1(&self.trial.c),
                self.barrier_value(&self.trial.x, f_t),
            )
        })
    }

    pub(super) fn alpha_min(&self, settings: &Settings, theta: f64, gphi_dx: f64) -> f64 {
        let g = settings.line_search.gamma_theta;
        let a = if gphi_dx < 0.0 {
            let b = g.min(settings.line_search.gamma_phi * theta / (-gphi_dx));
            if theta <= self.filter.theta_min {
                b.min(
                    settings.line_search.switching_delta
                        * libm::pow(theta, settings.line_search.s_theta)
                        / libm::pow(-gphi_dx, settings.line_search.s_phi),
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
    /// `extrapolate`: a full step accepted at the first trial may be extended along negative
    /// curvature ([`Core::extrapolate`]; the caller applies the setting and its scope).
    pub(super) fn line_search(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        extrapolate: bool,
    ) -> LsOutcome {
        let t0 = Instant::now();
        let fe0 = ctx.timing.function_evals;
        let base = Base {
            theta: norm_1(&self.evals.c),
            phi: self.barrier_value(&self.iterate.x, self.evals.f),
            gphi_dx: dot(&self.evals.grad_phi, &self.direction.dx),
        };
        let alpha_max = self.max_step_primal(&self.direction.dx);
        let amin = self.alpha_min(settings, base.theta, base.gphi_dx);
        let mut alpha = alpha_max;
        let mut trials = 0;
        let outcome = loop {
            if alpha < amin || trials > 60 {
                break LsOutcome::Failed;
            }
            trials += 1;
            if let Some((f_t, theta_t, phi_t)) = self.trial_point(ctx, alpha) {
                let verdict = self.acceptable(settings, base, alpha, theta_t, phi_t);
                if self.take_verdict(ctx, settings, verdict, base) {
                    self.trial.f = f_t;
                    if extrapolate && trials == 1 && alpha == 1.0 {
                        let a = self.extrapolate(ctx, settings, verdict, base, phi_t);
                        break LsOutcome::Accepted { alpha: a, trials };
                    }
                    break LsOutcome::Accepted { alpha, trials };
                }
                if trials == 1
                    && theta_t >= base.theta
                    && settings.line_search.max_soc > 0
                    && self.m > 0
                    && let Some(a) = self.second_order_correction(ctx, settings, alpha, base)
                {
                    break LsOutcome::Accepted { alpha: a, trials };
                }
            }
            alpha *= settings.line_search.alpha_red_factor;
        };
        let fe = ctx.timing.function_evals - fe0;
        ctx.timing.line_search += t0.elapsed().saturating_sub(fe);
        outcome
    }

    /// Curvature `dxᵀ (W + Σ) dx` of the barrier problem's Lagrangian along the primal step,
    /// from the factored KKT matrix (whose (1,1) block is `W + Σ + δ_w I`). Uses the
    /// refinement buffers `corr`, `resid`, free once the step is computed.
    fn step_curvature(&mut self) -> f64 {
        let n = self.n;
        self.kkt.corr[..n].copy_from_slice(&self.direction.dx);
        self.kkt.corr[n..].fill(0.0);
        self.kkt
            .matrix
            .mat
            .sym_matvec(&self.kkt.corr, &mut self.kkt.resid);
        dot(&self.direction.dx, &self.kkt.resid[..n])
            - self.reg.delta_w * dot(&self.direction.dx, &self.direction.dx)
    }

    /// Extrapolation along negative curvature (`LineSearchSettings::max_curvature_extrapolation`):
    /// after the full step (α = 1) was accepted with `verdict` in an iteration whose inertia
    /// needed δ_w above the proximal floor (a step the proximal term shortened on purpose is
    /// not extended), and the curvature along it is negative, doubles α up to the
    /// fraction-to-boundary step capped at the setting while the acceptance test gives the same
    /// verdict and φ_μ decreases. The verdict's bookkeeping (filter, reset counter) was done
    /// for α = 1 and depends on the current iterate only, so a longer step changes none of it.
    /// Returns the chosen α (1 if no longer step is better); `x_t, c_t, f_t` hold its point.
    fn extrapolate(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        verdict: Trial,
        base: Base,
        phi_1: f64,
    ) -> f64 {
        if self.reg.delta_w <= self.reg.proximal || self.step_curvature() >= 0.0 {
            return 1.0;
        }
        let cap = self.max_step_primal_upto(
            &self.direction.dx,
            settings.line_search.max_curvature_extrapolation,
        );
        if cap < 2.0 {
            return 1.0;
        }
        // The best point so far lives in `best_x, best_c`; each better trial is swapped in, and
        // the buffer it leaves in `x_t, c_t` is overwritten by the next trial.
        let (mut best_x, mut best_c) = (self.trial.x.clone(), self.trial.c.clone());
        let (mut best_alpha, mut best_phi, mut best_f) = (1.0, phi_1, self.trial.f);
        let mut alpha = 2.0;
        while alpha <= cap {
            let Some((f_t, theta_t, phi_t)) = self.trial_point(ctx, alpha) else {
                break;
            };
            let v = self.acceptable(settings, base, alpha, theta_t, phi_t);
            if v != verdict || phi_t >= best_phi {
                break;
            }
            std::mem::swap(&mut self.trial.x, &mut best_x);
            std::mem::swap(&mut self.trial.c, &mut best_c);
            (best_alpha, best_phi, best_f) = (alpha, phi_t, f_t);
            alpha *= 2.0;
        }
        self.trial.x = best_x;
        self.trial.c = best_c;
        self.trial.f = best_f;
        if best_alpha > 1.0 {
            ctx.counters.extrapolations += 1;
        }
        best_alpha
    }

    /// Second-order corrections (W&B Sect. 2.4). On success `x_t, c_t, f_t` hold the accepted
    /// point and `dx, dy, dz` the corrected step (taken with the returned α).
    pub(super) fn second_order_correction(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        alpha: f64,
        base: Base,
    ) -> Option<f64> {
        let mut c_soc: Vec<f64> = self
            .evals
            .c
            .iter()
            .zip(&self.trial.c)
            .map(|(c, ct)| alpha * c + ct)
            .collect();
        let mut theta_old = base.theta;
        let saved = (
            self.direction.dx.clone(),
            self.direction.dy.clone(),
            self.direction.dzl.clone(),
            self.direction.dzu.clone(),
        );
        for _ in 0..settings.line_search.max_soc {
            self.set_rhs(Some(&c_soc));
            self.solve_refined(ctx, settings);
            self.unpack_step();
            let a_soc = self.max_step_primal(&self.direction.dx);
            let Some((f_t, theta_t, phi_t)) = self.trial_point(ctx, a_soc) else {
                break;
            };
            // Judged against the same iterate, with the slope of the corrected step.
            let corrected = Base {
                gphi_dx: dot(&self.evals.grad_phi, &self.direction.dx),
                ..base
            };
            let verdict = self.acceptable(settings, corrected, a_soc, theta_t, phi_t);
            if self.take_verdict(ctx, settings, verdict, corrected) {
                self.trial.f = f_t;
                ctx.counters.soc_accepted += 1;
                return Some(a_soc);
            }
            if theta_t > settings.line_search.kappa_soc * theta_old {
                break;
            }
            theta_old = theta_t;
            for i in 0..self.m {
                c_soc[i] = a_soc * c_soc[i] + self.trial.c[i];
            }
        }
        self.direction.dx = saved.0;
        self.direction.dy = saved.1;
        self.direction.dzl = saved.2;
        self.direction.dzu = saved.3;
        self.set_rhs(None);
        None
    }

    /// Ipopt's "soft restoration" step: when the filter line search fails, try the primal-dual
    /// step with the common step size `α = min(α_max^pr, α_max^du)` and accept it if it reduces
    /// the barrier optimality error `E_μ` by the factor 0.9999 (avoids the full restoration
    /// phase at nearly feasible points of degenerate problems). On success `x_t, c_t, f_t` hold
    /// the trial point and α is returned.
    pub(super) fn soft_restoration_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        e_mu_current: f64,
    ) -> Option<f64> {
        // Only at nearly feasible points (θ ≤ θ_min), where the full restoration phase cannot
        // make progress on θ and would move x far from the current iterate.
        if self.restoration || norm_1(&self.evals.c) > self.filter.theta_min {
            return None;
        }
        let a = self
            .max_step_primal(&self.direction.dx)
            .min(self.max_step_dual());
        for j in 0..self.n {
            self.trial.x[j] = self.iterate.x[j] + a * self.direction.dx[j];
        }
        let (f_t, ok) = self.eval_fc(ctx, true);
        if !ok {
            return None;
        }
        let t = Instant::now();
        let mut grad = vec![0.0; self.n];
        let mut jac = vec![0.0; self.evals.jac.len()];
        self.prob.eval_grad(&self.trial.x, &mut grad);
        self.prob.eval_jac(&self.trial.x, &mut jac);
        ctx.timing.derivative_evals += t.elapsed();
        let y: Vec<f64> = (0..self.m)
            .map(|i| self.iterate.y[i] + a * self.direction.dy[i])
            .collect();
        let zl: Vec<f64> = (0..self.iterate.zl.len())
            .map(|k| self.iterate.zl[k] + a * self.direction.dzl[k])
            .collect();
        let zu: Vec<f64> = (0..self.iterate.zu.len())
            .map(|k| self.iterate.zu[k] + a * self.direction.dzu[k])
            .collect();
        let mut rd = grad;
        for (k, &(r, c)) in self.evals.jac_pat.iter().enumerate() {
            rd[c] += jac[k] * y[r];
        }
        let mut compl = 0.0f64;
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            rd[j] -= zl[k];
            compl =
                compl.max(((self.trial.x[j] - self.bounds.xl[j]) * zl[k] - self.barrier.mu).abs());
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            rd[j] += zu[k];
            compl =
                compl.max(((self.bounds.xu[j] - self.trial.x[j]) * zu[k] - self.barrier.mu).abs());
        }
        let nz = self.bounds.lo.len() + self.bounds.up.len();
        let zsum = norm_1(&zl) + norm_1(&zu);
        let smax = settings.termination.s_max;
        let s_d = smax.max((norm_1(&y) + zsum) / ((self.m + self.n) as f64).max(1.0)) / smax;
        let s_c = if nz > 0 {
            smax.max(zsum / nz as f64) / smax
        } else {
            1.0
        };
        let e = max_or_nan(
            max_or_nan(norm_inf(&rd) / s_d, norm_inf(&self.trial.c)),
            compl / s_c,
        );
        if e.is_finite()
            && e <= 0.9999 * e_mu_current
            && norm_1(&self.trial.c) <= self.filter.theta_max
        {
            self.trial.f = f_t;
            Some(a)
        } else {
            None
        }
    }
}
