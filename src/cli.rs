//! Command-line definitions (clap). Each subcommand maps to one stage of the pipeline:
//! `generate`/`eval` (the code generator, replacing the paper's Maple step, Sect. 5),
//! `simulate` (hybrid model of Sect. 3 / Fig. 3), `optimize` (multiphase optimal control,
//! Sect. 4), `paper` (the study of Sect. 6 end to end) and `report`.

use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};

/// Parses a number that must be finite and > 0. Negative values reach this parser (the options
/// allow leading hyphens), so the message says why `-1e-8` is wrong rather than calling it an
/// unknown argument.
pub fn positive(text: &str) -> Result<f64, String> {
    finite_number(text, |v| v > 0.0, "> 0")
}

pub use bf_sim::shown;

/// Parses a number that must be finite and ≥ 1 (a step-size cap).
pub fn at_least_one(text: &str) -> Result<f64, String> {
    finite_number(text, |v| v >= 1.0, "≥ 1")
}

/// Parses a finite number ≥ 0 (a weight that 0 turns off).
pub fn nonnegative(text: &str) -> Result<f64, String> {
    finite_number(text, |v| v >= 0.0, "≥ 0")
}

/// Parses a finite number for which `ok` holds; the message says it must be `bound`.
fn finite_number(text: &str, ok: impl Fn(f64) -> bool, bound: &str) -> Result<f64, String> {
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a number"))?;
    if v.is_finite() && ok(v) {
        Ok(v)
    } else {
        Err(format!(
            "must be a finite number {bound} (got {})",
            text.trim()
        ))
    }
}

/// Parses `--starts`: a whole number from 1 to 10000.
pub fn starts(text: &str) -> Result<u64, String> {
    match whole(text)? {
        n @ 1..=10000 => Ok(n as u64),
        n => Err(format!("must be from 1 to 10000 (got {n})")),
    }
}

/// Parses the periods of a tracking run: 1 to
/// [`MAX_TRACKING_PERIODS`](crate::paper::closed_loop::MAX_TRACKING_PERIODS), since every
/// period's samples are kept.
pub fn tracking_periods(text: &str) -> Result<usize, String> {
    use crate::paper::closed_loop::MAX_TRACKING_PERIODS;
    match whole(text)? {
        n @ 1..=MAX_TRACKING_PERIODS => Ok(n),
        n => Err(format!(
            "must be from 1 to {MAX_TRACKING_PERIODS} (got {n}); every period's samples are kept"
        )),
    }
}

/// Parses a whole number ≥ 0, with a message for negative and fractional values.
pub fn whole(text: &str) -> Result<usize, String> {
    let t = text.trim();
    if let Ok(v) = t.parse::<i128>() {
        return if v < 0 {
            Err(format!("must be a whole number, not negative (got {v})"))
        } else {
            usize::try_from(v).map_err(|_| format!("{v} is too large"))
        };
    }
    Err(format!("must be a whole number (got {text:?})"))
}

/// Parses a whole number ≥ 1 (a count or a limit that 0 would make empty).
pub fn positive_whole(text: &str) -> Result<usize, String> {
    match whole(text)? {
        0 => Err("must be a whole number ≥ 1 (got 0)".into()),
        v => Ok(v),
    }
}

/// ball-finger: a DH table or a URDF → verified flat Rust dynamics kernels; simulate, optimise
/// and control a finger rolling a trackball (Ball-and-finger system: modeling and optimal
/// trajectories).
#[derive(Debug, Parser)]
#[command(name = "ball-finger", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
    /// Nodes an expression graph may hold (kernels and node functions of a scene): a robot
    /// whose kernels need more ends with an error that names them instead of exhausting the
    /// machine's memory (up to about 400 bytes a node at the generator's peak) [default:
    /// 16777216, about 6 GiB]
    #[arg(long, global = true, value_name = "NODES", value_parser = clap::value_parser!(u64).range(1..u32::MAX as u64))]
    pub max_graph_nodes: Option<u64>,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once per process; boxing buys nothing
pub enum Command {
    /// Generate Rust kernels for a scene file (stdout or a file).
    Generate(GenerateArgs),
    /// Evaluate every kernel of a scene at one state and print one JSON object.
    Eval(EvalArgs),
    /// Time every kernel of a scene, compiled and interpreted, over random states.
    Bench(BenchArgs),
    /// Simulate the hybrid ball-and-finger model (paper Sect. 3, Fig. 3).
    Simulate(Box<SimulateArgs>),
    /// Solve a multiphase optimal-control problem (paper Sect. 4).
    ///
    /// Exit status: 0 when the solution is Solved or Acceptable and verified (re-integration
    /// defect at most 1e-4, after hp refinement if needed, and for a plan for the plant, a
    /// periodic problem with Newton's impact law, executed by `track`'s controller on the
    /// nominal plant; a perturbed plant of the robustness table that misses its target is
    /// printed as "robustness: MISSED" and recorded in solution.json, and the search prefers
    /// plans that meet it: docs/closed-loop.md) or not re-integrated (--verify-rtol 0); 1 when
    /// it did not converge or is unverified (the output set is still written, marked FAILED;
    /// solution.json's `status` says whether the solve converged, and `verification.verified`
    /// whether its re-integration agrees, with the defect: a solve stopped early can describe
    /// the model's motion and still be no optimum) and for other errors; 2 for usage errors.
    Optimize(OptimizeArgs),
    /// Reproduce the paper's study (Sect. 6) and write a report.
    Paper(PaperArgs),
    /// Write a stand-alone report.
    Report(ReportArgs),
    /// Execute an optimum in closed loop on the hybrid model (paper Sect. 6.2, 7): open loop,
    /// joint PD, or the hybrid controller (computed torque in free phases, event-timed
    /// force/velocity control in contact). Writes the files of `simulate` plus tracking.json.
    /// Which plans can be executed, and what to look at when one is not: docs/closed-loop.md.
    ///
    /// Exit status: 0 when every period made contact and all periods completed; 1 when the run
    /// lost the ball (the output set is still written, marked FAILED, and tracking.json says
    /// why) or its energy balance failed the simulator's check (marked FAILED likewise), and
    /// for other errors; 2 for usage errors.
    Track(TrackArgs),
    /// Check the paper against derivations (`appendix`: each Appendix A/B formula as printed
    /// vs derived, and the misprints; exits non-zero if a derivation fails).
    Verify(VerifyArgs),
}

/// Arguments of `generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// Scene file (TOML, or a URDF), e.g. scenes/paper.toml.
    pub scene: PathBuf,
    /// URDF scene file: the serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Write the generated Rust source to this file instead of stdout.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the op counts of every kernel, then the graph size, the code size and the total
    /// generation time (to stderr when the code goes to stdout).
    #[arg(long)]
    pub report: bool,
    /// Float type of the emitted kernels: arguments, constants and arithmetic.
    #[arg(long, value_enum, default_value_t = FloatArg::F64)]
    pub float: FloatArg,
    /// Emit every `a*b ± c` as a fused multiply-add (`mul_add`, one rounding instead of two).
    #[arg(long)]
    pub fma: bool,
    /// Emit a module for a `#![no_std]` crate: its own square root, sine and cosine, no
    /// allocating `eval_flat` (not with --fma).
    #[arg(long, conflicts_with = "fma")]
    pub no_std: bool,
}

/// `--base`/`--tip`: which serial chain of a URDF scene file is the model (docs/scene-format.md).
#[derive(Debug, Clone, Default, Args)]
pub struct ChainArgs {
    /// URDF: the chain's base link [default: the root link]; it stays where the URDF's joints
    /// from the root put it (moving ones at 0), the root being at the world origin.
    #[arg(long = "base", value_name = "LINK")]
    pub base: Option<String>,
    /// URDF: the chain's tip link [default: the leaf of a tree that does not branch].
    #[arg(long = "tip", value_name = "LINK")]
    pub tip: Option<String>,
}

impl ChainArgs {
    /// A usage error if `--base` or `--tip` is given without the scene option `option` they
    /// apply to (`scene` is that option's value).
    pub fn check_given_with(&self, scene: Option<&Path>, option: &str) -> anyhow::Result<()> {
        if scene.is_none() && (self.base.is_some() || self.tip.is_some()) {
            return Err(crate::errors::usage(format!(
                "--base/--tip choose the chain of a URDF scene; they need {option}"
            )));
        }
        Ok(())
    }

    /// As the scene loader's chain choice.
    pub fn choice(&self) -> bf_codegen::spec::ChainChoice {
        bf_codegen::spec::ChainChoice {
            base: self.base.clone(),
            tip: self.tip.clone(),
        }
    }
}

/// `--float` of `generate`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FloatArg {
    /// Double precision (the default; the module's own batched sine–cosine).
    F64,
    /// Single precision (the module's own sine–cosine, computed in f64 and rounded once to
    /// f32).
    F32,
}

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Scene file (TOML). Built-in scenes are evaluated through the compiled kernels, any other
    /// file (or URDF) through the expression-graph interpreter.
    pub scene: PathBuf,
    /// URDF scene file: the serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Joint angles q (rad), comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub q: String,
    /// Joint velocities q̇ (rad/s), comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub qd: String,
    /// Ball angular velocity ω (rad/s), comma-separated (default 0,0,0).
    #[arg(long, allow_hyphen_values = true)]
    pub omega: Option<String>,
    /// ε of the smooth saturation (eq. 59); default: the scene's `contact.smooth_eps`.
    #[arg(long, allow_hyphen_values = true)]
    pub eps: Option<f64>,
    /// Joint accelerations q̈ for the inverse-dynamics kernels, comma-separated (default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub qdd: Option<String>,
    /// Joint torques τ for `forward_dynamics`, comma-separated (default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub tau: Option<String>,
    /// Runtime parameter of the scene, `name=value` (repeatable; names from the scene's
    /// `runtime_parameters`, e.g. `ball.radius=0.8` for scenes/human.toml).
    #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub param: Vec<String>,
}

/// Arguments of `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Scene file (TOML). Built-in scenes are timed compiled and interpreted, any other file
    /// (or URDF) interpreted.
    pub scene: PathBuf,
    /// URDF scene file: the serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Total time budget (s), split over the kernels; at most 3600.
    #[arg(long, default_value_t = 3.0)]
    pub time: f64,
    /// Number of random states cycled through; at most 100000.
    #[arg(long, default_value_t = 256, value_parser = positive_whole)]
    pub states: usize,
    /// Seed of the random states.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Scene file. A compiled scene (same content as one of scenes/*.toml at build time) runs
    /// on the compiled kernels, any other file on kernels interpreted from the same expression
    /// graphs (slower, same numbers). Default: with `--init` a solution.json, the scene the
    /// solution records (its `scene_toml`, the text of the scene file it was solved on);
    /// otherwise scenes/paper.toml. A `.urdf` file is an arm
    /// (its chain chosen by `--base`/`--tip`).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// URDF scene file: the serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Runtime parameter of the scene, `name=value` (repeatable; names from the scene's
    /// `runtime_parameters`, e.g. `ball.radius=0.8` for scenes/human.toml).
    #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub param: Vec<String>,
    /// Joint torque time series (CSV `t,tau1,tau2,tau3` or JSON `{"t":[..],"tau":[[..],..]}`,
    /// as written by `optimize`; see sim/README.md).
    #[arg(long, conflicts_with = "pd")]
    pub torques: Option<PathBuf>,
    /// PD controller target joint angles (comma-separated, rad): τ = kp (target − q) − kd q̇.
    /// Without --torques and --pd the joints are unactuated (τ = 0).
    #[arg(long, allow_hyphen_values = true)]
    pub pd: Option<String>,
    /// PD gains `kp,kd` (all joints) or `kp1,kp2,kp3,kd1,kd2,kd3` (N m/rad, N m s/rad) of
    /// `--pd`; given without `--pd`, which has no PD controller to take them, they are refused
    /// rather than ignored (a default does not count as given).
    #[arg(
        long,
        value_name = "GAINS",
        allow_hyphen_values = true,
        default_value = "1.0,0.2",
        requires = "pd"
    )]
    pub pd_gains: String,
    /// Replay the solution of `--init` (a solution.json of `optimize`), periodically, with
    /// joint-space PD tracking of its trajectory: τ = τ*(t) + KP (q*(t) − q) + KD (q̇*(t) − q̇),
    /// gains `KP,KD` (N m/rad, N m s/rad; the paper study uses 1,0.2); the feedback acts in
    /// the solution's free phases (and in contact with --pd-track-contact). `0,0` is the pure
    /// open loop of the solution's torques.
    #[arg(
        long,
        value_name = "KP,KD",
        allow_hyphen_values = true,
        requires = "init",
        conflicts_with_all = ["torques", "pd"]
    )]
    pub pd_track: Option<String>,
    /// With --pd-track: the feedback acts during contact too.
    #[arg(long, requires = "pd_track")]
    pub pd_track_contact: bool,
    /// Initial joint angles q(0) (rad, comma-separated, one per joint) [default: 0.1,0.5,0.5
    /// for a 3-joint finger, zeros for any other number of joints; the --init file's q].
    #[arg(long, allow_hyphen_values = true)]
    pub q0: Option<String>,
    /// Initial joint velocities q̇(0) (rad/s) [default: 0,0,0].
    #[arg(long, allow_hyphen_values = true)]
    pub qd0: Option<String>,
    /// Initial ball angular velocity ω(0) (rad/s, world axes) [default: 0,0,0].
    #[arg(long, allow_hyphen_values = true)]
    pub omega0: Option<String>,
    /// Initial mode: free, stick or slip (contact modes need h(q0) ≈ 0) [default: free; with
    /// --init, the file's mode].
    #[arg(long)]
    pub mode0: Option<String>,
    /// Initial state file (JSON): `{"q":[..],"qd":[..],"omega":[..],"mode":"free"}`; `qd`,
    /// `omega` and `mode` are optional. A `solution.json` of `optimize` gives its own initial
    /// state and first mode (replay it with `--torques` of its `torques.csv`). --q0/--qd0/--omega0 override its entries, and so does
    /// --mode0.
    #[arg(long)]
    pub init: Option<PathBuf>,
    /// End time (s) [default: 10; with --torques, the series' last time where it is after the
    /// start; for an arm's `solution.json` given with --init and no --torques, its duration].
    /// Past the end of a --torques series its last torque is held, and before its start its
    /// first, which the run warns about (`torques_held`).
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Integrator: dopri5 or rk4.
    #[arg(long, default_value = "dopri5")]
    pub integrator: String,
    /// Relative tolerance of the adaptive integrator (dopri5) [default: 1e-8].
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub rtol: Option<f64>,
    /// Absolute tolerance of the adaptive integrator (dopri5), at most 0.1 [default: 1e-2 · rtol].
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub atol: Option<f64>,
    /// Fixed step of rk4 (s) [default: 0.001].
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub step: Option<f64>,
    /// Largest step of dopri5 (s) [default: 0.05].
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub h_max: Option<f64>,
    /// Step limit (accepted + rejected); the run stops with an error when it is reached, and a
    /// run that needs more steps (--t-end over --h-max or --step) is refused up front.
    #[arg(long, default_value_t = 10_000_000, allow_hyphen_values = true, value_parser = positive_whole)]
    pub max_steps: usize,
    /// Sample limit (every step and event, plus the --output-dt grid; each takes about 1.2 kB
    /// of memory and 1 kB of output); a run that reaches it stops with an error, and an
    /// --output-dt grid larger than it is refused up front.
    #[arg(long, default_value_t = 1_000_000, allow_hyphen_values = true, value_parser = positive_whole)]
    pub max_samples: usize,
    /// Wall-clock limit of the integration (s); a run that reaches it stops with an error.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = positive)]
    pub max_time: Option<f64>,
    /// Impact law: newton, stick, max-dissipation, min-slip (or normal-impulse). Newton's law
    /// (eq. 39, the paper's choice and the default) keeps the contact point's tangential
    /// velocity, which takes an impulse on the finger with a tangential part and no reaction on
    /// the ball (the paper's text calls it perpendicular; normal-impulse is that reading), so it
    /// can raise the energy at an impact; each such impact is reported as a warning. stick,
    /// max-dissipation, min-slip and normal-impulse dissipate [default: newton].
    #[arg(long)]
    pub impact_law: Option<String>,
    /// Disable the projection of h and of the velocity constraint after contact steps (the
    /// drift is then only bounded by the integrator tolerance and the contact tolerance).
    #[arg(long)]
    pub no_projection: bool,
    /// Also store samples on the uniform grid k · dt (s), besides every step and event.
    #[arg(long, allow_hyphen_values = true, value_parser = positive)]
    pub output_dt: Option<f64>,
    /// Output directory (trajectory.{json,csv}, events.{json,csv}, summary.json; the free
    /// motion of a scene without a ball writes trajectory.csv and summary.json; a failed run
    /// adds FAILED). It is replaced as a whole when the run ends, so it must be new, empty or
    /// an earlier output of `simulate`.
    #[arg(long, default_value = "out/simulate")]
    pub out: PathBuf,
}

/// Arguments of `track` (exit status: see [`Command::Track`]).
#[derive(Debug, Args)]
pub struct TrackArgs {
    /// The optimum to execute: a solution.json of `optimize` on a periodic problem, of a
    /// finger with 3 to 7 joints (the scene it records: compiled kernels where it is a
    /// compiled scene, interpreted otherwise).
    pub solution: PathBuf,
    /// open-loop (the optimal torques τ*(t)), pd (τ*(t) plus joint PD 1 N m/rad, 0.2 N m s/rad
    /// in the free phases), hybrid (bf-control's controller, torques saturated at the scene's
    /// bounds; docs/decisions/0012-control-layer.md and
    /// 0017-control-bounds-and-clearance.md) or hybrid-unbounded (the same
    /// without the bounds).
    #[arg(long, default_value = "hybrid")]
    pub controller: String,
    /// Periods to run (a period ends when the plant starts the optimum's first phase again), at
    /// most 1000: every period's samples are kept, in memory and in the output files. With
    /// --robustness at least 4: its target is judged from the 4th period on.
    #[arg(long, default_value_t = 10, value_parser = tracking_periods)]
    pub periods: usize,
    /// Scene file of the plant [default: the solution's own scene]; the controller always uses
    /// the solution's scene, so a second file tests model error. A copy of a compiled scene
    /// that changes only the ball's mass or inertia, friction or damping runs on the compiled
    /// kernels, any other change on the interpreter (the same numbers, slower).
    #[arg(long)]
    pub plant_scene: Option<PathBuf>,
    /// A URDF plant scene's serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// Impact law of the plant: newton, stick, max-dissipation, min-slip, normal-impulse.
    #[arg(long, default_value = "newton")]
    pub impact_law: String,
    /// Output directory (the files of `simulate` and tracking.json); replaced as a whole.
    #[arg(long, default_value = "out/track")]
    pub out: PathBuf,
    /// Re-plan at every lift-off (hybrid controllers): solve the transient period from the
    /// measured state back to the optimum's lift-off state, warm-started from the plan in
    /// force; tracking.json records each re-plan's wall time
    /// (docs/decisions/0030-replanning-at-lift-off.md).
    #[arg(long)]
    pub replan: bool,
    /// Interior-point iterations allowed per re-plan (with --replan) [default: 200]; a re-plan
    /// that needs more is not used (the optimum is tracked instead).
    #[arg(long, value_parser = positive_whole)]
    pub replan_iterations: Option<usize>,
    /// Run the robustness table instead of one plant: the controller on the solution's own
    /// scene perturbed (ball mass ×1.1; μ_s, μ_k ×0.8; socket damping ×1.5; every link's mass
    /// and inertia ×1.05; all four) with Newton's impact law, and on the nominal scene with the
    /// max-dissipation law. Writes robustness.md and robustness.json to --out and exits
    /// non-zero if a plant misses the target (ω error ≤ 5 % in every period from the 4th on,
    /// contact in every period). A scene without a value that a perturbation edits (no
    /// `[friction]`, say) gives that row an error.
    #[arg(long, conflicts_with_all = ["plant_scene", "impact_law"])]
    pub robustness: bool,
}

/// Arguments of `optimize` (exit status: see [`Command::Optimize`]).
#[derive(Debug, Args)]
#[command(subcommand_negates_reqs = true, args_conflicts_with_subcommands = true)]
pub struct OptimizeArgs {
    /// `merge DIR…`: combine the candidates of `--shard` runs.
    #[command(subcommand)]
    pub command: Option<OptimizeCommand>,
    /// Problem name (reach, reorient, rotate-ref, rotate-fast, periodic-qc, periodic-cot,
    /// periodic-cot-human; reach-arm for an arm without a ball, with --scene).
    #[arg(long, required = true)]
    pub problem: Option<String>,
    /// Scene file (default: the problem's built-in scene). Any finger-and-ball scene; its node
    /// functions run on the emitted kernels when they match, interpreted otherwise. With
    /// `--problem reach-arm`: any arm (required), also a `.urdf` file.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// URDF scene file: the serial chain (`--base LINK --tip LINK`).
    #[command(flatten)]
    pub chain: ChainArgs,
    /// `reach-arm`: start configuration q1,q2,… (rad; m for prismatic joints) [default: q = 0
    /// moved into the joint limits, or where the torque limits cannot hold the arm there
    /// against gravity the pose it settles in from there (docs/your-robot.md)].
    #[arg(long, value_name = "Q", allow_hyphen_values = true)]
    pub start: Option<String>,
    /// `reach-arm`: target configuration q1,q2,… (rad; m for prismatic joints) [default: the
    /// start + 0.5 rad on every revolute joint, + 0.05 m on every prismatic one, moved into
    /// the joint limits].
    #[arg(long, value_name = "Q", allow_hyphen_values = true)]
    pub target: Option<String>,
    /// `reach-arm`: effort weight w of the cost ∫(1 + w‖τ‖² + w_a‖q̈‖²) dt [default: 1].
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    pub effort_weight: Option<f64>,
    /// `reach-arm`: acceleration weight w_a of that cost [default: 1e-3].
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    pub acceleration_weight: Option<f64>,
    /// `reach-arm`: a fixed duration T (s, in [0.01, 20]) instead of the optimal one.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub duration: Option<f64>,
    /// `reach-arm`: keep the torques within tau_max between the collocation points too, by
    /// bounding the Bernstein coefficients of each element's torque polynomial elevated to M
    /// times its degree (1..=8; larger M is less conservative); 0: bounds at the collocation
    /// points only, where a bang-bang optimum overshoots between them [default: 2].
    #[arg(long, value_name = "M")]
    pub torque_hull: Option<usize>,
    /// Runtime parameter of the scene, `name=value` (repeatable; names from the scene's
    /// `runtime_parameters`, e.g. `ball.radius=0.8` for scenes/human.toml).
    #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub param: Vec<String>,
    /// Collocation points per phase (at most 200 with `--scheme lg`; with radau, split over
    /// `--elements`, rounded up to whole elements of at least 2 points, so `--points 2
    /// --elements 3` solves on 6; at most 64 per element and 5000 per phase).
    #[arg(long, default_value_t = 30, allow_hyphen_values = true, value_parser = whole)]
    pub points: usize,
    /// Transcription: lg (Legendre–Gauss, as the paper) or radau (hp Legendre–Gauss–Radau).
    #[arg(long, default_value = "radau")]
    pub scheme: String,
    /// Elements per phase for `--scheme radau` [default: 3] (`--scheme lg` has one polynomial
    /// per phase and refuses the option).
    #[arg(long, allow_hyphen_values = true, value_parser = whole)]
    pub elements: Option<usize>,
    /// Interior-point iteration limit.
    #[arg(long, default_value_t = 1500, allow_hyphen_values = true, value_parser = positive_whole)]
    pub max_iter: usize,
    /// ε of the smooth saturation (eq. 59), m; default: the scene's `contact.smooth_eps`
    /// (0.01 in every shipped scene).
    #[arg(long, allow_hyphen_values = true)]
    pub epsilon: Option<f64>,
    /// Warm start from a previous solution.json: from its primal–dual point as it is when it has
    /// one on the same problem and mesh, otherwise from its collocation data (its
    /// solution-internals.json) interpolated onto the mesh; the strategy table names which.
    /// A trajectory of one's own goes in the same way (docs/optima.md, "A guess of your own").
    #[arg(long)]
    pub warm_start: Option<PathBuf>,
    /// Static dual regularization δ_c of the KKT factorization at the start of a solve
    /// (default: 1e-9 with either scheme, which the solver raises to 3e-8 within a solve whose
    /// factor turns out misleading or inaccurate, optim/README.md). Another start value selects
    /// another path of the solve, sometimes to another local optimum.
    #[arg(long, value_name = "DELTA_C", allow_hyphen_values = true)]
    pub dual_regularization: Option<f64>,
    /// Judge the accuracy of each KKT solve by Ipopt's residual ratio ‖K s − r‖ / (‖r‖ + ‖s‖)
    /// instead of ‖K s − r‖ / ‖r‖. More lenient than the default, which accepts a solve that
    /// fails ‖K s − r‖ / ‖r‖ ≤ 1e-5 only when it is exact to rounding (its normwise backward
    /// error; docs/decisions/0008-one-kkt-regularization.md); it selects other paths and
    /// often other local optima (docs/optima.md); off by default.
    #[arg(long)]
    pub kkt_residual_ratio: bool,
    /// Extrapolate a full Newton step along negative curvature up to this step size (α ≥ 1,
    /// doubled while the line search accepts and the barrier objective decreases; 1 turns it
    /// off; default 16), on the barrier problems whose μ is at most the tolerance unless
    /// --extrapolate-every-barrier.
    /// Ends the crawls in descending valleys that leave some fine meshes at the iteration
    /// limit (docs/decisions/0010-curvature-extrapolation.md).
    #[arg(long, value_name = "ALPHA", allow_hyphen_values = true, value_parser = at_least_one)]
    pub curvature_extrapolation: Option<f64>,
    /// Extrapolate along negative curvature on every barrier problem, not only on those whose
    /// μ is at most the tolerance: moves most solves to other local optima
    /// (docs/decisions/0010-curvature-extrapolation.md).
    #[arg(long)]
    pub extrapolate_every_barrier: bool,
    /// Weight κ of the proximal term δ_w ≥ κ μ that a barrier problem above the tolerance
    /// carries once it has taken 60 iterations (0 turns it off; default 0.1). Ends the wander
    /// of a solve along a flat direction, where Newton steps are long and break the
    /// constraints' linearization (docs/decisions/0011-proximal-stalled-barrier.md).
    #[arg(long, value_name = "KAPPA", allow_hyphen_values = true, value_parser = nonnegative)]
    pub proximal_weight: Option<f64>,
    /// How to search for a good local optimum: `direct` (one solve from the paper's guess),
    /// `continuation` (period sweep + release + ε-homotopy, chains in parallel) or
    /// `multistart` (`--starts` seeded guesses, in parallel: with the global search each revolute
    /// joint anywhere in its revolution, within its limits if the scene gives any; with
    /// `--hops 0` within 0.6 rad of the default guess). Default with
    /// `--scheme radau`: multistart with 128 starts (seed 0) and the global search (`--hops`)
    /// for the periodic problems,
    /// continuation for the others; with `--scheme lg`: direct (an LG-30 solve takes about 4× a Radau
    /// 3 × 10 one). `periodic-qc` chains first bound the stick phase to ≥ 0.1 s and then relax
    /// it to --min-stick (warm-started). Every end point is re-integrated; one distinct optimum
    /// is kept per objective value, unverified optima better than the best verified one are
    /// hp-refined until they verify, and the best verified optimum wins (lowest start index
    /// among equal objectives, so the result does not depend on the number of threads). The
    /// result is a local optimum: docs/optima.md says how to look for better ones.
    #[arg(long, value_parser = ["direct", "continuation", "multistart"])]
    pub strategy: Option<String>,
    /// Number of starts of the multi-start (start 0 is the default guess) [default: 128 with
    /// the global search, 32 with `--hops 0`]; without --strategy it selects multistart.
    #[arg(long, allow_hyphen_values = true, value_parser = starts)]
    pub starts: Option<u64>,
    /// Seed of the multi-start guesses [default: 0]; without --strategy it selects
    /// multistart, like --starts.
    #[arg(long, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Basin hops of the global search at most [default: 64 for the periodic problems, none
    /// for the others; 0: no global search, the best verified of the starts on the problem's
    /// mesh]: the starts on a coarse mesh, reshaping
    /// moves and basin hopping there, the best optima re-solved on the mesh (docs/optima.md).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole)]
    pub hops: Option<usize>,
    /// Relative size of a basin hop: each phase duration is scaled by e^(s·u), u uniform in
    /// [−1, 1], and the joint angles shifted by up to 0.6·s rad (default 0.3); every other
    /// round of hops is 8/3 times as wide.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub hop_scale: Option<f64>,
    /// Run shard k of m of the multi-start (`k/m`, 1 ≤ k ≤ m): the starts whose index is
    /// k − 1 modulo m. `--out` then also holds one `candidate-NNNN.json` per distinct optimum
    /// found; `optimize merge DIR…` picks the best verified one. See docs/sharding.md.
    #[arg(long, value_name = "K/M", allow_hyphen_values = true)]
    pub shard: Option<String>,
    /// Lower bound of the stick phase's duration in the periodic problems (s). From cold
    /// starts most QC optima sit on it (short "taps" that spin the ball mostly by the impact
    /// impulse), and so do the default search's best optima of the sticking law (docs/optima.md).
    /// A larger value (e.g. 0.1) asks for a stick phase of real duration [default: 0.01].
    #[arg(long, value_name = "SECS", allow_hyphen_values = true, value_parser = positive)]
    pub min_stick: Option<f64>,
    /// Impact law of the plan: `newton` (eq. 39, the law of the paper's Sect. 6.2 simulations
    /// and of `track`'s nominal plant: ω unchanged, the finger's post-impact joint velocity
    /// within 1e-3 rad/s of what Newton's law gives from the same state on the plan's smoothed
    /// contact (the plant's exact contact adds the smoothing's difference), reaching the ball at
    /// 0.1 m/s or faster; 3 joints or more) or `stick` (eq. 40, the paper's Sect. 6: the impulse stops the contact
    /// point and spins the ball). A `stick` plan whose stick phase is short spins the ball
    /// mostly by the impact and cannot be executed on a Newton plant. Recorded in
    /// solution.json as `impact_law` [default: `newton` for the periodic problems on a
    /// finger of 3 joints or more, the plans `track` executes (docs/closed-loop.md); `stick`
    /// otherwise;
    /// `--impact-law stick` poses the paper's problem, margins and clearance 0 unless given].
    #[arg(long, value_name = "LAW")]
    pub impact_law: Option<String>,
    /// Share of the friction cone the plan's stick phases leave unused, in [0, 1): the plan
    /// keeps |λ_∥| ≤ (1 − M) μ_s λ_n, so that `track`'s force loop has grip to spare (it keeps
    /// 20 % of μ_s λ_n for feedback). Recorded in solution.json as `cone_margin` [default: 0].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub cone_margin: Option<f64>,
    /// Impose the impulse friction cone at the impact (eq. 66, the paper's Sect. 7):
    /// ‖ι_∥‖ ≤ μ_s ι·n, so that static friction holds the impulse the plan's impact law gives
    /// the finger. Without it a plan may need any friction at its impact; the verification
    /// records how much (`verification.impacts` in solution.json) and flags a plan that needs
    /// more than μ_s. Recorded in solution.json as `impulse_cone`.
    #[arg(long)]
    pub impulse_cone: bool,
    /// Share of every joint's torque limit the plan leaves unused, in [0, 1): |τ_i| ≤ (1 − M)
    /// τ_max,i at the collocation nodes (between them, and at a phase's end, the control
    /// polynomial of the element may pass it by a little; the verification reports any excess
    /// over τ_max itself), so that feedback keeps authority under the limit. Recorded in
    /// solution.json as
    /// `torque_margin` [default: 0.3 for a `newton` plan of a periodic problem
    /// (docs/closed-loop.md); 0 otherwise].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub torque_margin: Option<f64>,
    /// Clearance (m) the periodic problems' approach keeps from the ball at its collocation
    /// nodes, falling linearly to 0 over its last 1 %, so that the plan does not graze the
    /// ball before its impact (docs/optima.md, "Plans that graze the ball"); at most a tenth
    /// of the ball's radius. Recorded in solution.json as `approach_clearance` [default: for a
    /// `newton` plan of a periodic problem the gap `track`'s hybrid controller keeps from the
    /// ball in free flight (0.005 r: 5 mm on the paper's ball of 1 m); 0 otherwise].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub approach_clearance: Option<f64>,
    /// Adaptive hp mesh refinement (Radau only) after the solve, from the mesh the optimum is
    /// on (the verification's refinements may have refined it already), until the largest
    /// element error estimate is at most TOL (e.g. 1e-4). Each round after the first is solved warm
    /// from the round before in at most 500 iterations (or `--max-iter` if lower); a round
    /// that does not converge ends the refinement with the round before it. A refined optimum
    /// that does not re-integrate within the verification's tolerance goes on to the
    /// verification's own refinements (`--verify-refinements`); solution.json's `refinement`
    /// is then the last of them, and its stages list them. Refinement rounds that end without
    /// reaching TOL (the round or point limit, a round that did not converge) mark the set
    /// FAILED and exit with status 1, naming the largest element error reached.
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub refine: Option<f64>,
    /// Refinement rounds at most (with `--refine`; refused without it) [default: 8].
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole)]
    pub refine_rounds: Option<usize>,
    /// hp refinements of an unverified optimum before it is reported unverified (each up to
    /// 4 rounds driven by the element-wise re-integration defects, the first to 1e-4, each
    /// further one 10× tighter; default 5). With `reach-arm`: re-solves of a converged but
    /// unverified optimum on a mesh with twice the elements (default 3).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole)]
    pub verify_refinements: Option<usize>,
    /// Relative tolerance of the DOPRI5 re-integration that verifies the solution (0 skips it).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    pub verify_rtol: f64,
    /// Interior-point log on stderr: 0 none (a progress spinner), 1 one line per iteration,
    /// 2 and 3 more detail.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true, value_parser = clap::value_parser!(u8).range(0..=3))]
    pub print_level: u8,
    /// Output directory (solution.json, torques.csv; a run that does not end Solved or
    /// Acceptable adds FAILED). It is replaced as a whole when the run ends, so it must be new,
    /// empty or an earlier output of `optimize`.
    #[arg(long, default_value = "out/optimize")]
    pub out: PathBuf,
}

/// Subcommands of `optimize`.
#[derive(Debug, Subcommand)]
pub enum OptimizeCommand {
    /// Merge the candidates of `optimize --shard k/m` runs: the best verified one (lowest
    /// objective, then lowest start index; the unsharded multi-start's choice) is written to
    /// --out as solution.json and torques.csv, with the stage records of every shard.
    Merge(MergeArgs),
}

/// Arguments of `optimize merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// Output directories of the shard runs.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Output directory (as `optimize --out`).
    #[arg(long, default_value = "out/optimize")]
    pub out: PathBuf,
    /// `--hops` of the shards' command line (the basin hopping runs in the merge).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = whole)]
    pub hops: Option<usize>,
    /// `--hop-scale` of the shards' command line.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub hop_scale: Option<f64>,
}

/// Arguments of `paper`.
#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Output directory for report.md and every artefact, replaced as a whole when the run
    /// ends (it must be new, empty or an earlier output of `paper`).
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
    /// A smoke run for tests: one cold solve per problem (3 × 7 points per phase) in place of the
    /// searches' optima, no plans for the plant and no robustness tables, shorter closed
    /// loops, ladders and probes; about four fifths of the time.
    #[arg(long)]
    pub quick: bool,
    /// Run the global searches of Sect. 6.1 (`optimize`'s default search of the paper's
    /// sticking problems, seed 0) instead of presenting their stored optima (`data/optima/`,
    /// re-solved and verified in the run) and of the two default plans: seven searches, about
    /// four to seven more minutes on 2 cores.
    #[arg(long, conflicts_with = "quick")]
    pub search: bool,
}

/// Arguments of `report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Which report: speed-accuracy (integrator tolerances, meshes, ε, kernel variants) or
    /// strategies (cold start vs continuation vs multi-start on the periodic problems).
    pub which: String,
    /// Output directory [default: out/report/WHICH], replaced as a whole when the run ends (it
    /// must be new, empty or an earlier output of `report`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Short ladders (seconds instead of minutes; fewer points per table).
    #[arg(long)]
    pub quick: bool,
}

/// Arguments of `verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// What to verify: `appendix` (the paper's Appendix A/B and eq. 22b, 23).
    #[arg(value_parser = ["appendix"])]
    pub what: String,
}

/// The files and directories a run reads, which its `--out` directory must not hold: it is
/// replaced as a whole (bf-output's `OutputDir::create`).
pub trait Inputs {
    /// The paths the run reads, scene files with the URDF each names ([`scene_files`]).
    fn inputs(&self) -> Vec<PathBuf>;
}

/// A scene file and the URDF its `urdf` key names (resolved next to it), if any: what a run
/// on the scene reads. A file that cannot be read is returned alone (its reading fails later,
/// with its own error).
pub fn scene_files(scene: &Path) -> Vec<PathBuf> {
    let mut out = vec![scene.to_path_buf()];
    if let Ok(text) = bf_codegen::spec::read_input_text(scene)
        && let Some(urdf) =
            bf_codegen::spec::urdf_path(&text, scene.parent().unwrap_or(Path::new("")))
    {
        out.push(urdf);
    }
    out
}

/// `optimize --elements` when not given (hp-Radau elements per phase).
pub const DEFAULT_ELEMENTS: usize = 3;
/// `optimize --refine-rounds` when not given.
pub const DEFAULT_REFINE_ROUNDS: usize = 8;

/// `simulate --rtol` when not given.
pub const DEFAULT_RTOL: f64 = 1e-8;
/// `simulate --step` (rk4) when not given (s).
pub const DEFAULT_STEP: f64 = 1e-3;
/// `simulate --h-max` (dopri5) when not given (s).
pub const DEFAULT_H_MAX: f64 = 0.05;

/// The end time of a `simulate` run when neither `--t-end` nor an arm's solution gives one (s).
pub const DEFAULT_T_END: f64 = 10.0;

/// `simulate --mode0` when neither it nor an `--init` file gives the initial mode.
pub const DEFAULT_MODE0: &str = "free";

/// `simulate --impact-law` when not given: Newton's law (eq. 39), the paper's.
pub const DEFAULT_IMPACT_LAW: &str = "newton";

impl SimulateArgs {
    /// The end time of a run without a `--torques` series: `--t-end`, or [`DEFAULT_T_END`]
    /// (`simulate` ends a series' run with the series unless `--t-end` is given).
    pub fn t_end(&self) -> f64 {
        self.t_end.unwrap_or(DEFAULT_T_END)
    }

    /// `--rtol`, or [`DEFAULT_RTOL`].
    pub fn rtol(&self) -> f64 {
        self.rtol.unwrap_or(DEFAULT_RTOL)
    }

    /// `--step`, or [`DEFAULT_STEP`].
    pub fn step(&self) -> f64 {
        self.step.unwrap_or(DEFAULT_STEP)
    }

    /// `--h-max`, or [`DEFAULT_H_MAX`].
    pub fn h_max(&self) -> f64 {
        self.h_max.unwrap_or(DEFAULT_H_MAX)
    }

    /// `--impact-law`, or [`DEFAULT_IMPACT_LAW`].
    pub fn impact_law(&self) -> &str {
        self.impact_law.as_deref().unwrap_or(DEFAULT_IMPACT_LAW)
    }
}

/// The paths of `options` that were given, the scene `scene` with its URDF.
fn given(scene: &Option<PathBuf>, options: &[&Option<PathBuf>]) -> Vec<PathBuf> {
    let mut out = scene.as_deref().map(scene_files).unwrap_or_default();
    out.extend(options.iter().filter_map(|o| (*o).clone()));
    out
}

impl Inputs for SimulateArgs {
    fn inputs(&self) -> Vec<PathBuf> {
        given(&self.scene, &[&self.torques, &self.init])
    }
}

impl Inputs for TrackArgs {
    fn inputs(&self) -> Vec<PathBuf> {
        let mut paths = given(&self.plant_scene, &[]);
        paths.push(self.solution.clone());
        paths
    }
}

impl Inputs for OptimizeArgs {
    fn inputs(&self) -> Vec<PathBuf> {
        given(&self.scene, &[&self.warm_start])
    }
}

impl Inputs for MergeArgs {
    fn inputs(&self) -> Vec<PathBuf> {
        self.dirs.clone()
    }
}
