//! The Newton step of the primal-dual barrier method (Wächter & Biegler 2006, "W&B"):
//!
//! * the reduced primal-dual system (W&B eq. (13)) with `z_L, z_U` eliminated, assembled into
//!   the KKT matrix `K(δ_w, δ_c)` of [`crate::ipm::kkt`] and factored by [`SparseLdlt`](crate::ipm::kkt::SparseLdlt);
//! * inertia correction (W&B Sect. 3.1, Algorithm IC): the step is accepted when `K` has n
//!   positive and m negative eigenvalues and its refined solution is accurate; otherwise the
//!   chain of KKT strategies of `recovery` corrects the matrix (pivot-pair check, static δ_c
//!   raised, Jacobian regularization δ_c, δ_w grown) and [`Core::compute_step`] factors it
//!   again ([`Core::factor_trial`]: with `LinearSolverSettings::speculative_factorization`,
//!   the next trial's matrix is factored ahead on a second core and its factor taken when
//!   asked for, the same factor bit for bit; decision record 0036). A static `δ_c` is always
//!   on the constraint block and removed again by iterative
//!   refinement; on a stalled barrier problem above the tolerance the correction starts from
//!   the proximal floor `δ_w = κ_p μ` (`BarrierSettings::proximal_weight`, decision record
//!   0011); a step whose δ_w = 0 trial failed starts the next one from κ_w⁻ δ_w_last;
//! * the re-factorization of a rejected AMD factor's matrix with 2 × 2 pivot pairs
//!   ([`Core::try_pivot_pairs`], [`KktOrdering`](crate::ipm::settings::KktOrdering)), used by
//!   that chain;
//! * iterative refinement of each KKT solution against the unregularized matrix, judged by
//!   its residual relative to the right-hand side or, failing that, its normwise backward
//!   error ([`Core::solve_refined`]; decision records 0008 and 0009);
//! * recovery of `dz_L, dz_U` (W&B eq. (12));
//! * least-squares constraint multipliers for the initial point (W&B Sect. 3.6).

use std::time::Instant;

use super::recovery::{KKT_CHAIN, KktAction, Rejection, StepMemory, first_remedy, next_delta_w};
use super::{Core, Ctx, norm_inf};
use crate::error::OptimError;
use crate::ipm::kkt::{
    FactorizationFailure, Inertia, KktSolver, LdltOptions, LdltOrdering, SparseLdlt, Speculator,
};
use crate::ipm::settings::Settings;

/// The residual ratio of a KKT solve, `‖K sol − rhs‖ / (‖sol‖ + ‖rhs‖)` (∞-norms): a
/// backward-stable solve leaves a residual of order `ε ‖K‖ ‖sol‖`, so a long exact step is
/// judged against its own length. Ipopt's `PDFullSpaceSolver::ComputeResidualRatio` credits
/// `‖sol‖` only up to `10⁶ ‖rhs‖`; that cap binds late in the flat valleys of the fine
/// `periodic-cot` meshes and sends Radau 3 × 24 from `Solved` to `RestorationFailed`
/// (decision record 0002), so it is not applied.
fn residual_ratio(resid: f64, rhs: f64, sol: f64) -> f64 {
    resid / (sol + rhs).max(1e-300)
}

/// Largest accuracy measure of [`Core::solve_refined`] at which a KKT solution is accepted.
const ACCURATE_SOLVE: f64 = 1e-5;

/// Normwise backward error of a solution of `K sol = rhs` with residual norm `resid`
/// (Rigal–Gaches, Higham 2002 Thm. 7.1; `max|K_ij| ≤ ‖K‖_∞` stands for the norm, so the
/// value bounds the true one from above): the smallest relative
/// perturbation of `K` and `rhs` that `sol` solves exactly. ∞-norms throughout.
fn backward_error(resid: f64, rhs: f64, kmax: f64, sol: f64) -> f64 {
    resid / (kmax * sol + rhs).max(1e-300)
}

/// Step-computation result.
pub(super) enum StepResult {
    Ok,
    Failed,
}

impl Core<'_> {
    pub(super) fn factor_current(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
    ) -> Result<Inertia, FactorizationFailure> {
        let t = Instant::now();
        let r = self.kkt.solver.factor(&self.kkt.matrix.mat.values);
        ctx.counters.factorizations += 1;
        ctx.timing.factorization += t.elapsed();
        r
    }

    /// [`Core::factor_current`] for a trial of the inertia correction, with the speculative
    /// factorization of `LinearSolverSettings::speculative_factorization` (`kkt::speculative`):
    /// a finished factor of this very matrix from the second thread is taken instead of
    /// factoring; otherwise, before factoring, the second thread starts on the matrix the
    /// correction factors next if this one's inertia is wrong ([`HessianPerturbation`]'s δ_w,
    /// δ_c unchanged), if a core is idle. Either way the factor is the one `factor_current`
    /// computes.
    ///
    /// [`HessianPerturbation`]: super::recovery::HessianPerturbation
    fn factor_trial(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
    ) -> Result<Inertia, FactorizationFailure> {
        if !settings.linear_solver.speculative_factorization {
            return self.factor_current(ctx);
        }
        let speculate = *self
            .kkt
            .speculate
            .get_or_insert_with(|| Speculator::worthwhile(&self.kkt.solver));
        if !speculate {
            return self.factor_current(ctx);
        }
        let t = Instant::now();
        let kkt = &mut self.kkt;
        let taken = kkt
            .speculation
            .take(&mut kkt.solver, &kkt.matrix.mat.values);
        ctx.timing.speculative_factorization += kkt.speculation.take_busy();
        if let Some((result, _waited)) = taken {
            ctx.counters.factorizations += 1;
            ctx.timing.factorization += t.elapsed();
            if settings.output.print_level > 2 {
                println!("    KKT: factor from the second thread");
            }
            return result;
        }
        let next_w = next_delta_w(&self.reg, &settings.recovery);
        if self.kkt.speculation.idle_core() && next_w <= settings.recovery.max_hessian_perturbation
        {
            let change = next_w - self.reg.delta_w;
            let matrix = &self.kkt.matrix;
            self.kkt.speculation.start(&self.kkt.solver, |out| {
                matrix.shifted_values(change, 0.0, out)
            });
        }
        ctx.timing.factorization += t.elapsed();
        self.factor_current(ctx)
    }

    /// Solves `K sol = rhs` with refinement against `K(δ_w, δ_c_target)`; returns the final
    /// residual `‖K sol − rhs‖_∞` relative to `‖rhs‖_∞`, or with
    /// `ExperimentalSettings::residual_ratio_with_solution` Ipopt's residual ratio ([`residual_ratio`]),
    /// on which the caller judges the solution's accuracy (accepted at [`ACCURATE_SOLVE`]);
    /// where that measure rejects the solution but its normwise backward error
    /// ([`backward_error`]) is at most `LinearSolverSettings::backward_error_tol`, that backward error
    /// instead. Refinement takes `LinearSolverSettings::min_refinement_steps` steps unless the residual
    /// relative to `‖rhs‖_∞` reaches `refinement_tol`, then continues (up to
    /// `max_refinement_steps`) only while the solution fails that accuracy test and each step
    /// reduces the relative residual by `refinement_contraction`; a step that does not is
    /// undone (decision record 0009).
    pub(super) fn solve_refined(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) -> f64 {
        let t = Instant::now();
        let nm = self.n + self.m;
        self.kkt.sol.copy_from_slice(&self.kkt.rhs);
        if self.kkt.solver.solve(&mut self.kkt.sol).is_err() {
            ctx.timing.solve += t.elapsed();
            return f64::INFINITY;
        }
        let bnorm = norm_inf(&self.kkt.rhs);
        let mut best = f64::INFINITY;
        let mut by_backward_error = false;
        // max|K_ij| of the factored matrix, the same for every refinement step: computed once,
        // and only when a solve needs the backward-error test.
        let mut kmax: Option<f64> = None;
        for target in [self.reg.delta_c_target, self.reg.delta_c] {
            let shift = self.reg.delta_c - target;
            // (relative residual, accuracy measure, accepted on its backward error) before the
            // last correction.
            let mut previous: Option<(f64, f64, bool)> = None;
            for step in 0..=settings.linear_solver.max_refinement_steps {
                self.kkt
                    .matrix
                    .mat
                    .sym_matvec(&self.kkt.sol, &mut self.kkt.resid);
                for i in 0..nm {
                    let extra = if i >= self.n {
                        shift * self.kkt.sol[i]
                    } else {
                        0.0
                    };
                    self.kkt.resid[i] = self.kkt.rhs[i] - self.kkt.resid[i] - extra;
                }
                let rnorm = norm_inf(&self.kkt.resid);
                let rel = rnorm / bnorm.max(1e-300);
                let rn = if settings.experimental.residual_ratio_with_solution {
                    residual_ratio(rnorm, bnorm, norm_inf(&self.kkt.sol))
                } else {
                    rel
                };
                // Only a solve that the test above rejects is judged again, so every solve it
                // accepts keeps its path bit for bit.
                by_backward_error = false;
                let rn = if rn > ACCURATE_SOLVE && settings.linear_solver.backward_error_tol > 0.0 {
                    let kmax = *kmax.get_or_insert_with(|| norm_inf(&self.kkt.matrix.mat.values));
                    let eta = backward_error(rnorm, bnorm, kmax, norm_inf(&self.kkt.sol));
                    by_backward_error = eta <= settings.linear_solver.backward_error_tol
                        && rel <= settings.linear_solver.backward_error_forcing;
                    if settings.output.print_level > 2 {
                        println!(
                            "    KKT: refinement step {step}: residual {rn:.2e} relative, backward error {eta:.2e}"
                        );
                    }
                    if by_backward_error { eta } else { rn }
                } else {
                    rn
                };
                // NaN-safe: a non-finite residual has not contracted.
                let contracted = previous.is_some_and(|(prev_rel, _, _)| {
                    rel <= settings.linear_solver.refinement_contraction * prev_rel
                });
                if step > settings.linear_solver.min_refinement_steps
                    && !contracted
                    && let Some((_, prev_rn, prev_by_backward_error)) = previous
                {
                    // Beyond the minimum, a correction that did not reduce the residual by the
                    // contraction factor shows refinement converging too slowly to be worth
                    // more solves (LAPACK's xGERFS stops likewise): undo it, so the solution
                    // is the one the minimum steps produced or a better one.
                    self.kkt.sol.copy_from_slice(&self.kkt.sol_before);
                    best = prev_rn;
                    by_backward_error = prev_by_backward_error;
                    break;
                }
                if !rn.is_finite() {
                    best = f64::INFINITY;
                    break;
                }
                best = rn;
                // Steps beyond the minimum are for solves the accuracy test still rejects.
                if rel <= settings.linear_solver.refinement_tol
                    || step == settings.linear_solver.max_refinement_steps
                    || (step >= settings.linear_solver.min_refinement_steps && rn <= ACCURATE_SOLVE)
                {
                    break;
                }
                previous = Some((rel, rn, by_backward_error));
                ctx.counters.refinement_steps += 1;
                self.kkt.corr.copy_from_slice(&self.kkt.resid);
                // The factor that solved `sol` above solves the correction too.
                let _ = self.kkt.solver.solve(&mut self.kkt.corr);
                if step >= settings.linear_solver.min_refinement_steps {
                    // This correction may be undone (above): keep the solution bit for bit.
                    self.kkt.sol_before.copy_from_slice(&self.kkt.sol);
                }
                for i in 0..nm {
                    self.kkt.sol[i] += self.kkt.corr[i];
                }
            }
            if best <= 1e-6 || shift == 0.0 {
                break;
            }
            if settings.output.print_level > 2 {
                println!(
                    "    KKT: refinement against δ_c = {target:.1e} stalls at {best:.2e}: step of the regularized system"
                );
            }
            // Refinement against the unregularized matrix did not converge (rank-deficient J):
            // accept the step of the regularized system instead.
            self.kkt.sol.copy_from_slice(&self.kkt.rhs);
            let _ = self.kkt.solver.solve(&mut self.kkt.sol);
        }
        if by_backward_error && best <= ACCURATE_SOLVE {
            ctx.counters.backward_error_accepts += 1;
        }
        ctx.timing.solve += t.elapsed();
        best
    }

    /// Assembles and factors `K`, correcting the inertia (W&B Algorithm IC), then solves for the
    /// Newton step of the current right-hand side.
    pub(super) fn compute_step(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        use_hessian: bool,
    ) -> Result<StepResult, OptimError> {
        let t = Instant::now();
        for j in 0..self.n {
            self.kkt.diag_x[j] = 0.0;
        }
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            self.kkt.diag_x[j] += self.iterate.zl[k] / self.iterate.sl[k];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            self.kkt.diag_x[j] += self.iterate.zu[k] / self.iterate.su[k];
        }
        let static_c = if self.m > 0 {
            self.reg
                .static_dc
                .max(settings.linear_solver.static_dual_regularization)
        } else {
            0.0
        };
        self.reg.delta_c = static_c;
        self.reg.delta_c_target = 0.0;
        self.reg.delta_w = 0.0;
        if use_hessian {
            self.kkt.matrix.assemble(
                &self.evals.hess,
                &self.evals.jac,
                &self.kkt.diag_x,
                -self.reg.delta_c,
            );
        } else {
            let zeros = vec![0.0; self.evals.hess.len()];
            self.kkt
                .matrix
                .assemble(&zeros, &self.evals.jac, &self.kkt.diag_x, -self.reg.delta_c);
        }
        let dec = match settings.experimental.perturb_dec_fact_after_rejection {
            Some(after) if self.reg.grew_from_first_trial => after,
            _ => settings.recovery.perturb_dec_fact,
        };
        let first_w = dec * self.reg.delta_w_last;
        if use_hessian && self.reg.skip_zero_trial && first_w >= 1e-12 {
            self.reg.delta_w = first_w.max(settings.recovery.min_hessian_perturbation);
            self.kkt.matrix.shift_diagonal(self.reg.delta_w, 0.0);
        }
        // The proximal floor (`BarrierSettings::proximal_weight`); the inertia correction below
        // grows δ_w from it.
        if use_hessian && self.reg.proximal > self.reg.delta_w {
            self.kkt
                .matrix
                .shift_diagonal(self.reg.proximal - self.reg.delta_w, 0.0);
            self.reg.delta_w = self.reg.proximal;
        }
        let first_trial_w = self.reg.delta_w;
        ctx.timing.kkt_assembly += t.elapsed();
        let mut memory = StepMemory::default();
        loop {
            let inertia = self.factor_trial(ctx, settings);
            let good = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
            if settings.output.print_level > 2 {
                println!(
                    "    KKT: delta_w {:.2e} delta_c {:.2e} inertia {:?} (want {}+, {}-)",
                    self.reg.delta_w, self.reg.delta_c, inertia, self.n, self.m
                );
            }
            let mut rejection = Rejection {
                singular: inertia.is_err(),
                inaccurate: false,
                artefact: false,
                use_hessian,
                old_w: self.reg.delta_w,
                old_c: self.reg.delta_c,
                memory: &mut memory,
            };
            if good {
                let res = self.solve_refined(ctx, settings);
                if settings.output.print_level > 2 {
                    println!("    KKT: relative residual after refinement {res:.2e}");
                }
                if res <= ACCURATE_SOLVE {
                    self.accept_perturbation(use_hessian, first_trial_w);
                    return Ok(StepResult::Ok);
                }
                // Right inertia but refinement cannot reach the exact system: the matrix is
                // (numerically) singular and static pivoting hid it, or the unpivoted factor
                // is unstable.
                rejection.singular = true;
                rejection.inaccurate = true;
            }
            ctx.counters.rejected_factorizations += 1;
            // The inertia correction: the first strategy of the chain that acts decides
            // (`recovery`; its last link always acts).
            match first_remedy(&KKT_CHAIN, self, ctx, &mut rejection)? {
                Some((_, KktAction::Refactor)) => {}
                Some((_, KktAction::Solved)) => {
                    self.accept_perturbation(use_hessian, first_trial_w);
                    return Ok(StepResult::Ok);
                }
                Some((_, KktAction::GiveUp)) | None => return Ok(StepResult::Failed),
            }
        }
    }

    /// Bookkeeping of an accepted factorization with the current δ_w; `first_trial_w`: the
    /// δ_w of the step's first factorization.
    fn accept_perturbation(&mut self, use_hessian: bool, first_trial_w: f64) {
        if self.reg.delta_w == 0.0 && use_hessian {
            self.reg.skip_zero_trial = false;
        }
        if self.reg.delta_w > 0.0 {
            self.reg.delta_w_last = self.reg.delta_w;
        }
        if use_hessian {
            self.reg.grew_from_first_trial = self.reg.delta_w > first_trial_w;
        }
    }

    /// Re-factors the current matrix, which the AMD factor rejected, with AMD and 2 × 2 pivot
    /// pairs (analysed on first use) and solves with it; returns whether that factor has the
    /// right inertia and an accurate refined solution. If so and `switch`, its step stands
    /// and the solve keeps the pairs from now on; otherwise the AMD factor stays current. A
    /// pattern where AMD eliminates no constraint row bare has nothing to check.
    pub(super) fn try_pivot_pairs(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        switch: bool,
    ) -> bool {
        if self.kkt.other_solver.is_none() {
            let t = Instant::now();
            let options = LdltOptions {
                ordering: LdltOrdering::AmdPivotPairs {
                    constraint_rows_from: self.n,
                },
                // Never shared while a speculative job may run: both at once put three busy
                // threads on two cores (decision record 0090).
                parallel: self.kkt.solver.options().parallel && self.kkt.speculate != Some(true),
                ..self.kkt.solver.options().clone()
            };
            // An earlier run's solver with these options keeps its analyses (bit for bit the
            // ones a new solver would make).
            let mut pairs = match self
                .kkt
                .spare_pairs
                .iter()
                .position(|p| *p.options() == options)
            {
                Some(k) => self.kkt.spare_pairs.remove(k),
                None => SparseLdlt::with_options(options),
            };
            // The pairs start from AMD's order, which the solver's own analysis already made.
            let (dim, pattern) = (self.n + self.m, &self.kkt.matrix.mat);
            let amd = self.kkt.solver.amd_order();
            let analysed = pairs
                .analyse_in_amd_order(dim, &pattern.col_ptr, &pattern.row_idx, amd)
                .is_ok();
            ctx.timing.factorization += t.elapsed();
            if !analysed || !pairs.has_pivot_pairs() {
                self.kkt.check_pairs = false;
                // Kept for later runs: this pattern's answer is known without analysing again.
                self.kkt.spare_pairs.push(pairs);
                return false;
            }
            self.kkt.other_solver = Some(pairs);
        }
        let Some(pairs) = self.kkt.other_solver.as_mut() else {
            return false;
        };
        std::mem::swap(&mut self.kkt.solver, pairs);
        let inertia = self.factor_current(ctx);
        ctx.counters.pivot_pair_checks += 1;
        let good = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
        let res = if good {
            self.solve_refined(ctx, settings)
        } else {
            f64::INFINITY
        };
        if settings.output.print_level > 2 {
            println!("    KKT with pivot pairs: inertia {inertia:?}, relative residual {res:.2e}");
        }
        let accepted = res <= ACCURATE_SOLVE;
        if accepted && switch {
            self.kkt.check_pairs = false;
            self.kkt.switched_to_pairs = true;
            ctx.counters.pivot_pairs_from = Some(ctx.iter);
            if settings.output.print_level > 0 {
                println!(
                    "KKT: AMD's factor rejected where the pivot pairs' is right: pivot pairs from iteration {}",
                    ctx.iter
                );
            }
            return true;
        }
        if let Some(pairs) = self.kkt.other_solver.as_mut() {
            std::mem::swap(&mut self.kkt.solver, pairs);
        }
        accepted
    }

    /// Fills `rhs` with the Newton right-hand side `−(∇φ + Jᵀy, c_rhs)`.
    pub(super) fn set_rhs(&mut self, c_rhs: Option<&[f64]>) {
        for j in 0..self.n {
            self.kkt.rhs[j] = -(self.evals.grad_phi[j] + self.evals.jty[j]);
        }
        let c = c_rhs.unwrap_or(&self.evals.c);
        for i in 0..self.m {
            self.kkt.rhs[self.n + i] = -c[i];
        }
    }

    /// Unpacks `sol` into (dx, dy) and recovers (dz_L, dz_U) (W&B eq. (12)).
    pub(super) fn unpack_step(&mut self) {
        self.direction.dx.copy_from_slice(&self.kkt.sol[..self.n]);
        self.direction.dy.copy_from_slice(&self.kkt.sol[self.n..]);
        let mu = self.barrier.mu;
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            self.direction.dzl[k] = mu / self.iterate.sl[k]
                - self.iterate.zl[k]
                - self.iterate.zl[k] / self.iterate.sl[k] * self.direction.dx[j];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            self.direction.dzu[k] = mu / self.iterate.su[k] - self.iterate.zu[k]
                + self.iterate.zu[k] / self.iterate.su[k] * self.direction.dx[j];
        }
    }

    /// Least-squares constraint multipliers: `[I Jᵀ; J 0] [w; y] = −[∇f − z_L + z_U; 0]`.
    pub(super) fn least_squares_y(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) {
        if self.m == 0 {
            return;
        }
        let t = Instant::now();
        let ones = vec![1.0; self.n];
        let zeros = vec![0.0; self.evals.hess.len()];
        self.kkt.matrix.assemble(
            &zeros,
            &self.evals.jac,
            &ones,
            -settings.linear_solver.static_dual_regularization,
        );
        ctx.timing.kkt_assembly += t.elapsed();
        self.reg.delta_c = settings.linear_solver.static_dual_regularization;
        self.reg.delta_c_target = 0.0;
        let inertia = self.factor_current(ctx);
        let ok = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
        if !ok {
            self.iterate.y.iter_mut().for_each(|v| *v = 0.0);
            return;
        }
        for j in 0..self.n {
            self.kkt.rhs[j] = -self.evals.grad[j];
        }
        for (k, &j) in self.bounds.lo.iter().enumerate() {
            self.kkt.rhs[j] += self.iterate.zl[k];
        }
        for (k, &j) in self.bounds.up.iter().enumerate() {
            self.kkt.rhs[j] -= self.iterate.zu[k];
        }
        for i in 0..self.m {
            self.kkt.rhs[self.n + i] = 0.0;
        }
        self.solve_refined(ctx, settings);
        let ys = &self.kkt.sol[self.n..];
        if norm_inf(ys) <= settings.barrier.constr_mult_init_max && ys.iter().all(|v| v.is_finite())
        {
            self.iterate.y.copy_from_slice(ys);
        } else {
            self.iterate.y.iter_mut().for_each(|v| *v = 0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{backward_error, residual_ratio};

    /// The accuracy threshold of `compute_step`.
    const ACCEPT: f64 = 1e-5;

    #[test]
    fn a_long_exact_step_is_accurate_relative_to_its_length() {
        // The flat-valley step of a fine periodic-cot mesh (decision record 0002): ‖rhs‖
        // 1.9e-6, ‖sol‖ 0.175, residual 2e-5 ‖rhs‖ after refinement.
        let (rhs, sol) = (1.9e-6, 0.175);
        let resid = 2e-5 * rhs;
        assert!(resid / rhs > ACCEPT);
        assert!(residual_ratio(resid, rhs, sol) < 1e-9);
    }

    #[test]
    fn a_rounding_level_solve_of_a_flat_valley_passes_the_backward_error_test() {
        // K = [[1, 1], [1, 1 + 1e-13]] (one eigenvalue ≈ 5e-14), a right-hand side of 1e-6:
        // the exact step is 1e7 long. LDLᵀ in f64 rounds d₂ = 1e-13 by ≈ 1e-16 relative to
        // K, which leaves a residual far above 1e-5 ‖rhs‖ however exact the arithmetic.
        let k: [[f64; 2]; 2] = [[1.0, 1.0], [1.0, 1.0 + 1e-13]];
        let rhs: [f64; 2] = [1e-6, 2e-6];
        let d2 = k[1][1] - k[0][1] * k[0][1] / k[0][0];
        let x2 = (rhs[1] - rhs[0]) / d2;
        let x1 = rhs[0] - x2;
        let r = [
            rhs[0] - (k[0][0] * x1 + k[0][1] * x2),
            rhs[1] - (k[1][0] * x1 + k[1][1] * x2),
        ];
        let (rn, bn, xn) = (
            r[0].abs().max(r[1].abs()),
            rhs[0].abs().max(rhs[1].abs()),
            x1.abs().max(x2.abs()),
        );
        assert!(rn / bn > ACCEPT, "relative residual {:e}", rn / bn);
        let eta = backward_error(rn, bn, 1.0 + 1e-13, xn);
        assert!(eta <= 1e-14, "η = {eta:e}");
        // A solution 1 % off on a well-conditioned system (K = I) is rejected by both tests.
        let (rhs, x) = (1.0f64, 1.01f64);
        let rn = (rhs - x).abs();
        assert!(rn / rhs > ACCEPT && backward_error(rn, rhs, 1.0, x) > 1e-3);
    }
}
