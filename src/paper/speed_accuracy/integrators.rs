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

/// The Markdown section of study (a) and its figures `sa_sim_state`, `sa_sim_events`.
pub(super) fn section(t_end: f64, rows: &[WorkPrecisionRow], fig_dir: &Path) -> Result<String> {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### (a) Simulation: integrator work-precision\n\n\
         Paper scene, finger dropped from q = (0.1, 0.5, 0.5) onto the ball (τ = 0, Newton \
         impact): impact, slip, stick and lift-off events over {} s. Error of x(T) and of the \
         event times against a DOPRI5 run at rtol = 1e-13, atol = 1e-15 (Sect. 3, Fig. 3).\n",
        t_end
    );
    md.push_str(&format_table(rows));
    let series = |f: &dyn Fn(&WorkPrecisionRow) -> f64| -> Vec<WorkPrecisionSet> {
        ["dopri5", "rk4"]
            .iter()
            .map(|m| {
                let ok: Vec<&WorkPrecisionRow> = rows
                    .iter()
                    .filter(|r| r.method == *m && r.failure.is_none())
                    .collect();
                WorkPrecisionSet {
                    name: m.to_string(),
                    time_s: ok.iter().map(|r| r.cpu_seconds).collect(),
                    error: ok.iter().map(|r| f(r)).collect(),
                    // The ladder's knob: rtol for DOPRI5, the fixed step for RK4.
                    labels: ok
                        .iter()
                        .map(|r| {
                            if *m == "rk4" {
                                format!("h {:.0e} s", r.parameter)
                            } else {
                                format!("rtol {:.0e}", r.parameter)
                            }
                        })
                        .collect(),
                    joined: true,
                }
            })
            .collect()
    };
    let fig = wp_figure(
        "Simulation: state error vs CPU time",
        "‖x(T) − x_ref(T)‖∞",
        &series(&|r| r.error),
    )?;
    bf_plot::render(&fig, fig_dir.join("sa_sim_state"))?;
    let fig = wp_figure(
        "Simulation: event-time error vs CPU time",
        "max |t_event − t_event,ref| [s]",
        &series(&|r| {
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
    Ok(md)
}
