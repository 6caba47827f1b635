//! Records of how a solution was found, stored with it in `solution.json`: the solve
//! strategy's stages ([`StrategyReport`]), the mesh refinement's rounds ([`RefineReport`]) and
//! the re-integration of its phases by the simulator ([`Verification`], defects of eq. 26/29
//! and path checks of eq. 4, 12–14, 18). The study layer computes them; they are data here so
//! that a solution and its records form one schema.

use std::fmt;

use bf_optim::ipm::Status;
use bf_optim::ocp::MeshSpec;
use serde::{Deserialize, Serialize};

use crate::node::PhaseMode;

/// How the study layer searches for a good local optimum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Strategy {
    /// One solve from the default guess (geometric guess as fallback).
    Direct,
    /// Period sweep + release + ε-homotopy; the default.
    #[default]
    Continuation,
    /// `starts` guesses drawn around the default with seed `seed`.
    Multistart {
        /// Number of starts (≥ 1; start 0 is the default guess).
        starts: usize,
        /// Seed of the ChaCha8 generator.
        seed: u64,
    },
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Strategy::Direct => write!(f, "direct"),
            Strategy::Continuation => write!(f, "continuation"),
            Strategy::Multistart { starts, seed } => {
                write!(f, "multistart ({starts} starts, seed {seed})")
            }
        }
    }
}

/// One solve of a strategy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageRecord {
    /// Chain or start index.
    pub chain: usize,
    /// Stage name, e.g. `sweep T=1`, `release`, `eps 0.01`, `start 3`.
    pub stage: String,
    /// Solver status.
    pub status: Status,
    /// Objective φ at the end of the stage (of that stage's problem).
    pub objective: f64,
    /// Period (total duration) at the end of the stage (s).
    pub period: f64,
    /// Interior-point iterations of the stage.
    pub iterations: usize,
    /// Wall time of the stage (s, build included).
    pub seconds: f64,
}

/// Everything a strategy ran, and which result it kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StrategyReport {
    /// The strategy.
    pub strategy: Strategy,
    /// Every stage of every chain/start, in chain order.
    pub records: Vec<StageRecord>,
    /// The chain/start whose final stage was kept (`None` if none succeeded: then the best
    /// failed one is returned).
    pub chosen: Option<usize>,
    /// Total interior-point iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
}

impl StrategyReport {
    /// A plain-text table of the records, one line each, the kept chain marked `*`.
    pub fn table(&self) -> String {
        let mut s = format!(
            "strategy {}: {} solves, {} iterations, {:.2} s\n  chain  stage                 status          objective     period  iter  time(s)\n",
            self.strategy,
            self.records.len(),
            self.iterations,
            self.seconds
        );
        for r in &self.records {
            s.push_str(&format!(
                "{} {:5}  {:<20}  {:<14} {:>12.6e} {:>8.4} {:>5} {:>8.2}\n",
                if Some(r.chain) == self.chosen {
                    '*'
                } else {
                    ' '
                },
                r.chain,
                r.stage,
                status_name(r.status),
                r.objective,
                r.period,
                r.iterations,
                r.seconds
            ));
        }
        s
    }
}

/// One solve of the refinement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineRound {
    /// Round (0 = the initial mesh).
    pub round: usize,
    /// Elements per phase.
    pub elements: Vec<usize>,
    /// Collocation points per phase.
    pub points: Vec<usize>,
    /// Objective φ.
    pub objective: f64,
    /// Largest element error estimate per phase.
    pub phase_errors: Vec<f64>,
    /// Largest element error estimate.
    pub max_error: f64,
    /// Solver status.
    pub status: Status,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Wall time of the round: build, solve and estimate (s).
    pub seconds: f64,
}

/// The refinement record without the solution (stored in `solution.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineReport {
    /// Tolerance requested.
    pub tol: f64,
    /// True if the largest error estimate of the final solution is ≤ `tol`.
    pub converged: bool,
    /// Why the refinement stopped.
    pub stop_reason: String,
    /// Mesh of the final solution, per phase.
    pub mesh: Vec<MeshSpec>,
    /// Error estimate of the final solution, per phase and element.
    pub errors: Vec<Vec<f64>>,
    /// One entry per solve.
    pub history: Vec<RefineRound>,
}

/// JSON has no NaN/∞: non-finite values are written as `null` and read back as NaN.
pub(crate) mod nan_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_some(v)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// Torques between the collocation nodes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TorqueInterpolant {
    /// The element's collocation polynomial clamped to |τ_i| ≤ τ_max,i: the solution's dense
    /// output and `torques.csv` (what a simulation of the exported torques applies).
    #[default]
    Clamped,
    /// The element's collocation polynomial, unclamped (may exceed τ_max between nodes where
    /// the optimal torques saturate; closer to what the collocation equations imply).
    Polynomial,
}

/// Verification record of one phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseVerification {
    /// Phase index.
    pub phase: usize,
    /// Contact mode.
    pub mode: PhaseMode,
    /// Duration T (s).
    pub duration: f64,
    /// Phase-local time the re-integration reached (= T unless it failed).
    pub t_reached: f64,
    /// Why the re-integration stopped early (`None`: it reached T).
    pub failure: Option<String>,
    /// max_i |x_sim,i(T) − x_colloc,i(T)| over all 2 nq + 3 components (NaN on failure).
    #[serde(with = "nan_null")]
    pub defect: f64,
    /// The q part of `defect` (rad).
    #[serde(with = "nan_null")]
    pub defect_q: f64,
    /// The q̇ part of `defect` (rad/s).
    #[serde(with = "nan_null")]
    pub defect_qd: f64,
    /// The ω part of `defect` (rad/s).
    #[serde(with = "nan_null")]
    pub defect_omega: f64,
    /// Local accuracy of the collocation: max over the collocation elements of the end-state
    /// defect of a re-integration of that element alone, from its collocated start state
    /// (NaN if one failed). `defect` / `element_defect` ≫ 1 means the phase's open-loop
    /// dynamics amplify the local errors (unstable open-loop motion).
    #[serde(with = "nan_null")]
    pub element_defect: f64,
    /// Collocated initial state (the re-integration's start).
    pub x_start: Vec<f64>,
    /// Re-integrated state at `t_reached`.
    pub x_end: Vec<f64>,
    /// Collocated state at the phase end.
    pub x_colloc_end: Vec<f64>,
    /// Accepted DOPRI5 steps.
    pub steps: usize,
    /// Rejected DOPRI5 steps.
    pub rejected_steps: usize,
    /// Vector-field evaluations.
    pub rhs_evals: usize,
    /// Relative tolerance used.
    pub rtol: f64,
    /// Absolute tolerance used.
    pub atol: f64,
    /// Largest residual of the OCP dynamics (eq. 26 / 29, force and torque units) at the
    /// collocation nodes, evaluated with bf-model's kernels and parameters on the collocated
    /// (x, q̈, ω̇, λ, τ): near the NLP tolerance iff both sides use the same physics.
    #[serde(with = "nan_null")]
    pub node_residual: f64,
    /// Largest excess of the unclamped torque polynomial over τ_max along the samples (N m; 0
    /// when the torques stay within their limits between the nodes). With
    /// [`TorqueInterpolant::Clamped`] this torque error is part of the defects.
    pub max_torque_overshoot: f64,
    /// Free phases: min h along the re-integration (m; < 0 is penetration).
    pub min_h: Option<f64>,
    /// Stick phases: max ‖Δv‖ along the re-integration (m/s; drift of Δv = 0).
    pub max_delta_v: Option<f64>,
    /// Stick phases: min λ_n along the re-integration (N; < 0 means the contact would open).
    pub min_lambda_n: Option<f64>,
    /// Stick phases: min σ = μ_s λ_n − ‖λ_∥‖ (N; < 0 means the contact would slip).
    pub min_sigma: Option<f64>,
    /// Stick phases: max |h| along the re-integration (m).
    pub max_abs_h: Option<f64>,
}

/// Result of the verification; meant for `solution.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verification {
    /// Problem name.
    pub problem: String,
    /// Scene name.
    pub scene: String,
    /// ε of the smooth saturation (eq. 59) used by the re-integration.
    pub epsilon: f64,
    /// Torque interpolant between the collocation nodes.
    pub torque: TorqueInterpolant,
    /// DOPRI5 relative tolerance.
    pub rtol: f64,
    /// DOPRI5 absolute tolerance.
    pub atol: f64,
    /// Per-phase records.
    pub phases: Vec<PhaseVerification>,
    /// Max end-state defect over all phases (NaN if a phase failed).
    #[serde(with = "nan_null")]
    pub max_defect: f64,
    /// Max node residual over all phases.
    #[serde(with = "nan_null")]
    pub max_node_residual: f64,
    /// Wall time of the verification (s).
    pub seconds: f64,
    /// Largest `max_defect` at which the solution counts as verified (the study layer's
    /// `VERIFIED_DEFECT`).
    #[serde(default)]
    pub tolerance: f64,
    /// Whether every phase completed with `max_defect` ≤ `tolerance`; a solution that is not
    /// verified is flagged wherever it is shown.
    #[serde(default)]
    pub verified: bool,
}

impl Verification {
    /// Whether every phase was re-integrated to its end.
    pub fn completed(&self) -> bool {
        self.phases.iter().all(|p| p.failure.is_none())
    }

    /// Whether every phase completed with an end-state defect ≤ `tol`.
    pub fn passes(&self, tol: f64) -> bool {
        self.completed() && self.max_defect <= tol
    }

    /// A short table for the CLI (same text as `Display`).
    pub fn summary(&self) -> String {
        self.to_string()
    }
}

/// The solver status as user text: its serde name (`Solved`, `MaxIterations`), never Debug.
fn status_name(s: Status) -> &'static str {
    match s {
        Status::Solved => "Solved",
        Status::Acceptable => "Acceptable",
        Status::MaxIterations => "MaxIterations",
        Status::MaxTime => "MaxTime",
        Status::LocallyInfeasible => "LocallyInfeasible",
        Status::SearchDirectionTooSmall => "SearchDirectionTooSmall",
        Status::DivergingIterates => "DivergingIterates",
        Status::Unbounded => "Unbounded",
        Status::RestorationFailed => "RestorationFailed",
        Status::ErrorInStepComputation => "ErrorInStepComputation",
        Status::UserStop => "UserStop",
    }
}

impl fmt::Display for TorqueInterpolant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TorqueInterpolant::Clamped => "clamped",
            TorqueInterpolant::Polynomial => "polynomial",
        })
    }
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.2e}"))
}

impl fmt::Display for Verification {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "trajectory verification ({}, scene {}): DOPRI5 rtol {:.0e} atol {:.0e}, eps {}, {} torques, {:.3} s",
            self.problem, self.scene, self.rtol, self.atol, self.epsilon, self.torque, self.seconds
        )?;
        writeln!(
            f,
            "{:>5} {:>5} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>6} {:>9} {:>9}  path",
            "phase",
            "mode",
            "T (s)",
            "defect",
            "q",
            "qd",
            "omega",
            "element",
            "steps",
            "node res",
            "tau over"
        )?;
        for p in &self.phases {
            let mode = match p.mode {
                PhaseMode::Free => "free",
                PhaseMode::Stick => "stick",
            };
            let path = match p.mode {
                PhaseMode::Free => format!("min h {}", fmt_opt(p.min_h)),
                PhaseMode::Stick => format!(
                    "max|dv| {}  min lambda_n {}  min sigma {}  max|h| {}",
                    fmt_opt(p.max_delta_v),
                    fmt_opt(p.min_lambda_n),
                    fmt_opt(p.min_sigma),
                    fmt_opt(p.max_abs_h)
                ),
            };
            writeln!(
                f,
                "{:>5} {:>5} {:>9.4} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>6} {:>9.2e} {:>9.2e}  {}",
                p.phase,
                mode,
                p.duration,
                p.defect,
                p.defect_q,
                p.defect_qd,
                p.defect_omega,
                p.element_defect,
                p.steps,
                p.node_residual,
                p.max_torque_overshoot,
                path
            )?;
            if let Some(e) = &p.failure {
                writeln!(f, "      FAILED at t = {:.6} s: {e}", p.t_reached)?;
            }
        }
        writeln!(
            f,
            "(defect: max |x_sim - x_colloc| at the phase end; element: worst single-element \
             defect; node res: OCP dynamics residual with bf-model; tau over: torque polynomial \
             beyond tau_max)"
        )?;
        write!(f, "max end-state defect: {:.3e}", self.max_defect)
    }
}
