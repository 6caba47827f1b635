//! Feasibility restoration phase (Wächter & Biegler 2006, Sect. 3.3): when no acceptable step
//! is found, the same algorithm minimises `ρ‖p + n‖₁ + ζ/2 ‖D_R (x − x_R)‖²` s.t.
//! `c(x) − p + n = 0` (the problem is [`RestorationProblem`]), stopping as soon as the outer
//! filter accepts the point; the outer multipliers are then re-initialised (least squares for
//! `y`).

use super::{Core, CoreStart, Ctx, norm_1, norm_inf};
use crate::error::OptimError;
use crate::ipm::restoration::{OuterInfo, RestorationProblem};
use crate::ipm::settings::Settings;
use crate::ipm::solution::Status;

impl Core<'_> {
    /// Feasibility restoration (W&B Sect. 3.3): minimise `ρ‖p + n‖₁ + ζ/2 ‖D_R (x − x_R)‖²`
    /// s.t. `c(x) − p + n = 0` with the same IPM, stopping as soon as the outer filter accepts.
    /// Returns `Some(status)` when the outer solve must stop.
    pub(super) fn restoration_phase(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
    ) -> Result<Option<Status>, OptimError> {
        let theta = norm_1(&self.evals.c);
        let phi = self.barrier_value(&self.iterate.x, self.evals.f);
        self.filter.augment(theta, phi, settings);
        let outer = OuterInfo {
            xl: self.bounds.xl.clone(),
            xu: self.bounds.xu.clone(),
            lo: self.bounds.lo.clone(),
            up: self.bounds.up.clone(),
            damp: self.bounds.damp.clone(),
            kappa_d: self.barrier.kappa_d,
            mu: self.barrier.mu,
            filter: self.filter.entries().to_vec(),
            theta_ref: theta,
            kappa_resto: settings.recovery.resto_required_reduction,
            tol: settings.termination.tol,
        };
        let mu_r = self.barrier.mu.max(norm_inf(&self.evals.c));
        let rho = settings.recovery.resto_penalty;
        let n0 = self.n;
        let m = self.m;
        let mut w = self.iterate.x.clone();
        let mut p = vec![0.0; m];
        let mut nn = vec![0.0; m];
        for i in 0..m {
            let ci = self.evals.c[i];
            let a = (mu_r - rho * ci) / (2.0 * rho);
            nn[i] = a + (a * a + mu_r * ci / (2.0 * rho)).sqrt();
            p[i] = ci + nn[i];
        }
        w.extend_from_slice(&p);
        w.extend_from_slice(&nn);
        let mut zl = vec![0.0; n0 + 2 * m];
        let mut zu = vec![0.0; n0 + 2 * m];
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            zl[j] = self.iterate.zl[k].min(rho);
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            zu[j] = self.iterate.zu[k].min(rho);
        }
        for i in 0..m {
            zl[n0 + i] = mu_r / p[i];
            zl[n0 + m + i] = mu_r / nn[i];
        }
        let x_ref = self.iterate.x.clone();
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
            solvers: std::cell::Cell::new(
                self.kkt
                    .restoration_solvers
                    .take()
                    .map(|kept| *kept)
                    .unwrap_or_default(),
            ),
        };
        if settings.output.print_level > 1 {
            println!("  entering restoration phase (theta = {theta:.3e}, mu_R = {mu_r:.3e})");
        }
        let out = {
            let mut rp =
                RestorationProblem::new(&mut *self.prob, x_ref, rho, self.barrier.mu.sqrt(), outer);
            let mut inner = Core::new(&mut rp, settings, &start)?;
            inner.reg.delta_w_last = self.reg.delta_w_last;
            inner.reg.grew_from_first_trial = self.reg.grew_from_first_trial;
            let out = inner.run(ctx, &start);
            // The next phase (of this run or of a later one on this thread) meets the same
            // pattern again and takes the analysis back (decision record 0072).
            self.kkt.restoration_solvers = Some(Box::new(inner.into_kkt_solvers()));
            out?
        };
        let x_new = out.x[..n0].to_vec();
        let finish = |me: &mut Self, ctx: &mut Ctx<'_, '_>| -> Result<bool, OptimError> {
            me.iterate.x.copy_from_slice(&x_new);
            me.update_slacks();
            if me
                .iterate
                .sl
                .iter()
                .chain(&me.iterate.su)
                .any(|&s| s <= 0.0)
            {
                return Ok(false);
            }
            let (f, ok) = me.eval_fc(ctx, false);
            if !ok {
                return Ok(false);
            }
            me.evals.f = f;
            if !me.eval_derivs(ctx) {
                return Err(OptimError::NonFinite {
                    iter: ctx.iter,
                    what: "gradient or Jacobian after restoration",
                });
            }
            for (k, &j) in me.bounds.lo.iter().enumerate() {
                me.iterate.zl[k] = out.z_l[j];
            }
            for (k, &j) in me.bounds.up.iter().enumerate() {
                me.iterate.zu[k] = out.z_u[j];
            }
            let zmax = norm_inf(&me.iterate.zl).max(norm_inf(&me.iterate.zu));
            if zmax > 1e3 {
                me.iterate.zl.iter_mut().for_each(|z| *z = 1.0);
                me.iterate.zu.iter_mut().for_each(|z| *z = 1.0);
            }
            me.least_squares_y(ctx, settings);
            Ok(true)
        };
        if out.early_stopped {
            if finish(self, ctx)? {
                return Ok(self
                    .restoration_repeats(ctx.iter)
                    .then_some(Status::RestorationFailed));
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
                if viol > settings.termination.constr_viol_tol {
                    self.iterate.x.copy_from_slice(&x_in);
                    self.evals.c.copy_from_slice(&c);
                    self.update_slacks();
                    return Ok(Some(Status::LocallyInfeasible));
                }
                if finish(self, ctx)? {
                    self.filter.clear();
                    return Ok(self
                        .restoration_repeats(ctx.iter)
                        .then_some(Status::RestorationFailed));
                }
                Ok(Some(Status::RestorationFailed))
            }
            Status::MaxIterations | Status::MaxTime | Status::UserStop => Ok(Some(out.status)),
            _ => Ok(Some(Status::RestorationFailed)),
        }
    }

    /// Whether this restoration phase hands the run back at iteration `iter` exactly where the
    /// previous one did (μ, x and the multipliers bit for bit, no iteration in between, neither
    /// phase's nor the run's): the run would then repeat the same failed step and the same
    /// phase forever, without an iteration that `max_iter` counts (a constraint that is not
    /// finite at any trial point the line search tries, for instance). Judged only once a
    /// trial point of the run was not evaluable, so that no solve on finite values changes.
    fn restoration_repeats(&mut self, iter: usize) -> bool {
        if !self.met_non_finite_trial {
            return false;
        }
        let it = &self.iterate;
        let bits = std::iter::once(&self.barrier.mu)
            .chain(&it.x)
            .chain(&it.y)
            .chain(&it.zl)
            .chain(&it.zu)
            .map(|v| v.to_bits())
            .collect();
        let end = Some((iter, bits));
        let repeats = self.last_restoration_end == end;
        self.last_restoration_end = end;
        repeats
    }
}
