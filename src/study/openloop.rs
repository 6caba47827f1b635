//! The open-loop simulation of the paper's Sect. 6.2: the optimal COT torques of the robotic
//! finger (no joint limits) replayed, periodically, in the full hybrid model of Fig. 3 —
//! free, stick and slip modes, Newton's impact law (eq. 39) — starting from the optimal initial
//! state x⁽¹⁾(0), and compared with the optimal trajectory (the counterpart of Fig. 17).

use anyhow::{Context, Result, anyhow};
use bf_model::{ImpactLaw, Mode};
use bf_plot::paper::{SimModes, TimeSeries};
use bf_problem::OcpSolution;
use bf_sim::ball_finger::{BallFinger, BallFingerOptions};
use bf_sim::{SimSettings, TorqueSeries};
use std::fmt::Write as _;
use std::path::Path;

/// Figures of merit of the open-loop run.
#[derive(Debug, Clone)]
pub struct OpenLoop {
    /// Periods simulated.
    pub periods: usize,
    /// Simulated time reached (s); less than `periods · period` if the run stopped early.
    pub t_reached: f64,
    /// Why the run stopped early, if it did.
    pub stopped: Option<String>,
    /// max |ω_sim − ω_opt| over each period (rad/s).
    pub omega_error_per_period: Vec<f64>,
    /// Time spent in each mode (s): free, stick, slip.
    pub mode_time: [f64; 3],
    /// Events by guard name, with counts.
    pub events: Vec<(String, usize)>,
    /// First impact: (simulated time, optimal impact time t_f⁽¹⁾, max |Δq| (rad),
    /// max |Δq̇| (rad/s)) between the simulated pre-impact state and the optimal state at
    /// the end of phase 1 — separates drift of the free flight from the impact model.
    pub first_impact: Option<(f64, f64, f64, f64)>,
}

/// Interpolate the optimal ω at time `t` (periodic) from the dense samples.
fn omega_opt(sol: &OcpSolution, t: f64) -> [f64; 3] {
    let d = &sol.dense;
    let tm = t.rem_euclid(sol.period);
    let i = d.t.partition_point(|&s| s <= tm).clamp(1, d.t.len() - 1);
    let (t0, t1) = (d.t[i - 1], d.t[i]);
    let w = if t1 > t0 {
        ((tm - t0) / (t1 - t0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    std::array::from_fn(|k| d.omega[i - 1][k] * (1.0 - w) + d.omega[i][k] * w)
}

/// The optimal torques repeated `periods` times, as a torque series (strictly increasing times).
pub fn periodic_torques(sol: &OcpSolution, periods: usize) -> Result<TorqueSeries> {
    let d = &sol.dense;
    let (mut t, mut tau) = (Vec::new(), Vec::new());
    for p in 0..periods {
        for (i, &ti) in d.t.iter().enumerate() {
            let tt = ti + p as f64 * sol.period;
            if t.last().is_some_and(|&l: &f64| tt <= l) {
                continue;
            }
            t.push(tt);
            tau.push(d.tau[i].clone());
        }
    }
    TorqueSeries::new(t, tau).map_err(|e| anyhow!("optimal torques as a series: {e}"))
}

/// Run the open-loop simulation and write its trajectory, events and Fig. 17 into `dir`.
pub fn run_open_loop(sol: &OcpSolution, periods: usize, dir: &Path) -> Result<OpenLoop> {
    let model = bf_model::fixtures::paper_scene().context("paper scene")?;
    let input = periodic_torques(sol, periods)?;
    let sys = BallFinger::new(
        model,
        input,
        BallFingerOptions {
            impact_law: ImpactLaw::Newton,
            ..BallFingerOptions::default()
        },
    )?;
    let d = &sol.nodes;
    let x0: Vec<f64> = d.q[0]
        .iter()
        .chain(&d.qd[0])
        .chain(&d.omega[0])
        .copied()
        .collect();
    let t_end = periods as f64 * sol.period;
    let settings = SimSettings {
        rtol: 1e-8,
        output_dt: Some(sol.period / 400.0),
        ..SimSettings::default()
    };
    let cpu = std::time::Instant::now();
    let (out, stopped) = match bf_sim::simulate(&sys, settings, Mode::Free, 0.0, &x0, t_end) {
        Ok(out) => (out, None),
        Err(f) => {
            let msg = format!("stopped at t = {:.4} s: {}", f.t, f.error);
            (f.partial, Some(msg))
        }
    };
    // The files of `simulate` (same columns, units and mode names).
    sys.report(&out, 0.0, cpu.elapsed().as_secs_f64())
        .write_dir(dir, &out, stopped.as_deref())?;

    let tr = &out.trajectory;
    let mut err = vec![0.0f64; periods];
    let mut mode_time = [0.0; 3];
    for i in 0..tr.t.len() {
        let w = omega_opt(sol, tr.t[i]);
        let p = ((tr.t[i] / sol.period) as usize).min(periods - 1);
        let e = (0..3)
            .map(|k| (tr.x[i][6 + k] - w[k]).abs())
            .fold(0.0, f64::max);
        err[p] = err[p].max(e);
        if i > 0 {
            let dt = tr.t[i] - tr.t[i - 1];
            let m = match tr.mode[i - 1] {
                Mode::Free => 0,
                Mode::Stick => 1,
                Mode::Slip => 2,
            };
            mode_time[m] += dt;
        }
    }
    let mut events: Vec<(String, usize)> = Vec::new();
    for e in &out.events {
        let key = format!(
            "{} ({})",
            crate::names::transition(&e.mode_before, e.mode_after.as_ref()),
            e.guard
        );
        match events.iter_mut().find(|(k, _)| *k == key) {
            Some(entry) => entry.1 += 1,
            None => events.push((key, 1)),
        }
    }

    let first_impact = out
        .events
        .iter()
        .find(|e| e.mode_before == Mode::Free)
        .and_then(|e| {
            let t1 = *sol.phase_durations.first()?;
            // The optimal state at the end of phase 1: the last dense sample of phase 0.
            let d = &sol.dense;
            let i = d.phase.iter().rposition(|&p| p == 0)?;
            let dq = (0..3)
                .map(|k| (e.x_pre[k] - d.q[i][k]).abs())
                .fold(0.0, f64::max);
            let dqd = (0..3)
                .map(|k| (e.x_pre[3 + k] - d.qd[i][k]).abs())
                .fold(0.0, f64::max);
            Some((e.t, t1, dq, dqd))
        });

    // Fig. 17: open-loop vs optimal ω.
    let names = ["ω_x", "ω_y", "ω_z"].map(String::from).to_vec();
    let open = TimeSeries {
        t: tr.t.clone(),
        values: (0..3)
            .map(|k| tr.x.iter().map(|x| x[6 + k]).collect())
            .collect(),
        names: names.clone(),
    };
    let opt_t: Vec<f64> = tr.t.clone();
    let optimal = TimeSeries {
        values: (0..3)
            .map(|k| opt_t.iter().map(|&t| omega_opt(sol, t)[k]).collect())
            .collect(),
        t: opt_t,
        names,
    };
    // The optimum's switching times (impact, lift-off) repeated every period, over the
    // simulated horizon; the simulation's own contact modes are shaded.
    let one_period = super::scenarios::phases_of(sol);
    let mut phases = bf_plot::paper::Phases::default();
    for p in 0..periods {
        let offset = p as f64 * sol.period;
        for (t, label) in &one_period.switches {
            if offset + t <= out.t_final {
                phases.switches.push((offset + t, label.clone()));
            }
        }
    }
    let modes = SimModes::from_trace(&tr.t, &tr.mode)?;
    bf_plot::render_panels(
        &bf_plot::paper::fig_open_loop_vs_optimal_modes(
            "Fig. 17 counterpart: open-loop simulation vs optimal ω (COT, robotic finger)",
            &optimal,
            &open,
            &phases,
            &modes,
        )?,
        dir.join("..").join("figures").join("fig17_open_loop"),
    )?;
    Ok(OpenLoop {
        periods,
        t_reached: out.t_final,
        stopped,
        omega_error_per_period: err,
        mode_time,
        events,
        first_impact,
    })
}

/// The report section.
pub fn markdown(o: &OpenLoop) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "{} periods of the optimal `periodic-cot` torques replayed open loop in the hybrid model \
         (Newton's impact law, slip allowed, DOPRI5 rtol 1e-8), from the optimal initial state. \
         Trajectory: `open-loop/trajectory.json`, events: `open-loop/events.csv`.\n",
        o.periods
    )?;
    if let Some(msg) = &o.stopped {
        writeln!(
            s,
            "**The run stopped early** ({msg}); the partial trajectory is reported.\n"
        )?;
    }
    writeln!(
        s,
        "| period | max abs ω error vs optimal (rad/s) |\n|---|---|"
    )?;
    for (i, e) in o.omega_error_per_period.iter().enumerate() {
        writeln!(s, "| {} | {e:.4} |", i + 1)?;
    }
    writeln!(
        s,
        "\nTime in each mode over {:.2} s: free {:.3} s, stick {:.3} s, slip {:.3} s.\n",
        o.t_reached, o.mode_time[0], o.mode_time[1], o.mode_time[2]
    )?;
    if let Some((t, t1, dq, dqd)) = o.first_impact {
        writeln!(
            s,
            "First impact at t = {t:.4} s (optimal: {t1:.4} s); the simulated pre-impact state \
             differs from the optimal one by max |Δq| = {dq:.2e} rad, max |Δq̇| = {dqd:.2e} rad/s \
             (open-loop drift of the free flight; the optimiser's torques are interpolated \
             between collocation nodes).\n"
        )?;
    }
    writeln!(s, "| transition (guard) | count |\n|---|---|")?;
    for (k, n) in &o.events {
        writeln!(s, "| {k} | {n} |")?;
    }
    writeln!(
        s,
        "\n![Fig. 17 counterpart](figures/fig17_open_loop.svg)\n\n\
         Shaded: the simulation's slip (orange) and stick (green) intervals; dashed lines: the \
         optimum's switching times, repeated every period.\n\n\
         Paper (Sect. 6.2): the open-loop angular velocities match well at the beginning and \
         drift as time passes; a short slip window follows each impact with Newton's law, then \
         sticking. Here: the error in the first period is {:.3} rad/s and in the last {:.3} rad/s; \
         slip time {:.3} s in total.",
        o.omega_error_per_period
            .first()
            .copied()
            .unwrap_or(f64::NAN),
        o.omega_error_per_period.last().copied().unwrap_or(f64::NAN),
        o.mode_time[2]
    )?;
    Ok(s)
}
