//! Figures of a closed-loop run, period by period (`tracking.json`).
//!
//! A period runs from one impact (Free → Stick/Slip) to the next: the optimum's period holds
//! one contact phase, and its mean ω is the same over any window of one period, so ω̄_k over
//! [impact k, impact k + 1) compares with the optimum's ω̄*; the flight before the first
//! impact (a run that starts in contact: the first sample) is the lead-in, not a period. Per
//! period: the mean ω̄_k = (1/T_k) ∫ ω dt (trapezoidal rule over the samples, the counterpart
//! of the optimum's mean ω, eq. 61), its relative error ‖ω̄_k − ω̄*‖ / ‖ω̄*‖, whether the finger
//! touched the ball, the time spent in Stick and in Slip, and the largest |τ_i| of its samples.

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
    /// Whether the finger was in contact at some sample of the period.
    pub contact: bool,
    /// Time in Stick (s).
    pub stick_time: f64,
    /// Time in Slip (s).
    pub slip_time: f64,
    /// Largest |τ_i| over the period's samples (N m).
    pub max_abs_tau: f64,
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
    let boundary = |i: usize| mode[i - 1] == Mode::Free && mode[i] != Mode::Free;
    let mut out = Vec::new();
    let Some(mut first) =
        (0..n).find(|&i| (i == 0 && mode[0] != Mode::Free) || (i > 0 && boundary(i)))
    else {
        return out;
    };
    for i in first + 1..n {
        if !boundary(i) {
            continue;
        }
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
        for k in first..=i {
            p.max_abs_tau = tau[k].iter().fold(p.max_abs_tau, |m, v| m.max(v.abs()));
            if k < i && mode[k] != Mode::Free {
                p.contact = true;
            }
            if k == i {
                break;
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
