//! `ball-finger simulate`: the hybrid ball-and-finger model of the paper's Sect. 3 / Fig. 3
//! (modes Free / Stick / Slip, eq. 44–47; transitions eq. 48–50, σ ≤ 0, ‖Δv‖ ≤ ε; impact laws
//! eq. 39–43) driven by an open-loop torque series (Sect. 6.2) or a joint-space PD controller.
//!
//! ```text
//! ball-finger simulate --scene scenes/paper.toml [--torques FILE | --pd TARGET [--pd-gains KP,KD]]
//!     [--q0 Q --qd0 QD --omega0 W --mode0 free|stick|slip | --init FILE]
//!     [--t-end S] [--integrator dopri5|rk4] [--rtol X] [--atol X] [--step H]
//!     [--impact-law newton|stick|max-dissipation|min-slip] [--no-projection] [--output-dt DT]
//!     --out DIR
//! ```
//!
//! Only the built-in contact scenes run (the scene file must be exactly `scenes/paper.toml` or
//! `scenes/human.toml`), because the simulator evaluates the compiled kernels. Output in DIR:
//! `trajectory.{json,csv}` (t, mode, q, q̇, ω, τ, λ, λ_n, h, σ, ‖Δv‖, ḣ, E, drift per sample),
//! `events.{json,csv}` and `summary.json`, all written atomically; a summary goes to stdout.
//! A run that fails midway still writes everything up to the failure and exits non-zero.

use crate::cli::SimulateArgs;
use crate::io::parse_list;
use anyhow::{Context, Result, anyhow, bail};
use bf_model::{HumanKernels, ImpactLaw, Kernels, Mode, Model, PaperKernels, State, Vec3};
use bf_sim::ball_finger::{BallFinger, BallFingerOptions};
use bf_sim::{
    Input, Method, PdController, SimError, SimSettings, Simulator, StopReason, TorqueSeries,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;
use std::time::{Duration, Instant};

/// Default initial joint angles (rad): the paper's "q constant nonzero" initial guess
/// (PARAMS.md); for the paper scene the fingertip is then 1.4 m above the ball.
pub const DEFAULT_Q0: [f64; 3] = [0.1, 0.5, 0.5];

/// Joint torques of a CLI run: a time series, a PD controller, or none (τ = 0).
#[derive(Debug, Clone)]
pub enum CliInput {
    /// Open-loop torques τ(t) (`--torques`).
    Series(TorqueSeries),
    /// τ = kp (target − q) − kd q̇ (`--pd`).
    Pd(PdController),
    /// Unactuated joints.
    Zero,
}

impl Input for CliInput {
    fn dim(&self) -> usize {
        match self {
            CliInput::Series(s) => s.dim(),
            CliInput::Pd(p) => p.dim(),
            CliInput::Zero => 3,
        }
    }
    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        match self {
            CliInput::Series(s) => s.tau(t, q, qd, out),
            CliInput::Pd(p) => p.tau(t, q, qd, out),
            CliInput::Zero => {
                out.fill(0.0);
                Ok(())
            }
        }
    }
}

/// Parses an impact-law name of the CLI (`newton`, `stick`, `max-dissipation`, `min-slip`,
/// `normal-impulse`; underscores are accepted too).
pub fn parse_impact_law(name: &str) -> Result<ImpactLaw> {
    Ok(match name.replace('_', "-").as_str() {
        "newton" => ImpactLaw::Newton,
        "stick" => ImpactLaw::Stick,
        "max-dissipation" => ImpactLaw::MaxDissipation,
        "min-slip" | "min-relative-velocity" => ImpactLaw::MinRelativeVelocity,
        "normal-impulse" => ImpactLaw::NormalImpulse,
        _ => bail!(
            "unknown impact law `{name}`; expected one of: newton, stick, max-dissipation, \
             min-slip, normal-impulse"
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
        "rk4" => Method::Rk4 { h: args.step },
        other => bail!("unknown integrator `{other}`; expected dopri5 or rk4"),
    };
    let pos = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(anyhow!("{name} must be a finite number > 0 (got {v})"))
        }
    };
    pos("--rtol", args.rtol)?;
    pos("--step", args.step)?;
    pos("--h-max", args.h_max)?;
    let atol = args.atol.unwrap_or(1e-2 * args.rtol);
    pos("--atol", atol)?;
    if let Some(dt) = args.output_dt {
        pos("--output-dt", dt)?;
    }
    let set = SimSettings {
        method,
        rtol: args.rtol,
        atol,
        h_max: args.h_max,
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
    q: [f64; 3],
    #[serde(default)]
    qd: [f64; 3],
    #[serde(default)]
    omega: [f64; 3],
    #[serde(default)]
    mode: Option<String>,
}

/// Initial mode and state from `--init` and the `--q0/--qd0/--omega0/--mode0` overrides.
pub fn initial_state(args: &SimulateArgs) -> Result<(Mode, State)> {
    let (mut q, mut qd, mut w, mut mode) = (DEFAULT_Q0, [0.0; 3], [0.0; 3], None);
    if let Some(path) = &args.init {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read initial-state file", path.display()))?;
        let f: InitFile = serde_json::from_str(&text).with_context(|| {
            format!(
                "{}: initial-state file must be JSON {{\"q\":[3 numbers], \"qd\":[..], \
                 \"omega\":[..], \"mode\":\"free|stick|slip\"}}",
                path.display()
            )
        })?;
        (q, qd, w) = (f.q, f.qd, f.omega);
        mode = f.mode;
        for (name, v) in [("q", &q), ("qd", &qd), ("omega", &w)] {
            if !v.iter().all(|x| x.is_finite()) {
                bail!("{}: `{name}` must be finite", path.display());
            }
        }
    }
    let arr = |v: Vec<f64>| [v[0], v[1], v[2]];
    if let Some(s) = &args.q0 {
        q = arr(parse_list("--q0", s, Some(3))?);
    }
    if let Some(s) = &args.qd0 {
        qd = arr(parse_list("--qd0", s, Some(3))?);
    }
    if let Some(s) = &args.omega0 {
        w = arr(parse_list("--omega0", s, Some(3))?);
    }
    // --mode0 has a default, so the file's mode wins unless --mode0 is given explicitly as
    // something other than the default.
    let mode = match (mode, args.mode0.as_str()) {
        (Some(m), "free") => parse_mode(&m)?,
        (_, m) => parse_mode(m)?,
    };
    Ok((
        mode,
        State::new(Vec3::from(q), Vec3::from(qd), Vec3::from(w)),
    ))
}

/// The joint torques of the run.
pub fn input(args: &SimulateArgs) -> Result<CliInput> {
    if let Some(path) = &args.torques {
        let s = TorqueSeries::from_path(path)?;
        if s.dim() != 3 {
            bail!(
                "{}: the contact scenes have 3 joints, the torque series has {} columns",
                path.display(),
                s.dim()
            );
        }
        return Ok(CliInput::Series(s));
    }
    if let Some(target) = &args.pd {
        let target = parse_list("--pd", target, Some(3))?;
        let g = parse_list("--pd-gains", &args.pd_gains, None)?;
        let (kp, kd) = match g.len() {
            2 => (vec![g[0]; 3], vec![g[1]; 3]),
            6 => (g[..3].to_vec(), g[3..].to_vec()),
            n => bail!("--pd-gains: expected 2 values (kp,kd) or 6 (kp1..3,kd1..3), got {n}"),
        };
        return Ok(CliInput::Pd(PdController::new(kp, kd, target)?));
    }
    Ok(CliInput::Zero)
}

/// Run `simulate`.
pub fn run(args: &SimulateArgs) -> Result<()> {
    let (scene, text) = super::load_scene(&args.scene)?;
    // Validate every option before the (possibly long) run.
    if !(args.t_end.is_finite() && args.t_end > 0.0) {
        bail!("--t-end must be a finite number > 0 (got {})", args.t_end);
    }
    let set = settings(args)?;
    let law = parse_impact_law(&args.impact_law)?;
    let (mode0, x0) = initial_state(args)?;
    let inp = input(args)?;
    let opts = BallFingerOptions {
        impact_law: law,
        project: !args.no_projection,
        ..BallFingerOptions::default()
    };
    match scene.name.as_str() {
        "paper" if text == bf_generated::paper::SCENE_TOML => {
            let model = Model::from_kernels(PaperKernels::new())?;
            run_model(args, model, inp, opts, set, mode0, x0)
        }
        "human" if text == bf_generated::human::SCENE_TOML => {
            let model = Model::from_kernels(HumanKernels::new())?;
            run_model(args, model, inp, opts, set, mode0, x0)
        }
        name => bail!(
            "{}: scene `{name}` cannot be simulated: only the built-in contact scenes \
             (scenes/paper.toml and scenes/human.toml, unmodified) can be simulated, because \
             simulation uses the compiled kernels (edit a scene, then rebuild with it as a \
             built-in scene to simulate it)",
            args.scene.display()
        ),
    }
}

fn run_model<K: Kernels>(
    args: &SimulateArgs,
    model: Model<K>,
    inp: CliInput,
    opts: BallFingerOptions,
    set: SimSettings,
    mode0: Mode,
    x0: State,
) -> Result<()> {
    let sys = BallFinger::new(model, inp, opts)?;
    let x0 = x0.to_array();
    let h0 = sys.gap(&x0)?;
    let tol = sys.model.settings().contact_tolerance * sys.model.params().ball_radius();
    if mode0 == Mode::Free && h0 < -tol {
        bail!("the initial state penetrates the ball: h(q0) = {h0:e} m");
    }
    let t0 = 0.0;
    let t_end = args.t_end;
    let mut sim = Simulator::new(&sys, set, mode0, t0, &x0, t_end)
        .map_err(|e| anyhow!("cannot start the simulation: {e}"))?;
    let pb = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::hidden());
    pb.set_style(
        ProgressStyle::with_template("simulate {bar:40} t = {msg} s ({elapsed}, eta {eta})")
            .map_err(|e| anyhow!("progress bar template: {e}"))?,
    );
    let start = Instant::now();
    let mut shown = false;
    let mut error = None;
    loop {
        let r = match sim.step() {
            Ok(StopReason::Step) => Ok(()),
            Ok(StopReason::RootFound { .. }) => sim.apply_reset(),
            Ok(StopReason::TEndReached | StopReason::Terminated) => break,
            Err(e) => Err(e),
        };
        if let Err(e) = r {
            error = Some(e);
            break;
        }
        // Only long runs get a visible bar (checked cheaply every 64 steps).
        if sim.stats().accepted_steps % 64 == 0 {
            if !shown && start.elapsed() > Duration::from_millis(500) {
                pb.set_draw_target(ProgressDrawTarget::stderr());
                shown = true;
            }
            if shown {
                pb.set_position((1000.0 * (sim.t() - t0) / (t_end - t0)) as u64);
                pb.set_message(format!("{:.3}", sim.t()));
            }
        }
    }
    let cpu = start.elapsed().as_secs_f64();
    pb.finish_and_clear();
    let (t_stop, mode_stop) = (sim.t(), sim.mode());
    let out = sim.finish();
    let report = sys.report(&out, t0, cpu);
    let msg = error.as_ref().map(|e| e.to_string());
    report
        .write_dir(&args.out, &out, msg.as_deref())
        .with_context(|| format!("cannot write the output to {}", args.out.display()))?;
    println!(
        "scene {}, impact law {}, {}",
        sys.model.kernels().scene_name(),
        opts.impact_law.name(),
        describe_method(&args.integrator, args)
    );
    println!("{}", report.summary);
    for line in report.summary.warning_lines() {
        eprintln!("warning: {line}");
    }
    println!("output: {}", args.out.display());
    if let Some(e) = error {
        bail!(
            "simulation failed at t = {t_stop} s in mode {mode_stop:?}: {e}\n\
             the trajectory up to the failure ({} samples, {} events) was written to {}",
            out.trajectory.len(),
            out.events.len(),
            Path::new(&args.out).display()
        );
    }
    Ok(())
}

fn describe_method(name: &str, args: &SimulateArgs) -> String {
    if name == "rk4" {
        format!("rk4, step {} s", args.step)
    } else {
        format!(
            "dopri5, rtol {:e}, atol {:e}",
            args.rtol,
            args.atol.unwrap_or(1e-2 * args.rtol)
        )
    }
}
