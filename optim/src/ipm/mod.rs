//! Sparse primal-dual interior-point NLP solver — an Ipopt replacement (Wächter & Biegler,
//! "On the implementation of an interior-point filter line-search algorithm for large-scale
//! nonlinear programming", Math. Program. 106, 2006; cited as W&B).
//!
//! It solves the collocation NLPs of the paper's trajectory optimisation (Sect. 4) and any
//! [`Nlp`]:
//!
//! ```text
//! min f(x)  s.t.  g_L ≤ g(x) ≤ g_U,  x_L ≤ x ≤ x_U
//! ```
//!
//! Symbols (W&B notation): `c(x) = 0` the internal equality constraints (inequalities get
//! slacks), `y` = λ their multipliers, `z_L, z_U` bound multipliers, μ the barrier parameter,
//! `θ = ‖c‖₁` infeasibility, `φ_μ` barrier objective, δ_w/δ_c the inertia-correction shifts of the
//! KKT matrix (eq. (13)), τ the fraction-to-boundary parameter (eq. (15)), `E_μ` the scaled
//! optimality error (eq. (5)).
//!
//! Modules: [`nlp`] (problem trait, derivative checker), [`settings`], [`solution`],
//! [`kkt`] (KKT assembly and its sparse LDLᵀ [`KktSolver`]), `stdform` (user problem → standard
//! form), `core` (the algorithm), `restoration` (feasibility restoration problem), and with the
//! `ipopt` feature `ipopt_adapter`.
//!
//! ```no_run
//! use bf_optim::ipm::{solve, Settings};
//! # fn demo(problem: &dyn bf_optim::ipm::Nlp) -> Result<(), bf_optim::OptimError> {
//! let sol = solve(problem, &Settings::default())?;
//! println!("{:?} f = {} after {} iterations", sol.status, sol.objective, sol.iterations);
//! # Ok(()) }
//! ```

mod core;
pub mod kkt;
pub mod nlp;
mod restoration;
pub mod settings;
pub mod solution;
mod stdform;

#[cfg(feature = "ipopt")]
pub mod ipopt_adapter;

use std::time::Instant;

pub use kkt::{
    FactorizationFailure, Inertia, KktSolver, LdltBackend, LdltOptions, LdltOrdering, SparseLdlt,
};
pub use nlp::{BOUND_INF, DerivativeReport, Nlp, NlpScaling, check_derivatives};
pub use settings::{
    BarrierSettings, ExperimentalSettings, ExtrapolationScope, KktOrdering, LineSearchSettings,
    LinearSolverSettings, MuStrategy, OutputSettings, RecoverySettings, ScalingMethod,
    ScalingSettings, Settings, TerminationSettings,
};
pub use solution::{Counters, IterationInfo, Solution, Status, Timing, WarmStart};

use self::core::{Core, CoreStart, Ctx, KeptSolvers};
use crate::error::OptimError;
use stdform::{Reformulated, StdProblem};

/// Solves `nlp` from its initial point with `settings`.
///
/// Non-convergence is not an error: it is the [`Status`] of the returned [`Solution`].
///
/// # Errors
///
/// [`solve`], [`solve_with`] and [`solve_in`] return
/// * [`OptimError::InvalidSetting`]: a setting out of its range ([`Settings::validate`]);
/// * [`OptimError::DimensionMismatch`]: a warm-start vector or the user constraint scaling
///   ([`Nlp::scaling`]) of the wrong length;
/// * [`OptimError::InvalidValue`]: a non-finite warm-start entry, or a user scaling factor
///   that is not positive and finite;
/// * [`OptimError::InvalidBounds`]: variable or constraint bounds that are NaN, crossed, or a
///   lower bound ≥ [`BOUND_INF`] or an upper bound ≤ −[`BOUND_INF`];
/// * [`OptimError::InvalidPattern`]: a Jacobian or Hessian triplet out of range, or a Hessian
///   triplet above the diagonal;
/// * [`OptimError::NonFinite`]: a function or derivative value that no step cut can avoid
///   (the cases are listed at [`Nlp`]);
/// * [`OptimError::Factorization`]: the symbolic analysis of the KKT matrix failed (index
///   overflow, a matrix too large, out of memory).
pub fn solve(nlp: &dyn Nlp, settings: &Settings) -> Result<Solution, OptimError> {
    solve_with(nlp, settings, None, None)
}

/// State kept between solves: the KKT solver with its symbolic analyses (AMD ordering,
/// elimination tree, supernodes, workspaces; the current pattern's and those of the last
/// [`kkt::KEPT_ANALYSES`] others), the solvers with 2 × 2 pivot pairs that checked rejected
/// AMD factors, and the same again for the feasibility restoration phases. Pass the same
/// `Workspace` to [`solve_in`] for repeated solves (parameter sweeps, mesh-fixed re-solves,
/// warm starts, a search that alternates between meshes); a pattern not seen before is
/// analysed automatically (decision records 0062 and 0072).
#[derive(Debug, Default)]
pub struct Workspace {
    /// The KKT solver, the solvers with 2 × 2 pivot pairs that checked rejected AMD factors
    /// (one per `LdltOptions`, most recent last) and those of the restoration phases.
    solvers: KeptSolvers,
}

impl Workspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// Symbolic analyses computed by the solvers this workspace holds, over the solves it
    /// served: a pattern analysed before and kept (the restoration problem's included) is not
    /// counted again, so a repeated solve that adds nothing here analysed nothing.
    pub fn analyses(&self) -> usize {
        self.solvers.analyses()
    }
}

thread_local! {
    /// The workspace of this thread's last [`solve_with`]: the starts of a multi-start, the
    /// re-solves of a parameter sweep or of a fixed mesh share one NLP structure, so the
    /// symbolic analysis of its KKT pattern is made once per thread instead of once per solve.
    /// A reused analysis is the one a fresh solver would make (same pattern, same options), so
    /// results do not depend on what the thread solved before.
    static LAST_WORKSPACE: std::cell::RefCell<Workspace> = std::cell::RefCell::new(Workspace::new());
}

/// Solves `nlp`, optionally from a primal-dual warm start (its multipliers in the convention of
/// [`Solution`]; from the solution of the same problem, consider a small `mu_init` with small
/// bound pushes, e.g. `mu_init` and `warm_start_bound_push` 1e-9, `warm_start_mult_bound_push`
/// 1e-12, with which the tests' warm starts converge in at most three iterations) and
/// with a per-iteration callback (return `false` to stop with [`Status::UserStop`]). The KKT
/// solver of the thread's previous solve is reused, and with it its symbolic analysis when the
/// pattern is the same (a [`Workspace`] kept per thread; [`solve_in`] takes one explicitly).
/// Errors: as [`solve`].
pub fn solve_with(
    nlp: &dyn Nlp,
    settings: &Settings,
    warm: Option<&WarmStart>,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<Solution, OptimError> {
    // Taken out for the solve, so that a solve started from the callback finds an empty one.
    let mut workspace = LAST_WORKSPACE.with(|w| w.take());
    let result = solve_in(&mut workspace, nlp, settings, warm, callback);
    LAST_WORKSPACE.with(|w| w.replace(workspace));
    result
}

/// [`solve_with`] reusing (and updating) `workspace` so that repeated solves of the same
/// structure skip the symbolic analysis of the KKT matrix. Errors: as [`solve`].
pub fn solve_in(
    workspace: &mut Workspace,
    nlp: &dyn Nlp,
    settings: &Settings,
    warm: Option<&WarmStart>,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<Solution, OptimError> {
    settings.validate()?;
    let t_start = Instant::now();
    let n = nlp.num_variables();
    let m = nlp.num_constraints();
    let x0_user = match warm {
        Some(w) => {
            for (what, len, exp) in [
                ("warm-start x", w.x.len(), n),
                ("warm-start lambda", w.lambda.len(), m),
                ("warm-start z_l", w.z_l.len(), n),
                ("warm-start z_u", w.z_u.len(), n),
            ] {
                if len != exp {
                    return Err(OptimError::DimensionMismatch {
                        what,
                        expected: exp,
                        found: len,
                    });
                }
            }
            // A non-finite λ would reach the iterate, and every optimality measure, unchecked;
            // a non-finite x or z would be silently replaced (pushed into the bounds, raised
            // to the multiplier floor): either way not the start the caller meant.
            for (what, v) in [
                ("warm-start x", &w.x),
                ("warm-start lambda", &w.lambda),
                ("warm-start z_l", &w.z_l),
                ("warm-start z_u", &w.z_u),
            ] {
                if let Some(index) = v.iter().position(|x| !x.is_finite()) {
                    return Err(OptimError::InvalidValue {
                        what,
                        index,
                        value: v[index],
                        expected: "finite",
                    });
                }
            }
            w.x.clone()
        }
        None => {
            let mut x = vec![0.0; n];
            nlp.initial_point(&mut x);
            x
        }
    };
    let mut reform = Reformulated::new(nlp, settings, &x0_user)?;
    // Evaluate slacks at the initial point clamped into the bounds so that fixed variables and
    // bound-violating starts do not produce NaN in the slack initialisation.
    let x0c: Vec<f64> = (0..n)
        .map(|j| {
            let v = x0_user[j].clamp(reform.x_l_user[j], reform.x_u_user[j]);
            if v.is_nan() { x0_user[j] } else { v }
        })
        .collect();
    let x_int = reform.internal_point(&x0c);
    let os = reform.obj_scale;
    let nint = reform.n();
    let start = match warm {
        None => CoreStart {
            x: x_int,
            y: None,
            z_l: None,
            z_u: None,
            mu: settings.barrier.mu_init,
            bound_push: settings.barrier.bound_push,
            bound_frac: settings.barrier.bound_frac,
            mult_floor: 0.0,
            relax_bounds: true,
            restoration: false,
            solvers: std::cell::Cell::new(std::mem::take(&mut workspace.solvers)),
        },
        Some(w) => {
            let mut y = vec![0.0; m];
            let mut zl = vec![0.0; nint];
            let mut zu = vec![0.0; nint];
            for i in 0..m {
                y[i] = w.lambda[i] * os / reform.con_scale[i];
                let s = reform.slack[i];
                if s != usize::MAX {
                    if y[i] < 0.0 {
                        zl[s] = -y[i];
                    } else {
                        zu[s] = y[i];
                    }
                }
            }
            for (k, &j) in reform.free.iter().enumerate() {
                zl[k] = w.z_l[j] * os;
                zu[k] = w.z_u[j] * os;
            }
            CoreStart {
                x: x_int,
                y: Some(y),
                z_l: Some(zl),
                z_u: Some(zu),
                mu: settings.barrier.mu_init,
                bound_push: settings.barrier.warm_start_bound_push,
                bound_frac: settings.barrier.warm_start_bound_push,
                mult_floor: settings.barrier.warm_start_mult_bound_push,
                relax_bounds: true,
                restoration: false,
                solvers: std::cell::Cell::new(std::mem::take(&mut workspace.solvers)),
            }
        }
    };
    let mut ctx = Ctx {
        settings,
        timing: Timing::default(),
        counters: Counters::default(),
        iter: 0,
        start: t_start,
        callback,
    };
    let out = {
        let mut core = Core::new(&mut reform, settings, &start)?;
        let out = core.run(&mut ctx, &start);
        workspace.solvers = core.into_kkt_solvers();
        out?
    };
    // Map back to user space.
    let mut x = reform.to_user(&out.x);
    for j in 0..n {
        x[j] = x[j].clamp(reform.x_l_user[j], reform.x_u_user[j]);
    }
    let lambda: Vec<f64> = (0..m)
        .map(|i| out.y[i] * reform.con_scale[i] / os)
        .collect();
    let mut z_l = vec![0.0; n];
    let mut z_u = vec![0.0; n];
    for (k, &j) in reform.free.iter().enumerate() {
        z_l[j] = out.z_l[k] / os;
        z_u[j] = out.z_u[k] / os;
    }
    let t_eval = Instant::now();
    let objective = nlp.objective(&x);
    let mut g = vec![0.0; m];
    nlp.constraints(&x, &mut g);
    let mut grad = vec![0.0; n];
    nlp.gradient(&x, &mut grad);
    let jp = reform.user_jac_pattern().to_vec();
    let mut jv = vec![0.0; jp.len()];
    nlp.jacobian_values(&x, &mut jv);
    ctx.timing.function_evals += t_eval.elapsed();
    let mut rd = grad;
    for (k, &(r, c)) in jp.iter().enumerate() {
        rd[c] += jv[k] * lambda[r];
    }
    // Fixed variables: their multipliers are the reduced gradient.
    for j in 0..n {
        if reform.inv[j] == usize::MAX {
            if rd[j] >= 0.0 {
                z_l[j] = rd[j];
            } else {
                z_u[j] = -rd[j];
            }
        }
    }
    // `f64::max` would drop a NaN row; a g(x) that is not finite has no violation to report.
    let viol = if g.iter().all(|v| v.is_finite()) {
        let mut viol = 0.0f64;
        for i in 0..m {
            viol = viol.max(reform.g_l[i] - g[i]).max(g[i] - reform.g_u[i]);
        }
        viol.max(0.0)
    } else {
        f64::NAN
    };
    // As the termination test measures them at the final iterate, in user units.
    let (dual_inf, compl) = (out.dual_infeasibility, out.complementarity);
    ctx.timing.total = t_start.elapsed();
    if settings.output.print_level > 0 {
        println!(
            "status {:?}: f = {:.10e}, iterations {}, constraint violation {:.2e}, dual infeasibility {:.2e}",
            out.status, objective, ctx.iter, viol, dual_inf
        );
    }
    Ok(Solution {
        status: out.status,
        x,
        lambda,
        z_l,
        z_u,
        objective,
        iterations: ctx.iter,
        constraint_violation: viol,
        dual_infeasibility: dual_inf,
        complementarity: compl,
        mu: out.mu,
        timing: ctx.timing,
        counters: ctx.counters,
    })
}
