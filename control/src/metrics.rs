//! Figures of a closed-loop run, period by period (`tracking.json`).
//!
//! A period runs from one impact (Free → Stick/Slip) to the next: the optimum's period holds
//! one contact phase, and its mean ω is the same over any window of one period, so ω̄_k over
//! [impact k, impact k + 1) compares with the optimum's ω̄*; the flight before the first
//! impact (a run that starts in contact: the first sample) is the lead-in, not a period. An
//! impact after a flight shorter than [`MIN_FLIGHT`] is a bounce of the contact it left, not
//! the start of a period ([`PeriodStarts`]): a finger that chatters on the ball (impact,
//! lift-off, impact again microseconds later) is one contact phase, and counting each bounce
//! as a period once ended a run of six planned periods of 2.6 s at 0.56 s, "6 of 6 periods"
//! (docs/decisions/0081-a-bounce-is-not-a-period.md). Per
//! period: the mean ω̄_k = (1/T_k) ∫ ω dt (trapezoidal rule over the samples, the counterpart
//! of the optimum's mean ω, eq. 61), its relative error ‖ω̄_k − ω̄*‖ / ‖ω̄*‖, whether it has a
//! contact phase (more than the impact's instant), the time spent in Stick and in Slip, and the largest
//! |τ_i| of its samples, less those of modes passed through at one instant (their τ acts for
//! no time). [`PeriodMetrics::contact_failure`] says whether a period executed the
//! plan's contact phase and its flight: some time on the ball, and a length below
//! [`MAX_PERIOD_RATIO`] times the plan's period (a longer one missed the ball) and above
//! [`MIN_PERIOD_RATIO`] times it (a shorter one cut its flight short).

use bf_model::Mode;
use serde::Serialize;

/// One period of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodMetrics {
    /// Start time (s).
    pub start: f64,
    /// End time (s).
    pub end: f64,
    /// Mean ω over the period (rad/s).
    pub mean_omega: [f64; 3],
    /// ‖ω̄_k − ω̄*‖ / ‖ω̄*‖.
    pub omega_error: f64,
    /// Whether the period has a contact phase: some time in Stick or Slip, or a contact after
    /// the impact's instant (the finger bouncing on the ball, flights shorter than
    /// [`MIN_FLIGHT`]). A period starts at an impact, so a touch alone (an impact that let go
    /// at once and flew on) is no contact phase of the plan.
    pub contact: bool,
    /// Time in Stick (s).
    pub stick_time: f64,
    /// Time in Slip (s).
    pub slip_time: f64,
    /// Largest |τ_i| over the period's samples that begin or end a stretch of time (N m): a
    /// sample between two at its own time (a mode passed through at one instant) is left out.
    pub max_abs_tau: f64,
}

/// The shortest flight between two contacts that makes the second one the start of a new
/// period (s). The periodic problems bound each free phase below by 0.01 s, so a plan's flight
/// (the release and the approach) lasts at least 0.02 s; a flight of less than half of that is
/// no flight of a plan but a bounce of the contact phase.
pub const MIN_FLIGHT: f64 = 0.01;

/// How much longer than the plan's period a run's period may last before it counts as a
/// missed contact ([`PeriodMetrics::contact_failure`]). A period runs from impact to impact,
/// so a finger that misses the ball once makes a period of about twice the plan's; a tracked
/// period stays within a few per cent of it, and a perturbed plant's within some ten.
pub const MAX_PERIOD_RATIO: f64 = 1.5;

/// How much shorter than the plan's period a run's period may be before it counts as a flight
/// cut short ([`PeriodMetrics::contact_failure`]): the hybrid controller's outer loop paces
/// only a flight's middle, at most three times the plan's speed (the controller's pace
/// limits), so no period it commands is as short as a third of the plan's; a shorter one is a
/// finger that struck the ball again early (a joint PD on the `periodic-qc` plan: 0.11 s
/// against 0.75 s). Paced periods do get short: 0.65 of the plan's on the human finger's
/// plan with socket damping ×1.5.
pub const MIN_PERIOD_RATIO: f64 = 1.0 / crate::controller::PACE_LIMITS.1;

impl PeriodMetrics {
    /// Why the period did not execute the plan's one contact phase and its flight, if it did
    /// not: the finger only touched the ball ([`contact`](Self::contact) false), the period
    /// lasted at least [`MAX_PERIOD_RATIO`] times the plan's `period` (s), so the finger missed
    /// the ball and found it again a period or more later, or at most [`MIN_PERIOD_RATIO`]
    /// times it, so the finger struck the ball again before its flight was done.
    pub fn contact_failure(&self, period: f64) -> Option<String> {
        let len = self.end - self.start;
        if !self.contact {
            Some(format!(
                "the finger only touched the ball at t = {:.4} s and flew on",
                self.start
            ))
        } else if len >= MAX_PERIOD_RATIO * period || len.is_nan() {
            Some(format!(
                "the period from t = {:.4} s lasted {len:.4} s, {:.2} times the plan's \
                 {period:.4} s: the finger missed the ball",
                self.start,
                len / period
            ))
        } else if len <= MIN_PERIOD_RATIO * period {
            Some(format!(
                "the period from t = {:.4} s lasted {len:.4} s, {:.2} times the plan's \
                 {period:.4} s: the finger struck the ball again before its flight was done",
                self.start,
                len / period
            ))
        } else {
            None
        }
    }
}

/// The period starts of a run, found sample by sample (module doc): the first sample if the run
/// starts in contact, and every impact (a contact sample after a free one) whose flight since
/// the last contact sample lasted at least [`MIN_FLIGHT`], or that ends the lead-in.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PeriodStarts {
    /// Whether the last sample seen was free; `None` before the first.
    last_free: Option<bool>,
    /// Time of the last contact sample seen.
    last_contact: Option<f64>,
}

impl PeriodStarts {
    /// Whether the next sample of the run, at time `t` in plant mode `mode`, starts a period.
    pub fn starts(&mut self, t: f64, mode: Mode) -> bool {
        let free = mode == Mode::Free;
        let start = !free
            && match self.last_free {
                None => true,
                Some(was_free) => was_free && self.last_contact.is_none_or(|c| t - c >= MIN_FLIGHT),
            };
        self.last_free = Some(free);
        if !free {
            self.last_contact = Some(t);
        }
        start
    }
}

/// The completed periods of a run sampled at `t` (non-decreasing) with plant modes `mode`, ball
/// angular velocities `omega` and torques `tau`, against the optimum's mean ω `optimum`
/// (module doc).
pub fn period_metrics(
    t: &[f64],
    mode: &[Mode],
    omega: &[[f64; 3]],
    tau: &[Vec<f64>],
    optimum: [f64; 3],
) -> Vec<PeriodMetrics> {
    let n = t.len().min(mode.len()).min(omega.len()).min(tau.len());
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let scale = norm(optimum);
    let mut starts = PeriodStarts::default();
    let boundaries: Vec<usize> = (0..n).filter(|&i| starts.starts(t[i], mode[i])).collect();
    let mut out = Vec::new();
    let Some((&start, rest)) = boundaries.split_first() else {
        return out;
    };
    let mut first = start;
    for &i in rest {
        let mut p = PeriodMetrics {
            start: t[first],
            end: t[i],
            mean_omega: [0.0; 3],
            omega_error: f64::NAN,
            contact: false,
            stick_time: 0.0,
            slip_time: 0.0,
            max_abs_tau: 0.0,
        };
        let mut integral = [0.0; 3];
        // Every contact sample of the period belongs to the contact phase that its impact
        // starts: a contact after a flight of MIN_FLIGHT would have started the next period.
        let mut last_contact = t[first];
        // Sample i, the next period's impact, is the next period's.
        for k in first..i {
            // A sample between two at its own time is a mode the plant passed through at one
            // instant (the slip of a chained stick → slip → free lift-off): its τ acts for no
            // time, so it is no torque the actuators delivered.
            let instant = k > 0 && t[k - 1] == t[k] && t[k + 1] == t[k];
            if !instant {
                p.max_abs_tau = tau[k].iter().fold(p.max_abs_tau, |m, v| m.max(v.abs()));
            }
            if mode[k] != Mode::Free {
                last_contact = t[k];
            }
            let dt = t[k + 1] - t[k];
            match mode[k] {
                Mode::Stick => p.stick_time += dt,
                Mode::Slip => p.slip_time += dt,
                Mode::Free => {}
            }
            for j in 0..3 {
                integral[j] += 0.5 * (omega[k][j] + omega[k + 1][j]) * dt;
            }
        }
        p.contact = p.stick_time + p.slip_time > 0.0 || last_contact > p.start;
        let len = p.end - p.start;
        if len > 0.0 {
            p.mean_omega = integral.map(|v| v / len);
            let diff = std::array::from_fn(|j| p.mean_omega[j] - optimum[j]);
            p.omega_error = norm(diff) / scale;
        }
        out.push(p);
        first = i;
    }
    out
}
