//! The open-loop simulation of the paper's Sect. 6.2: the optimal COT torques of the robotic
//! finger (no joint limits) replayed, periodically, in the full hybrid model of Fig. 3 —
//! free, stick and slip modes, Newton's impact law (eq. 39) — starting from the optimal initial
//! state x⁽¹⁾(0), and compared with the optimal trajectory (the counterpart of Fig. 17).
//!
//! The paper's Sect. 7 names the remedy for the drift of that open loop: feedback around the
//! optimal trajectory. [`run_open_loop_study`] replays the same torques twice, once purely
//! open loop ([`run_open_loop`]) and once with a joint-space PD ([`PdTrack`], bf-sim's
//! [`TrackingPd`]) τ = τ*(t) + K_p (q*(t) − q) + K_d (q̇*(t) − q̇) added during the optimum's
//! free phases (optionally in contact too), and compares both with the optimum period by
//! period (ω and q errors) in one figure.

use anyhow::{Context, Result, anyhow, bail};
use bf_model::{ImpactLaw, Kernels, Mode, Model};
use bf_plot::paper::{SimModes, TimeSeries};
use bf_problem::OcpSolution;
use bf_sim::ball_finger::{BallFinger, BallFingerSettings, RunReport};
use bf_sim::{HybridSystem, Input, SimOutput, SimSettings, TorqueSeries, TrackingPd};
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
    /// max |q_sim − q_opt| over each period (rad).
    pub q_error_per_period: Vec<f64>,
    /// The largest |ω| component of the optimum over a period (rad/s), the scale of
    /// [`OpenLoop::first_period_matches`].
    pub omega_scale: f64,
    /// The PD tracking of the run (`None`: pure open loop).
    pub feedback: Option<PdTrack>,
    /// The simulated trajectory (states q, q̇, ω at the output grid and the events).
    pub trajectory: bf_sim::Trajectory<Mode>,
    /// Time spent in each mode (s): free, stick, slip.
    pub mode_time: [f64; 3],
    /// Events by guard name, with counts.
    pub events: Vec<(String, usize)>,
    /// First impact: (simulated time, optimal impact time t_f⁽¹⁾, max |Δq| (rad),
    /// max |Δq̇| (rad/s)) between the simulated pre-impact state and the optimal state at
    /// the end of phase 1 — separates drift of the free flight from the impact model.
    pub first_impact: Option<(f64, f64, f64, f64)>,
    /// The simulator's warnings of the run (`RunSummary::warnings`: impacts that raised the
    /// energy, a failed energy-balance check, Zeno fallbacks), in time order.
    pub warnings: Vec<bf_sim::SimWarning>,
    /// The largest energy gain of an impact (J; `RunSummary::max_impact_energy_gain`).
    pub max_impact_energy_gain: f64,
    /// The energy at the run's first sample (J), the scale of the gains.
    pub energy_initial: f64,
}

/// The share of [`OpenLoop::omega_scale`] up to which a replay's ω error counts as a match
/// ([`OpenLoop::first_period_matches`]).
pub const MATCH_SHARE: f64 = 0.1;

impl OpenLoop {
    /// Whether the replay matches the optimum in its first period: the largest ω error there
    /// is at most [`MATCH_SHARE`] of the optimum's largest |ω| component.
    pub fn first_period_matches(&self) -> bool {
        self.omega_error_per_period
            .first()
            .is_some_and(|&e| e <= MATCH_SHARE * self.omega_scale)
    }
}

/// Joint-space PD tracking of the optimal trajectory, the stabilising feedback of the paper's
/// Sect. 7: τ = τ*(t) + K_p (q*(t) − q) + K_d (q̇*(t) − q̇), the same gains on every joint.
///
/// Default gains [`DEFAULT_PD_TRACK`]: K_p = 1 N m/rad, K_d = 0.2 N m s/rad (the defaults of
/// `simulate --pd-gains`). The paper finger (links of 1 m and 0.02 kg, scenes/paper.toml) has
/// mass-matrix diagonal entries from about 7e-3 kg m² (distal joint) to 0.18 kg m² (proximal
/// joint, finger stretched), so per joint these gains give natural frequencies √(K_p/M) of
/// about 2.4–12 rad/s and damping ratios K_d / (2 √(K_p M)) of about 0.24–1.2: fast against
/// the free phases of the optima (0.1–9 s), and within the paper's torque bound of 1 N m for
/// angle errors up to about 1 rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PdTrack {
    /// Proportional gain K_p (N m/rad), non-negative.
    pub kp: f64,
    /// Derivative gain K_d (N m s/rad), non-negative.
    pub kd: f64,
    /// Also while the optimum is in contact (default: free phases only, where the finger
    /// alone moves and the feedback cannot fight the contact constraint).
    pub during_contact: bool,
}

/// The default PD tracking ([`PdTrack`]).
pub const DEFAULT_PD_TRACK: PdTrack = PdTrack {
    kp: 1.0,
    kd: 0.2,
    during_contact: false,
};

impl PdTrack {
    /// A short description for legends and tables, e.g. "PD 1/0.2, free phases".
    pub fn label(&self) -> String {
        format!(
            "PD {}/{}, {}",
            self.kp,
            self.kd,
            if self.during_contact {
                "always"
            } else {
                "free phases"
            }
        )
    }
}

impl Default for PdTrack {
    fn default() -> Self {
        DEFAULT_PD_TRACK
    }
}

/// The optimal (q, q̇, ω) at time `t` (periodic), interpolated linearly in the dense samples.
fn reference_at(sol: &OcpSolution, t: f64) -> [Vec<f64>; 3] {
    let d = &sol.dense;
    let tm = t.rem_euclid(sol.period);
    let i = d.t.partition_point(|&s| s <= tm).clamp(1, d.t.len() - 1);
    let (t0, t1) = (d.t[i - 1], d.t[i]);
    let w = if t1 > t0 {
        ((tm - t0) / (t1 - t0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let lerp = |v: &[Vec<f64>]| -> Vec<f64> {
        v[i - 1]
            .iter()
            .zip(&v[i])
            .map(|(a, b)| a * (1.0 - w) + b * w)
            .collect()
    };
    [lerp(&d.q), lerp(&d.qd), lerp(&d.omega)]
}

/// The dense samples `rows` of the optimum repeated `periods` times, as a piecewise-linear
/// series (strictly increasing times: of two samples at one time, the first is kept).
fn periodic_series(sol: &OcpSolution, periods: usize, rows: &[Vec<f64>]) -> Result<TorqueSeries> {
    let d = &sol.dense;
    let (mut t, mut v) = (Vec::new(), Vec::new());
    for p in 0..periods {
        for (i, &ti) in d.t.iter().enumerate() {
            let tt = ti + p as f64 * sol.period;
            if t.last().is_some_and(|&l: &f64| tt <= l) {
                continue;
            }
            t.push(tt);
            v.push(rows[i].clone());
        }
    }
    TorqueSeries::new(t, v).map_err(|e| anyhow!("optimal trajectory as a series: {e}"))
}

/// The optimal torques repeated `periods` times, as a torque series (strictly increasing times).
pub fn periodic_torques(sol: &OcpSolution, periods: usize) -> Result<TorqueSeries> {
    periodic_series(sol, periods, &sol.dense.tau)
}

/// The time windows [t_a, t_b) of the optimum's free phases over `periods` periods.
fn free_windows(sol: &OcpSolution, periods: usize) -> Vec<(f64, f64)> {
    let mut w = Vec::new();
    for p in 0..periods {
        let mut t = p as f64 * sol.period;
        for (mode, &d) in sol.modes.iter().zip(&sol.phase_durations) {
            if *mode == bf_problem::node::PhaseMode::Free {
                w.push((t, t + d));
            }
            t += d;
        }
    }
    w
}

/// The optimal torques with the PD tracking `pd` around the optimal trajectory (feedback in
/// the free phases, or over the whole horizon with [`PdTrack::during_contact`]).
pub fn tracking_input(sol: &OcpSolution, periods: usize, pd: &PdTrack) -> Result<TrackingPd> {
    let n = sol.dense.tau.first().map_or(0, Vec::len);
    let windows = if pd.during_contact {
        vec![(f64::MIN, f64::MAX)]
    } else {
        free_windows(sol, periods)
    };
    TrackingPd::new(
        periodic_torques(sol, periods)?,
        periodic_series(sol, periods, &sol.dense.q)?,
        periodic_series(sol, periods, &sol.dense.qd)?,
        vec![pd.kp; n],
        vec![pd.kd; n],
        windows,
    )
    .map_err(|e| anyhow!("PD tracking (K_p {}, K_d {}): {e}", pd.kp, pd.kd))
}

/// Simulates `periods` periods under `input` from the optimal initial state and writes the
/// files of `simulate` into `dir`; a failed run returns its partial output and the reason.
/// The run's summary comes with it, for its warnings.
fn replay<I: Input>(
    sol: &OcpSolution,
    periods: usize,
    input: I,
    dir: &Path,
) -> Result<(
    SimOutput<Mode>,
    Option<String>,
    bf_sim::ball_finger::RunSummary,
)> {
    let model = bf_model::fixtures::paper_scene().context("paper scene")?;
    let settings = BallFingerSettings {
        impact_law: ImpactLaw::Newton,
        ..BallFingerSettings::default()
    };
    let t_end = periods as f64 * sol.period;
    let (out, report, stopped) = simulate_optimum(sol, model, input, settings, t_end)?;
    // The files of `simulate` (same columns, units and mode names).
    report.write_dir(dir, &out, stopped.as_deref())?;
    Ok((out, stopped, report.summary))
}

/// Simulates `plant` under `input` with `settings` from the optimum's initial state x(0) (its
/// first collocation point) and first mode until `t_end` (DOPRI5, rtol 1e-8, 400 output
/// samples per period besides steps and events); returns the output, its per-sample report
/// and, for a run that stopped early, why (the output is then the partial trajectory).
pub fn simulate_optimum<K: Kernels<N>, I: Input, const N: usize>(
    sol: &OcpSolution,
    plant: Model<K, N>,
    input: I,
    settings: BallFingerSettings,
    t_end: f64,
) -> Result<(SimOutput<Mode>, RunReport<N>, Option<String>)> {
    let max_steps = SimSettings::default().max_steps;
    simulate_optimum_until(sol, plant, input, settings, t_end, max_steps, None)
}

/// When [`simulate_optimum_until`] ends a run: asked with the trajectory recorded so far.
pub type Until<'a> = &'a dyn Fn(&bf_sim::Trajectory<Mode>) -> bool;

/// [`simulate_optimum`] with a budget of `max_steps` attempted steps (the simulator's default
/// budget fits a few hundred seconds of these plans), ended early where `until` says so: it is
/// asked after every accepted step and every event with the trajectory recorded so far, and
/// `true` ends the run there (ended without error, `t_final` before `t_end`). The steps up to
/// that point are those of the whole run, sample for sample ([`bf_sim::simulate_until`]).
pub fn simulate_optimum_until<K: Kernels<N>, I: Input, const N: usize>(
    sol: &OcpSolution,
    plant: Model<K, N>,
    input: I,
    settings: BallFingerSettings,
    t_end: f64,
    max_steps: usize,
    until: Option<Until<'_>>,
) -> Result<(SimOutput<Mode>, RunReport<N>, Option<String>)> {
    let sys = BallFinger::new(plant, input, settings)?;
    let x0 = initial_state(sol)?;
    if x0.len() != 2 * N + 3 {
        bail!(
            "the solution's initial state has {} values, the plant's finger {N} joints \
             (q, qd, omega: {} values)",
            x0.len(),
            2 * N + 3
        );
    }
    let mode0 = if sol.modes.first() == Some(&bf_problem::node::PhaseMode::Stick) {
        Mode::Stick
    } else {
        Mode::Free
    };
    let sim = SimSettings {
        rtol: 1e-8,
        output_dt: Some(sol.period / 400.0),
        max_steps,
        ..SimSettings::default()
    };
    let cpu = std::time::Instant::now();
    let (out, stopped) = match bf_sim::simulate_until(
        &sys as &dyn HybridSystem<Mode = Mode>,
        sim,
        mode0,
        0.0,
        &x0,
        t_end,
        |tr| until.is_some_and(|u| u(tr)),
    ) {
        Ok(out) => (out, None),
        Err(f) => {
            // The simulator's message carries full-precision times and Rust's mode names; the
            // tables this ends up in want neither.
            let msg = format!(
                "stopped at t = {:.4} s: {}",
                f.t,
                crate::names::tidy(&f.error.to_string())
            );
            (f.partial, Some(msg))
        }
    };
    let report = sys.report(&out, 0.0, cpu.elapsed().as_secs_f64());
    Ok((out, report, stopped))
}

/// The optimum's initial state x(0) = (q, q̇, ω) at its first collocation point: 2N + 3
/// values for a finger with N joints.
pub fn initial_state(sol: &OcpSolution) -> Result<Vec<f64>> {
    let d = &sol.nodes;
    let first = |v: &[Vec<f64>]| v.first().cloned().unwrap_or_default();
    let (q, qd, omega) = (first(&d.q), first(&d.qd), first(&d.omega));
    let n = q.len();
    if n == 0 || qd.len() != n || omega.len() != 3 {
        bail!(
            "the solution's initial state is not (q, qd, omega) of one finger: {} joint \
             angles, {} joint rates, {} ball rates",
            n,
            qd.len(),
            omega.len()
        );
    }
    let x0: Vec<f64> = q.into_iter().chain(qd).chain(omega).collect();
    if x0.iter().any(|v| !v.is_finite()) {
        bail!("the solution's initial state is not finite (q, qd, omega of {n} joints)");
    }
    Ok(x0)
}

/// The figures of merit of a replay `out` of `sol` over `periods` periods.
fn analyse(
    sol: &OcpSolution,
    periods: usize,
    (out, stopped, summary): (
        SimOutput<Mode>,
        Option<String>,
        bf_sim::ball_finger::RunSummary,
    ),
    feedback: Option<PdTrack>,
) -> OpenLoop {
    let tr = &out.trajectory;
    let nq = sol.dense.q.first().map_or(0, Vec::len);
    let mut err = vec![0.0f64; periods];
    let mut q_err = vec![0.0f64; periods];
    let mut mode_time = [0.0; 3];
    for i in 0..tr.t.len() {
        let [q, _, w] = reference_at(sol, tr.t[i]);
        let p = ((tr.t[i] / sol.period) as usize).min(periods - 1);
        let e = (0..3)
            .map(|k| (tr.x[i][2 * nq + k] - w[k]).abs())
            .fold(0.0, f64::max);
        err[p] = err[p].max(e);
        let eq = (0..nq)
            .map(|k| (tr.x[i][k] - q[k]).abs())
            .fold(0.0, f64::max);
        q_err[p] = q_err[p].max(eq);
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
            let dq = (0..nq)
                .map(|k| (e.x_pre[k] - d.q[i][k]).abs())
                .fold(0.0, f64::max);
            let dqd = (0..nq)
                .map(|k| (e.x_pre[nq + k] - d.qd[i][k]).abs())
                .fold(0.0, f64::max);
            Some((e.t, t1, dq, dqd))
        });
    OpenLoop {
        periods,
        t_reached: out.t_final,
        stopped,
        omega_error_per_period: err,
        q_error_per_period: q_err,
        omega_scale: sol
            .dense
            .omega
            .iter()
            .flatten()
            .fold(0.0, |m: f64, v| m.max(v.abs())),
        feedback,
        trajectory: out.trajectory,
        mode_time,
        events,
        first_impact,
        warnings: summary.warnings,
        max_impact_energy_gain: summary.max_impact_energy_gain,
        energy_initial: summary.energy_initial,
    }
}

/// ω of a replay as a figure series.
fn omega_series(tr: &bf_sim::Trajectory<Mode>, nq: usize) -> TimeSeries {
    TimeSeries {
        t: tr.t.clone(),
        values: (0..3)
            .map(|k| tr.x.iter().map(|x| x[2 * nq + k]).collect())
            .collect(),
        names: ["ω_x", "ω_y", "ω_z"].map(String::from).to_vec(),
    }
}

/// Writes Fig. 17 into `dir/../figures/fig17_open_loop`: the optimal ω, the pure open loop
/// and the PD-tracked replays `tracked`; the pure open loop's contact modes are shaded.
fn write_figure(
    sol: &OcpSolution,
    open: &OpenLoop,
    tracked: &[OpenLoop],
    dir: &Path,
) -> Result<()> {
    let nq = sol.dense.q.first().map_or(0, Vec::len);
    let tr = &open.trajectory;
    let open_w = omega_series(tr, nq);
    let optimal = TimeSeries {
        values: (0..3)
            .map(|k| tr.t.iter().map(|&t| reference_at(sol, t)[2][k]).collect())
            .collect(),
        t: tr.t.clone(),
        names: open_w.names.clone(),
    };
    // The optimum's switching times (impact, lift-off) repeated every period, over the
    // simulated horizon; the simulation's own contact modes are shaded.
    let one_period = super::scenarios::phases_of(sol);
    let mut phases = bf_plot::paper::Phases::default();
    for p in 0..open.periods {
        let offset = p as f64 * sol.period;
        for (t, label) in &one_period.switches {
            if offset + t <= open.t_reached {
                phases.switches.push((offset + t, label.clone()));
            }
        }
    }
    let modes = SimModes::from_trace(&tr.t, &tr.mode)?;
    let title = if tracked.is_empty() {
        "Fig. 17 counterpart: open-loop simulation vs optimal ω (COT, robotic finger)"
    } else {
        "Fig. 17 counterpart: open loop and PD-tracked replays vs optimal ω (COT, robotic finger)"
    };
    let mut fig =
        bf_plot::paper::fig_open_loop_vs_optimal_modes(title, &optimal, &open_w, &phases, &modes)?;
    let styles = [
        ((44, 160, 44), bf_plot::Dash::Dotted),
        ((148, 103, 189), bf_plot::Dash::LongDash),
    ];
    for (j, o) in tracked.iter().enumerate() {
        let w = omega_series(&o.trajectory, nq);
        let ((r, g, b), dash) = styles[j % styles.len()];
        let style = bf_plot::SeriesStyle {
            colour: bf_plot::Colour::Rgb(r, g, b),
            dash,
            ..bf_plot::SeriesStyle::default()
        };
        let name = o.feedback.map_or("replay".to_string(), |pd| pd.label());
        // A replay without a contact phase leaves ω as it was (Newton's impact law does not
        // change it): a flat line that says nothing unless the legend does.
        let name = match (o.mode_time[1] + o.mode_time[2] > 0.0, o.events.is_empty()) {
            (true, _) => name,
            (false, true) => format!("{name} (never reaches the ball)"),
            (false, false) => format!("{name} (bounces off: no contact phase)"),
        };
        for (k, panel) in fig.panels.iter_mut().enumerate() {
            panel
                .series
                .push(bf_plot::Series::new(name.clone(), w.points(k)).styled(style));
        }
    }
    bf_plot::render_panels(&fig, dir.join("..").join("figures").join("fig17_open_loop"))?;
    Ok(())
}

/// Run the open-loop simulation and write its trajectory, events and Fig. 17 into `dir`.
pub fn run_open_loop(sol: &OcpSolution, periods: usize, dir: &Path) -> Result<OpenLoop> {
    let run = replay(sol, periods, periodic_torques(sol, periods)?, dir)?;
    let o = analyse(sol, periods, run, None);
    write_figure(sol, &o, &[], dir)?;
    Ok(o)
}

/// Replays the optimal torques with the PD tracking `pd` ([`tracking_input`]) and writes its
/// trajectory and events into `dir` (no figure).
pub fn run_pd_tracked(
    sol: &OcpSolution,
    periods: usize,
    pd: &PdTrack,
    dir: &Path,
) -> Result<OpenLoop> {
    let run = replay(sol, periods, tracking_input(sol, periods, pd)?, dir)?;
    Ok(analyse(sol, periods, run, Some(*pd)))
}

/// The pure open loop (files in `dir/open-loop`) and a PD-tracked replay of the same torques
/// for every entry of `variants` (`dir/open-loop-pd`, `dir/open-loop-pd-2`, …), side by side in
/// Fig. 17 (`dir/figures/fig17_open_loop`).
pub fn run_open_loop_study(
    sol: &OcpSolution,
    periods: usize,
    variants: &[PdTrack],
    dir: &Path,
) -> Result<(OpenLoop, Vec<OpenLoop>)> {
    let open_dir = dir.join("open-loop");
    let run = replay(sol, periods, periodic_torques(sol, periods)?, &open_dir)?;
    let open = analyse(sol, periods, run, None);
    let mut tracked = Vec::new();
    for (j, pd) in variants.iter().enumerate() {
        let name = match j {
            0 => "open-loop-pd".to_string(),
            _ => format!("open-loop-pd-{}", j + 1),
        };
        tracked.push(run_pd_tracked(sol, periods, pd, &dir.join(name))?);
    }
    write_figure(sol, &open, &tracked, &open_dir)?;
    Ok((open, tracked))
}

/// Kind of the warning of a failed energy-balance check (bf-sim's `RunSummary`).
const ENERGY_ERROR: &str = "energy_error";

impl OpenLoop {
    /// The simulator's warnings of the run, one sentence per kind: how many, the worst (the
    /// largest energy gain of an impact, as a share of the run's initial energy), when the
    /// first occurred; with each, whether it is the failed energy-balance check, the run's own
    /// accuracy check (its figures then measure the integration as much as the open loop; the
    /// report marks it), rather than a measurement of the model.
    pub fn warning_lines(&self) -> Vec<(bool, String)> {
        let mut kinds: Vec<&str> = Vec::new();
        for w in &self.warnings {
            if !kinds.contains(&w.kind) {
                kinds.push(w.kind);
            }
        }
        kinds
            .into_iter()
            .map(|kind| {
                let failed_check = kind == ENERGY_ERROR;
                let of: Vec<&bf_sim::SimWarning> =
                    self.warnings.iter().filter(|w| w.kind == kind).collect();
                let first = of[0];
                let n = of.len();
                let line = match kind {
                    "energy_raising_impact" => {
                        let share = if self.energy_initial.abs() > 0.0 {
                            format!(
                                " ({:.1} % of the run's initial energy {:.3e} J)",
                                100.0 * self.max_impact_energy_gain / self.energy_initial.abs(),
                                self.energy_initial
                            )
                        } else {
                            String::new()
                        };
                        format!(
                            "{n} impact{} raised the energy (`{kind}`), the largest by \
                             {:+.3e} J{share}, the first at t = {:.4} s: Newton's law (eq. 39) \
                             does not guarantee dissipation",
                            if n == 1 { "" } else { "s" },
                            self.max_impact_energy_gain,
                            first.t
                        )
                    }
                    ENERGY_ERROR => format!(
                        "the energy balance failed its check (`{kind}`) at t = {:.4} s: {}",
                        first.t,
                        crate::names::tidy(&first.message)
                    ),
                    _ => format!(
                        "{n} `{kind}` warning{}, the first at t = {:.4} s: {}",
                        if n == 1 { "" } else { "s" },
                        first.t,
                        crate::names::tidy(&first.message)
                    ),
                };
                (failed_check, line)
            })
            .collect()
    }
}

/// The simulator's warnings of the run `o` named `name` as a paragraph ("none" too: the reader
/// should not have to guess whether they were looked at).
fn warnings_markdown(name: &str, o: &OpenLoop) -> String {
    let lines = o.warning_lines();
    if lines.is_empty() {
        return format!("Simulator warnings, {name}: none.\n");
    }
    let n = o.warnings.len();
    let mut s = format!("Simulator warnings, {name} ({n} in its `summary.json`'s `warnings`):\n\n");
    for (failed_check, l) in lines {
        if failed_check {
            s.push_str(&format!("- **failed check:** {l}\n"));
        } else {
            s.push_str(&format!("- {l}\n"));
        }
    }
    s
}

/// The report section.
pub fn markdown(o: &OpenLoop) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "{} period{} of the optimal `periodic-cot` torques replayed open loop in the hybrid \
         model (Newton's impact law, slip allowed, DOPRI5 rtol 1e-8), from the optimal initial \
         state. Trajectory: `open-loop/trajectory.json`, events: `open-loop/events.csv`.\n",
        o.periods,
        if o.periods == 1 { "" } else { "s" }
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
    writeln!(s, "\n{}", warnings_markdown("open loop", o))?;
    writeln!(
        s,
        "\n![Fig. 17 counterpart](figures/fig17_open_loop.svg)\n\n\
         Shaded: the open-loop simulation's slip (orange) and stick (green) intervals (the \
         PD-tracked replays' modes are in their own `events.json`; a slip of no duration is \
         drawn a few pixels wide); dashed lines: the optimum's switching times, repeated every \
         period.\n\n\
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

/// The report section comparing the pure open loop `open` with the PD-tracked replays
/// `tracked` of the same torques (after [`markdown`] of the pure open loop).
pub fn pd_markdown(open: &OpenLoop, tracked: &[OpenLoop]) -> Result<String> {
    let mut s = String::new();
    writeln!(
        s,
        "\n\n### Joint-space PD tracking (Sect. 7)\n\n\
         The same torques with τ = τ*(t) + K_p (q*(t) − q) + K_d (q̇*(t) − q̇) added (q*, q̇*: \
         the optimal trajectory, repeated every period; gains in N m/rad and N m s/rad), either \
         only while the optimum is in a free phase (\"free phases\", the paper's suggestion) or \
         over the whole horizon (\"always\"). Trajectories: `open-loop-pd*/trajectory.json`; \
         the dotted and long-dashed curves of the figure above.\n"
    )?;
    for o in tracked {
        let label = o.feedback.map_or(String::new(), |pd| pd.label());
        if let Some(msg) = &o.stopped {
            writeln!(
                s,
                "**The run {label} stopped early** ({msg}); the partial trajectory is reported.\n"
            )?;
        }
        writeln!(s, "{}", warnings_markdown(&label, o))?;
    }
    let runs: Vec<(String, &OpenLoop)> = std::iter::once(("open loop".to_string(), open))
        .chain(
            tracked
                .iter()
                .map(|o| (o.feedback.map_or(String::new(), |pd| pd.label()), o)),
        )
        .collect();
    let mut head = String::from("| period |");
    let mut rule = String::from("|---|");
    for (name, _) in &runs {
        write!(head, " ω error, {name} (rad/s) |")?;
        rule.push_str("---|");
    }
    for (name, _) in &runs {
        write!(head, " q error, {name} (rad) |")?;
        rule.push_str("---|");
    }
    writeln!(s, "{head}\n{rule}")?;
    for i in 0..open.periods {
        let at = |v: &[f64]| v.get(i).map_or("—".to_string(), |e| format!("{e:.4}"));
        write!(s, "| {} |", i + 1)?;
        for (_, o) in &runs {
            write!(s, " {} |", at(&o.omega_error_per_period))?;
        }
        for (_, o) in &runs {
            write!(s, " {} |", at(&o.q_error_per_period))?;
        }
        writeln!(s)?;
    }
    writeln!(
        s,
        "\nErrors: the largest absolute component error against the optimum over each period. \
         First period (match: ω error ≤ {:.0} % of the optimum's largest |ω| component, \
         {:.3} rad/s):",
        100.0 * MATCH_SHARE,
        MATCH_SHARE * open.omega_scale
    )?;
    for (name, o) in &runs {
        writeln!(
            s,
            "- {name}: {} (time in free / stick / slip: {:.3} / {:.3} / {:.3} s)",
            if o.first_period_matches() {
                "matches"
            } else {
                "does not match"
            },
            o.mode_time[0],
            o.mode_time[1],
            o.mode_time[2]
        )?;
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(warnings: Vec<bf_sim::SimWarning>) -> OpenLoop {
        OpenLoop {
            periods: 1,
            t_reached: 3.0,
            stopped: None,
            omega_error_per_period: vec![0.5],
            q_error_per_period: vec![0.1],
            omega_scale: 1.0,
            feedback: None,
            trajectory: bf_sim::Trajectory::default(),
            mode_time: [3.0, 0.0, 0.0],
            events: vec![],
            first_impact: None,
            max_impact_energy_gain: 5.534e-3,
            energy_initial: 0.11,
            warnings,
        }
    }

    fn impact(t: f64, gain: f64) -> bf_sim::SimWarning {
        bf_sim::SimWarning {
            t,
            kind: "energy_raising_impact",
            message: format!("newton impact raised the energy by {gain:+.3e} J"),
        }
    }

    /// The simulator's warnings reach the report section: per kind, the count, the worst gain
    /// and its share of the run's energy; a failed energy check is marked; no warnings say so.
    #[test]
    fn the_open_loop_section_shows_the_simulators_warnings() {
        let o = run(vec![
            impact(2.0662460095657007, 5.534e-3),
            impact(5.93, 5.5e-3),
        ]);
        let md = markdown(&o).unwrap();
        assert!(
            md.contains(
                "- 2 impacts raised the energy (`energy_raising_impact`), the largest by \
                 +5.534e-3 J (5.0 % of the run's initial energy 1.100e-1 J), the first at \
                 t = 2.0662 s"
            ),
            "{md}"
        );
        assert!(o.warning_lines().iter().all(|(failed, _)| !failed));
        let mut failed = run(vec![bf_sim::SimWarning {
            t: 1.4299208130706953,
            kind: "energy_error",
            message: "energy-balance error 3.211e-3 J from t = 0 s exceeds 1e-3 J".into(),
        }]);
        failed.feedback = Some(DEFAULT_PD_TRACK);
        assert_eq!(
            failed.warning_lines(),
            [(
                true,
                "the energy balance failed its check (`energy_error`) at t = 1.4299 s: \
                 energy-balance error 3.211e-3 J from t = 0 s exceeds 1e-3 J"
                    .to_string()
            )]
        );
        let md = pd_markdown(&run(vec![]), &[failed]).unwrap();
        assert!(
            md.contains(
                "- **failed check:** the energy balance failed its check (`energy_error`) at \
                 t = 1.4299 s"
            ),
            "{md}"
        );
        assert!(
            markdown(&run(vec![]))
                .unwrap()
                .contains("Simulator warnings, open loop: none.")
        );
    }
}
