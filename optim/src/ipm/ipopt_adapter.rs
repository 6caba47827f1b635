//! Optional cross-check: solve the same [`Nlp`] with C++ Ipopt through the `ipopt` 0.6 crate
//! (feature `ipopt`, off by default; see `optim/README.md` for the Debian packages and the
//! pkg-config shim it needs). Same problem statement and sign conventions as the native solver
//! (`L = f + λᵀg`), so the two [`Solution`]s are directly comparable.

use std::time::Instant;

use ipopt::{
    BasicProblem, ConstrainedProblem, Index, IntermediateCallbackData, Ipopt, Number, SolveStatus,
};

use super::nlp::{BOUND_INF, Nlp};
use super::settings::Settings;
use super::solution::{Counters, Solution, Status, Timing};
use crate::error::{FactorizationError, OptimError};

/// Wraps `&dyn Nlp` as an Ipopt problem.
struct Adapter<'a> {
    nlp: &'a dyn Nlp,
    jac: Vec<(usize, usize)>,
    hess: Vec<(usize, usize)>,
    iterations: usize,
}

fn clip_inf(v: &mut [f64]) {
    for e in v {
        if *e >= BOUND_INF {
            *e = 2e19;
        } else if *e <= -BOUND_INF {
            *e = -2e19;
        }
    }
}

impl BasicProblem for Adapter<'_> {
    fn num_variables(&self) -> usize {
        self.nlp.num_variables()
    }
    fn bounds(&self, x_l: &mut [Number], x_u: &mut [Number]) -> bool {
        self.nlp.variable_bounds(x_l, x_u);
        clip_inf(x_l);
        clip_inf(x_u);
        true
    }
    fn initial_point(&self, x: &mut [Number]) -> bool {
        self.nlp.initial_point(x);
        true
    }
    fn objective(&self, x: &[Number], _new_x: bool, obj: &mut Number) -> bool {
        *obj = self.nlp.objective(x);
        obj.is_finite()
    }
    fn objective_grad(&self, x: &[Number], _new_x: bool, grad_f: &mut [Number]) -> bool {
        self.nlp.gradient(x, grad_f);
        grad_f.iter().all(|v| v.is_finite())
    }
}

impl ConstrainedProblem for Adapter<'_> {
    fn num_constraints(&self) -> usize {
        self.nlp.num_constraints()
    }
    fn num_constraint_jacobian_non_zeros(&self) -> usize {
        self.jac.len()
    }
    fn constraint(&self, x: &[Number], _new_x: bool, g: &mut [Number]) -> bool {
        self.nlp.constraints(x, g);
        g.iter().all(|v| v.is_finite())
    }
    fn constraint_bounds(&self, g_l: &mut [Number], g_u: &mut [Number]) -> bool {
        self.nlp.constraint_bounds(g_l, g_u);
        clip_inf(g_l);
        clip_inf(g_u);
        true
    }
    fn constraint_jacobian_indices(&self, rows: &mut [Index], cols: &mut [Index]) -> bool {
        for (k, &(r, c)) in self.jac.iter().enumerate() {
            rows[k] = r as Index;
            cols[k] = c as Index;
        }
        true
    }
    fn constraint_jacobian_values(&self, x: &[Number], _new_x: bool, vals: &mut [Number]) -> bool {
        self.nlp.jacobian_values(x, vals);
        vals.iter().all(|v| v.is_finite())
    }
    fn num_hessian_non_zeros(&self) -> usize {
        self.hess.len()
    }
    fn hessian_indices(&self, rows: &mut [Index], cols: &mut [Index]) -> bool {
        for (k, &(r, c)) in self.hess.iter().enumerate() {
            rows[k] = r as Index;
            cols[k] = c as Index;
        }
        true
    }
    fn hessian_values(
        &self,
        x: &[Number],
        _new_x: bool,
        obj_factor: Number,
        lambda: &[Number],
        vals: &mut [Number],
    ) -> bool {
        self.nlp.hessian_values(x, obj_factor, lambda, vals);
        vals.iter().all(|v| v.is_finite())
    }
}

fn count_iterations(p: &mut Adapter<'_>, data: IntermediateCallbackData) -> bool {
    p.iterations = data.iter_count.max(0) as usize;
    true
}

fn map_status(s: SolveStatus) -> Status {
    match s {
        SolveStatus::SolveSucceeded | SolveStatus::FeasiblePointFound => Status::Solved,
        SolveStatus::SolvedToAcceptableLevel => Status::Acceptable,
        SolveStatus::InfeasibleProblemDetected => Status::LocallyInfeasible,
        SolveStatus::SearchDirectionBecomesTooSmall => Status::SearchDirectionTooSmall,
        SolveStatus::DivergingIterates => Status::DivergingIterates,
        SolveStatus::UserRequestedStop => Status::UserStop,
        SolveStatus::MaximumIterationsExceeded => Status::MaxIterations,
        SolveStatus::MaximumCpuTimeExceeded => Status::MaxTime,
        SolveStatus::RestorationFailed => Status::RestorationFailed,
        _ => Status::ErrorInStepComputation,
    }
}

/// Solves `nlp` with Ipopt using the tolerances, limits and μ strategy of `settings`.
/// Timing fields other than `total` and the counters are not available from Ipopt (zero).
pub fn solve_with_ipopt(nlp: &dyn Nlp, settings: &Settings) -> Result<Solution, OptimError> {
    settings.validate()?;
    let t0 = Instant::now();
    let adapter = Adapter {
        nlp,
        jac: nlp.jacobian_structure(),
        hess: nlp.hessian_structure(),
        iterations: 0,
    };
    let mut solver =
        Ipopt::new(adapter).map_err(|e| FactorizationError::Ipopt(format!("{e:?}")))?;
    let print_level = if settings.output.print_level > 0 {
        5
    } else {
        0
    };
    let mu_strategy = match settings.barrier.mu_strategy {
        super::settings::MuStrategy::Monotone => "monotone",
        super::settings::MuStrategy::Adaptive => "adaptive",
    };
    solver.set_option("tol", settings.termination.tol);
    solver.set_option("acceptable_tol", settings.termination.acceptable_tol);
    solver.set_option(
        "max_iter",
        settings.termination.max_iter.min(i32::MAX as usize) as i32,
    );
    solver.set_option("mu_init", settings.barrier.mu_init);
    solver.set_option("mu_strategy", mu_strategy);
    solver.set_option("print_level", print_level);
    solver.set_intermediate_callback(Some(count_iterations));
    let res = solver.solve();
    let status = map_status(res.status);
    let sol = res.solver_data.solution;
    let iterations = res.solver_data.problem.iterations;
    let x = sol.primal_variables.to_vec();
    let lambda = sol.constraint_multipliers.to_vec();
    let z_l = sol.lower_bound_multipliers.to_vec();
    let z_u = sol.upper_bound_multipliers.to_vec();
    let objective = res.objective_value;
    let n = nlp.num_variables();
    let m = nlp.num_constraints();
    // Unscaled errors recomputed here so both solvers report the same quantities.
    let mut g = vec![0.0; m];
    nlp.constraints(&x, &mut g);
    let (mut gl, mut gu) = (vec![0.0; m], vec![0.0; m]);
    nlp.constraint_bounds(&mut gl, &mut gu);
    let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
    nlp.variable_bounds(&mut xl, &mut xu);
    let mut viol = 0.0f64;
    for i in 0..m {
        viol = viol.max(gl[i] - g[i]).max(g[i] - gu[i]);
    }
    for j in 0..n {
        viol = viol.max(xl[j] - x[j]).max(x[j] - xu[j]);
    }
    let mut rd = vec![0.0; n];
    nlp.gradient(&x, &mut rd);
    let jp = nlp.jacobian_structure();
    let mut jv = vec![0.0; jp.len()];
    nlp.jacobian_values(&x, &mut jv);
    for (k, &(r, c)) in jp.iter().enumerate() {
        rd[c] += jv[k] * lambda[r];
    }
    let dual = (0..n).fold(0.0f64, |a, j| a.max((rd[j] - z_l[j] + z_u[j]).abs()));
    let mut compl = 0.0f64;
    for j in 0..n {
        if xl[j] > -BOUND_INF {
            compl = compl.max(((x[j] - xl[j]) * z_l[j]).abs());
        }
        if xu[j] < BOUND_INF {
            compl = compl.max(((xu[j] - x[j]) * z_u[j]).abs());
        }
    }
    Ok(Solution {
        status,
        x,
        lambda,
        z_l,
        z_u,
        objective,
        iterations,
        constraint_violation: viol.max(0.0),
        dual_infeasibility: dual,
        complementarity: compl,
        mu: f64::NAN,
        timing: Timing {
            total: t0.elapsed(),
            ..Timing::default()
        },
        counters: Counters::default(),
    })
}
