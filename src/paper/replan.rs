//! Re-planning at each lift-off (`track --replan`): bf-control's [`Replanner`] on the solve
//! pipeline. At the plant's lift-off in the measured state x_m the transient period of the
//! optimum's problem (bf-problem's `catalogue::replan`: release from x_m, approach, stick,
//! ending on the optimum's lift-off state x*_lo, the same ratio objective eq. 60) is solved,
//! warm-started from the plan in force, and becomes the controller's reference until the next
//! lift-off.
//!
//! * The NLP is transcribed once; each re-plan only moves the bounds of its fixed first state
//!   (`catalogue::replan::set_measured`), so a re-plan after a successful one starts from its
//!   primal-dual point exactly (the pipeline's warm start, μ₀ = 1e-4), and the first one from
//!   the optimum rotated to start at the lift-off (primal point only).
//! * A re-plan that does not converge within [`REPLAN_MAX_ITER`] iterations is not used: the
//!   controller then tracks the optimum from its lift-off (rotated the same way), and the
//!   next re-plan starts from it again.
//! * Determinism: the plant waits for the plan in simulated time (bf-control's controller
//!   calls the replanner at the lift-off event and tracks the result from that instant), and
//!   the iteration limit, not a time limit, ends a re-plan, so a run is the same on any
//!   machine; the wall time of every re-plan is recorded ([`ReplanRecord`]) against the
//!   budget of a tenth of the period.

use crate::pipeline::solve::{INTERPOLATED_MU_INIT_MAX, settings_of, solve, solve_recentred};
use anyhow::{Context, Result};
use bf_control::{Reference, Replanner};
use bf_model::{DynKernels, Model};
use bf_problem::catalogue::replan::{LiftOff, lift_off_state, rotate_to_lift_off, set_measured};
use bf_problem::{BuiltProblem, OcpSolution, warm_initial_point};
use serde::Serialize;
use std::cell::RefCell;
use std::rc::Rc;
use std::time::Instant;

/// Iteration limit of one re-plan (the optimum's own solves converge from a warm start in
/// far fewer; a re-plan that needs more is not converging and would overrun its budget).
pub const REPLAN_MAX_ITER: usize = 200;

/// One re-plan of a run, as `tracking.json` records it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplanRecord {
    /// Plant time of the lift-off (s).
    pub t: f64,
    /// Wall time of the re-plan (s): moving the measured state, the warm start, the solve and
    /// the reference.
    pub seconds: f64,
    /// Interior-point iterations.
    pub iterations: usize,
    /// The solver's status.
    pub status: String,
    /// Whether the plan was used (converged); otherwise the optimum was tracked.
    pub used: bool,
    /// The plan's objective (the ratio eq. 60 over its transient period).
    pub objective: f64,
    /// Largest distance of the measured lift-off state from the optimum's, max |x_m − x*_lo|.
    pub deviation: f64,
}

/// The re-plans of a run: the one solve made when the replanner is set up (from the
/// optimum's own lift-off state, [`SolverReplanner::new`]) and one per lift-off.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ReplanLog {
    /// The set-up solve (`t` = 0, deviation 0), if the replanner was made.
    pub setup: Option<ReplanRecord>,
    /// One per lift-off, in time order.
    pub replans: Vec<ReplanRecord>,
}

/// How a solution becomes the controller's reference on its model (the closed loop's
/// `reference_of`, handed in so that this module does not import the one that uses it).
pub type ReferenceOf<const N: usize = 3> =
    fn(&OcpSolution, &Model<DynKernels<N>, N>) -> Result<Reference<N>>;

/// The solve pipeline as bf-control's [`Replanner`] (module doc) for a finger with `N` joints.
#[derive(Debug)]
pub struct SolverReplanner<const N: usize = 3> {
    problem: BuiltProblem,
    model: Model<DynKernels<N>, N>,
    reference_of: ReferenceOf<N>,
    /// x*_lo.
    target: Vec<f64>,
    /// The optimum as a solution of the re-plan from its own lift-off state (the rotated
    /// optimum if that solve failed): the warm start after a failed re-plan.
    nominal: OcpSolution,
    /// The rotated optimum as a reference: the plan when a re-plan fails.
    nominal_reference: Reference<N>,
    /// The plan in force, the warm start of the next re-plan.
    current: OcpSolution,
    log: Rc<RefCell<ReplanLog>>,
}

/// The re-plan problem of the periodic optimum `sol` (a solution that records its problem and
/// scene), transcribed once from the optimum's own lift-off state x*_lo with the iteration
/// limit `max_iter` ([`REPLAN_MAX_ITER`] by default), with `sol` rotated to start there (its
/// warm start) and x*_lo itself.
pub fn replan_problem(
    sol: &OcpSolution,
    max_iter: usize,
) -> Result<(BuiltProblem, OcpSolution, Vec<f64>)> {
    let (problem, mut settings) =
        settings_of(sol).context("re-planning needs the solution's problem and scene")?;
    let target = lift_off_state(sol)?;
    let rotated = rotate_to_lift_off(sol)?;
    // A refined optimum's mesh, phase by phase in the transient's order.
    settings.mesh = sol.refinement.as_ref().map(|r| {
        [2, 0, 1]
            .iter()
            .filter_map(|&p| r.mesh.get(p).cloned())
            .collect()
    });
    settings.max_iter = max_iter;
    settings.replan = Some(LiftOff {
        measured: target.clone(),
        target: target.clone(),
    });
    settings.warm_start = Some(rotated.clone());
    let problem = crate::pipeline::build(problem, &settings)?;
    Ok((problem, rotated, target))
}

/// Solves the re-plan `p` ([`replan_problem`]) from the measured lift-off state `x`,
/// warm-started from `warm`. When `warm` is a previous solution of `p` (its primal-dual point
/// fits `p`'s NLP), exactly from that point, re-centred at the barrier parameter
/// μ₀ = clamp(v, tol / 10, 10⁻⁴) with v its largest constraint violation in `p` (the measured
/// state moved): the pipeline's warm start takes μ₀ = 10⁻⁴ whatever the start's distance,
/// which cost the human finger's COT re-plan from its own optimum 47 iterations where the
/// start is optimal. Otherwise from `warm`'s primal point (the pipeline's [`solve`], which
/// takes μ₀ from the violation in the same way).
pub fn solve_replan(p: &mut BuiltProblem, warm: &OcpSolution, x: &[f64]) -> Result<OcpSolution> {
    set_measured(p, x)?;
    warm_initial_point(p, warm)?;
    p.settings.warm_start = Some(warm.clone());
    let n = bf_optim::ipm::Nlp::num_variables(&p.nlp);
    let m = bf_optim::ipm::Nlp::num_constraints(&p.nlp);
    let exact = warm.nlp_warm.as_ref().filter(|w| {
        warm.nlp_size == (n, m) && w.x.len() == n && w.lambda.len() == m && w.z_l.len() == n
    });
    match exact {
        Some(w) => {
            let tol = crate::pipeline::solver_settings(&p.settings)
                .termination
                .tol;
            let (violation, _) = p.nlp.max_violation(&w.x);
            let mu = if violation.is_finite() {
                violation.clamp(0.1 * tol, INTERPOLATED_MU_INIT_MAX)
            } else {
                INTERPOLATED_MU_INIT_MAX
            };
            Ok(solve_recentred(p, w, mu)?)
        }
        None => Ok(solve(p, None)?),
    }
}

impl<const N: usize> SolverReplanner<N> {
    /// The replanner of the optimum `sol` ([`replan_problem`], `max_iter` iterations per
    /// re-plan) with the controller's model `model`, whose references `reference_of` makes;
    /// the set-up solve and every re-plan are recorded in `log`. Transcribes the
    /// re-plan problem once and solves it once from the optimum's own lift-off state (where it
    /// is the optimum, rotated), so that every re-plan starts from a primal-dual point of its
    /// own NLP; if that solve fails, the first re-plan starts from the rotated optimum's primal
    /// point.
    pub fn new(
        sol: &OcpSolution,
        model: Model<DynKernels<N>, N>,
        reference_of: ReferenceOf<N>,
        max_iter: usize,
        log: Rc<RefCell<ReplanLog>>,
    ) -> Result<Self> {
        let start = Instant::now();
        let (mut problem, nominal, target) = replan_problem(sol, max_iter)?;
        let nominal_reference = reference_of(&nominal, &model)?;
        let own = solve_replan(&mut problem, &nominal, &target);
        let (iterations, status, objective) = match &own {
            Ok(s) => (s.iterations, format!("{:?}", s.status), s.objective),
            Err(e) => (0, crate::errors::render(e), f64::NAN),
        };
        let used = own.as_ref().is_ok_and(|s| s.status.is_success());
        let nominal = match own {
            Ok(own) if used => own,
            _ => nominal,
        };
        log.borrow_mut().setup = Some(ReplanRecord {
            t: 0.0,
            seconds: start.elapsed().as_secs_f64(),
            iterations,
            status,
            used,
            objective,
            deviation: 0.0,
        });
        Ok(SolverReplanner {
            problem,
            model,
            reference_of,
            target,
            current: nominal.clone(),
            nominal,
            nominal_reference,
            log,
        })
    }
}

impl<const N: usize> Replanner<N> for SolverReplanner<N> {
    fn replan(&mut self, t: f64, x: &[f64]) -> Option<Reference<N>> {
        let start = Instant::now();
        let deviation = x
            .iter()
            .zip(&self.target)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let solved = solve_replan(&mut self.problem, &self.current, x);
        let (plan, record) = match solved {
            Ok(sol) if sol.status.is_success() => match (self.reference_of)(&sol, &self.model) {
                Ok(r) => {
                    let rec = (
                        sol.iterations,
                        format!("{:?}", sol.status),
                        true,
                        sol.objective,
                    );
                    self.current = sol;
                    (r, rec)
                }
                Err(e) => {
                    self.current = self.nominal.clone();
                    let why = format!("{:?} (no reference: {e})", sol.status);
                    (
                        self.nominal_reference.clone(),
                        (sol.iterations, why, false, sol.objective),
                    )
                }
            },
            Ok(sol) => {
                self.current = self.nominal.clone();
                let status = format!("{:?}", sol.status);
                (
                    self.nominal_reference.clone(),
                    (sol.iterations, status, false, sol.objective),
                )
            }
            Err(e) => {
                self.current = self.nominal.clone();
                (
                    self.nominal_reference.clone(),
                    (0, crate::errors::render(&e), false, f64::NAN),
                )
            }
        };
        let (iterations, status, used, objective) = record;
        self.log.borrow_mut().replans.push(ReplanRecord {
            t,
            seconds: start.elapsed().as_secs_f64(),
            iterations,
            status,
            used,
            objective,
            deviation,
        });
        Some(plan)
    }
}
