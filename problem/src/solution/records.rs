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
    /// `starts` guesses drawn with seed `seed` (with the global search each revolute joint over
    /// its revolution, without it near the default guess).
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
    /// Distinct sampled optima and basin hops of the global search that ended in the basin of
    /// its best point (the same shape: objective and phase durations within 2 %; `None`: no
    /// global search ran, or a file from before it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub basin_hits: Option<usize>,
    /// The hp refinements that the verification ran on candidates (each a run of refinement
    /// rounds, `refine start K to TOL`), in the order they ran; their iterations are in the
    /// solution's total but not in [`StrategyReport::iterations`]. Empty in a file from
    /// before they were recorded.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub refinements: Vec<StageRecord>,
}

impl StrategyReport {
    /// A plain-text table of the records, one line each, the kept chain marked `*` (the
    /// verification refinements are not in it: `optimize` prints them after it).
    pub fn table(&self) -> String {
        let rows: Vec<StageRow> = self.records.iter().map(|r| self.row(r)).collect();
        format!("{}\n{}", self.summary(), stage_table(&rows))
    }

    /// The rows of the kept chain: its stages, then the verification refinements of that
    /// chain (a global search records hundreds of stages; [`stage_table`] prints them, under
    /// [`StrategyReport::summary`], with the rows a report adds after them).
    pub fn kept_rows(&self) -> Vec<StageRow> {
        let kept = |r: &&StageRecord| Some(r.chain) == self.chosen;
        self.records
            .iter()
            .chain(&self.refinements)
            .filter(kept)
            .map(|r| self.row(r))
            .collect()
    }

    /// One line: the strategy, its solves and iterations, the verification refinements'
    /// where there were any, and the wall time of all of them.
    pub fn summary(&self) -> String {
        let refined = if self.refinements.is_empty() {
            String::new()
        } else {
            let n = self.refinements.len();
            format!(
                ", {n} verification refinement{} of {} iterations",
                if n == 1 { "" } else { "s" },
                self.refinements.iter().map(|r| r.iterations).sum::<usize>()
            )
        };
        format!(
            "strategy {}: {} solves, {} iterations{refined}, {:.2} s",
            self.strategy,
            self.records.len(),
            self.iterations,
            self.seconds
        )
    }

    /// One line per verification refinement, as `optimize` and `optimize merge` print them
    /// after [`StrategyReport::table`].
    pub fn refinement_lines(&self) -> String {
        self.refinement_lines_from(0)
    }

    /// [`StrategyReport::refinement_lines`] of the refinements from the `first`-th on (those
    /// a step after the search added).
    pub fn refinement_lines_from(&self, first: usize) -> String {
        self.refinements
            .iter()
            .skip(first)
            .map(|r| {
                format!(
                    "verification refinement: {}: {}, objective {:.6e}, period {:.4} s, {} \
                     iterations in {:.1} s\n",
                    r.stage,
                    status_name(r.status),
                    r.objective,
                    r.period,
                    r.iterations,
                    r.seconds
                )
            })
            .collect()
    }

    fn row(&self, r: &StageRecord) -> StageRow {
        StageRow {
            kept: Some(r.chain) == self.chosen,
            chain: Some(r.chain),
            stage: r.stage.clone(),
            status: r.status,
            objective: r.objective,
            period: Some(r.period),
            iterations: r.iterations,
            seconds: r.seconds,
        }
    }
}

/// One line of a table of solve stages ([`stage_table`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StageRow {
    /// Marked `*`: a stage of the kept chain.
    pub kept: bool,
    /// Chain or start index (`-`: none).
    pub chain: Option<usize>,
    /// What ran.
    pub stage: String,
    /// Solver status.
    pub status: Status,
    /// Objective φ at its end.
    pub objective: f64,
    /// Period at its end (s; `-`: not recorded).
    pub period: Option<f64>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
}

/// Column heads and one line per row, the stage column as wide as its longest name, so that
/// the columns after it stay aligned whatever a stage is called.
pub fn stage_table(rows: &[StageRow]) -> String {
    let w = rows
        .iter()
        .map(|r| r.stage.chars().count())
        .max()
        .unwrap_or(0)
        .max("stage".len());
    let sw = rows
        .iter()
        .map(|r| status_name(r.status).len())
        .max()
        .unwrap_or(0)
        .max("status".len());
    let mut s = format!(
        "  chain  {:<w$}  {:<sw$} {:>12} {:>8} {:>5} {:>8}\n",
        "stage", "status", "objective", "period", "iter", "time(s)"
    );
    for r in rows {
        let chain = r.chain.map_or("-".to_string(), |c| c.to_string());
        let period = r.period.map_or("-".to_string(), |p| format!("{p:.4}"));
        s.push_str(&format!(
            "{} {chain:>5}  {:<w$}  {:<sw$} {:>12.6e} {period:>8} {:>5} {:>8.2}\n",
            if r.kept { '*' } else { ' ' },
            r.stage,
            status_name(r.status),
            r.objective,
            r.iterations,
            r.seconds
        ));
    }
    s
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
    /// Largest element error per phase (of the report's criterion).
    pub phase_errors: Vec<f64>,
    /// Largest element error.
    pub max_error: f64,
    /// Solver status.
    pub status: Status,
    /// Interior-point iterations (of both solves where the round was solved again).
    pub iterations: usize,
    /// Wall time of the round: build, solve and estimate (s).
    pub seconds: f64,
    /// Whether the round's first solve left the optimum of the round before it and the round
    /// was solved again from a closer barrier start (its objective or phase durations moved
    /// beyond `bf`'s `RefineSettings::max_rise` or `max_shift`), whichever of the two
    /// solutions it kept. Absent in files written before it: false.
    #[serde(default)]
    pub solved_again: bool,
}

/// What the mesh refinement measures in each element.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub enum RefineCriterion {
    /// The collocation error estimate between the nodes (relative; `bf_optim::ocp::mesh`).
    #[default]
    Estimate,
    /// The element-wise re-integration defect of the trajectory verification (state units;
    /// [`PhaseVerification::element_defects`]) with the DOPRI5 relative tolerance `rtol`.
    Reintegration {
        /// DOPRI5 relative tolerance of the re-integration.
        rtol: f64,
    },
}

/// The refinement record without the solution (stored in `solution.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineReport {
    /// Tolerance requested.
    pub tol: f64,
    /// What the element errors measure.
    #[serde(default)]
    pub criterion: RefineCriterion,
    /// True if the largest element error of the final solution is ≤ `tol`.
    pub converged: bool,
    /// Why the refinement stopped.
    pub stop_reason: String,
    /// Mesh of the final solution, per phase.
    pub mesh: Vec<MeshSpec>,
    /// Element errors (of `criterion`) of the final solution, per phase and element.
    pub errors: Vec<Vec<f64>>,
    /// One entry per solve.
    pub history: Vec<RefineRound>,
    /// The strategy's verification refinement whose iterations these rounds are: the
    /// [`StageRecord::stage`] of its record in [`StrategyReport::refinements`], whose chain is
    /// the candidate the mesh was refined for. A hop or reshaping move solved on that mesh
    /// keeps the record, so its chain differs from the kept one. `None` for a refinement the
    /// strategy did not record (`optimize --refine`) or a file from before this field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<String>,
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

/// [`nan_null`] for vectors: non-finite entries are written as `null` and read back as NaN.
pub(crate) mod nan_null_vec {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|x| x.is_finite().then_some(*x)))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Option<f64>>::deserialize(d)?
            .into_iter()
            .map(|x| x.unwrap_or(f64::NAN))
            .collect())
    }
}

/// The value of a figure missing from an older file.
fn nan() -> f64 {
    f64::NAN
}

/// The ball radius of an older file's verification: every such file is of a scene with the
/// paper's ball of 1 m.
fn paper_radius() -> f64 {
    1.0
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

/// Verification record of one phase. The verification re-integrates every collocation
/// element alone, from its collocated start state, and compares its end with the collocated
/// state there (the element-wise defect, the criterion): the error of the transcription,
/// independent of how the phase's motion amplifies errors over longer spans. Beside it, for
/// information only: the same from every collocation point to the next
/// (`interval_defect`, the accuracy of the interior nodes) and the open-loop replay of the
/// whole phase from its collocated initial state (`open_loop_*`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseVerification {
    /// Phase index, 0-based (text for readers counts phases from 1).
    pub phase: usize,
    /// Contact mode.
    pub mode: PhaseMode,
    /// Duration T (s).
    pub duration: f64,
    /// Phase-local time the element re-integrations reached (= T unless one failed: then
    /// where the first failed one stopped).
    pub t_reached: f64,
    /// Why an element re-integration stopped early (`None`: all reached their end).
    pub failure: Option<String>,
    /// Element-wise defect: max over the elements and the 2 nq + 3 components of
    /// |x_sim,i − x_colloc,i| at the element's end (NaN if an element failed); the
    /// verification's criterion.
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
    /// The defect of each collocation element (NaN where it failed): the per-element error of
    /// the refinement that a failed verification triggers.
    #[serde(default, with = "nan_null_vec")]
    pub element_defects: Vec<f64>,
    /// max_i |x_sim,i − x_colloc,i| over the collocation intervals (from each collocation
    /// point to the next, inside an element), each re-integrated from its collocated start
    /// (NaN if one failed or not recorded): how well the interior nodes, which Radau
    /// collocation approximates to a lower order than the element ends, follow the
    /// dynamics. Informative, not a verification criterion.
    #[serde(default = "nan", with = "nan_null")]
    pub interval_defect: f64,
    /// Open-loop drift: max_i |x_sim,i(T) − x_colloc,i(T)| of one re-integration of the whole
    /// phase from its collocated initial state (NaN if it failed or was not recorded). ≫
    /// `defect` when the phase's motion is open-loop unstable; not a verification criterion.
    #[serde(default = "nan", with = "nan_null")]
    pub open_loop_defect: f64,
    /// Why the open-loop replay stopped early (`None`: it reached T).
    #[serde(default)]
    pub open_loop_failure: Option<String>,
    /// Collocated initial state (the re-integration's start).
    pub x_start: Vec<f64>,
    /// State of the open-loop replay at T (at the start of the element where it failed).
    pub x_end: Vec<f64>,
    /// Collocated state at the phase end.
    pub x_colloc_end: Vec<f64>,
    /// Accepted DOPRI5 steps of the element re-integrations.
    pub steps: usize,
    /// Rejected DOPRI5 steps of the element re-integrations.
    pub rejected_steps: usize,
    /// Vector-field evaluations of the element re-integrations.
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
    /// Free phases: min h along the element re-integrations (m; < 0 is penetration).
    pub min_h: Option<f64>,
    /// Free phases: min h along each element's re-integration (m; NaN where it failed or the
    /// element is empty; empty in stick phases and in older files): where the collocated path
    /// dips into the ball between its nodes, so that a refinement splits those elements.
    #[serde(default, with = "nan_null_vec")]
    pub element_min_h: Vec<f64>,
    /// Free phases that end at an impact: the phase-local time (s) at which the exact contact
    /// distance (the plant's, without the smoothing ε of eq. 58–59) first reaches 0 along the
    /// element re-integrations after the path has been clear of the ball; `None` when it does
    /// not (and in other phases and older files). A plant with the exact contact makes contact
    /// there, `duration` − this before the plan's own impact.
    #[serde(default)]
    pub first_touch: Option<f64>,
    /// Free phases: the largest |h₀ − h_ε| along the element re-integrations at the samples
    /// where either distance is within 10⁻² radii of the ball (m): the exact contact distance
    /// (the plant's, eq. 3–4) against the smoothed one the problem bounds (eq. 58–59, the
    /// solution's ε). `None` in stick phases and older files. A coarse ε keeps a path clear
    /// of the ball by the smoothed distance that a plant's finger enters.
    #[serde(default)]
    pub smoothing_error: Option<f64>,
    /// Stick phases: max ‖Δv‖ along the element re-integrations (m/s; drift of Δv = 0).
    pub max_delta_v: Option<f64>,
    /// Stick phases: min λ_n along the element re-integrations (N; < 0 means the contact
    /// would open).
    pub min_lambda_n: Option<f64>,
    /// Stick phases: max λ_n along the element re-integrations (N): the scale of the
    /// friction cone, whose margin σ is judged against a fraction of μ_s · this (absent in
    /// free phases and in older files).
    #[serde(default)]
    pub max_lambda_n: Option<f64>,
    /// Stick phases: min σ = μ_s λ_n − ‖λ_∥‖ (N; < 0 means the contact would slip).
    pub min_sigma: Option<f64>,
    /// Stick phases: min σ along each element's re-integration (N; NaN where it failed or the
    /// element is empty; empty in free phases and in older files): where the contact slips
    /// between the nodes, so that a refinement splits those elements.
    #[serde(default, with = "nan_null_vec")]
    pub element_min_sigma: Vec<f64>,
    /// Stick phases: max |h| along the element re-integrations (m).
    pub max_abs_h: Option<f64>,
}

/// A planned impact's impulse against the friction cone (eq. 66): whether static friction
/// can hold the impulse ι that the plan's impact law (eq. 39 or 40) gives the finger, or the
/// contact would slip at the impact instead of sticking as the plan assumes. The paper poses
/// the cone as an option of the problem (Sect. 7, `optimize --impulse-cone`); without it a
/// plan may need any friction, and the record says how much.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImpactCone {
    /// The free phase that ends at the impact, 0-based (text for readers counts from 1).
    pub phase: usize,
    /// ι on the finger (N s, world axes): the plan's own impulse parameter.
    pub impulse: [f64; 3],
    /// ι·n (N s): positive when the ball pushes the finger away, as a contact can.
    pub normal: f64,
    /// ‖ι_∥‖ = ‖ι − (ι·n) n‖ (N s).
    pub tangential: f64,
    /// μ_s ι·n − ‖ι_∥‖ (N s, eq. 66): non-negative when static friction holds the impulse.
    pub margin: f64,
    /// −n·v_c⁻ (m/s, eq. 36): the speed at which the contact point reaches the ball, from the
    /// free phase's collocated last state. A larger impact speed gives the impulse more
    /// normal part, which is how a plan meets the cone (the paper's Sect. 7 on COT).
    pub impact_speed: f64,
    /// Whether the problem imposed eq. 66 on its impulse (`impulse_cone`): then a margin below
    /// its allowance fails the verdict; otherwise the record informs and a negative margin is
    /// flagged where the plan is shown.
    pub imposed: bool,
}

impl ImpactCone {
    /// ‖ι_∥‖ / ι·n: the least static friction coefficient that holds the impulse (∞ when the
    /// impulse does not push, ι·n ≤ 0).
    pub fn friction_needed(&self) -> f64 {
        if self.normal > 0.0 {
            self.tangential / self.normal
        } else {
            f64::INFINITY
        }
    }
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
    /// Max element-wise defect over all phases, the verification's criterion (NaN if an
    /// element failed).
    #[serde(with = "nan_null")]
    pub max_defect: f64,
    /// Max collocation-interval defect over all phases
    /// (`PhaseVerification::interval_defect`; informative, NaN if not recorded).
    #[serde(default = "nan", with = "nan_null")]
    pub max_interval_defect: f64,
    /// Max open-loop drift over all phases (`PhaseVerification::open_loop_defect`;
    /// informative, NaN if a replay failed or was not recorded).
    #[serde(default = "nan", with = "nan_null")]
    pub max_open_loop_defect: f64,
    /// Max node residual over all phases.
    #[serde(with = "nan_null")]
    pub max_node_residual: f64,
    /// Static friction coefficient μ_s of the re-integrated stick dynamics (the σ of the
    /// stick phases; NaN in older files, whose cone margins then decide nothing).
    #[serde(default = "nan", with = "nan_null")]
    pub mu_s: f64,
    /// Radius r of the ball (m): the unit of the penetration allowance of the free paths (the
    /// problems' tolerance on h is in radii too; 1 in older files, whose scenes all have the
    /// paper's ball).
    #[serde(default = "paper_radius")]
    pub radius: f64,
    /// Wall time of the verification (s).
    pub seconds: f64,
    /// Largest `max_defect` at which the solution counts as verified (the study layer's
    /// `VERIFIED_DEFECT`).
    #[serde(default)]
    pub tolerance: f64,
    /// Whether every phase completed with `max_defect` ≤ `tolerance` and its path checks
    /// within their allowances (the study layer's verification: the free phases' penetration,
    /// the stick phases' friction-cone margin);
    /// a solution that is not verified is flagged wherever it is shown.
    #[serde(default)]
    pub verified: bool,
    /// The closed-loop execution of a plan for the plant (Newton's impact law), when the
    /// search that made it ran one ([`ExecutionCheck`]); absent for the paper's problems and in
    /// older files. A plan that the controller does not execute is not verified.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub execution: Option<ExecutionCheck>,
    /// Why the closed-loop execution that the search runs on a plan for the plant was not
    /// run on this one, whose re-integration passed: its objective lies above a verified and
    /// robust plan's, so it could not have been chosen. Such a plan is not verified (it was
    /// not executed); absent where the execution ran or was not asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub not_executed: Option<String>,
    /// Every planned impact's impulse against the friction cone ([`ImpactCone`]), in phase
    /// order; empty for problems without an impact and in older files.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub impacts: Vec<ImpactCone>,
}

/// A plan run in closed loop: the hybrid controller (computed torque in free flight, hybrid
/// force/velocity control in contact, torques within the scene's bounds) on the hybrid model,
/// from the plan's first state, on the nominal plant of its own scene with Newton's impact
/// law and on the perturbed plants of `track --robustness`. A plan whose collocation and
/// re-integration agree can still be one that no controller follows (a release that grazes
/// the ball falls back onto it and chatters) or one that only the exact model lets it follow,
/// and only the execution shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExecutionCheck {
    /// The controller (`track --controller`).
    pub controller: String,
    /// Periods run on the nominal plant.
    pub periods: usize,
    /// Largest relative error of a period's mean ball spin ‖ω̄_k − ω̄*‖ / ‖ω̄*‖ on the nominal
    /// plant over the periods completed (NaN when none completed).
    #[serde(with = "nan_null")]
    pub max_omega_error: f64,
    /// Largest `max_omega_error` that passes.
    pub tolerance: f64,
    /// Periods run on each perturbed plant (0: not run, the nominal run failed); a plant's run
    /// ends early at its first period from the 4th on that misses the target.
    pub robustness_periods: usize,
    /// Largest error from the 4th period on over the perturbed plants (NaN: not run, or a
    /// plant that completed fewer than four periods); on a plant whose run ended at a missed
    /// period, up to that period.
    #[serde(with = "nan_null")]
    pub robustness_error: f64,
    /// Largest `robustness_error` that passes.
    pub robustness_tolerance: f64,
    /// Why the plan is not executed on the nominal plant (an error beyond its tolerance; a
    /// lost ball; a simulation that failed); `None`: executed.
    pub failure: Option<String>,
    /// Why a perturbed plant misses the robustness target (the plant named), where the
    /// perturbed plants ran; `None`: every one met it, or they did not run. A miss grades the
    /// plan below the plans that meet the target but does not unverify it: it measures the
    /// controller's margin against model error, not whether the plan is executed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robustness_failure: Option<String>,
}

impl ExecutionCheck {
    /// One line: the nominal plant's error against its tolerance, the perturbed plants' where
    /// they ran, and the verdict where it is not a pass.
    pub fn summary(&self) -> String {
        let mut out = format!(
            "closed loop ({} controller, Newton's impact law): nominal plant max omega error \
             {:.3} % over {} periods (tolerance {} %)",
            self.controller,
            100.0 * self.max_omega_error,
            self.periods,
            100.0 * self.tolerance,
        );
        // The perturbed plants run only after the nominal one passed. NaN: a plant gave no
        // error from the 4th period (it could not be run, lost the ball or completed too few
        // periods; `robustness_failure` says which).
        if self.robustness_periods > 0 {
            if self.robustness_error.is_finite() {
                // A run ends at its first missed period, so after a miss the largest error is
                // a floor: the later periods (`track --robustness`) may be worse.
                let floor = if self.robustness_failure.is_some() {
                    "at least "
                } else {
                    ""
                };
                out += &format!(
                    "; perturbed plants {floor}{:.3} % from the 4th of {} periods (tolerance {} \
                     %{})",
                    100.0 * self.robustness_error,
                    self.robustness_periods,
                    100.0 * self.robustness_tolerance,
                    if floor.is_empty() {
                        ""
                    } else {
                        "; each plant's run ends at its first miss"
                    }
                );
            } else {
                out += &format!(
                    "; perturbed plants: one gave no error from the 4th of {} periods",
                    self.robustness_periods
                );
            }
        }
        if let Some(why) = &self.failure {
            out += &format!(": FAILED, {why}");
        } else if let Some(why) = &self.robustness_failure {
            out += &format!(": executed; robustness target MISSED, {why}");
        }
        out
    }
}

impl Verification {
    /// Whether every collocation element of every phase was re-integrated to its end.
    pub fn completed(&self) -> bool {
        self.phases.iter().all(|p| p.failure.is_none())
    }

    /// Whether every phase completed with an element-wise defect ≤ `tol`.
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
            "{:>5} {:>5} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>6} {:>9} {:>9}  path",
            "phase",
            "mode",
            "T (s)",
            "defect",
            "q",
            "qd",
            "omega",
            "interval",
            "open loop",
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
                PhaseMode::Free => format!(
                    "min h {}  smoothing {}",
                    fmt_opt(p.min_h),
                    fmt_opt(p.smoothing_error)
                ),
                PhaseMode::Stick => format!(
                    "max|dv| {}  lambda_n {} .. {}  min sigma {}  max|h| {}",
                    fmt_opt(p.max_delta_v),
                    fmt_opt(p.min_lambda_n),
                    fmt_opt(p.max_lambda_n),
                    fmt_opt(p.min_sigma),
                    fmt_opt(p.max_abs_h)
                ),
            };
            writeln!(
                f,
                "{:>5} {:>5} {:>9.4} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>6} {:>9.2e} {:>9.2e}  {}",
                // Phases are counted from 1 in text, as in every report (`phase` of the record
                // is the 0-based index).
                p.phase + 1,
                mode,
                p.duration,
                p.defect,
                p.defect_q,
                p.defect_qd,
                p.defect_omega,
                p.interval_defect,
                p.open_loop_defect,
                p.steps,
                p.node_residual,
                p.max_torque_overshoot,
                path
            )?;
            if let Some(e) = &p.failure {
                writeln!(f, "      FAILED at t = {:.6} s: {e}", p.t_reached)?;
            }
            if let Some(e) = &p.open_loop_failure {
                writeln!(f, "      open-loop replay stopped: {e}")?;
            }
        }
        writeln!(
            f,
            "(defect: max |x_sim - x_colloc| at the element ends, each element re-integrated \
             from its collocated start; interval: the same from every collocation point to the \
             next; open loop: end-of-phase drift of one re-integration of the whole phase; \
             node res: OCP dynamics residual with bf-model; tau over: torque polynomial beyond \
             tau_max)"
        )?;
        write!(
            f,
            "max element-wise defect: {:.3e} (informative: collocation intervals {:.3e}, \
             open-loop drift {:.3e})",
            self.max_defect, self.max_interval_defect, self.max_open_loop_defect
        )?;
        for c in &self.impacts {
            write!(
                f,
                "\nimpact at the end of phase {} at {:.3e} m/s: iota.n {:.3e} N s, |iota_t| \
                 {:.3e} N s, needs static friction {:.3} (mu_s {}){}",
                c.phase + 1,
                c.impact_speed,
                c.normal,
                c.tangential,
                c.friction_needed(),
                self.mu_s,
                if c.imposed {
                    ", cone imposed (eq. 66)"
                } else {
                    ""
                }
            )?;
        }
        if let Some(e) = &self.execution {
            write!(f, "\n{}", e.summary())?;
        }
        if let Some(why) = &self.not_executed {
            write!(f, "\nclosed loop: NOT RUN, {why}")?;
        }
        Ok(())
    }
}

/// A bound a solution sits on (`solution.json`'s `active_bounds`): a phase duration, the
/// period, a torque or a joint limit, with its value and on how many samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ActiveBound {
    /// What is bounded, e.g. "phase 2 (stick) duration (s)".
    pub what: String,
    /// Its value at the solution (the sample nearest to the bound).
    pub value: f64,
    /// The bound.
    pub bound: f64,
    /// `true`: the lower bound, `false`: the upper.
    pub lower: bool,
    /// At how many of the quantity's samples it is on the bound (1 for a scalar).
    pub hits: usize,
    /// Of how many samples.
    pub of: usize,
}

/// A bound as text: up to six decimals, trailing zeros dropped.
fn fmt_bound(b: f64) -> String {
    let s = format!("{b:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// A value on a bound as text: six decimals, or three significant digits where six decimals
/// would round it to zero. A row bounded at 0 sits within rounding of it, on either side, and
/// "-0.000000" would say neither how far nor on which side.
fn fmt_value(v: f64) -> String {
    let fixed = format!("{v:.6}");
    // Decided on the printed digits themselves: a threshold such as 5e-7 is not exactly
    // where the rounding to six decimals turns to zero.
    if !fixed.bytes().all(|b| matches!(b, b'-' | b'0' | b'.')) {
        fixed
    } else if v == 0.0 {
        // -0.0 included.
        "0.000000".into()
    } else {
        format!("{v:.2e}")
    }
}

impl ActiveBound {
    /// "phase 2 (stick) duration (s) = 0.010000 on its minimum 0.01".
    pub fn describe(&self) -> String {
        let side = if self.lower { "minimum" } else { "maximum" };
        if self.of > 1 {
            format!(
                "{} on its {side} {} at {} of {} nodes",
                self.what,
                fmt_bound(self.bound),
                self.hits,
                self.of
            )
        } else {
            format!(
                "{} = {} on its {side} {}",
                self.what,
                fmt_value(self.value),
                fmt_bound(self.bound)
            )
        }
    }
}

/// The settings of `optimize` that shape which optimum a search reports but that the problem,
/// scene, mesh and ε do not determine (`solution.json`'s `search_settings`): the stick-phase
/// bound and its continuation, the verification and its refinement limits, and the
/// interior-point options. `optimize merge` compares them so that shards searched under other
/// settings do not compete as one run; files written before they were recorded have none.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchSettings {
    /// Lower bound of the stick phase's duration (s; `--min-stick`).
    pub min_stick: f64,
    /// First stick-phase lower bound of the stick continuation (s; `None`: no continuation).
    pub stick_continuation: Option<f64>,
    /// DOPRI5 relative tolerance of the verification (`--verify-rtol`; 0 skips it).
    pub verify_rtol: f64,
    /// hp refinements of one unverified optimum at most (`--verify-refinements`).
    pub verify_refinements: usize,
    /// Rounds of one such refinement.
    pub refine_rounds: usize,
    /// Element-defect tolerance of the first such refinement.
    pub refine_tol: f64,
    /// Collocation points per phase such a refinement may reach.
    pub max_points: usize,
    /// Distinct unverified optima refined at most.
    pub clusters: usize,
    /// Interior-point iteration limit (`--max-iter`).
    pub max_iter: usize,
    /// `--dual-regularization` (`None`: the solver's default).
    pub dual_regularization: Option<f64>,
    /// `--kkt-residual-ratio`.
    pub kkt_residual_ratio: bool,
    /// `--curvature-extrapolation` (`None`: the solver's default).
    pub curvature_extrapolation: Option<f64>,
    /// `--extrapolate-every-barrier`.
    pub extrapolate_every_barrier: bool,
    /// `--proximal-weight` (`None`: the solver's default).
    pub proximal_weight: Option<f64>,
    /// Basin hops of the global search at most (`--hops`; 0: no global search, so no coarse
    /// sampling either); `None` in files written before it was recorded.
    #[serde(default)]
    pub hops: Option<usize>,
    /// Relative size of a hop (`--hop-scale`); `None` without hops and in older files.
    #[serde(default)]
    pub hop_scale: Option<f64>,
}

impl SearchSettings {
    /// Each setting as (the `optimize` option or quantity that sets it, its value as text),
    /// in a fixed order.
    pub fn entries(&self) -> [(&'static str, String); 16] {
        let opt = |v: Option<f64>| v.map_or_else(|| "default".to_string(), |v| format!("{v:e}"));
        [
            ("--min-stick", format!("{:e}", self.min_stick)),
            ("stick continuation bound (s)", opt(self.stick_continuation)),
            ("--verify-rtol", format!("{:e}", self.verify_rtol)),
            ("--verify-refinements", self.verify_refinements.to_string()),
            (
                "rounds per verification refinement",
                self.refine_rounds.to_string(),
            ),
            (
                "verification refinement tolerance",
                format!("{:e}", self.refine_tol),
            ),
            (
                "verification refinement point limit",
                self.max_points.to_string(),
            ),
            ("refined optima at most", self.clusters.to_string()),
            ("--max-iter", self.max_iter.to_string()),
            ("--dual-regularization", opt(self.dual_regularization)),
            ("--kkt-residual-ratio", self.kkt_residual_ratio.to_string()),
            (
                "--curvature-extrapolation",
                opt(self.curvature_extrapolation),
            ),
            (
                "--extrapolate-every-barrier",
                self.extrapolate_every_barrier.to_string(),
            ),
            ("--proximal-weight", opt(self.proximal_weight)),
            (
                "--hops",
                self.hops
                    .map_or_else(|| "not recorded".to_string(), |h| h.to_string()),
            ),
            ("--hop-scale", opt(self.hop_scale)),
        ]
    }

    /// The first setting in which `self` and `other` differ: (its name, `self`'s value,
    /// `other`'s value); `None` when they agree in every one.
    pub fn first_difference(
        &self,
        other: &SearchSettings,
    ) -> Option<(&'static str, String, String)> {
        self.entries()
            .into_iter()
            .zip(other.entries())
            .find(|((_, a), (_, b))| a != b)
            .map(|((name, a), (_, b))| (name, a, b))
    }
}

#[cfg(test)]
mod tests {

    /// After a perturbed plant's miss its run has ended there, so the error printed is a
    /// floor and the line says so; without a miss it is the largest error over all periods.
    #[test]
    fn a_robustness_error_after_a_miss_reads_as_a_floor() {
        let mut c = ExecutionCheck {
            controller: "hybrid".into(),
            periods: 10,
            max_omega_error: 1e-4,
            tolerance: 0.02,
            robustness_periods: 10,
            robustness_error: 0.02,
            robustness_tolerance: 0.05,
            failure: None,
            robustness_failure: None,
        };
        let line = c.summary();
        assert!(line.contains("perturbed plants 2.000 %"), "{line}");
        assert!(!line.contains("at least"), "{line}");
        c.robustness_error = 0.409;
        c.robustness_failure = Some("socket damping x1.5".into());
        let line = c.summary();
        assert!(
            line.contains("perturbed plants at least 40.900 %"),
            "{line}"
        );
        assert!(
            line.contains("first miss") && line.contains("MISSED"),
            "{line}"
        );
    }

    use super::*;

    /// A perturbed plant that gave no error (NaN) is said so, with the reason, never "NaN %".
    #[test]
    fn an_execution_summary_never_shows_nan() {
        let mut e = ExecutionCheck {
            controller: "hybrid".into(),
            periods: 10,
            max_omega_error: 0.004,
            tolerance: 0.02,
            robustness_periods: 10,
            robustness_error: 0.03,
            robustness_tolerance: 0.05,
            failure: None,
            robustness_failure: None,
        };
        let ok = e.summary();
        assert!(
            ok.contains("0.400 %") && ok.contains("perturbed plants 3.000 %"),
            "{ok}"
        );
        e.robustness_error = f64::NAN;
        e.robustness_failure = Some("the plant `heavy ball` lost the ball".into());
        let missed = e.summary();
        assert!(!missed.contains("NaN"), "{missed}");
        assert!(
            missed.contains("one gave no error") && missed.contains("`heavy ball` lost"),
            "{missed}"
        );
    }

    /// A value within rounding of a bound at 0 says how far and on which side, never
    /// "-0.000000"; a value away from zero keeps six decimals.
    #[test]
    fn a_value_on_a_bound_at_zero_keeps_its_sign_and_size() {
        let at = |value, bound, lower| ActiveBound {
            what: "row".into(),
            value,
            bound,
            lower,
            hits: 1,
            of: 1,
        };
        let below = at(-2.5e-9, 0.0, false).describe();
        assert_eq!(below, "row = -2.50e-9 on its maximum 0");
        let above = at(3.1e-10, 0.0, true).describe();
        assert_eq!(above, "row = 3.10e-10 on its minimum 0");
        // At the edge of the rounding: 5e-7 is stored just below it and prints as zero
        // with six decimals, so it is written out; 6e-7 rounds to 0.000001.
        assert_eq!(
            at(5e-7, 0.0, false).describe(),
            "row = 5.00e-7 on its maximum 0"
        );
        assert_eq!(
            at(-6e-7, 0.0, true).describe(),
            "row = -0.000001 on its minimum 0"
        );
        assert_eq!(
            at(-0.0, 0.0, true).describe(),
            "row = 0.000000 on its minimum 0"
        );
        assert_eq!(
            at(0.010000307, 0.01, true).describe(),
            "row = 0.010000 on its minimum 0.01"
        );
        assert_eq!(
            at(-0.100009, -0.1, false).describe(),
            "row = -0.100009 on its maximum -0.1"
        );
    }

    /// The kept table keeps the summary of every solve and the kept chain's stages only, each
    /// marked `*`; the whole table has every stage.
    #[test]
    fn the_kept_table_has_the_kept_chain_only() {
        let rec = |chain, stage: &str, objective| StageRecord {
            chain,
            stage: stage.into(),
            status: Status::Solved,
            objective,
            period: 1.0,
            iterations: 10,
            seconds: 0.1,
        };
        let report = StrategyReport {
            strategy: Strategy::Multistart { starts: 2, seed: 0 },
            records: vec![
                rec(0, "start 0", 2.0),
                rec(1, "start 1", 1.0),
                rec(1, "relax", 0.5),
            ],
            chosen: Some(1),
            iterations: 30,
            seconds: 0.3,
            basin_hits: None,
            refinements: Vec::new(),
        };
        let kept = format!("{}\n{}", report.summary(), stage_table(&report.kept_rows()));
        let lines: Vec<&str> = kept.lines().collect();
        assert!(lines[0].contains("3 solves"), "{kept}");
        assert_eq!(lines.len(), 4, "{kept}");
        assert!(lines[2..].iter().all(|l| l.starts_with('*')), "{kept}");
        assert!(lines[3].contains("relax"));
        assert_eq!(report.table().lines().count(), 5);

        // The verification's refinements: the kept chain's follow its stages, counted in the
        // summary; a long stage name widens its column instead of shifting the others.
        let long = "refine start 1 to 1e-4 (defect 9.0e0, path 6143.4x its allowance)";
        let report = StrategyReport {
            refinements: vec![rec(0, "refine start 0 to 1e-4", 1.5), rec(1, long, 0.4)],
            ..report
        };
        let kept = format!("{}\n{}", report.summary(), stage_table(&report.kept_rows()));
        let lines: Vec<&str> = kept.lines().collect();
        assert!(
            lines[0]
                .contains("3 solves, 30 iterations, 2 verification refinements of 20 iterations"),
            "{kept}"
        );
        assert_eq!(lines.len(), 5, "{kept}");
        assert!(
            lines[4].contains(long) && lines[4].starts_with('*'),
            "{kept}"
        );
        let col = lines[1].find("status").unwrap();
        assert!(
            lines[2..].iter().all(|l| l[col..].starts_with("Solved")),
            "{kept}"
        );
        // The full table leaves them to the lines `optimize` prints after it.
        assert_eq!(report.table().lines().count(), 5);
    }
}
