//! Study (a), integrator work-precision (paper Sect. 3, Fig. 3): the paper finger dropped
//! onto the ball (τ = 0, Newton impact; impact, slip, stick and lift-off events), simulated
//! with DOPRI5 over an rtol ladder and with RK4 over a step ladder. Error of the final state
//! ‖x(T) − x_ref(T)‖∞ and of the event times against a DOPRI5 run at rtol = 1e-13, versus CPU
//! time (`bf_sim::work_precision`).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Result, anyhow};
use bf_model::{ImpactLaw, Mode as SimMode, PaperKernels, State, Vec3, fixtures};
use bf_plot::paper::WorkPrecisionSet;
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::work_precision::{WorkPrecisionRow, format_table, ladder, work_precision};
use bf_sim::{Method, PdController, SimSettings};

use super::{bar, wp_figure};

/// Integrator settings of the study: `method` at `rtol` (atol = rtol/100), steps ≤ 0.05 s.
pub fn sim_settings(method: Method, rtol: f64) -> SimSettings {
    SimSettings {
        method,
        rtol,
        atol: 1e-2 * rtol,
        h_max: 0.05,
        ..SimSettings::default()
    }
}

/// The scenario of the study: the paper finger with zero torque and Newton's impact law, and
/// its initial state q = (0.1, 0.5, 0.5) at rest above the ball.
pub fn dropped_finger() -> Result<(BallFinger<PaperKernels, PdController>, [f64; 9])> {
    let sys = BallFinger::new(
        fixtures::paper_scene().map_err(|e| anyhow!("paper scene: {e}"))?,
        PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3])
            .map_err(|e| anyhow!("zero input: {e}"))?,
        BallFingerSettings {
            impact_law: ImpactLaw::Newton,
            ..BallFingerSettings::default()
        },
    )
    .map_err(|e| anyhow!("ball-finger system: {e}"))?;
    let x0 = State::new(Vec3::new(0.1, 0.5, 0.5), Vec3::zeros(), Vec3::zeros()).to_array();
    Ok((sys, x0))
}

/// Runs the ladders; returns the simulated span T (s) and one row per setting.
pub(super) fn measure(quick: bool) -> Result<(f64, Vec<WorkPrecisionRow>)> {
    let t_end = if quick { 3.0 } else { 10.0 };
    let (sys, x0) = dropped_finger()?;
    let reference = SimSettings {
        rtol: 1e-13,
        atol: 1e-15,
        ..sim_settings(Method::Dopri5, 1e-13)
    };
    let (rtols, steps, repeats): (&[f64], &[f64], usize) = if quick {
        (&[1e-3, 1e-5, 1e-7, 1e-9], &[1e-2, 1e-3], 1)
    } else {
        (
            &[
                1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
            ],
            &[1e-2, 3e-3, 1e-3, 3e-4, 1e-4],
            3,
        )
    };
    let configs = ladder(&sim_settings(Method::Dopri5, 1e-8), rtols, 1e-2, steps);
    let pb = bar(configs.len(), "(a) simulation");
    let mut rows = Vec::with_capacity(configs.len());
    // One configuration at a time so the bar moves; the reference is cheap (< 0.1 s).
    for c in &configs {
        pb.set_message(crate::names::method(&c.method));
        let mut r = work_precision(
            &sys,
            SimMode::Free,
            0.0,
            &x0,
            t_end,
            &reference,
            std::slice::from_ref(c),
            repeats,
        )
        .map_err(|e| anyhow!("reference simulation failed: {e}"))?;
        rows.append(&mut r);
        pb.inc(1);
    }
    pb.finish_and_clear();
    Ok((t_end, rows))
}

/// The ladder's knob of a row as the figures label it: the fixed step for RK4, rtol for DOPRI5.
fn knob(r: &WorkPrecisionRow) -> String {
    if r.method == "rk4" {
        format!("h {:.0e} s", r.parameter)
    } else {
        format!("rtol {:.0e}", r.parameter)
    }
}

/// The runs of `method` that a figure leaves out: those that failed, and, for the event-time
/// figure (`events`), those whose event sequence differs from the reference's (their event
/// times cannot be compared one to one).
fn left_out<'a>(
    rows: &'a [WorkPrecisionRow],
    method: &str,
    events: bool,
) -> Vec<&'a WorkPrecisionRow> {
    rows.iter()
        .filter(|r| r.method == method)
        .filter(|r| r.failure.is_some() || (events && !r.same_events))
        .collect()
}

/// The legend name of `method`'s set in a figure, with how many of its runs the figure
/// leaves out ([`left_out`]), so that a missing point is never taken for a missing run.
fn set_name(rows: &[WorkPrecisionRow], method: &str, events: bool) -> String {
    let all = rows.iter().filter(|r| r.method == method).count();
    let out = left_out(rows, method, events).len();
    if out == 0 {
        method.to_string()
    } else {
        format!("{method} ({out} of {all} runs not shown)")
    }
}

/// The sentence under the figures naming the runs they leave out and why; empty when none.
fn left_out_note(rows: &[WorkPrecisionRow]) -> String {
    let mut s = String::new();
    for (figure, events) in [("sa_sim_state", false), ("sa_sim_events", true)] {
        let mut parts = Vec::new();
        for m in ["dopri5", "rk4"] {
            let failed: Vec<String> = left_out(rows, m, false).iter().map(|r| knob(r)).collect();
            let differs: Vec<String> = left_out(rows, m, events)
                .iter()
                .filter(|r| r.failure.is_none())
                .map(|r| knob(r))
                .collect();
            if !failed.is_empty() {
                parts.push(format!("{m} {} (the run failed)", failed.join(", ")));
            }
            if !differs.is_empty() {
                parts.push(format!(
                    "{m} {} (event sequence differs from the reference's, so its event times \
                     cannot be compared)",
                    differs.join(", ")
                ));
            }
        }
        if !parts.is_empty() {
            let _ = write!(s, "`{figure}` leaves out {}. ", parts.join("; "));
        }
    }
    s.trim_end().to_string()
}

/// The Markdown section of study (a) and its figures `sa_sim_state`, `sa_sim_events`.
pub(super) fn section(t_end: f64, rows: &[WorkPrecisionRow], fig_dir: &Path) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### (a) Simulation: integrator work-precision\n\n\
         Paper scene, finger dropped from q = (0.1, 0.5, 0.5) onto the ball (τ = 0, Newton \
         impact): impact, slip, stick and lift-off events over {} s. Error of x(T) and of the \
         event times against a DOPRI5 run at rtol = 1e-13, atol = 1e-15 (Sect. 3, Fig. 3). \
         The reference has its own error: errors near 1e-8 in x(T) and 1e-12 s in the event \
         times are of the order of its difference from a run at rtol = 1e-14, so rows there \
         do not rank the tolerances. Runs with the reference's transitions are compared event \
         by event even where another guard fired: a fixed step cannot resolve the slip's \
         stop (the iteration hovers at a slip speed of about half its deceleration times the \
         step), so RK4 ends the slip where it would stop within one step (the `slip_stop` \
         guard), an event-time error of at most one step.\n",
        t_end
    );
    md.push_str(&format_table(rows));
    let series = |events: bool, f: &dyn Fn(&WorkPrecisionRow) -> f64| -> Vec<WorkPrecisionSet> {
        ["dopri5", "rk4"]
            .iter()
            .map(|m| {
                let ok: Vec<&WorkPrecisionRow> = rows
                    .iter()
                    .filter(|r| r.method == *m && r.failure.is_none())
                    .collect();
                WorkPrecisionSet {
                    name: set_name(rows, m, events),
                    time_s: ok.iter().map(|r| r.cpu_seconds).collect(),
                    error: ok.iter().map(|r| f(r)).collect(),
                    labels: ok.iter().map(|r| knob(r)).collect(),
                    joined: true,
                }
            })
            .collect()
    };
    let fig = wp_figure(
        "Simulation: state error vs CPU time",
        "‖x(T) − x_ref(T)‖∞",
        &series(false, &|r| r.error),
    )?;
    bf_plot::render(&fig, fig_dir.join("sa_sim_state"))?;
    let fig = wp_figure(
        "Simulation: event-time error vs CPU time",
        "max |t_event − t_event,ref| [s]",
        &series(true, &|r| {
            if r.same_events {
                r.event_time_error
            } else {
                f64::NAN
            }
        }),
    )?;
    bf_plot::render(&fig, fig_dir.join("sa_sim_events"))?;
    md.push_str(
        "\n![state error vs time](figures/sa_sim_state.svg)\n\
         ![event-time error vs time](figures/sa_sim_events.svg)\n\n",
    );
    let note = left_out_note(rows);
    if !note.is_empty() {
        let _ = writeln!(md, "{note}\n");
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(
        method: &'static str,
        parameter: f64,
        same_events: bool,
        failed: bool,
    ) -> WorkPrecisionRow {
        WorkPrecisionRow {
            method,
            parameter,
            error: if failed { f64::INFINITY } else { 1e-3 },
            event_time_error: if same_events { 1e-4 } else { f64::NAN },
            same_events,
            cpu_seconds: 1e-3,
            steps: 10,
            rhs_evals: 40,
            failure: failed.then(|| "step limit".to_string()),
        }
    }

    /// The event-time figure says, in its legend and in the text, which runs it leaves out
    /// because their event sequence differs; the state figure leaves out failed runs only.
    #[test]
    fn runs_left_out_of_the_figures_are_named() {
        let rows = [
            row("dopri5", 1e-3, true, false),
            row("dopri5", 1e-6, true, false),
            row("rk4", 1e-2, false, false),
            row("rk4", 3e-3, false, false),
            row("rk4", 1e-3, true, false),
            row("rk4", 1e-4, true, true),
        ];
        assert_eq!(set_name(&rows, "dopri5", true), "dopri5");
        assert_eq!(set_name(&rows, "rk4", true), "rk4 (3 of 4 runs not shown)");
        assert_eq!(set_name(&rows, "rk4", false), "rk4 (1 of 4 runs not shown)");
        let note = left_out_note(&rows);
        assert!(
            note.contains(
                "`sa_sim_events` leaves out rk4 h 1e-4 s (the run failed); rk4 h 1e-2 s, \
                 h 3e-3 s (event sequence differs"
            ),
            "{note}"
        );
        assert!(
            note.contains("`sa_sim_state` leaves out rk4 h 1e-4 s (the run failed)."),
            "{note}"
        );
        let clean = [row("dopri5", 1e-3, true, false)];
        assert_eq!(left_out_note(&clean), "");
    }
}
