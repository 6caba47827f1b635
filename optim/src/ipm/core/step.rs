//! The Newton step of the primal-dual barrier method (Wächter & Biegler 2006, "W&B"):
//!
//! * the reduced primal-dual system (W&B eq. (13)) with `z_L, z_U` eliminated, assembled into
//!   the KKT matrix `K(δ_w, δ_c)` of [`crate::ipm::kkt`] and factored by [`SparseLdlt`](crate::ipm::kkt::SparseLdlt);
//! * inertia correction (W&B Sect. 3.1, Algorithm IC): the step is accepted when `K` has n
//!   positive and m negative eigenvalues; otherwise δ_w grows (first `δ_w⁰`, then by κ̄_w⁺ or
//!   κ_w⁺, starting from κ_w⁻ δ_w_last), and a singular `K` gets `δ_c = δ̄_c μ^κ_c`; a static
//!   `δ_c` is always on the constraint block and removed again by iterative refinement; on a
//!   stalled barrier problem above the tolerance the correction starts from the proximal
//!   floor `δ_w = κ_p μ` (`Settings::proximal_weight`, decision record 0011);
//! * the checks of a rejected AMD factor ([`KktOrdering`]): the same matrix re-factored once
//!   per step with 2 × 2 (variable, constraint row) pivots tells an artefact of AMD's bare
//!   −δ_c pivots from a genuine need for δ_w; an artefact, or a factor with the right inertia
//!   that does not solve its own matrix after refinement (growth ∝ 1/δ_c), raises the static
//!   δ_c of the solve (up to `static_dual_regularization_max`) instead of δ_w, or, with
//!   `AmdThenPivotPairs`, moves the solve to the pairs' order;
//! * iterative refinement of each KKT solution against the unregularized matrix, judged by
//!   its residual relative to the right-hand side or, failing that, its normwise backward
//!   error ([`Core::solve_refined`]; decision records 0008 and 0009);
//! * recovery of `dz_L, dz_U` (W&B eq. (12));
//! * least-squares constraint multipliers for the initial point (W&B Sect. 3.6).

use std::time::Instant;

use super::{Core, Ctx, norm_inf};
use crate::ipm::kkt::{
    FactorizationFailure, Inertia, KktSolver, LdltOptions, LdltOrdering, SparseLdlt,
};
use crate::ipm::settings::{KktOrdering, Settings};

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
        let r = self.solver.factor(&self.kkt.mat.values);
        ctx.counters.factorizations += 1;
        ctx.timing.factorization += t.elapsed();
        r
    }

    /// Solves `K sol = rhs` with refinement against `K(δ_w, δ_c_target)`; returns the final
    /// residual `‖K sol − rhs‖_∞` relative to `‖rhs‖_∞`, or with
    /// `Settings::residual_ratio_with_solution` Ipopt's residual ratio ([`residual_ratio`]),
    /// on which the caller judges the solution's accuracy (accepted at [`ACCURATE_SOLVE`]);
    /// where that measure rejects the solution but its normwise backward error
    /// ([`backward_error`]) is at most `Settings::backward_error_tol`, that backward error
    /// instead. Refinement takes `Settings::min_refinement_steps` steps unless the residual
    /// relative to `‖rhs‖_∞` reaches `refinement_tol`, then continues (up to
    /// `max_refinement_steps`) only while the solution fails that accuracy test and each step
    /// reduces the relative residual by `refinement_contraction`; a step that does not is
    /// undone (decision record 0009).
    pub(super) fn solve_refined(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) -> f64 {
        let t = Instant::now();
        let nm = self.n + self.m;
        self.sol.copy_from_slice(&self.rhs);
        if self.solver.solve(&mut self.sol).is_err() {
            ctx.timing.solve += t.elapsed();
            return f64::INFINITY;
        }
        let bnorm = norm_inf(&self.rhs);
        let mut best = f64::INFINITY;
        let mut by_backward_error = false;
        // max|K_ij| of the factored matrix, the same for every refinement step: computed once,
        // and only when a solve needs the backward-error test.
        let mut kmax: Option<f64> = None;
        for target in [self.delta_c_target, self.delta_c] {
            let shift = self.delta_c - target;
            // (relative residual, accuracy measure, accepted on its backward error) before the
            // last correction.
            let mut previous: Option<(f64, f64, bool)> = None;
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
                let rnorm = norm_inf(&self.resid);
                let rel = rnorm / bnorm.max(1e-300);
                let rn = if settings.residual_ratio_with_solution {
                    residual_ratio(rnorm, bnorm, norm_inf(&self.sol))
                } else {
                    rel
                };
                // Only a solve that the test above rejects is judged again, so every solve it
                // accepts keeps its path bit for bit.
                by_backward_error = false;
                let rn = if rn > ACCURATE_SOLVE && settings.backward_error_tol > 0.0 {
                    let kmax = *kmax.get_or_insert_with(|| norm_inf(&self.kkt.mat.values));
                    let eta = backward_error(rnorm, bnorm, kmax, norm_inf(&self.sol));
                    by_backward_error = eta <= settings.backward_error_tol
                        && rel <= settings.backward_error_forcing;
                    if settings.print_level > 2 {
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
                    rel <= settings.refinement_contraction * prev_rel
                });
                if step > settings.min_refinement_steps
                    && !contracted
                    && let Some((_, prev_rn, prev_by_backward_error)) = previous
                {
                    // Beyond the minimum, a correction that did not reduce the residual by the
                    // contraction factor shows refinement converging too slowly to be worth
                    // more solves (LAPACK's xGERFS stops likewise): undo it, so the solution
                    // is the one the minimum steps produced or a better one.
                    self.sol.copy_from_slice(&self.sol_before);
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
                if rel <= settings.refinement_tol
                    || step == settings.max_refinement_steps
                    || (step >= settings.min_refinement_steps && rn <= ACCURATE_SOLVE)
                {
                    break;
                }
                previous = Some((rel, rn, by_backward_error));
                ctx.counters.refinement_steps += 1;
                self.corr.copy_from_slice(&self.resid);
                // The factor that solved `sol` above solves the correction too.
                let _ = self.solver.solve(&mut self.corr);
                if step >= settings.min_refinement_steps {
                    // This correction may be undone (above): keep the solution bit for bit.
                    self.sol_before.copy_from_slice(&self.sol);
                }
                for i in 0..nm {
                    self.sol[i] += self.corr[i];
                }
            }
            if best <= 1e-6 || shift == 0.0 {
                break;
            }
            if settings.print_level > 2 {
                println!(
                    "    KKT: refinement against δ_c = {target:.1e} stalls at {best:.2e}: step of the regularized system"
                );
            }
            // Refinement against the unregularized matrix did not converge (rank-deficient J):
            // accept the step of the regularized system instead.
            self.sol.copy_from_slice(&self.rhs);
            let _ = self.solver.solve(&mut self.sol);
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
            self.static_dc.max(settings.static_dual_regularization)
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
        // The proximal floor (`Settings::proximal_weight`); the inertia correction below
        // grows δ_w from it.
        if use_hessian && self.proximal > self.delta_w {
            self.kkt.shift_diagonal(self.proximal - self.delta_w, 0.0);
            self.delta_w = self.proximal;
        }
        ctx.timing.kkt_assembly += t.elapsed();
        let mut singular_handled = false;
        let mut pairs_checked = false;
        let mut inaccurate = false;
        let mut raised_c = false;
        loop {
            let inertia = self.factor_current(ctx);
            let good = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
            // No usable factor, or (below) one that cannot solve its own matrix.
            let mut singular = inertia.is_err();
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
                if res <= ACCURATE_SOLVE {
                    self.accept_perturbation(use_hessian);
                    return StepResult::Ok;
                }
                // Right inertia but refinement cannot reach the exact system: the matrix is
                // (numerically) singular and static pivoting hid it, or the unpivoted factor
                // is unstable.
                singular = true;
                inaccurate = true;
            }
            // A rejected AMD factor may be an artefact of its bare −δ_c pivots rather than a
            // genuine need for δ_w or δ_c: the same matrix with the pivot pairs decides, once
            // per step. `AmdThenPivotPairs` keeps the pairs' factor and order from then on,
            // `AmdCheckedByPivotPairs` takes it as evidence for a larger δ_c below.
            let mut artefact = false;
            if self.check_pairs && !pairs_checked {
                pairs_checked = true;
                let switch = settings.kkt_ordering == KktOrdering::AmdThenPivotPairs;
                if self.try_pivot_pairs(ctx, settings, switch) {
                    if switch {
                        self.accept_perturbation(use_hessian);
                        return StepResult::Ok;
                    }
                    artefact = true;
                }
            }
            // A factor with the right inertia that does not solve its own matrix to 1e-5 after
            // refinement has grown like 1/δ_c, and so have the bare pivots of an AMD factor
            // that the pairs showed to be spurious: a larger static δ_c for the rest of the
            // solve (refinement still targets the unregularized system) rather than a larger
            // δ_w, which would damp every later step.
            if (inaccurate || artefact) && self.m > 0 && !raised_c {
                let raised = (self.delta_c * settings.static_dual_regularization_growth)
                    .min(settings.static_dual_regularization_max);
                if raised > self.delta_c {
                    raised_c = true;
                    inaccurate = false;
                    ctx.counters.dual_regularization_raised_at = Some(ctx.iter);
                    if settings.print_level > 0 {
                        println!(
                            "KKT: {}: static δ_c {:.1e} → {raised:.1e} from iteration {}",
                            if artefact {
                                "AMD's factor rejected where the pivot pairs' is right"
                            } else {
                                "factor with the right inertia but inaccurate"
                            },
                            self.delta_c,
                            ctx.iter
                        );
                    }
                    let old_c = self.delta_c;
                    self.static_dc = self.static_dc.max(raised);
                    self.delta_c = raised;
                    self.delta_c_target = self.delta_c_target.min(raised);
                    let t = Instant::now();
                    self.kkt.shift_diagonal(0.0, raised - old_c);
                    ctx.timing.kkt_assembly += t.elapsed();
                    continue;
                }
                if settings.kkt_ordering == KktOrdering::AmdCheckedByPivotPairs {
                    // δ_c at its largest: the checks have nothing more to decide.
                    self.check_pairs = false;
                }
            }
            inaccurate = false;
            // Wrong inertia, singular, or inaccurate: perturb.
            if self.delta_w == 0.0 && use_hessian {
                self.skip_zero_trial = true;
            }
            let old_w = self.delta_w;
            let old_c = self.delta_c;
            if singular && !singular_handled && self.m > 0 {
                singular_handled = true;
                let dc = settings.jacobian_regularization_value
                    * self.mu.powf(settings.jacobian_regularization_exponent);
                self.delta_c = dc.max(self.static_dc);
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

    /// Bookkeeping of an accepted factorization with the current δ_w.
    fn accept_perturbation(&mut self, use_hessian: bool) {
        if self.delta_w == 0.0 && use_hessian {
            self.skip_zero_trial = false;
        }
        if self.delta_w > 0.0 {
            self.delta_w_last = self.delta_w;
        }
    }

    /// Re-factors the current matrix, which the AMD factor rejected, with AMD and 2 × 2 pivot
    /// pairs (analysed on first use) and solves with it; returns whether that factor has the
    /// right inertia and an accurate refined solution. If so and `switch`, its step stands
    /// and the solve keeps the pairs from now on; otherwise the AMD factor stays current. A
    /// pattern where AMD eliminates no constraint row bare has nothing to check.
    fn try_pivot_pairs(
        &mut self,
        ctx: &mut Ctx<'_, '_>,
        settings: &Settings,
        switch: bool,
    ) -> bool {
        if self.other_solver.is_none() {
            let t = Instant::now();
            let mut pairs = SparseLdlt::with_options(LdltOptions {
                ordering: LdltOrdering::AmdPivotPairs {
                    constraint_rows_from: self.n,
                },
                ..self.solver.options().clone()
            });
            let analysed = pairs
                .analyse(
                    self.n + self.m,
                    &self.kkt.mat.col_ptr,
                    &self.kkt.mat.row_idx,
                )
                .is_ok();
            ctx.timing.factorization += t.elapsed();
            if !analysed || !pairs.has_pivot_pairs() {
                self.check_pairs = false;
                return false;
            }
            self.other_solver = Some(pairs);
        }
        let Some(pairs) = self.other_solver.as_mut() else {
            return false;
        };
        std::mem::swap(&mut self.solver, pairs);
        let inertia = self.factor_current(ctx);
        let good = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
        let res = if good {
            self.solve_refined(ctx, settings)
        } else {
            f64::INFINITY
        };
        if settings.print_level > 2 {
            println!("    KKT with pivot pairs: inertia {inertia:?}, relative residual {res:.2e}");
        }
        let accepted = res <= ACCURATE_SOLVE;
        if accepted && switch {
            self.check_pairs = false;
            self.switched_to_pairs = true;
            ctx.counters.pivot_pairs_from = Some(ctx.iter);
            if settings.print_level > 0 {
                println!(
                    "KKT: AMD's factor rejected where the pivot pairs' is right: pivot pairs from iteration {}",
                    ctx.iter
                );
            }
            return true;
        }
        if let Some(pairs) = self.other_solver.as_mut() {
            std::mem::swap(&mut self.solver, pairs);
        }
        accepted
    }

    /// Fills `rhs` with the Newton right-hand side `−(∇φ + Jᵀy, c_rhs)`.
    pub(super) fn set_rhs(&mut self, c_rhs: Option<&[f64]>) {
        for j in 0..self.n {
            self.rhs[j] = -(self.grad_phi[j] + self.jty[j]);
        }
        let c = c_rhs.unwrap_or(&self.c);
        for i in 0..self.m {
            self.rhs[self.n + i] = -c[i];
        }
    }

    /// Unpacks `sol` into (dx, dy) and recovers (dz_L, dz_U) (W&B eq. (12)).
    pub(super) fn unpack_step(&mut self) {
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

    /// Least-squares constraint multipliers: `[I Jᵀ; J 0] [w; y] = −[∇f − z_L + z_U; 0]`.
    pub(super) fn least_squares_y(&mut self, ctx: &mut Ctx<'_, '_>, settings: &Settings) {
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
        let ok = matches!(inertia, Ok(i) if i.positive == self.n && i.negative == self.m);
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
