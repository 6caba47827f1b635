//! Optimality measures and termination tests (Wächter & Biegler 2006, "W&B"):
//!
//! * the scaled optimality error `E_μ = max(‖∇f + Jᵀy − z_L + z_U‖_∞ / s_d, ‖c‖_∞,
//!   ‖S z − μ e‖_∞ / s_c)` with the multiplier scalings `s_d`, `s_c` capped by `s_max`
//!   (W&B eq. (5)–(6)); `E_0` is the error of the original problem;
//! * the unscaled dual infeasibility, constraint violation and complementarity (objective and
//!   constraint scaling undone) that `Solved` also requires, as Ipopt's `dual_inf_tol`,
//!   `constr_viol_tol` and `compl_inf_tol`;
//! * the "acceptable" level (W&B Sect. 3.9) and the stops for unboundedness (a very negative
//!   scaled objective, so that the verdict does not depend on the objective's units, at a
//!   feasible point while a variable with a free or one-sided bound grows; never for an
//!   all-boxed problem), diverging iterates, the iteration limit and the wall-clock limit.

use super::{Core, Ctx, max_or_nan, norm_1, norm_inf};
use crate::ipm::settings::Settings;
use crate::ipm::solution::Status;

/// Optimality errors at the current iterate.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Errors {
    pub(super) dual_inf: f64,
    pub(super) primal_inf: f64,
    /// ‖S z‖_∞ (μ = 0)
    pub(super) compl0: f64,
    pub(super) s_d: f64,
    pub(super) s_c: f64,
}

impl Errors {
    /// The scaled optimality error with complementarity `compl` (W&B eq. (5)); NaN if a part
    /// is NaN, so that a NaN measure never passes a test.
    pub(super) fn e(&self, compl: f64) -> f64 {
        max_or_nan(
            max_or_nan(self.dual_inf / self.s_d, self.primal_inf),
            compl / self.s_c,
        )
    }
}

/// Outcome of the termination tests at one iterate.
pub(super) enum Verdict {
    /// Keep iterating; `pr_u` is the unscaled constraint violation.
    Continue {
        /// Unscaled constraint violation ‖c‖_∞ (constraint scaling undone).
        pr_u: f64,
    },
    /// Stop with this status.
    Stop(Status),
}

impl Core<'_> {
    pub(super) fn errors(&self, settings: &Settings) -> Errors {
        let mut rd = self.evals.grad.clone();
        for j in 0..self.n {
            rd[j] += self.evals.jty[j];
        }
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            rd[j] -= self.iterate.zl[k];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            rd[j] += self.iterate.zu[k];
        }
        let compl0 = self
            .iterate
            .sl
            .iter()
            .zip(&self.iterate.zl)
            .chain(self.iterate.su.iter().zip(&self.iterate.zu))
            .fold(0.0f64, |a, (s, z)| a.max((s * z).abs()));
        let nz = self.bounds.lo.len() + self.bounds.up.len();
        let zsum = norm_1(&self.iterate.zl) + norm_1(&self.iterate.zu);
        let smax = settings.termination.s_max;
        let s_d = (smax
            .max((norm_1(&self.iterate.y) + zsum) / ((self.m + self.n) as f64).max(1.0)))
            / smax;
        let s_c = if nz > 0 {
            smax.max(zsum / nz as f64) / smax
        } else {
            1.0
        };
        Errors {
            dual_inf: norm_inf(&rd),
            primal_inf: norm_inf(&self.evals.c),
            compl0,
            s_d,
            s_c,
        }
    }

    pub(super) fn compl_mu(&self, mu: f64) -> f64 {
        self.iterate
            .sl
            .iter()
            .zip(&self.iterate.zl)
            .chain(self.iterate.su.iter().zip(&self.iterate.zu))
            .fold(0.0f64, |a, (s, z)| a.max((s * z - mu).abs()))
    }

    pub(super) fn avg_compl(&self) -> Option<(f64, f64)> {
        let nz = self.bounds.lo.len() + self.bounds.up.len();
        if nz == 0 {
            return None;
        }
        let mut sum = 0.0;
        let mut min = f64::INFINITY;
        for (s, z) in self
            .iterate
            .sl
            .iter()
            .zip(&self.iterate.zl)
            .chain(self.iterate.su.iter().zip(&self.iterate.zu))
        {
            sum += s * z;
            min = min.min(s * z);
        }
        Some((sum / nz as f64, min))
    }

    /// Unscaled (dual, primal, complementarity) for the `Solved` test.
    pub(super) fn unscaled(&self, e: &Errors) -> (f64, f64, f64) {
        let (os, cs) = self.prob.scales();
        let primal = match cs {
            Some(cs) => self
                .evals
                .c
                .iter()
                .zip(cs)
                .fold(0.0f64, |a, (c, s)| a.max((c / s).abs())),
            None => e.primal_inf,
        };
        (e.dual_inf / os, primal, e.compl0 / os)
    }

    /// The termination tests at the current iterate (errors `err`, `E_0 = e0`), counting
    /// consecutive acceptable iterates in `acceptable_count`.
    pub(super) fn termination(
        &self,
        ctx: &Ctx<'_, '_>,
        err: &Errors,
        e0: f64,
        acceptable_count: &mut usize,
    ) -> Verdict {
        let settings = ctx.settings;
        let (du_u, pr_u, co_u) = self.unscaled(err);
        if e0 <= settings.termination.tol
            && du_u <= settings.termination.dual_inf_tol
            && pr_u <= settings.termination.constr_viol_tol
            && co_u <= settings.termination.compl_inf_tol
        {
            return Verdict::Stop(Status::Solved);
        }
        if settings.termination.acceptable_iter > 0
            && e0 <= settings.termination.acceptable_tol
            && pr_u <= settings.termination.acceptable_constr_viol_tol
        {
            *acceptable_count += 1;
            if *acceptable_count >= settings.termination.acceptable_iter {
                return Verdict::Stop(Status::Acceptable);
            }
        } else {
            *acceptable_count = 0;
        }
        // Only a variable of the problem (not an inequality slack, bounded when the variables
        // are) with a free or one-sided bound can run away: the largest of them must exceed
        // its largest value at every earlier iterate.
        let unboxed = (0..self.prob.n_own())
            .filter(|&j| !(self.bounds.xl[j].is_finite() && self.bounds.xu[j].is_finite()))
            .map(|j| self.iterate.x[j].abs())
            .fold(f64::NEG_INFINITY, f64::max);
        let prev = self.unboxed_max.get();
        let growing = unboxed.is_finite() && prev.is_finite() && unboxed > prev;
        self.unboxed_max.set(prev.max(unboxed));
        if !self.restoration
            && growing
            && pr_u <= settings.termination.constr_viol_tol
            && self.evals.f < -settings.termination.unbounded_objective
        {
            return Verdict::Stop(Status::Unbounded);
        }
        if norm_inf(&self.iterate.x) > settings.termination.diverging_iterates_tol {
            return Verdict::Stop(Status::DivergingIterates);
        }
        if ctx.iter >= settings.termination.max_iter {
            return Verdict::Stop(Status::MaxIterations);
        }
        if ctx.start.elapsed().as_secs_f64() > settings.termination.max_wall_time {
            return Verdict::Stop(Status::MaxTime);
        }
        Verdict::Continue { pr_u }
    }
}
