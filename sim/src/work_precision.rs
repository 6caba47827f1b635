//! Work-precision measurement: error against a tight-tolerance reference run versus CPU time,
//! for DOPRI5 at a ladder of `rtol` and RK4 at a ladder of step sizes (`docs/architecture.md`; the
//! paper's Sect. 6.2 open-loop simulation is the use case).
//!
//! For a hybrid trajectory the error of a run is measured at the end time, ‖x(t_end) −
//! x_ref(t_end)‖_∞ (which includes the effect of every event-time error on the state), together
//! with the largest event-time difference against the reference when the transition sequences
//! (mode before → mode after) agree. A run whose event sequence differs from the reference is reported
//! with `same_events = false` (its error is then that of a different trajectory branch).

use crate::{EventRecord, HybridSystem, Method, SimError, SimSettings, SimStats, Simulator};
use serde::Serialize;
use std::time::Instant;

/// DOPRI5 relative tolerances of the standard table (1e-3 … 1e-12).
pub const RTOL_LADDER: [f64; 10] = [
    1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
];

/// RK4 step sizes of the standard table (s).
pub const RK4_LADDER: [f64; 5] = [1e-2, 3e-3, 1e-3, 3e-4, 1e-4];

/// One row of a work-precision table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorkPrecisionRow {
    /// `dopri5` or `rk4`.
    pub method: &'static str,
    /// rtol (DOPRI5) or step size in s (RK4).
    pub parameter: f64,
    /// ‖x(t_end) − x_ref(t_end)‖_∞ (state units); +inf if the run failed.
    pub error: f64,
    /// Largest |t_event − t_event,ref| (s) when the event sequences agree, else NaN.
    pub event_time_error: f64,
    /// Whether the run produced the same sequence of transitions (mode before → mode after)
    /// as the reference (the guard may differ, e.g. `slip_reversal` instead of `slip_speed`).
    pub same_events: bool,
    /// Best wall-clock time of `repeats` runs (s).
    pub cpu_seconds: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Vector-field evaluations.
    pub rhs_evals: usize,
    /// Error message if the run failed.
    pub failure: Option<String>,
}

/// The configurations to measure: DOPRI5 at each rtol (atol = `atol_factor`·rtol), RK4 at
/// each step.
pub fn ladder(
    base: &SimSettings,
    rtols: &[f64],
    atol_factor: f64,
    steps: &[f64],
) -> Vec<SimSettings> {
    let mut v: Vec<SimSettings> = rtols
        .iter()
        .map(|&r| SimSettings {
            method: Method::Dopri5,
            rtol: r,
            atol: r * atol_factor,
            ..base.clone()
        })
        .collect();
    v.extend(steps.iter().map(|&h| SimSettings {
        method: Method::Rk4 { h },
        ..base.clone()
    }));
    v
}

/// Final state, event log and counters of one run (or the error and the counters so far).
type RunResult<M> = Result<(Vec<f64>, Vec<EventRecord<M>>, SimStats), Box<(SimError, SimStats)>>;

/// One run to `t_end` without storing samples; returns the final state, events and counters.
fn run_to_end<S: HybridSystem + ?Sized>(
    sys: &S,
    set: &SimSettings,
    mode0: S::Mode,
    t0: f64,
    x0: &[f64],
    t_end: f64,
) -> RunResult<S::Mode> {
    let set = SimSettings {
        record_steps: false,
        output_dt: None,
        ..set.clone()
    };
    let mut sim = Simulator::new(sys, set, mode0, t0, x0, t_end)
        .map_err(|e| Box::new((e, SimStats::default())))?;
    loop {
        match sim.advance() {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(Box::new((e, sim.stats()))),
        }
    }
    let x = sim.x().to_vec();
    let out = sim.finish();
    Ok((x, out.events, out.stats))
}

/// Runs `sys` from (`mode0`, `t0`, `x0`) to `t_end` once with `reference` settings and then with
/// every entry of `configs` (`repeats` ≥ 1 times each, best time kept), and returns one row per
/// configuration. Fails only if the reference run fails.
pub fn work_precision<S: HybridSystem + ?Sized>(
    sys: &S,
    mode0: S::Mode,
    t0: f64,
    x0: &[f64],
    t_end: f64,
    reference: &SimSettings,
    configs: &[SimSettings],
    repeats: usize,
) -> Result<Vec<WorkPrecisionRow>, SimError> {
    let (xref, ref_events, _) =
        run_to_end(sys, reference, mode0, t0, x0, t_end).map_err(|b| b.0)?;
    let mut rows = Vec::with_capacity(configs.len());
    for set in configs {
        let (method, parameter) = match set.method {
            Method::Dopri5 => ("dopri5", set.rtol),
            Method::Rk4 { h } => ("rk4", h),
        };
        let mut best = f64::INFINITY;
        let mut result = None;
        for _ in 0..repeats.max(1) {
            let start = Instant::now();
            let r = run_to_end(sys, set, mode0, t0, x0, t_end);
            best = best.min(start.elapsed().as_secs_f64());
            result = Some(r);
        }
        let row = match result.expect("at least one repeat") {
            Ok((x, events, stats)) => {
                let error = x
                    .iter()
                    .zip(&xref)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
                let same_events = events.len() == ref_events.len()
                    && events.iter().zip(&ref_events).all(|(a, b)| {
                        a.mode_before == b.mode_before && a.mode_after == b.mode_after
                    });
                let event_time_error = if same_events {
                    events
                        .iter()
                        .zip(&ref_events)
                        .map(|(a, b)| (a.t - b.t).abs())
                        .fold(0.0, f64::max)
                } else {
                    f64::NAN
                };
                WorkPrecisionRow {
                    method,
                    parameter,
                    error,
                    event_time_error,
                    same_events,
                    cpu_seconds: best,
                    steps: stats.accepted_steps,
                    rhs_evals: stats.rhs_evals,
                    failure: None,
                }
            }
            Err(b) => {
                let (e, stats) = *b;
                WorkPrecisionRow {
                    method,
                    parameter,
                    error: f64::INFINITY,
                    event_time_error: f64::NAN,
                    same_events: false,
                    cpu_seconds: best,
                    steps: stats.accepted_steps,
                    rhs_evals: stats.rhs_evals,
                    failure: Some(e.to_string()),
                }
            }
        };
        rows.push(row);
    }
    Ok(rows)
}

/// Formats rows as a Markdown table (method, rtol / h, error, largest event-time error, CPU
/// time, steps, f-evals).
pub fn format_table(rows: &[WorkPrecisionRow]) -> String {
    let mut s = String::from(
        "| method | rtol / h (s) | error ‖x(T) − x_ref(T)‖∞ | max event-time error (s) | CPU (ms) | steps | f evals |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let ev = if r.same_events {
            format!("{:.2e}", r.event_time_error)
        } else {
            "event sequence differs".into()
        };
        let err = match &r.failure {
            Some(m) => format!("failed: {m}"),
            None => format!("{:.2e}", r.error),
        };
        s.push_str(&format!(
            "| {} | {:.0e} | {} | {} | {:.3} | {} | {} |\n",
            r.method,
            r.parameter,
            err,
            ev,
            1e3 * r.cpu_seconds,
            r.steps,
            r.rhs_evals
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulate;
    use crate::toys::Oscillator;

    /// On the harmonic oscillator the error must fall with rtol and with h (RK4: 4th order,
    /// so a 10× smaller step gives ≥ 1000× smaller error), and the reference itself has ~0 error.
    #[test]
    fn errors_decrease_along_the_ladders() {
        let sys = Oscillator { omega: 2.0 };
        let base = SimSettings {
            h_max: 1.0,
            ..SimSettings::default()
        };
        let reference = SimSettings {
            rtol: 1e-13,
            atol: 1e-15,
            ..base.clone()
        };
        let cfg = ladder(&base, &[1e-4, 1e-7, 1e-10], 1e-2, &[1e-2, 1e-3]);
        let rows = work_precision(&sys, (), 0.0, &[1.0, 0.0], 10.0, &reference, &cfg, 1).unwrap();
        assert_eq!(rows.len(), 5);
        eprintln!("{}", format_table(&rows));
        assert!(rows.iter().all(|r| r.same_events && r.failure.is_none()));
        assert!(rows[0].error > rows[1].error && rows[1].error > rows[2].error);
        assert!(rows[2].error < 1e-8, "{}", rows[2].error);
        assert!(
            rows[3].error > 1e3 * rows[4].error * 0.5,
            "{} {}",
            rows[3].error,
            rows[4].error
        );
        // Independent check against the closed form x(10) = cos(20).
        let exact = libm::cos(20f64);
        let out = simulate(&sys, cfg[2].clone(), (), 0.0, &[1.0, 0.0], 10.0).unwrap();
        let x = out.trajectory.x.last().unwrap()[0];
        assert!((x - exact).abs() < 10.0 * rows[2].error.max(1e-12));
        let table = format_table(&rows);
        assert_eq!(table.lines().count(), 2 + rows.len());
    }
}
