//! The solution of a ball-and-finger problem as `solution.json` stores it ([`OcpSolution`]):
//! status, objective φ = c₁/c₂ or c₁ (eq. 60), phase durations, the trajectory at the
//! collocation points and on a dense grid ([`Samples`], with h eq. 4, σ eq. 18 and α eq. 2),
//! the raw collocation data for warm starts, and the records of how it was found
//! ([`records`]). It is data only: the catalogue builds it from a transcribed problem at an NLP
//! point ([`crate::catalogue::solution_at`]) and interpolates one onto another mesh for a warm
//! start ([`crate::catalogue::warm_initial_point`]).

pub mod records;

use bf_optim::ipm::{Counters, Status, Timing, WarmStart};
use bf_optim::ocp::{PhaseTrajectory, Scheme};
use serde::{Deserialize, Serialize};

use crate::node::PhaseMode;
use records::{RefineReport, StrategyReport, Verification};

/// Trajectory samples (at the collocation state points or on a dense grid).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Phase index of each sample.
    pub phase: Vec<usize>,
    /// Joint angles.
    pub q: Vec<Vec<f64>>,
    /// Joint rates.
    pub qd: Vec<Vec<f64>>,
    /// Ball angular velocity.
    pub omega: Vec<Vec<f64>>,
    /// Torques.
    pub tau: Vec<Vec<f64>>,
    /// Contact force λ (zero in free phases).
    pub lambda: Vec<Vec<f64>>,
    /// Distance h (eq. 4).
    pub h: Vec<f64>,
    /// Slip margin σ = μ_s λ_n − ‖λ_∥‖ (eq. 18; zero in free phases).
    pub sigma: Vec<f64>,
    /// α (eq. 2).
    pub alpha: Vec<f64>,
}

/// The impact law a plan assumes at its impacts (`solution.json`'s `impact_law`,
/// [`crate::ProblemSettings::impact_law`], `optimize --impact-law`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PlannedImpact {
    /// The sticking impact (eq. 40): the impulse stops the contact point and changes ω. The
    /// paper's problems; files written before the law was recorded planned with it.
    #[default]
    Stick,
    /// Newton's law with restitution 0 (eq. 39): ω unchanged, the finger arriving without
    /// tangential velocity relative to the ball ([`crate::points::impact`]).
    Newton,
}

impl PlannedImpact {
    /// The name on the command line and in `solution.json`.
    pub fn name(self) -> &'static str {
        match self {
            PlannedImpact::Stick => "stick",
            PlannedImpact::Newton => "newton",
        }
    }

    /// Parses `stick` or `newton`; the error says what was given and what is accepted.
    pub fn parse(text: &str) -> Result<Self, String> {
        match text {
            "stick" => Ok(PlannedImpact::Stick),
            "newton" => Ok(PlannedImpact::Newton),
            other => Err(format!(
                "unknown impact law {other:?}; use `stick` (eq. 40) or `newton` (eq. 39)"
            )),
        }
    }
}

/// A solution of a problem; serialises to `solution.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OcpSolution {
    /// Problem name.
    pub problem: String,
    /// Solver status.
    pub status: Status,
    /// Objective φ.
    pub objective: f64,
    /// Cost states c_1(t_f), c_2(t_f).
    pub c1: f64,
    /// Second cost state.
    pub c2: f64,
    /// Phase modes.
    pub modes: Vec<PhaseMode>,
    /// Phase durations (s).
    pub phase_durations: Vec<f64>,
    /// Total duration (period for the periodic problems).
    pub period: f64,
    /// Mean ω over [0, t_f] (quadrature).
    pub mean_omega: [f64; 3],
    /// Impact impulse ι (if any).
    pub impulse: Vec<f64>,
    /// Interior-point iterations (all continuation stages).
    pub iterations: usize,
    /// Wall time of the solve (s, all stages).
    pub solve_seconds: f64,
    /// Strategy stages run: (description, status, iterations).
    pub stages: Vec<(String, Status, usize)>,
    /// Final constraint violation.
    pub constraint_violation: f64,
    /// Final dual infeasibility.
    pub dual_infeasibility: f64,
    /// Solver time breakdown of the final stage.
    pub timing: Timing,
    /// Solver counters of the final stage.
    pub counters: Counters,
    /// NLP size: variables, constraints.
    pub nlp_size: (usize, usize),
    /// Collocation points per phase and scheme.
    pub points: usize,
    /// Scheme.
    pub scheme: Scheme,
    /// ε of the smooth saturation.
    pub epsilon: f64,
    /// Values at the state points.
    pub nodes: Samples,
    /// Dense interpolation (100 samples per phase).
    pub dense: Samples,
    /// Raw per-phase collocation data (warm starts, interpolation).
    pub raw: Vec<PhaseTrajectory>,
    /// Static parameters.
    pub params: Vec<f64>,
    /// Primal-dual point of the final NLP (for an exact warm start on the same mesh; stored
    /// in solution.json so that `--warm-start` is exact when the mesh is unchanged).
    #[serde(default)]
    pub nlp_warm: Option<WarmStart>,
    /// How the solution was found: every stage or start with its status and objective.
    #[serde(default)]
    pub strategy: Option<StrategyReport>,
    /// Adaptive mesh refinement that produced this solution (`optimize --refine TOL`); its
    /// `mesh` is the final mesh (`points`/`scheme` above are the starting mesh's).
    #[serde(default)]
    pub refinement: Option<RefineReport>,
    /// Re-integration of each phase with the optimal torques (the study layer's verification).
    #[serde(default)]
    pub verification: Option<Verification>,
    /// The scene the problem was posed on (its `name`).
    #[serde(default)]
    pub scene: String,
    /// Which kernels evaluated the phase node functions: `"compiled"` (every phase on an
    /// emitted node kernel), `"interpreted"` (none) or `"mixed"`.
    #[serde(default)]
    pub kernels: String,
    /// The text of the scene file the problem was posed on (empty when not recorded, as in
    /// files written before it was): with [`OcpSolution::scene_params`] a solution names its
    /// scene completely, so a replay or a merge needs nothing else.
    #[serde(default)]
    pub scene_toml: String,
    /// The runtime-parameter values set on that scene text (`--param`).
    #[serde(default)]
    pub scene_params: Vec<(String, f64)>,
    /// The bounds the solution sits on, as `optimize` computed them against its problem's
    /// bounds; `None` where they were not computed (files of other commands, older files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_bounds: Option<Vec<records::ActiveBound>>,
    /// The search settings `optimize` ran with (stick bound, verification and refinement
    /// limits, solver options), which `optimize merge` compares across shards; `None` in files
    /// of other commands and in files written before they were recorded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search_settings: Option<records::SearchSettings>,
    /// The impact law the plan assumed at its impacts (`stick` in files written before it was
    /// recorded, which all planned with eq. 40); `track` reports it next to the plant's.
    #[serde(default)]
    pub impact_law: PlannedImpact,
    /// The share of the friction cone the plan left unused ([`crate::ProblemSettings::cone_margin`];
    /// 0 in files written before it was recorded).
    #[serde(default)]
    pub cone_margin: f64,
    /// Whether the plan's impact imposed the impulse friction cone (eq. 66,
    /// [`crate::ProblemSettings::impulse_cone`]; false in older files, which all left it out).
    #[serde(default)]
    pub impulse_cone: bool,
    /// The share of the torque limits the plan left unused
    /// ([`crate::ProblemSettings::torque_margin`]; 0 in older files).
    #[serde(default)]
    pub torque_margin: f64,
    /// The clearance (m) the plan's approach kept from the ball
    /// ([`crate::ProblemSettings::approach_clearance`]; 0 in older files).
    #[serde(default)]
    pub approach_clearance: f64,
}

impl OcpSolution {
    /// The duration of the plan's stick phase (s), `None` if it has none.
    pub fn stick_duration(&self) -> Option<f64> {
        self.modes
            .iter()
            .position(|m| *m == crate::node::PhaseMode::Stick)
            .and_then(|i| self.phase_durations.get(i).copied())
    }

    /// The torques as `t [s],tau1 [N m],...,tauN [N m]` CSV (sim/README.md): dense samples with strictly
    /// increasing times (a sample equal in time to the previous one, at a phase boundary, is
    /// dropped), full precision.
    pub fn torques_csv(&self) -> String {
        let nq = self.dense.tau.first().map_or(0, |v| v.len());
        let mut s = String::from("t [s]");
        for i in 1..=nq {
            s.push_str(&format!(",tau{i} [N m]"));
        }
        s.push('\n');
        let mut last = f64::NEG_INFINITY;
        for (k, &t) in self.dense.t.iter().enumerate() {
            if t <= last || !t.is_finite() {
                continue;
            }
            last = t;
            s.push_str(&format!("{t:?}"));
            for v in &self.dense.tau[k] {
                s.push_str(&format!(",{v:?}"));
            }
            s.push('\n');
        }
        s
    }
}
