//! `ball-finger simulate`: the hybrid ball-and-finger model of the paper's Sect. 3 / Fig. 3
//! (modes Free / Stick / Slip, eq. 44–47; transitions eq. 48–50, σ ≤ 0, ‖Δv‖ ≤ ε; impact laws
//! eq. 39–43) driven by an open-loop torque series (Sect. 6.2), a joint-space PD controller,
//! or (`--pd-track`) the torques of a solution with PD tracking of its trajectory (Sect. 7,
//! `ball_finger::paper::openloop::tracking_input`).
//!
//! ```text
//! ball-finger simulate --scene scenes/paper.toml [--torques FILE | --pd TARGET [--pd-gains KP,KD]
//!     | --init SOLUTION --pd-track KP,KD [--pd-track-contact]]
//!     [--q0 Q --qd0 QD --omega0 W --mode0 free|stick|slip | --init FILE]
//!     [--t-end S] [--integrator dopri5|rk4] [--rtol X] [--atol X] [--step H]
//!     [--impact-law newton|stick|max-dissipation|min-slip] [--no-projection] [--output-dt DT]
//!     --out DIR
//! ```
//!
//! Any finger-and-ball scene file with 1 to [`MAX_CONTACT_JOINTS`] joints runs (the model and
//! simulator are generic over the number of joints N; the command dispatches at run time on
//! the scene's N to one instantiation per N): a compiled scene (equal to one of
//! `scenes/*.toml` at build time, runtime parameters aside) on its compiled kernels, any other
//! file (a scene outside the repository, or a built-in name with other numbers) on kernels
//! interpreted from the same expression graphs (`bf_model::registry`); stderr, stdout and
//! `summary.json` (`kernels`) say which ran. `--q0`, `--qd0`, `--pd`, `--torques` and
//! `--init` take N joint values (default q0: [`DEFAULT_Q0`] for N = 3, zeros otherwise). `--param name=value` sets runtime parameters.
//! A scene without a ball (an arm such as `scenes/puma560.toml`, any number of joints)
//! simulates the free motion M q̈ = τ − C q̇ − g − μ_v q̇ (`bf_sim::arm`) from `--q0`/`--qd0`
//! (default 0) under `--torques`, `--pd` or zero torques, and writes `trajectory.csv`
//! (t, q, q̇, τ, E) and `summary.json` (energy balance). Contact-scene output in DIR:
//! `trajectory.{json,csv}` (t, mode, q, q̇, ω, τ, λ, λ_n, h, σ, ‖Δv‖, ḣ, E, drift per sample),
//! `events.{json,csv}` and `summary.json`; a summary goes to stdout. DIR is one output set
//! (`bf_output::OutputDir`): it is checked before the run and replaced as a whole at the end,
//! so it never mixes files of two runs. A run that fails midway still writes everything up to
//! the failure, marks the set with a `FAILED` file and exits non-zero. So does a run that ends
//! with its energy balance (E(t) − E(0) − ∫P dt − ΣΔE of the events, as it accumulates over any
//! 10 s of the run) off by more than the simulator's tolerance (1e-3 J): its integration was too
//! coarse for the dynamics (the step or the tolerance), and the whole trajectory is written but
//! marked as failed.
//!
//! Resources are bounded: a run whose `--t-end` needs more steps than `--max-steps` (at least
//! t_end / h_max with DOPRI5, t_end / step with RK4), or whose `--output-dt` grid has more
//! samples than `--max-samples`, is refused before it starts; a run that reaches
//! `--max-samples` or `--max-time` stops with an error like a failed one. Runs longer than a
//! second show their progress on stderr (a bar on a terminal, a line every 10 s otherwise).

use crate::cli::Inputs as _;
use crate::cli::SimulateArgs;
use crate::errors::bail_usage;
use crate::io::parse_list;
use anyhow::{Context, Result, anyhow, bail};
use bf_model::{ImpactLaw, KernelSource, Kernels, Mode, Model, State, Vec3, VecN};
use bf_output::{DirSpec, Outcome, OutputDir};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{HybridSystem, Method, SimSettings, Simulator};
use std::time::{Duration, Instant};

mod arm;
mod progress;
mod scene;
mod torques;

use arm::run_arm;
use progress::Progress;
pub use scene::scene_of_args;
use torques::max_torque;
pub use torques::{CliInput, MAX_TRACKED_PERIODS, input};

/// The output directory of `simulate`.
pub const OUTPUT_DIR: DirSpec<'static> = DirSpec {
    option: "--out",
    command: "simulate",
};

/// Settings of a run that are not on the command line.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunSettings {
    /// Make the n-th output write fail, as if the process stopped there (tests). The first
    /// write is the trajectory, events and summary, the second the set's manifest.
    pub fail_at_write: Option<usize>,
}

/// Torques above this (N m) get a warning: the paper's bound is 1 N m, and such torques force
/// tiny steps (the run is still bounded by `--max-steps`, `--max-samples`, `--max-time`).
pub const LARGE_TORQUE: f64 = 1e3;

/// Default initial joint angles (rad) of a 3-joint finger: the paper's "q constant nonzero"
/// initial guess (docs/parameters.md); for the paper scene the fingertip is then 1.4 m above
/// the ball. Fingers with other numbers of joints start at q = 0 unless `--q0` says otherwise.
pub const DEFAULT_Q0: [f64; 3] = [0.1, 0.5, 0.5];

/// Largest number of joints of a finger-and-ball scene `simulate` runs (one instantiation of
/// the generic model and simulator per N = 1..=this).
pub const MAX_CONTACT_JOINTS: usize = 7;

/// Parses an impact-law name of the CLI (`newton`, `stick`, `max-dissipation`, `min-slip`,
/// `normal-impulse`; underscores are accepted too).
pub fn parse_impact_law(name: &str) -> Result<ImpactLaw> {
    Ok(match name.replace('_', "-").as_str() {
        "newton" => ImpactLaw::Newton,
        "stick" => ImpactLaw::Stick,
        "max-dissipation" => ImpactLaw::MaxDissipation,
        "min-slip" | "min-relative-velocity" => ImpactLaw::MinRelativeVelocity,
        "normal-impulse" => ImpactLaw::NormalImpulse,
        _ => bail_usage!(
            "--impact-law: unknown impact law `{name}`; expected one of: newton, stick, \
             max-dissipation, min-slip, normal-impulse"
        ),
    })
}

fn parse_mode(name: &str) -> Result<Mode> {
    Ok(match name {
        "free" => Mode::Free,
        "stick" => Mode::Stick,
        "slip" => Mode::Slip,
        _ => bail!("unknown mode `{name}`; expected free, stick or slip"),
    })
}

/// Builds the integrator settings from the CLI options (validated).
pub fn settings(args: &SimulateArgs) -> Result<SimSettings> {
    let method = match args.integrator.as_str() {
        "dopri5" => Method::Dopri5,
        "rk4" => Method::Rk4 { h: args.step() },
        other => bail_usage!("--integrator: unknown integrator `{other}`; expected dopri5 or rk4"),
    };
    // An option of the other integrator would be ignored: refused instead, also at its
    // default value (given is given).
    let foreign: &[(&str, bool)] = match method {
        Method::Dopri5 => &[("--step", args.step.is_some())],
        Method::Rk4 { .. } => &[
            ("--rtol", args.rtol.is_some()),
            ("--atol", args.atol.is_some()),
            ("--h-max", args.h_max.is_some()),
        ],
    };
    if let Some((opt, _)) = foreign.iter().find(|(_, given)| *given) {
        bail_usage!(
            "{opt} does not apply to --integrator {}: --step sets rk4's fixed step, --rtol, \
             --atol and --h-max the adaptive dopri5",
            args.integrator
        );
    }
    let pos = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(crate::errors::usage(format!(
                "{name} must be a finite number > 0 (got {})",
                crate::cli::shown(v)
            )))
        }
    };
    let rtol = args.rtol();
    pos("--rtol", rtol)?;
    if let Some(why) = bf_sim::rtol_out_of_range(rtol) {
        bail_usage!("--rtol {why}");
    }
    pos("--step", args.step())?;
    pos("--h-max", args.h_max())?;
    // The adaptive step's floor: a largest step below it leaves the controller no step.
    let h_min = SimSettings::default().h_min;
    if args.h_max() < h_min {
        return Err(crate::errors::usage(format!(
            "--h-max must be at least {h_min:e} s, the adaptive step's floor (got {})",
            crate::cli::shown(args.h_max())
        )));
    }
    let atol = args.atol.unwrap_or(1e-2 * rtol);
    pos("--atol", atol)?;
    if let Some(why) = bf_sim::atol_out_of_range(atol) {
        bail_usage!("--atol {why}");
    }
    if let Some(dt) = args.output_dt {
        pos("--output-dt", dt)?;
    }
    let set = SimSettings {
        method,
        rtol,
        atol,
        h_max: args.h_max(),
        max_steps: args.max_steps,
        output_dt: args.output_dt,
        ..SimSettings::default()
    };
    set.validate()?;
    Ok(set)
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct InitFile {
    q: Vec<f64>,
    #[serde(default)]
    qd: Option<Vec<f64>>,
    #[serde(default)]
    omega: [f64; 3],
    #[serde(default)]
    mode: Option<String>,
}

/// Initial mode and state of a finger with `N` joints from `--init` and the
/// `--q0/--qd0/--omega0/--mode0` overrides.
pub fn initial_state<const N: usize>(args: &SimulateArgs) -> Result<(Mode, State<N>)> {
    let mut q = [0.0; N];
    if N == 3 {
        q.copy_from_slice(&DEFAULT_Q0);
    }
    let (mut qd, mut w, mut mode) = ([0.0; N], [0.0; 3], None);
    if let Some(path) = &args.init {
        let text = bf_codegen::spec::read_input_text(path)
            .with_context(|| format!("{}: cannot read initial-state file", path.display()))?;
        let shape = || {
            format!(
                "{}: initial-state file must be JSON {{\"q\":[{N} numbers], \"qd\":[..], \
                 \"omega\":[3 numbers], \"mode\":\"free|stick|slip\"}} or a solution.json \
                 of `optimize`",
                path.display()
            )
        };
        let v: serde_json::Value = crate::io::json_value(&text).with_context(shape)?;
        if crate::pipeline::arm::is_arm_solution(&v) {
            bail!(
                "--init {}: an arm solution of `optimize --problem {}` (scene `{}`, without \
                 a ball), the scene of this run has a ball: replay it without --scene (the \
                 solution stores its arm scene)",
                path.display(),
                bf_problem::arm::REACH_ARM,
                v.get("scene").and_then(|s| s.as_str()).unwrap_or("?")
            );
        }
        let is_solution = ["schema_version", "problem", "nodes"]
            .iter()
            .any(|k| v.get(k).is_some());
        if is_solution {
            // A solution of `optimize` (one with a field deleted too, which the solution's
            // checks then name): replay it from its own initial state and mode.
            // Every error of the check names the file it is about.
            crate::pipeline::solution_io::check_public_fields(&v, path).context("--init")?;
            // Honest output: a replay of a plan that failed its own checks is no check of it.
            let status = v.get("status").and_then(|s| s.as_str()).unwrap_or("?");
            let verified = v.get("verified").and_then(|b| b.as_bool()) != Some(false);
            let converged = matches!(status, "Solved" | "Acceptable");
            if !verified || !converged {
                let why = match (verified, converged) {
                    (false, false) => format!("not verified, and its solve ended {status}"),
                    (false, true) => "not verified".to_string(),
                    _ => format!("from a solve that ended {status} (not converged)"),
                };
                crate::errln!(
                    "warning: --init {}: the solution is {why}: its replay shows that plan, \
                     not a verified optimum",
                    path.display(),
                );
            }
            // A plan replayed under another impact law than it was planned with is no replay
            // of its impacts (files before the law was recorded planned with eq. 40).
            let planned = v
                .get("impact_law")
                .and_then(|s| s.as_str())
                .unwrap_or("stick");
            let run_law = parse_impact_law(args.impact_law()).map(|l| l.name());
            let modes = v.get("modes").and_then(|m| m.as_array());
            let impacts = modes.is_some_and(|m| m.iter().any(|m| m != "free"));
            if impacts && run_law.is_ok_and(|l| l != planned) {
                crate::errln!(
                    "warning: --init {}: the solution was planned with the {planned} impact \
                     law, this run uses {} (--impact-law {planned} replays it under its own)",
                    path.display(),
                    args.impact_law()
                );
            }
            let (sq, sqd, sw, smode) = crate::pipeline::solution_io::initial_state_of(&v)
                .with_context(|| {
                    format!(
                        "{}: solution file without a readable first node (nodes, modes, \
                         state_names)",
                        path.display()
                    )
                })?;
            if sq.len() != N || sqd.len() != N {
                bail!(
                    "{}: the solution has {} joints, the scene {N}",
                    path.display(),
                    sq.len()
                );
            }
            q.copy_from_slice(&sq);
            qd.copy_from_slice(&sqd);
            w = sw;
            mode = Some(smode);
        } else {
            let f: InitFile = serde_json::from_value(v).with_context(shape)?;
            let fqd = f.qd.unwrap_or_else(|| vec![0.0; N]);
            for (name, v) in [("q", &f.q), ("qd", &fqd)] {
                if v.len() != N {
                    bail!(
                        "--init {}: `{name}` has {} values, the scene has {N} joints (one \
                         value per joint expected)",
                        path.display(),
                        v.len()
                    );
                }
            }
            q.copy_from_slice(&f.q);
            qd.copy_from_slice(&fqd);
            w = f.omega;
            mode = f.mode;
        }
        for (name, v) in [("q", &q[..]), ("qd", &qd[..]), ("omega", &w[..])] {
            if !v.iter().all(|x| x.is_finite()) {
                bail!("{}: `{name}` must be finite", path.display());
            }
        }
        if let Some(m) = &mode {
            parse_mode(m).with_context(|| format!("--init {}: `mode`", path.display()))?;
        }
    }
    if let Some(s) = &args.q0 {
        q.copy_from_slice(&parse_list("--q0", s, Some(N))?);
    }
    if let Some(s) = &args.qd0 {
        qd.copy_from_slice(&parse_list("--qd0", s, Some(N))?);
    }
    if let Some(s) = &args.omega0 {
        w.copy_from_slice(&parse_list("--omega0", s, Some(3))?);
    }
    // --mode0, given, overrides the file's mode; neither starts free.
    let mode = match (mode, args.mode0.as_deref()) {
        (_, Some(m)) => parse_mode(m).map_err(|e| crate::errors::usage(format!("--mode0: {e}")))?,
        (Some(m), None) => parse_mode(&m)?,
        (None, None) => parse_mode(crate::cli::DEFAULT_MODE0)?,
    };
    Ok((
        mode,
        State::new(VecN::<N>::from(q), VecN::<N>::from(qd), Vec3::from(w)),
    ))
}

/// Refuses a run that cannot fit its limits: fewer than the necessary steps or too many
/// samples (see the module docs). The error names the options and the limit.
pub(super) fn check_limits(args: &SimulateArgs, set: &SimSettings, run_end: RunEnd) -> Result<()> {
    let (h, h_opt) = match set.method {
        Method::Rk4 { h } => (h, "--step"),
        Method::Dopri5 => (set.h_max, "--h-max"),
    };
    let t_end = run_end.t;
    let end = run_end.named();
    let min_steps = t_end / h;
    // t_end / h overflows for a t_end near f64's largest; no count of steps is that large.
    let at_least = match min_steps.is_finite() {
        true => format!("at least {min_steps:.3e}"),
        false => "more than 1e308".to_string(),
    };
    let h = crate::cli::shown(h);
    if min_steps > args.max_steps as f64 {
        bail_usage!(
            "{end} needs {at_least} steps of at most {h_opt} {h} s, more than \
             --max-steps {}; shorten --t-end or raise --max-steps",
            args.max_steps
        );
    }
    if set.record_steps && min_steps > args.max_samples as f64 {
        bail_usage!(
            "{end} needs {at_least} steps of at most {h_opt} {h} s, each stored \
             as a sample, more than --max-samples {}; shorten --t-end or raise --max-samples",
            args.max_samples
        );
    }
    if let Some(dt) = args.output_dt {
        // The grid k·dt, k = 0 ..= ⌊t_end / dt⌋, besides the samples of the steps.
        let grid = (t_end / dt).floor() + 1.0;
        let steps = if set.record_steps { min_steps } else { 0.0 };
        let n = grid + steps;
        if n > args.max_samples as f64 {
            bail_usage!(
                "--output-dt {} s over {end} is {grid:.3e} grid samples{}, more than \
                 --max-samples {}; raise --output-dt or --max-samples",
                crate::cli::shown(dt),
                if steps > 0.0 {
                    format!(" and at least {steps:.3e} step samples")
                } else {
                    String::new()
                },
                args.max_samples
            );
        }
    }
    Ok(())
}

/// Advances `sim` to its end, or until it fails or reaches a limit of `args` (`--max-samples`,
/// `--max-time`), with the progress display: the error that stopped it, if any, and the
/// seconds it ran. The ball-and-finger and the arm runs share it, so both keep the limits.
pub(super) fn advance_within_limits<S: HybridSystem + ?Sized>(
    sim: &mut Simulator<'_, S>,
    args: &SimulateArgs,
    t0: f64,
    t_end: f64,
) -> Result<(Option<String>, f64)> {
    let mut progress = Progress::new(t0, t_end)?;
    let start = Instant::now();
    let mut error = None;
    loop {
        match sim.advance() {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                error = Some(crate::errors::chain(&e));
                break;
            }
        }
        let samples = sim.trajectory().len();
        if samples >= args.max_samples {
            error = Some(format!(
                "sample limit reached: {samples} samples (--max-samples {})",
                args.max_samples
            ));
            break;
        }
        // The clock and the progress display are looked at every 64 steps only.
        if sim.stats().accepted_steps % 64 == 0 {
            let elapsed = start.elapsed();
            if let Some(limit) = args.max_time
                && elapsed.as_secs_f64() > limit
            {
                let secs = elapsed.as_secs_f64();
                // One decimal of a second says nothing of a limit below a tenth.
                let secs = if secs < 0.1 {
                    format!("{secs:.1e}")
                } else {
                    format!("{secs:.1}")
                };
                error = Some(format!(
                    "time limit reached: {secs} s of computation (--max-time {limit})"
                ));
                break;
            }
            progress.update(elapsed, sim.t(), sim.stats().accepted_steps, samples);
        }
    }
    let cpu = start.elapsed().as_secs_f64();
    progress.finish();
    Ok((error, cpu))
}

/// What set a run's end: a message names it by that, never by a flag the command line did
/// not give.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum EndBy {
    /// `--t-end`.
    Flag,
    /// The duration of the `--init` solution replayed (an arm's).
    Solution,
    /// The last time of the `--torques` series.
    Series,
    /// [`crate::cli::DEFAULT_T_END`].
    Default,
}

/// A run's end time (s) and what set it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RunEnd {
    /// The end time (s).
    pub t: f64,
    /// What set it.
    pub by: EndBy,
}

impl RunEnd {
    /// The end as a message names it, e.g. "--t-end 2 s" or "the run's end at 0.3 s, where
    /// its --torques series ends (--t-end sets another)".
    pub(super) fn named(&self) -> String {
        let shown = crate::cli::shown(self.t);
        match self.by {
            EndBy::Flag => format!("--t-end {shown} s"),
            EndBy::Solution => format!(
                "the run's end at {shown} s, the duration of its --init solution (--t-end sets \
                 another)"
            ),
            EndBy::Series => format!(
                "the run's end at {shown} s, where its --torques series ends (--t-end sets \
                 another)"
            ),
            EndBy::Default => {
                format!("the default run's end at {shown} s (--t-end sets another)")
            }
        }
    }
}

/// The warnings of a run that holds a torque its series does not give: the first torque of a
/// `--torques` series that starts after the run does (at t = 0), until the series starts
/// ([`torques_held_after`] for its end).
pub(super) fn torques_held(inp: &CliInput, end: RunEnd) -> Vec<bf_sim::SimWarning> {
    let first = match inp {
        CliInput::Series(s) => s.times().first().copied().filter(|&t| t > 0.0),
        _ => None,
    };
    let before = first.map(|first| bf_sim::SimWarning {
        t: 0.0,
        kind: "torques_held",
        message: format!(
            "the --torques series starts at t = {} s, after the run starts at t = 0: the run \
             holds its first torque until then",
            crate::cli::shown(first)
        ),
    });
    before
        .into_iter()
        .chain(torques_held_after(inp, end))
        .collect()
}

/// The warning of a run that goes on past the end of its torques, whose last torque it then
/// holds: a `--torques` series (a solution's `torques.csv` covers one period, and held torques
/// are no replay of it) or an arm solution replayed by `--init` (its torques cover its own
/// duration). A run ends with its torques unless `--t-end` or a replayed solution sets
/// another end, or they end where the run starts (a one-row series: a constant torque, held
/// over the default run).
fn torques_held_after(inp: &CliInput, end: RunEnd) -> Option<bf_sim::SimWarning> {
    let last = inp.series_end()?;
    if end.t <= last * (1.0 + 1e-9) {
        return None;
    }
    let (what, advice) = match inp {
        CliInput::Replay(_) => (
            "the torques of the --init solution end",
            "they cover the solution's own duration (leave out --t-end to end the run with it)",
        ),
        _ => (
            "the --torques series ends",
            "a solution's torques.csv covers one period (end the run with the series by \
             leaving out --t-end, or, for a finger's solution, repeat it with --pd-track 0,0)",
        ),
    };
    let message = if last <= 0.0 && end.by == EndBy::Default {
        let at = if last < 0.0 {
            "before the run starts at t = 0"
        } else {
            "where the run starts"
        };
        format!(
            "{what} at t = {} s, {at}: its last torque is held to {}",
            crate::cli::shown(last),
            end.named()
        )
    } else {
        format!(
            "{what} at t = {} s and the run holds its last torque from there to {}; {advice}",
            crate::cli::shown(last),
            end.named()
        )
    };
    Some(bf_sim::SimWarning {
        t: last,
        kind: "torques_held",
        message,
    })
}

/// The run's initial angles `q` against the kernels' range ([`crate::commands::check_angles`]):
/// an angle of the command line's `--q0` is a usage error, one of an `--init` file's initial
/// state an error of that file, named.
pub(super) fn check_initial_angles(
    args: &SimulateArgs,
    scene: &bf_codegen::Scene,
    q: &[f64],
) -> Result<()> {
    match (&args.q0, &args.init) {
        (None, Some(path)) => {
            let source = format!("--init {}: its initial state", path.display());
            match crate::commands::angle_beyond_range(&source, scene, q) {
                Some(why) => bail!("{why}"),
                None => Ok(()),
            }
        }
        _ => crate::commands::check_angles("--q0", scene, q),
    }
}

/// Refuses an end time that is not a finite number > 0.
pub(super) fn check_t_end(t_end: f64) -> Result<()> {
    if !(t_end.is_finite() && t_end > 0.0) {
        bail_usage!(
            "--t-end must be a finite number > 0 (got {})",
            crate::cli::shown(t_end)
        );
    }
    Ok(())
}

/// Run `simulate`.
pub fn run(args: &SimulateArgs) -> Result<()> {
    run_with(args, RunSettings::default())
}

/// Run `simulate` with `opts`.
pub fn run_with(args: &SimulateArgs, opts: RunSettings) -> Result<()> {
    args.chain
        .check_given_with(args.scene.as_deref(), "--scene")?;
    if let Some(path) = &args.init {
        crate::commands::optimize::check_solution_values("--init", path)?;
    }
    let (scene, scene_label) = scene_of_args(args)?;
    if scene.ball.is_none() {
        return run_arm(args, opts, &scene, &scene_label);
    }
    // Validate every option before the (possibly long) run; a default end time is valid.
    if let Some(t_end) = args.t_end {
        check_t_end(t_end)?;
    }
    let nq = scene.links.len();
    match nq {
        1 => run_contact::<1>(args, opts, &scene, &scene_label),
        2 => run_contact::<2>(args, opts, &scene, &scene_label),
        3 => run_contact::<3>(args, opts, &scene, &scene_label),
        4 => run_contact::<4>(args, opts, &scene, &scene_label),
        5 => run_contact::<5>(args, opts, &scene, &scene_label),
        6 => run_contact::<6>(args, opts, &scene, &scene_label),
        7 => run_contact::<7>(args, opts, &scene, &scene_label),
        n => bail!(
            "{scene_label}: scene `{}` has {n} joints; the ball-and-finger simulator runs fingers \
             with 1 to {MAX_CONTACT_JOINTS} joints",
            scene.name
        ),
    }
}

/// The contact run of a finger with `N` joints (options validated before the run).
fn run_contact<const N: usize>(
    args: &SimulateArgs,
    opts: RunSettings,
    scene: &bf_codegen::Scene,
    scene_label: &str,
) -> Result<()> {
    let set = settings(args)?;
    let inp = input(args, &scene.name, N)?;
    let end = run_end(args, &inp, None);
    check_limits(args, &set, end)?;
    let law = parse_impact_law(args.impact_law())?;
    let (mode0, x0) = initial_state::<N>(args)?;
    check_initial_angles(args, scene, x0.q.as_slice())?;
    if let (CliInput::Series(s), Some(path)) = (&inp, &args.torques) {
        let m = max_torque(s);
        if m > LARGE_TORQUE {
            crate::errln!(
                "warning: --torques {}: |τ| reaches {m:e} N m (the paper's bound is 1 N m); \
                 expect very small steps",
                path.display()
            );
        }
    }
    let run_opts = opts;
    let opts = BallFingerSettings {
        impact_law: law,
        project: !args.no_projection,
        ..BallFingerSettings::default()
    };
    let setup = Instant::now();
    let (kernels, source) = bf_model::registry::contact_kernels_n::<N>(scene)
        .with_context(|| format!("{scene_label}: scene cannot be simulated"))?;
    let model = Model::from_kernels(kernels)
        .with_context(|| format!("{scene_label}: scene cannot be simulated"))?;
    crate::errln!(
        "simulate: scene `{}` from {scene_label} on the {source} kernels{}",
        scene.name,
        interpreted_note(source, setup.elapsed())
    );
    let run = Run {
        set,
        mode0,
        x0,
        end,
    };
    run_model(args, run_opts, model, source, inp, opts, run)
}

/// Where a run ends: `--t-end`, or the end of its `--torques` series or replayed solution
/// where it is after the start (a replay of a solution's torques ends with them), or the
/// `solution` duration of an arm's `--init` solution (when `--pd` drives the arm from its
/// start), or [`crate::cli::DEFAULT_T_END`].
pub(super) fn run_end(args: &SimulateArgs, inp: &CliInput, solution: Option<f64>) -> RunEnd {
    let by_input = inp.series_end().filter(|&t| t > 0.0).map(|t| RunEnd {
        t,
        by: match inp {
            CliInput::Replay(_) => EndBy::Solution,
            _ => EndBy::Series,
        },
    });
    // A --torques series sets the end itself, or leaves the default (one that ends where the
    // run starts is a constant torque): the solution gives only the start then.
    let by_solution = solution
        .filter(|_| !matches!(inp, CliInput::Series(_)))
        .map(|t| RunEnd {
            t,
            by: EndBy::Solution,
        });
    match args.t_end {
        Some(t) => RunEnd { t, by: EndBy::Flag },
        None => by_input.or(by_solution).unwrap_or(RunEnd {
            t: crate::cli::DEFAULT_T_END,
            by: EndBy::Default,
        }),
    }
}

/// The integration of a contact run: settings, initial mode and state, end time.
struct Run<const N: usize> {
    set: SimSettings,
    mode0: Mode,
    x0: State<N>,
    end: RunEnd,
}

/// What running on interpreted kernels means, for the stderr line (empty for compiled ones).
fn interpreted_note(source: KernelSource, setup: Duration) -> String {
    match source {
        KernelSource::Compiled => String::new(),
        KernelSource::Interpreted => format!(
            " (not a compiled scene: kernels built at run time from its expression graphs in \
             {:.0} ms, evaluated by the interpreter, slower per call than compiled ones)",
            1e3 * setup.as_secs_f64()
        ),
    }
}

/// Names the options the initial state came from, for errors about it.
pub(super) fn initial_state_options(args: &SimulateArgs) -> String {
    let mut v: Vec<String> = Vec::new();
    if let Some(p) = &args.init {
        v.push(format!("--init {}", p.display()));
    }
    for (name, value) in [
        ("--q0", &args.q0),
        ("--qd0", &args.qd0),
        ("--omega0", &args.omega0),
    ] {
        if let Some(x) = value {
            v.push(format!("{name} {x}"));
        }
    }
    if v.is_empty() {
        "the default initial state".into()
    } else {
        v.join(", ")
    }
}

/// Names the torque input, for errors about non-finite values.
pub(super) fn input_options(args: &SimulateArgs, inp: &CliInput) -> String {
    match (inp, &args.torques) {
        (CliInput::Series(s), Some(p)) => {
            format!(
                "--torques {} (|τ| up to {:e} N m)",
                p.display(),
                max_torque(s)
            )
        }
        (CliInput::Tracking(_), _) => format!(
            "--pd-track {} on the solution of --init",
            args.pd_track.as_deref().unwrap_or("")
        ),
        (CliInput::Pd(_), _) => format!(
            "--pd {} --pd-gains {}",
            args.pd.as_deref().unwrap_or(""),
            args.pd_gains
        ),
        (CliInput::Replay(_), _) => "the torques of the --init solution".into(),
        _ => "zero torques".into(),
    }
}

fn run_model<K: Kernels<N>, const N: usize>(
    args: &SimulateArgs,
    run_opts: RunSettings,
    model: Model<K, N>,
    source: KernelSource,
    inp: CliInput,
    opts: BallFingerSettings,
    run: Run<N>,
) -> Result<()> {
    let Run {
        set,
        mode0,
        x0,
        end,
    } = run;
    let t_end = end.t;
    let inputs = input_options(args, &inp);
    let held = torques_held(&inp, end);
    let sys = BallFinger::new(model, inp, opts)?;
    let x0 = x0.to_vec();
    // Overflow at the initial state (e.g. --qd0 1e300) would otherwise surface as an error
    // deep in the first step that names neither the option nor the quantity.
    // The contact modes hold the finger on the ball (h = 0): started away from it, their
    // forces are not defined and every quantity below would only say "not finite".
    // h depends on q only: evaluated at rest, so that an overflowing --qd0 is named below.
    let mut at_rest = x0.clone();
    at_rest[N..].iter_mut().for_each(|v| *v = 0.0);
    let h0 = sys.gap(&at_rest)?;
    let tol = sys.model.settings().contact_tolerance * sys.model.params().ball_radius();
    if mode0 == Mode::Free && h0 < -tol {
        bail!("the initial state penetrates the ball: h(q0) = {h0:e} m");
    }
    if mode0 != Mode::Free && h0.abs() > tol {
        bail!(
            "initial mode {} (--mode0 or --init): a contact mode needs the finger on the \
             ball, but the distance h(q0) = {h0:e} m exceeds the contact tolerance {tol:e} m; \
             start with --mode0 free, or with --q0 on the ball",
            crate::names::name(&mode0)
        );
    }
    let info = sys.sample_info(mode0, 0.0, &x0).map_err(|e| {
        anyhow!(
            "the model cannot be evaluated at the initial state in mode {}: {}; initial state: \
             {}; torques: {inputs}",
            crate::names::name(&mode0),
            crate::errors::chain(&e),
            initial_state_options(args)
        )
    })?;
    let mut quantities = vec![
        ("energy".to_string(), info.energy),
        ("distance h".to_string(), info.h),
    ];
    quantities.extend(
        info.tau
            .iter()
            .enumerate()
            .map(|(i, &t)| (format!("torque τ{}", i + 1), t)),
    );
    if let Some((name, v)) = quantities.iter().find(|(_, v)| !v.is_finite()) {
        bail!(
            "the {name} at the initial state is not finite ({v}); initial state: {}; \
             torques: {inputs}",
            initial_state_options(args)
        );
    }
    // A contact mode holds the contact point on the ball's surface (n·v_c = 0, eq. 36), and
    // Stick also with it (Δv = 0, eq. 13). The first step's projection would remove any
    // mismatch without an event, so a finger started moving off the ball, or slipping in
    // Stick, would silently lose that motion and its energy.
    if mode0 != Mode::Free {
        let vtol = sys.model.settings().slip_eps;
        let slip = if mode0 == Mode::Stick {
            info.slip_speed
        } else {
            0.0
        };
        if info.normal_velocity.abs() > vtol || slip > vtol {
            bail!(
                "initial mode {} (--mode0 or --init): the contact point must move with the \
                 ball's surface{}, but n·v_c = {:.3e} m/s and ‖Δv‖ = {:.3e} m/s at the initial \
                 state (tolerance {vtol:e} m/s); give velocities that keep the contact (e.g. \
                 --qd0 0 and --omega0 0), or start in {}; initial state: {}",
                crate::names::name(&mode0),
                if mode0 == Mode::Stick {
                    " and stick to it (n·v_c = 0, Δv = 0)"
                } else {
                    " (n·v_c = 0)"
                },
                info.normal_velocity,
                info.slip_speed,
                if mode0 == Mode::Stick {
                    "slip (--mode0 slip) if it slides, or free if it leaves the ball"
                } else {
                    "free (--mode0 free)"
                },
                initial_state_options(args)
            );
        }
    }
    let mut out_dir = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    if let Some(n) = run_opts.fail_at_write {
        out_dir.inject_fault_at_write(n);
    }
    let t0 = 0.0;
    // A trait object: one compiled copy of the simulator serves every joint count (the virtual
    // calls cost nothing beside the kernels they make).
    let dyn_sys: &dyn HybridSystem<Mode = Mode> = &sys;
    // Finite torques can still overflow the accelerations (M⁻¹ τ): the error names the inputs.
    let mut sim = Simulator::new(dyn_sys, set, mode0, t0, &x0, t_end).map_err(|e| {
        anyhow!(
            "cannot start the simulation: {e}; initial state: {}; torques: {inputs}",
            initial_state_options(args)
        )
    })?;
    let (error, cpu) = advance_within_limits(&mut sim, args, t0, t_end)?;
    let (t_stop, mode_stop) = (sim.t(), sim.mode());
    let out = sim.finish();
    let mut report = sys.report(&out, t0, cpu);
    report.summary.kernels = Some(source.name().to_string());
    report.summary.warnings.extend(held);
    // A run that ends with a non-finite energy has not produced a result, whatever the
    // integrator said.
    let s = &report.summary;
    let error = error.or_else(|| {
        [
            ("initial energy", s.energy_initial),
            ("final energy", s.energy_final),
            ("final time", s.t_final),
        ]
        .iter()
        .find(|(_, v)| !v.is_finite())
        .map(|(name, v)| format!("the {name} of the run is not finite ({v})"))
    });
    let error = error.map(|e| {
        let non_finite = ["finite", "NaN", "inf"].iter().any(|w| e.contains(w));
        if non_finite {
            format!(
                "{e} (initial state: {}; torques: {inputs})",
                initial_state_options(args)
            )
        } else {
            e
        }
    });
    // A run that ends but whose energy balance fails its own check (the integration too
    // coarse for the dynamics) has a trajectory no one should take for a result: the set is
    // written whole and marked as failed. A run that stopped early reports its stop instead
    // (`failure`).
    let unbalanced = report.summary.energy_check_failure().map(|w| {
        format!(
            "the energy balance failed its check at t = {} s: {}; the whole trajectory ({} \
                 samples, {} events) was written to {}",
            w.t,
            w.message,
            out.trajectory.len(),
            out.events.len(),
            args.out.display()
        )
    });
    out_dir.file("summary.json")?;
    report
        // summary.json's `error` says why the run is no result, as an arm's does.
        .write_dir(
            out_dir.path(),
            &out,
            error.as_deref().or(unbalanced.as_deref()),
        )
        .map_err(|e| anyhow!(out_dir.rename_in(&crate::errors::chain(&e))))
        .with_context(|| format!("cannot write the output to {}", args.out.display()))?;
    let failure = error.as_ref().map(|e| {
        format!(
            "simulation failed at t = {t_stop} s in mode {}: {e}\n\
             the trajectory up to the failure ({} samples, {} events) was written to {}",
            crate::names::name(&mode_stop),
            out.trajectory.len(),
            out.events.len(),
            args.out.display()
        )
    });
    let failure = failure.or(unbalanced);
    out_dir.commit(match &failure {
        Some(f) => Outcome::Failed(f),
        None => Outcome::Success,
    })?;
    crate::outln!(
        "scene {} ({source} kernels), impact law {}, {}",
        sys.model.kernels().scene_name(),
        opts.impact_law.name(),
        describe_method(&args.integrator, args)
    )?;
    crate::outln!("{}", report.summary)?;
    for line in report.summary.warning_lines() {
        crate::errln!("warning: {line}");
    }
    crate::outln!("output: {}", args.out.display())?;
    match failure {
        Some(f) => bail!("{f}"),
        None => Ok(()),
    }
}

fn describe_method(name: &str, args: &SimulateArgs) -> String {
    if name == "rk4" {
        format!("rk4, step {} s", args.step())
    } else {
        format!(
            "dopri5, rtol {:e}, atol {:e}",
            args.rtol(),
            args.atol.unwrap_or(1e-2 * args.rtol())
        )
    }
}
