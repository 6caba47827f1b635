//! Re-planning a periodic optimum from a measured lift-off state (paper Sect. 7: feedback on
//! the plan itself; issue "closed loop": re-solve at each lift-off, warm-started from the
//! current plan).
//!
//! The periodic problems (Sect. 6.1) start their period at the apex of the free arc and close
//! it by periodicity, x⁽³⁾(T₃) = x⁽¹⁾(0). A plant that lifts off the ball in a state x_m other
//! than the optimum's x*_lo cannot be put on that problem: its period passes through x_m only
//! if a periodic orbit does. [`LiftOff`] turns a periodic problem into its **transient
//! period** (`archetypes::periodic_from_lift_off`): release (free, from
//! x⁽¹⁾(0) = x_m), approach (free, from the apex ḣ = 0 to the impact), stick (ending at
//! x⁽³⁾(T₃) = x*_lo), under the periodic problem's objective (the QC or COT ratio eq. 60 over
//! the three phases) and constraints. It ends on the periodic orbit, so the plan after it is
//! the optimum again, and from x_m = x*_lo its feasible set is the periodic problem's with the
//! lift-off state fixed, which holds the optimum: the re-plan is the optimum with its phases
//! rotated ([`rotate_to_lift_off`]), on the same mesh per phase.
//!
//! [`lift_off_state`] reads x*_lo from a periodic solution; [`rotate_to_lift_off`] gives the
//! solution in the transient's phase order, the warm start of a first re-plan.

use super::BuiltProblem;
use crate::ProblemError;
use crate::node::PhaseMode;
use crate::solution::{OcpSolution, Samples};

/// The name of the point function that fixes the transient's first state.
pub const MEASURED_ROWS: &str = "measured lift-off state";

/// The lift-off states of a re-plan ([`super::ProblemSettings::replan`]): the transient
/// period starts at `measured` and ends at `target` (both (q, q̇, ω), `2 nq + 3` values).
#[derive(Debug, Clone, PartialEq)]
pub struct LiftOff {
    /// x_m, the measured state at the plant's lift-off.
    pub measured: Vec<f64>,
    /// x*_lo, the periodic optimum's lift-off state (the start of its release phase).
    pub target: Vec<f64>,
}

impl LiftOff {
    /// Checks the lengths (`nx`) and that every value is finite; the error names the state,
    /// the component and the value.
    pub fn validate(&self, nx: usize) -> Result<(), ProblemError> {
        for (what, x) in [
            ("measured lift-off state", &self.measured),
            ("target lift-off state", &self.target),
        ] {
            if x.len() != nx {
                return Err(ProblemError::Replan {
                    msg: format!(
                        "the {what} has {} values, expected {nx} (q, qd, omega)",
                        x.len()
                    ),
                });
            }
            if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(ProblemError::Replan {
                    msg: format!("component {i} of the {what} is {v}, expected a finite value"),
                });
            }
        }
        Ok(())
    }
}

/// Checks that `sol` is a periodic solution in the catalogue's order (free, stick, free) with
/// its phase trajectories.
fn check_periodic(sol: &OcpSolution) -> Result<(), ProblemError> {
    let order = [PhaseMode::Free, PhaseMode::Stick, PhaseMode::Free];
    if sol.modes != order || sol.raw.len() != 3 || sol.phase_durations.len() != 3 {
        return Err(ProblemError::Replan {
            msg: format!(
                "solution of `{}` has phases {:?} ({} trajectories), expected a periodic \
                 solution free, stick, free",
                sol.problem,
                sol.modes,
                sol.raw.len()
            ),
        });
    }
    Ok(())
}

/// x*_lo: the first state of the periodic solution's release phase (its third), the state
/// the optimum lifts off the ball in.
pub fn lift_off_state(sol: &OcpSolution) -> Result<Vec<f64>, ProblemError> {
    check_periodic(sol)?;
    let release = &sol.raw[2];
    // Radau's first state point is the phase's start (τ = −1); any other mesh interpolates.
    if release.state_tau.first() == Some(&-1.0)
        && let Some(x) = release.x.first()
    {
        return Ok(x.clone());
    }
    Ok(release.x_at(-1.0))
}

/// The periodic solution with its phases in the transient's order (release, approach,
/// stick), times from the lift-off: trajectories, durations, modes and samples. Objective,
/// cost states, impulse and period are the same (one period's worth, rotated); the NLP point
/// is dropped (it belongs to the periodic problem's layout).
pub fn rotate_to_lift_off(sol: &OcpSolution) -> Result<OcpSolution, ProblemError> {
    check_periodic(sol)?;
    let order = [2, 0, 1];
    let mut out = sol.clone();
    out.modes = order.iter().map(|&p| sol.modes[p]).collect();
    out.phase_durations = order.iter().map(|&p| sol.phase_durations[p]).collect();
    let mut t0 = 0.0;
    out.raw = order
        .iter()
        .map(|&p| {
            let mut r = sol.raw[p].clone();
            r.t0 = t0;
            t0 += r.duration;
            r
        })
        .collect();
    out.nodes = rotate_samples(&sol.nodes, &order, &sol.phase_durations);
    out.dense = rotate_samples(&sol.dense, &order, &sol.phase_durations);
    out.nlp_warm = None;
    Ok(out)
}

/// `s` with its phases in `order` (new phase k = old phase `order[k]`), times shifted so the
/// first new phase starts at 0.
fn rotate_samples(s: &Samples, order: &[usize], durations: &[f64]) -> Samples {
    let old_start: Vec<f64> = durations
        .iter()
        .scan(0.0, |acc, d| {
            let t = *acc;
            *acc += d;
            Some(t)
        })
        .collect();
    let mut out = Samples::default();
    let mut new_start = 0.0;
    for (k, &p) in order.iter().enumerate() {
        for i in (0..s.t.len()).filter(|&i| s.phase[i] == p) {
            out.t.push(s.t[i] - old_start[p] + new_start);
            out.phase.push(k);
            out.q.push(s.q[i].clone());
            out.qd.push(s.qd[i].clone());
            out.omega.push(s.omega[i].clone());
            out.tau.push(s.tau[i].clone());
            out.lambda.push(s.lambda[i].clone());
            out.h.push(s.h[i]);
            out.sigma.push(s.sigma[i]);
            out.alpha.push(s.alpha[i]);
        }
        new_start += durations[p];
    }
    out
}

/// Moves the re-plan `p` (built with [`super::ProblemSettings::replan`]) to start from the
/// measured state `x` instead: the bounds of its fixed first state and its settings, without
/// transcribing it again (its NLP layout stays, so a previous re-plan's primal-dual point
/// warm-starts it exactly). Errors when `p` is not a re-plan or `x` is not a finite state of
/// its length.
pub fn set_measured(p: &mut BuiltProblem, x: &[f64]) -> Result<(), ProblemError> {
    let nx = 2 * p.physics.nq + 3;
    let Some(r) = p.settings.replan.as_mut() else {
        return Err(ProblemError::Replan {
            msg: format!("`{}` was not built as a re-plan", p.name),
        });
    };
    let next = LiftOff {
        measured: x.to_vec(),
        target: r.target.clone(),
    };
    next.validate(nx)?;
    let bounds: Vec<(f64, f64)> = x.iter().map(|&v| (v, v)).collect();
    p.nlp.set_block_bounds(MEASURED_ROWS, &bounds)?;
    *r = next;
    Ok(())
}
