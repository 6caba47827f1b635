//! Command-line definitions (clap). Each subcommand maps to one stage of the pipeline:
//! `generate`/`eval` (the code generator, replacing the paper's Maple step, Sect. 5),
//! `simulate` (hybrid model of Sect. 3 / Fig. 3), `optimize` (multiphase optimal control,
//! Sect. 4), `paper` (the study of Sect. 6 end to end) and `report`.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// ball-finger: DH table → verified flat Rust dynamics kernels; simulate and optimise a finger
/// rolling a trackball (Ball-and-finger system: modeling and optimal trajectories).
#[derive(Debug, Parser)]
#[command(name = "ball-finger", version, about, long_about = None)]
pub struct Cli {
    /// The command to run.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Generate Rust kernels for a scene file (stdout or a file).
    Generate(GenerateArgs),
    /// Evaluate every kernel of a scene at one state and print one JSON object.
    Eval(EvalArgs),
    /// Simulate the hybrid ball-and-finger model (paper Sect. 3, Fig. 3).
    Simulate(SimulateArgs),
    /// Solve a multiphase optimal-control problem (paper Sect. 4).
    Optimize(OptimizeArgs),
    /// Reproduce the paper's study (Sect. 6) and write a report.
    Paper(PaperArgs),
    /// Write a stand-alone report.
    Report(ReportArgs),
}

/// Arguments of `generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// Scene file (TOML), e.g. scenes/paper.toml.
    pub scene: PathBuf,
    /// Write the generated Rust source to this file instead of stdout.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print op counts and generation time per kernel (to stderr when the code goes to stdout).
    #[arg(long)]
    pub report: bool,
}

/// Arguments of `eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Scene file (TOML). Built-in scenes are evaluated through the compiled kernels, any other
    /// file through the expression-graph interpreter.
    pub scene: PathBuf,
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
}

/// Arguments of `simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Scene file.
    #[arg(long, default_value = "scenes/paper.toml")]
    pub scene: PathBuf,
    /// Joint torque time series (CSV or JSON, as written by `optimize`).
    #[arg(long)]
    pub torques: Option<PathBuf>,
    /// PD controller target joint angles (comma-separated).
    #[arg(long, allow_hyphen_values = true)]
    pub pd: Option<String>,
    /// End time (s).
    #[arg(long, default_value_t = 10.0)]
    pub t_end: f64,
    /// Integrator: dopri5 or rk4.
    #[arg(long, default_value = "dopri5")]
    pub integrator: String,
    /// Relative tolerance of the adaptive integrator.
    #[arg(long, default_value_t = 1e-8)]
    pub rtol: f64,
    /// Impact law: newton, stick, max-dissipation or min-slip.
    #[arg(long, default_value = "newton")]
    pub impact_law: String,
    /// Output directory.
    #[arg(long, default_value = "out/simulate")]
    pub out: PathBuf,
}

/// Arguments of `optimize`.
#[derive(Debug, Args)]
pub struct OptimizeArgs {
    /// Problem name (reach, reorient, rotate-ref, rotate-fast, periodic-qc, periodic-cot,
    /// periodic-cot-human).
    #[arg(long)]
    pub problem: String,
    /// Scene file.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Collocation points per phase.
    #[arg(long, default_value_t = 30)]
    pub points: usize,
    /// Transcription: lg or radau.
    #[arg(long, default_value = "lg")]
    pub scheme: String,
    /// ε of the smooth saturation.
    #[arg(long, default_value_t = 0.01)]
    pub epsilon: f64,
    /// Warm start from a previous solution.json.
    #[arg(long)]
    pub warm_start: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out/optimize")]
    pub out: PathBuf,
}

/// Arguments of `paper`.
#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Output directory for report.md and every artefact.
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
    /// Shorter run (fewer states, smaller problems) for tests.
    #[arg(long)]
    pub quick: bool,
}

/// Arguments of `report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Which report: speed-accuracy.
    pub which: String,
    /// Output directory.
    #[arg(long, default_value = "out/report")]
    pub out: PathBuf,
}
