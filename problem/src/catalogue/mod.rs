//! Problem library (paper Sect. 4.1 archetypes, Sect. 6.1 periodic problems) and the library
//! API the CLI calls: [`build`] → [`solve`] → [`OcpSolution`] (JSON) and
//! [`OcpSolution::write_torques_csv`] (sim/README.md format).
//!
//! | name | phases | objective |
//! |---|---|---|
//! | `periodic-qc` | free–stick–free, periodic | QC ratio (eq. 60, 64–65), w = 1, ω_ref = (0,0,2.2) |
//! | `periodic-cot` | free–stick–free, periodic | COT ratio (eq. 60–63), w = 10, ω̂ = (1,−1,0)/√2, period ≤ 10 s |
//! | `periodic-cot-human` | as `periodic-cot` | human scene: 0 ≤ q2 ≤ 90°, 0 ≤ q3 ≤ 100° |
//! | `reach` | free | ∫(1 + ‖τ‖²): from rest at q⁰ to touching the ball at rest |
//! | `reorient` | free–stick | ∫(1 + 0.1‖τ‖²) s.t. ∫ω_z dt = π/2 (ball turned by 90° about z) |
//! | `rotate-ref` | free–stick | ∫‖ω − ω_ref‖² + 0.1‖τ‖² over a fixed 3 s horizon, ω_ref = (0,0,1) |
//! | `rotate-fast` | free–stick | ∫(0.01‖τ‖² − ω_z) over a fixed 2 s horizon |
//!
//! Transcription: the default is Legendre–Gauss–Radau with 3 elements per phase (30 points
//! per phase in total). The paper's Legendre–Gauss scheme ([`Scheme::Lg`]) is available. With
//! it the stick phases impose the no-slip constraint at the acceleration level,
//! d(Δv)/dt = 0 at the Gauss nodes ([`bf::StickLevel::Acceleration`]), with Δv⁺ = 0 from the
//! impact law and no end-point Δv row: at the velocity level the stick phase is an index-2
//! DAE, which Gauss collocation (not stiffly accurate) resolves with an undamped alternating
//! mode, and LG-20/30 stalled with δ_w ≈ 1e-3 in every iteration. The Gauss defects are in
//! integral form (`ocp::transcription`): with the differential form (rows with the O(N²)
//! entries of the Gauss differentiation matrix) `periodic-cot`/`-human` LG-30 stalled
//! (δ_w ≈ 1e-2 in every iteration, MaxIterations) and `periodic-qc` LG-30 needed an extra
//! inactive period row.
//!
//! LG solves use a larger static dual regularization ([`RAISED_DUAL_REGULARIZATION`],
//! 3e-8 instead of the solver's 1e-9). The unpivoted LDLᵀ of the KKT matrix eliminates many
//! constraint rows of the LG KKTs before any of their primal columns (AMD: ≈ 700 of the 1624
//! rows of `periodic-cot` LG-30), and such a pivot is exactly −δ_c; at δ_c = 1e-9 the growth
//! 1/δ_c swamps the reduced-Hessian curvature (smallest eigenvalue ≈ 6e-9, positive), so the
//! factor reports 1–2 spurious negative pivots for δ_w ≤ 1e-7 and its refined residual
//! fails the 1e-5 test for δ_w ≲ 1e-5 (checked against dense eigenvalues and a pivoted dense
//! LU of dumped KKTs). The inertia correction then kept δ_w ≈ 1e-5 in every iteration, which
//! shrank each step along the weakest direction by λ/(λ + δ_w) ≈ 6e-4: the COT problems crept
//! to an Acceptable exit (172 and 378 iterations; Solved only after 2440 with the acceptable
//! test off). With δ_c = 3e-8 they end Solved in 65 and 69 iterations at the same optima, and
//! `periodic-qc` LG-30 in 79 (was 84). The Radau KKTs keep 1e-9: their default meshes solve
//! as before, bit for bit (a larger δ_c there moves the 3 × 10 solves to other local optima).
//!
//! The periodic problems start the period at the apex of the free arc (ḣ(0) = 0), which
//! removes the time-shift degeneracy of the free arc without changing the optimum.
//! Common constraints: |τ_i| ≤ τ_max (1 N m), h ≥ 0 in free approach phases, λ_n ≥ 0 and the
//! smooth friction cone in stick, the sticking impact law (eq. 40) with ι_n ≥ 0,
//! 0 ≤ h(t_f⁽¹⁾) ≤ 10⁻⁴ and h⁽³⁾ ≥ −10⁻⁴ (Sect. 7 work-arounds), Δv = 0 at the stick phase's
//! end point with Radau (LG: see above), and |h| ≤ 10⁻⁴ at the stick nodes of the free–stick
//! archetypes: Δv = 0 (or its rate) alone does not hold h where the contact point slides over
//! the smoothed fingertip (sat, eq. 58–59), and the fixed-horizon spinning problems exploited
//! that (`rotate-fast` LG-30: J = −28 with the finger 0.76 m inside the ball). The periodic
//! problems' stick phases stay within 1.1e-4 without the row (measured on the dense samples of
//! all three, both schemes), and the row's narrow barrier band lengthens their solves (Radau
//! `periodic-qc` 72 → 110 iterations, `periodic-cot` to an Acceptable 1616), so they go
//! without it.

pub mod bf;
pub mod refine;
pub mod strategy;
pub mod verify;

use std::path::Path;
use std::time::Instant;

use bf_codegen::Scene;
use serde::{Deserialize, Serialize};

use crate::ipm::{Counters, IterationInfo, Settings, Solution, Status, Timing, WarmStart};
use crate::ocp::{
    Objective, Ocp, OcpError, Param, Phase, PhaseGuess, PhaseTrajectory, PointFunction, Scheme,
    Transcription, VarRef, extract, solve_nlp,
};
use bf::{CostKind, Diagnostics, EndQuantity, Mode, NodeOptions, Physics};

/// Names of the problems [`build`] knows.
pub const PROBLEMS: &[&str] = &[
    "periodic-qc",
    "periodic-cot",
    "periodic-cot-human",
    "reach",
    "reorient",
    "rotate-ref",
    "rotate-fast",
];

/// Static dual regularization δ_c of the KKT matrix ([`Settings::static_dual_regularization`])
/// where the solver's default 1e-9 misleads the unpivoted LDLᵀ: the default of Legendre–Gauss
/// solves, and the retry of a failed Radau solve in [`solve`]. The factorization eliminates
/// many constraint rows before their primal columns, with pivot −δ_c, and at 1e-9 that growth
/// hides the curvature (module docs).
pub const RAISED_DUAL_REGULARIZATION: f64 = 3e-8;

/// Upper bound of the total period of the COT problems (s): the COT ratio is otherwise free
/// to trade period length against efficiency without limit.
pub const COT_MAX_PERIOD: f64 = 10.0;

/// The constant joint configuration of the default initial guess (PARAMS.md: "q constant
/// nonzero"): the finger bent towards the ball, h ≈ 0.95 r.
pub const Q_GUESS: [f64; 3] = [0.1, 0.6, 0.9];

/// A configuration pressed into the ball (h < 0) used to find the contact configuration of
/// the geometric guess by bisection on the segment [`Q_GUESS`] → `Q_DEEP`.
pub const Q_DEEP: [f64; 3] = [0.1, 1.0, 1.6];

/// Kind of the initial guess.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GuessKind {
    /// PARAMS.md / Sect. 6.1: q ≡ q⁰ = [`Q_GUESS`], t_f⁽ⁱ⁾ = i, all else 0.
    Paper,
    /// Geometric: free phases move linearly between q⁰ and a contact configuration q_c
    /// (h(q_c) = 0, found by bisection), stick phases hold q_c; velocities consistent.
    Contact,
    /// `Paper` first; if the solve fails, `Contact` (the default strategy).
    Auto,
}

/// Settings of [`build`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ProblemSettings {
    /// Collocation points per phase (paper: 30).
    pub points: usize,
    /// Transcription scheme (default: Radau with 3 elements; see the module docs for LG).
    pub scheme: Scheme,
    /// ε of the smooth saturation (eq. 59); `None` = the scene's `smooth_eps` (0.01).
    pub epsilon: Option<f64>,
    /// Warm start from a previous solution (interpolated onto the new mesh).
    #[serde(skip)]
    pub warm_start: Option<OcpSolution>,
    /// Impulse friction cone at the impact (eq. 66).
    pub impulse_cone: bool,
    /// ḣ margins of Sect. 7 (ḣ ≤ −m in the approach, ḣ ≥ m in the release phase).
    pub hdot_margin: Option<f64>,
    /// Initial guess (ignored with a warm start).
    pub guess: GuessKind,
    /// Interior-point settings (`None`: defaults with `tol` = 1e-8); `max_iter` and
    /// `print_level` below override theirs.
    pub ipm: Option<Settings>,
    /// Interior-point iteration limit.
    pub max_iter: usize,
    /// Solver log level (0 silent).
    pub print_level: u8,
    /// Override of the default guess's joint configuration and phase durations (multi-start
    /// draws these; ignored with a warm start).
    pub start: Option<StartGuess>,
    /// Factor on the effort term of the QC cost (eq. 64: w‖τ‖² becomes s·w‖τ‖²); 1 is the
    /// paper's cost. A continuation stage knob: small s = the simpler "track ω_ref" cost. Must
    /// be positive, so the sparsity pattern of the Lagrangian Hessian does not change.
    pub effort_scale: f64,
    /// Bounds on the period of the periodic problems (intersected with the problem's own:
    /// 3 × 5 s for QC, [`COT_MAX_PERIOD`] for COT); a continuation stage fixes it. `Some` adds
    /// a period row to QC (same optimum with `Some((0.0, f64::MAX))`).
    pub period_bounds: Option<(f64, f64)>,
    /// Custom hp-Radau mesh per phase (overrides `points`; needs the Radau scheme), e.g. from
    /// [`refine::refine`].
    pub mesh: Option<Vec<crate::ocp::MeshSpec>>,
    /// Static dual regularization δ_c of the KKT factorization
    /// ([`Settings::static_dual_regularization`]); `None`: [`RAISED_DUAL_REGULARIZATION`]
    /// with LG, the solver's 1e-9 with Radau, and [`solve`] retries a failed solve with
    /// [`RAISED_DUAL_REGULARIZATION`]. Raise it (e.g. to 3e-8) when a Radau mesh finer than
    /// the default ends Acceptable with δ_w > 0 in every iteration (module docs); `Some`
    /// disables the retry. Overrides `ipm`.
    pub dual_regularization: Option<f64>,
}

/// A guess of constant joint angles `q` and phase durations `durations` (the paper's guess is
/// q ≡ [`Q_GUESS`], every duration 1 s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StartGuess {
    /// Joint angles (rad), one per joint.
    pub q: Vec<f64>,
    /// Phase durations (s), one per phase.
    pub durations: Vec<f64>,
}

impl Default for ProblemSettings {
    fn default() -> Self {
        ProblemSettings {
            points: 30,
            scheme: Scheme::Radau { elements: 3 },
            epsilon: None,
            warm_start: None,
            impulse_cone: false,
            hdot_margin: None,
            guess: GuessKind::Auto,
            ipm: None,
            max_iter: 1500,
            print_level: 0,
            start: None,
            effort_scale: 1.0,
            period_bounds: None,
            mesh: None,
            dual_regularization: None,
        }
    }
}

/// A transcribed problem ready to solve.
#[derive(Debug, Clone)]
pub struct BuiltProblem {
    /// Problem name.
    pub name: String,
    /// Scene.
    pub scene: Scene,
    /// Physical constants.
    pub physics: Physics,
    /// Mode of every phase.
    pub modes: Vec<Mode>,
    /// The multiphase problem.
    pub ocp: Ocp,
    /// Its transcription.
    pub nlp: Transcription,
    /// ε used.
    pub epsilon: f64,
    /// Settings used.
    pub settings: ProblemSettings,
}

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

/// Result of [`solve`]; serialises to `solution.json`.
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
    pub modes: Vec<Mode>,
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
    pub strategy: Option<strategy::StrategyReport>,
    /// Adaptive mesh refinement that produced this solution (`optimize --refine TOL`); its
    /// `mesh` is the final mesh (`points`/`scheme` above are the starting mesh's).
    #[serde(default)]
    pub refinement: Option<refine::RefineReport>,
    /// Re-integration of each phase with the optimal torques ([`verify::verify`]).
    #[serde(default)]
    pub verification: Option<verify::Verification>,
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> OcpError {
    OcpError::Io {
        path: path.display().to_string(),
        msg: e.to_string(),
    }
}

/// Write through a sibling temporary file and a rename, so a failed or interrupted write never
/// leaves a truncated `solution.json` / `torques.csv` behind.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OcpError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(|e| io_err(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_err(path, e)
    })
}

impl OcpSolution {
    /// Writes `solution.json`.
    pub fn write_json(&self, path: &Path) -> Result<(), OcpError> {
        let s = serde_json::to_string_pretty(self).map_err(|e| io_err(path, e))?;
        write_atomic(path, s.as_bytes())
    }

    /// Reads a solution written by [`OcpSolution::write_json`].
    pub fn read_json(path: &Path) -> Result<OcpSolution, OcpError> {
        let s = std::fs::read_to_string(path).map_err(|e| io_err(path, e))?;
        serde_json::from_str(&s).map_err(|e| io_err(path, e))
    }

    /// The torques as `t,tau1,...,tauN` CSV (sim/README.md): dense samples with strictly
    /// increasing times (a sample equal in time to the previous one, at a phase boundary, is
    /// dropped), full precision.
    pub fn torques_csv(&self) -> String {
        let nq = self.dense.tau.first().map_or(0, |v| v.len());
        let mut s = String::from("t");
        for i in 1..=nq {
            s.push_str(&format!(",tau{i}"));
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

    /// Writes [`OcpSolution::torques_csv`] to `path`.
    pub fn write_torques_csv(&self, path: &Path) -> Result<(), OcpError> {
        write_atomic(path, self.torques_csv().as_bytes())
    }
}

/// Scene text by name (`paper`, `human`).
fn scene_by_name(name: &str) -> Result<Scene, OcpError> {
    let text = match name {
        "paper" => bf_generated::paper::SCENE_TOML,
        "human" => bf_generated::human::SCENE_TOML,
        _ => return Err(OcpError::Model(format!("unknown scene {name}"))),
    };
    Scene::from_toml_str(text, name).map_err(|e| OcpError::Model(e.to_string()))
}

struct PhaseDef {
    mode: Mode,
    h: Option<(f64, f64)>,
    hdot: Option<(f64, f64)>,
    duration: (f64, f64),
    guess_duration: f64,
}

#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn make_phases(
    scene: &Scene,
    ph: &Physics,
    defs: &[PhaseDef],
    cost: CostKind,
    eps: f64,
    points: usize,
    q_limits: &[(f64, f64)],
    start: Option<&StartGuess>,
    stick: bf::StickLevel,
) -> Result<Vec<Phase>, OcpError> {
    let nq = ph.nq;
    if let Some(sg) = start {
        let ok = sg.q.len() == nq
            && sg.durations.len() == defs.len()
            && sg.q.iter().all(|v| v.is_finite())
            && sg.durations.iter().all(|v| v.is_finite() && *v > 0.0);
        if !ok {
            return Err(OcpError::InvalidProblem(format!(
                "start guess needs {nq} finite joint angles and {} positive durations, got {:?}",
                defs.len(),
                sg
            )));
        }
    }
    let mut out = Vec::new();
    for (k, d) in defs.iter().enumerate() {
        let (node, _) = bf::node_function_with(
            scene,
            ph,
            &NodeOptions {
                mode: d.mode,
                cost,
                h_bounds: d.h,
                hdot_bounds: d.hdot,
                eps,
            },
            stick,
        )?;
        let mut x_bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); 2 * nq + 3];
        x_bounds[..nq].copy_from_slice(q_limits);
        let na = node.a.len();
        let mut xg = vec![0.0; 2 * nq + 3];
        for i in 0..nq {
            xg[i] = start.map_or(Q_GUESS[i % 3], |sg| sg.q[i]);
            let (lo, hi) = q_limits[i];
            if lo.is_finite() || hi.is_finite() {
                xg[i] = xg[i].clamp(lo, hi);
            }
        }
        out.push(Phase {
            name: format!("{:?}", d.mode).to_lowercase(),
            node,
            x_bounds,
            a_bounds: vec![(f64::NEG_INFINITY, f64::INFINITY); na],
            u_bounds: ph.tau_max.iter().map(|&t| (-t, t)).collect(),
            duration_bounds: d.duration,
            points,
            guess: PhaseGuess::constant(
                xg,
                vec![0.0; na],
                vec![0.0; nq],
                start.map_or(d.guess_duration, |sg| {
                    sg.durations[k].clamp(d.duration.0, d.duration.1)
                }),
            ),
        });
    }
    Ok(out)
}

/// The point constraints of a free → stick switch at the end of phase 0: touch
/// (0 ≤ h⁽¹⁾(t_f) ≤ tol_h, Sect. 7), the sticking impact law (eq. 40) with the impulse ι as
/// parameters, and (Radau only) the stick constraint Δv = 0 at the end of phase 1, which the
/// Radau points do not include.
///
/// With Legendre–Gauss the stick phases impose d(Δv)/dt = 0 at the Gauss nodes
/// ([`bf::StickLevel::Acceleration`]) and the impact imposes Δv⁺ = 0 (eq. 40c) at the start, so
/// Δv = 0 at the quadrature end point holds up to the Gauss quadrature error (exactly when Δv
/// is linear in the state); imposing it again would make the constraint Jacobian (nearly) rank
/// deficient.
fn contact_sequence(
    scene: &Scene,
    ph: &Physics,
    eps: f64,
    tol_h: f64,
    settings: &ProblemSettings,
) -> Result<Vec<PointFunction>, OcpError> {
    let lg = settings.scheme == Scheme::Lg;
    let mut points = vec![
        bf::end_point(
            scene,
            eps,
            0,
            true,
            EndQuantity::H(0.0, tol_h),
            "0 <= h1(tf) <= 1e-4",
        )?,
        bf::impact(scene, ph, eps, 0, 0, settings.impulse_cone, lg)?,
    ];
    if !lg {
        points.push(bf::end_point(
            scene,
            eps,
            1,
            true,
            EndQuantity::DeltaV,
            "stick end: delta v = 0",
        )?);
    }
    Ok(points)
}

fn duration_sum(nphases: usize, lo: f64, hi: f64, name: &str) -> PointFunction {
    let mut g = bf_codegen::graph::Graph::new();
    let v: Vec<_> = (0..nphases as u32).map(|i| g.var(i)).collect();
    let s = g.sum(&v);
    PointFunction {
        name: name.into(),
        graph: g,
        vars: (0..nphases)
            .map(|i| (i as u32, VarRef::Duration(i)))
            .collect(),
        fixed: vec![],
        outputs: vec![s],
        bounds: vec![(lo, hi)],
    }
}

/// Fixes x(0) of phase 0 to `x0`.
fn initial_state(x0: &[f64]) -> PointFunction {
    let mut g = bf_codegen::graph::Graph::new();
    let v: Vec<_> = (0..x0.len() as u32).map(|i| g.var(i)).collect();
    PointFunction {
        name: "initial state".into(),
        graph: g,
        vars: (0..x0.len())
            .map(|i| (i as u32, VarRef::Initial { phase: 0, i }))
            .collect(),
        fixed: vec![],
        outputs: v,
        bounds: x0.iter().map(|&x| (x, x)).collect(),
    }
}

/// Fixes components `idx` of the final state of `phase` to 0.
fn final_zero(phase: usize, idx: &[usize], name: &str) -> PointFunction {
    let mut g = bf_codegen::graph::Graph::new();
    let v: Vec<_> = (0..idx.len() as u32).map(|i| g.var(i)).collect();
    PointFunction {
        name: name.into(),
        graph: g,
        vars: idx
            .iter()
            .enumerate()
            .map(|(k, &i)| (k as u32, VarRef::Final { phase, i }))
            .collect(),
        fixed: vec![],
        outputs: v,
        bounds: vec![(0.0, 0.0); idx.len()],
    }
}

/// Builds the named problem.
///
/// Runs on a helper thread with a large stack: building the graphs of a scene with runtime
/// parameters (`human`) recurses deeper in bf-codegen than a default 2 MiB test thread allows.
pub fn build(name: &str, settings: &ProblemSettings) -> Result<BuiltProblem, OcpError> {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(s, || build_inner(name, settings))
            .map_err(|e| OcpError::Model(format!("cannot spawn the build thread: {e}")))?
            .join()
            .map_err(|_| OcpError::Model("the problem build panicked".into()))?
    })
}

fn build_inner(name: &str, settings: &ProblemSettings) -> Result<BuiltProblem, OcpError> {
    let scene_name = if name == "periodic-cot-human" {
        "human"
    } else {
        "paper"
    };
    let scene = scene_by_name(scene_name)?;
    let ph = bf::physics(&scene)?;
    let eps = settings
        .epsilon
        .or(scene.contact.as_ref().map(|c| c.smooth_eps))
        .unwrap_or(0.01);
    if !(eps.is_finite() && eps > 0.0) {
        return Err(OcpError::InvalidProblem(format!(
            "epsilon must be positive, got {eps}"
        )));
    }
    if !(settings.effort_scale.is_finite() && settings.effort_scale > 0.0) {
        return Err(OcpError::InvalidProblem(format!(
            "effort_scale must be positive, got {}",
            settings.effort_scale
        )));
    }
    let nq = ph.nq;
    let nx = 2 * nq + 3;
    let r = ph.radius;
    let tol_h = 1e-4;
    let free_limits = vec![(f64::NEG_INFINITY, f64::INFINITY); nq];
    let margin = settings.hdot_margin;
    let pts = settings.points;
    let mut cost_bounds = vec![];
    let (defs, cost, objective, mut points, params): (
        Vec<PhaseDef>,
        CostKind,
        Objective,
        Vec<PointFunction>,
        Vec<Param>,
    );
    let iota_params = || -> Vec<Param> {
        (0..3)
            .map(|i| Param {
                name: format!("iota{}", i + 1),
                lower: -1e3,
                upper: 1e3,
                guess: 0.0,
            })
            .collect()
    };
    let q_limits = if scene_name == "human" {
        ph.q_limits.clone()
    } else {
        free_limits
    };
    let mut x_rest = vec![0.0; nx];
    x_rest[..nq].copy_from_slice(&Q_GUESS[..nq.min(3)]);
    match name {
        "periodic-qc" | "periodic-cot" | "periodic-cot-human" => {
            let qc = name == "periodic-qc";
            // Phase durations: ≤ 5 s for QC (its optimum has a short period); for COT only the
            // total period is bounded (≤ COT_MAX_PERIOD).
            let tmax = if qc { 5.0 } else { COT_MAX_PERIOD };
            defs = vec![
                PhaseDef {
                    mode: Mode::Free,
                    h: Some((0.0, f64::INFINITY)),
                    hdot: margin.map(|m| (f64::NEG_INFINITY, -m)),
                    duration: (0.01, tmax),
                    guess_duration: 1.0,
                },
                PhaseDef {
                    mode: Mode::Stick,
                    h: None,
                    hdot: None,
                    duration: (0.01, tmax),
                    guess_duration: 1.0,
                },
                PhaseDef {
                    mode: Mode::Free,
                    h: Some((-tol_h, f64::INFINITY)),
                    hdot: margin.map(|m| (m, f64::INFINITY)),
                    duration: (0.01, tmax),
                    guess_duration: 1.0,
                },
            ];
            cost = if qc {
                CostKind::Qc {
                    w: settings.effort_scale,
                    omega_ref: [0.0, 0.0, 2.2],
                }
            } else {
                let s = std::f64::consts::FRAC_1_SQRT_2;
                CostKind::Cot {
                    w: 10.0,
                    omega_hat: [s, -s, 0.0],
                }
            };
            objective = Objective::Ratio(0, 1);
            params = iota_params();
            points = vec![
                bf::end_point(
                    &scene,
                    eps,
                    0,
                    false,
                    EndQuantity::H(0.3 * r, f64::INFINITY),
                    "h(0) >= 0.3 r",
                )?,
                // The period may start anywhere on the free arc with h ≥ 0.3 r: a continuum of
                // equivalent optima (a flat direction that stalls Newton's method). Starting at
                // the arc's apex (ḣ(0) = 0) picks one without changing the optimal value, since
                // the apex is where h is largest.
                bf::end_point(
                    &scene,
                    eps,
                    0,
                    false,
                    EndQuantity::HDot(0.0, 0.0),
                    "apex start: hdot(0) = 0",
                )?,
            ];
            points.extend(contact_sequence(&scene, &ph, eps, tol_h, settings)?);
            points.push(bf::continuity(nx, 1, 2, "stick -> free continuity"));
            points.push(bf::continuity(nx, 2, 0, "periodicity"));
            // COT bounds the period; for QC the duration bounds imply 0.03 ≤ T ≤ 15 s, and the
            // row is only added when `period_bounds` is given (a continuation gives it in every
            // stage, so all stages share one NLP layout for primal-dual warm starts). An
            // inactive row is not free: it changes the barrier path (Radau: 72 → 82
            // iterations). LG no longer needs it: with the integral-form Gauss defects
            // (`ocp::transcription`) LG-30 is Solved without it (issue 6).
            let (plo, phi) = if qc {
                (0.03, 3.0 * tmax)
            } else {
                (0.0, COT_MAX_PERIOD)
            };
            let (plo, phi) = match settings.period_bounds {
                Some((lo, hi)) => (lo.max(plo), hi.min(phi)),
                None => (plo, phi),
            };
            if !(plo <= phi && plo.is_finite() && phi.is_finite()) {
                return Err(OcpError::InvalidProblem(format!(
                    "period bounds [{plo}, {phi}] are empty or not finite"
                )));
            }
            if !qc || settings.period_bounds.is_some() {
                points.push(duration_sum(
                    3,
                    plo,
                    phi,
                    if qc {
                        "period bounds"
                    } else {
                        "period <= 10 s"
                    },
                ));
            }
            if !qc {
                // The rotation measure must stay positive for the ratio to be meaningful.
                cost_bounds = vec![(f64::NEG_INFINITY, f64::INFINITY), (1e-3, f64::INFINITY)];
            }
        }
        "reach" => {
            defs = vec![PhaseDef {
                mode: Mode::Free,
                h: Some((0.0, f64::INFINITY)),
                hdot: None,
                duration: (0.05, 10.0),
                guess_duration: 1.0,
            }];
            cost = CostKind::TimeEffort { w: 1.0 };
            objective = Objective::Cost(0);
            params = vec![];
            points = vec![
                initial_state(&x_rest),
                bf::end_point(
                    &scene,
                    eps,
                    0,
                    true,
                    EndQuantity::H(0.0, tol_h),
                    "touch: 0 <= h(tf) <= 1e-4",
                )?,
                final_zero(0, &(nq..2 * nq).collect::<Vec<_>>(), "at rest at tf"),
            ];
        }
        "reorient" | "rotate-ref" | "rotate-fast" => {
            defs = vec![
                PhaseDef {
                    mode: Mode::Free,
                    h: Some((0.0, f64::INFINITY)),
                    hdot: None,
                    duration: (0.05, 5.0),
                    guess_duration: 1.0,
                },
                // |h| ≤ tol_h at the stick nodes: Δv = 0 (or its rate) alone let h drift when
                // the contact point slides over the smoothed fingertip (sat, eq. 58–59), and
                // the fixed-horizon spinning problems exploited it (rotate-fast LG-30 reached
                // J = −28 with the finger 0.76 m inside the ball; Radau −3.8 with 0.05 m).
                PhaseDef {
                    mode: Mode::Stick,
                    h: Some((-tol_h, tol_h)),
                    hdot: None,
                    duration: (0.05, 5.0),
                    guess_duration: 1.0,
                },
            ];
            params = iota_params();
            points = vec![initial_state(&x_rest)];
            points.extend(contact_sequence(&scene, &ph, eps, tol_h, settings)?);
            objective = Objective::Cost(0);
            match name {
                "reorient" => {
                    cost = CostKind::Reorient {
                        w: 0.1,
                        axis: [0.0, 0.0, 1.0],
                    };
                    let th = std::f64::consts::FRAC_PI_2;
                    cost_bounds = vec![(f64::NEG_INFINITY, f64::INFINITY), (th, th)];
                    points.push(duration_sum(2, 0.1, 10.0, "total time <= 10 s"));
                }
                "rotate-ref" => {
                    cost = CostKind::Track {
                        w: 0.1,
                        omega_ref: [0.0, 0.0, 1.0],
                    };
                    points.push(duration_sum(2, 3.0, 3.0, "horizon = 3 s"));
                }
                _ => {
                    cost = CostKind::Spin {
                        w: 0.01,
                        axis: [0.0, 0.0, 1.0],
                    };
                    points.push(duration_sum(2, 2.0, 2.0, "horizon = 2 s"));
                }
            }
        }
        _ => return Err(OcpError::UnknownProblem(name.into(), PROBLEMS.join(", "))),
    }
    let modes: Vec<Mode> = defs.iter().map(|d| d.mode).collect();
    let mut phases = make_phases(
        &scene,
        &ph,
        &defs,
        cost,
        eps,
        pts,
        &q_limits,
        settings.start.as_ref(),
        // LG: the index-1 stick constraint (see `bf::node_function_with`).
        if settings.scheme == Scheme::Lg {
            bf::StickLevel::Acceleration
        } else {
            bf::StickLevel::Velocity
        },
    )?;
    // A warm start replaces the whole initial point after the transcription (below).
    if settings.warm_start.is_none() && settings.guess == GuessKind::Contact {
        contact_guess(&scene, eps, &mut phases, &modes)?;
    }
    let ocp = Ocp {
        phases,
        n_costs: 2,
        params,
        points,
        cost_bounds,
        objective,
        scheme: settings.scheme,
    };
    let meshes: Vec<_> = settings.mesh.iter().flatten().cloned().map(Some).collect();
    let nlp = Transcription::with_meshes(&ocp, &meshes)?;
    let mut built = BuiltProblem {
        name: name.into(),
        scene,
        physics: ph,
        modes,
        ocp,
        nlp,
        epsilon: eps,
        settings: settings.clone(),
    };
    if let Some(ws) = &settings.warm_start {
        // The element polynomials of the previous solution evaluated at the new mesh's points
        // (exact where the meshes agree), rather than the sampled phase guess above.
        refine::warm_initial_point(&mut built, ws)?;
    }
    Ok(built)
}

/// The contact configuration q_c on the segment Q_GUESS → Q_DEEP with h(q_c) = 0.
fn contact_configuration(diag: &Diagnostics, nq: usize) -> Vec<f64> {
    let at = |s: f64| -> Vec<f64> {
        let mut x = vec![0.0; 2 * nq + 3];
        for i in 0..nq.min(3) {
            x[i] = Q_GUESS[i] + s * (Q_DEEP[i] - Q_GUESS[i]);
        }
        x
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if diag.eval(&at(mid)).h > 0.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    at(lo)[..nq].to_vec()
}

fn contact_guess(
    scene: &Scene,
    eps: f64,
    phases: &mut [Phase],
    modes: &[Mode],
) -> Result<(), OcpError> {
    let diag = Diagnostics::new(scene, eps)?;
    let nq = scene.links.len();
    let qc = contact_configuration(&diag, nq);
    let qf: Vec<f64> = phases[0].guess.x[0][..nq].to_vec();
    let n = phases.len();
    for (k, ph) in phases.iter_mut().enumerate() {
        let (qa, qb) = match modes[k] {
            Mode::Stick => (qc.clone(), qc.clone()),
            Mode::Free if k + 1 < n && modes[k + 1] == Mode::Stick => (qf.clone(), qc.clone()),
            Mode::Free if k > 0 => (qc.clone(), qf.clone()),
            // A lone free phase (reach) approaches the ball.
            Mode::Free => (qf.clone(), qc.clone()),
        };
        let t = ph.guess.duration;
        let mut xa = ph.guess.x[0].clone();
        let mut xb = xa.clone();
        for i in 0..nq {
            xa[i] = qa[i];
            xb[i] = qb[i];
            let v = (qb[i] - qa[i]) / t;
            xa[nq + i] = v;
            xb[nq + i] = v;
        }
        ph.guess.s = vec![0.0, 1.0];
        ph.guess.x = vec![xa, xb];
    }
    Ok(())
}

fn samples(p: &BuiltProblem, diag: &Diagnostics, traj: &[PhaseTrajectory], dense: bool) -> Samples {
    let nq = p.physics.nq;
    let mut s = Samples::default();
    for (pi, tr) in traj.iter().enumerate() {
        let taus: Vec<f64> = if dense {
            (0..100).map(|k| -1.0 + 2.0 * k as f64 / 99.0).collect()
        } else {
            tr.state_tau.clone()
        };
        for (k, &tau) in taus.iter().enumerate() {
            let x = if dense { tr.x_at(tau) } else { tr.x[k].clone() };
            // Interpolated controls may overshoot the bounds between nodes: clamp to |τ| ≤ τ_max.
            let u: Vec<f64> = tr
                .u_at(tau)
                .iter()
                .zip(&p.physics.tau_max)
                .map(|(u, m)| u.clamp(-m, *m))
                .collect();
            let a = tr.a_at(tau);
            let lam = if p.modes[pi] == Mode::Stick && a.len() >= nq + 6 {
                a[nq + 3..nq + 6].to_vec()
            } else {
                vec![0.0; 3]
            };
            let c = diag.eval(&x);
            let ln: f64 = lam.iter().zip(&c.n).map(|(a, b)| a * b).sum();
            let par: Vec<f64> = (0..3).map(|i| lam[i] - ln * c.n[i]).collect();
            let sigma = if p.modes[pi] == Mode::Stick {
                p.physics.mu_s * ln - par.iter().map(|v| v * v).sum::<f64>().sqrt()
            } else {
                0.0
            };
            s.t.push(tr.time(tau));
            s.phase.push(pi);
            s.q.push(x[..nq].to_vec());
            s.qd.push(x[nq..2 * nq].to_vec());
            s.omega.push(x[2 * nq..2 * nq + 3].to_vec());
            s.tau.push(u);
            s.lambda.push(lam);
            s.h.push(c.h);
            s.sigma.push(sigma);
            s.alpha.push(c.alpha);
        }
    }
    s
}

/// Builds the [`OcpSolution`] of `p` at the NLP point `x`.
pub fn solution_at(p: &BuiltProblem, x: &[f64], status: Status) -> Result<OcpSolution, OcpError> {
    let diag = Diagnostics::new(&p.scene, p.epsilon)?;
    let traj = extract(&p.nlp, x);
    let nq = p.physics.nq;
    let period: f64 = traj.iter().map(|t| t.duration).sum();
    let mut mean = [0.0; 3];
    for tr in &traj {
        for (k, &sp) in tr.node_state.iter().enumerate() {
            for i in 0..3 {
                mean[i] += 0.5 * tr.duration * tr.node_weight[k] * tr.x[sp][2 * nq + i];
            }
        }
    }
    if period > 0.0 {
        mean.iter_mut().for_each(|v| *v /= period);
    }
    let c0 = p.nlp.c0;
    let np = p.ocp.params.len();
    let (viol, _) = p.nlp.max_violation(x);
    Ok(OcpSolution {
        problem: p.name.clone(),
        status,
        objective: crate::ipm::Nlp::objective(&p.nlp, x),
        c1: x[c0],
        c2: x[c0 + 1],
        modes: p.modes.clone(),
        phase_durations: traj.iter().map(|t| t.duration).collect(),
        period,
        mean_omega: mean,
        impulse: x[p.nlp.p0..p.nlp.p0 + np].to_vec(),
        iterations: 0,
        solve_seconds: 0.0,
        stages: vec![],
        constraint_violation: viol,
        dual_infeasibility: f64::NAN,
        timing: Timing::default(),
        counters: Counters::default(),
        nlp_size: (
            crate::ipm::Nlp::num_variables(&p.nlp),
            crate::ipm::Nlp::num_constraints(&p.nlp),
        ),
        points: p.settings.points,
        scheme: p.settings.scheme,
        epsilon: p.epsilon,
        nodes: samples(p, &diag, &traj, false),
        dense: samples(p, &diag, &traj, true),
        raw: traj,
        params: x[p.nlp.p0..p.nlp.p0 + np].to_vec(),
        nlp_warm: None,
        strategy: None,
        refinement: None,
        verification: None,
    })
}

/// Interior-point settings used by [`solve`].
pub fn solver_settings(s: &ProblemSettings) -> Settings {
    let base = s.ipm.clone().unwrap_or_else(|| Settings {
        tol: 1e-8,
        static_dual_regularization: match s.scheme {
            Scheme::Lg => RAISED_DUAL_REGULARIZATION,
            Scheme::Radau { .. } => Settings::default().static_dual_regularization,
        },
        ..Settings::default()
    });
    Settings {
        max_iter: s.max_iter,
        print_level: s.print_level,
        static_dual_regularization: s
            .dual_regularization
            .unwrap_or(base.static_dual_regularization),
        ..base
    }
}

type Callback<'a> = Option<&'a mut dyn FnMut(&IterationInfo) -> bool>;

fn reborrow<'a>(c: &'a mut Callback<'_>) -> Callback<'a> {
    match c {
        Some(f) => Some(&mut **f),
        None => None,
    }
}

/// Solves `p` directly. Initial point: an exact primal-dual warm start when `p.settings`
/// carries a warm-start solution of the same problem on the same mesh, else its interpolated
/// primal point or the guess of [`ProblemSettings::guess`]; with [`GuessKind::Auto`], a failed
/// solve from the PARAMS.md guess is repeated from the geometric [`GuessKind::Contact`] guess.
/// Before that, a failed solve with the default static dual regularization (Radau: 1e-9) is
/// repeated from the same start with [`RAISED_DUAL_REGULARIZATION`] (unless
/// [`ProblemSettings::dual_regularization`] is set): on Radau meshes finer than the default
/// the unpivoted LDLᵀ otherwise stalls (module docs). `callback` sees every iteration (return
/// `false` to stop). The library's default [`strategy::Strategy`] wraps this in a
/// continuation.
pub fn solve(
    p: &BuiltProblem,
    mut callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<OcpSolution, OcpError> {
    let start = Instant::now();
    let mut stages = Vec::new();
    let mut iters = 0;
    let exact = p
        .settings
        .warm_start
        .as_ref()
        .and_then(|ws| exact_warm_start(p, ws));
    let settings = if p.settings.warm_start.is_some() {
        warm_settings(&p.settings)
    } else {
        solver_settings(&p.settings)
    };
    let label = match (exact.is_some(), p.settings.warm_start.is_some()) {
        (true, _) => "exact warm start".to_string(),
        (false, true) => "interpolated warm start".to_string(),
        (false, false) => format!("{:?} guess", p.settings.guess),
    };
    let mut sol = solve_nlp(&p.nlp, &settings, exact, reborrow(&mut callback))?;
    iters += sol.iterations;
    stages.push((
        format!("{label}, eps {}", p.epsilon),
        sol.status,
        sol.iterations,
    ));
    // The stall of an unpivoted LDLᵀ whose δ_c hides the curvature (module docs): one retry
    // from the same start with the raised δ_c, unless the caller chose δ_c.
    if !sol.status.is_success()
        && p.settings.dual_regularization.is_none()
        && settings.static_dual_regularization < RAISED_DUAL_REGULARIZATION
    {
        let raised = Settings {
            static_dual_regularization: RAISED_DUAL_REGULARIZATION,
            ..settings
        };
        let retry = solve_nlp(&p.nlp, &raised, exact, reborrow(&mut callback))?;
        iters += retry.iterations;
        stages.push((
            format!(
                "{label}, eps {}, dual regularization {RAISED_DUAL_REGULARIZATION:e}",
                p.epsilon
            ),
            retry.status,
            retry.iterations,
        ));
        if retry.status.is_success() {
            sol = retry;
        }
    }
    let mut best = (sol, p);
    let fallback;
    if !best.0.status.is_success()
        && p.settings.warm_start.is_none()
        && p.settings.guess == GuessKind::Auto
    {
        let s1 = ProblemSettings {
            guess: GuessKind::Contact,
            ..p.settings.clone()
        };
        fallback = build(&p.name, &s1)?;
        let sol1 = solve_nlp(
            &fallback.nlp,
            &solver_settings(&p.settings),
            None,
            reborrow(&mut callback),
        )?;
        iters += sol1.iterations;
        stages.push((
            format!("Contact guess, eps {}", p.epsilon),
            sol1.status,
            sol1.iterations,
        ));
        best = (sol1, &fallback);
    }
    let (sol, pp) = best;
    let mut out = finish_solution(pp, &sol)?;
    out.iterations = iters;
    out.solve_seconds = start.elapsed().as_secs_f64();
    out.stages = stages;
    Ok(out)
}

/// Interior-point settings for a warm-started stage: a small initial μ and bound pushes, so
/// the iterates stay near the previous solution instead of re-centring (unless the caller set
/// its own [`ProblemSettings::ipm`]).
pub fn warm_settings(s: &ProblemSettings) -> Settings {
    let mut st = solver_settings(s);
    if s.ipm.is_none() {
        st.mu_init = 1e-4;
        st.warm_start_bound_push = 1e-6;
        st.warm_start_mult_bound_push = 1e-6;
    }
    st
}

/// The primal-dual point of `ws` if it belongs to the same problem on the same mesh (same
/// NLP layout), so that it can warm-start `p` exactly rather than by interpolation.
fn exact_warm_start<'a>(p: &BuiltProblem, ws: &'a OcpSolution) -> Option<&'a WarmStart> {
    let w = ws.nlp_warm.as_ref()?;
    let n = crate::ipm::Nlp::num_variables(&p.nlp);
    let m = crate::ipm::Nlp::num_constraints(&p.nlp);
    let same = ws.problem == p.name
        && ws.scheme == p.settings.scheme
        && ws.points == p.settings.points
        && ws.nlp_size == (n, m)
        && w.x.len() == n
        && w.lambda.len() == m
        && w.z_l.len() == n
        && w.z_u.len() == n
        && w.x.iter().all(|v| v.is_finite());
    same.then_some(w)
}

/// Solves `p` from the primal-dual point `warm` (same NLP layout) with [`warm_settings`].
pub fn solve_warm(
    p: &BuiltProblem,
    warm: &WarmStart,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<OcpSolution, OcpError> {
    let start = Instant::now();
    let sol = solve_nlp(&p.nlp, &warm_settings(&p.settings), Some(warm), callback)?;
    let mut out = finish_solution(p, &sol)?;
    out.iterations = sol.iterations;
    out.solve_seconds = start.elapsed().as_secs_f64();
    out.stages = vec![(
        format!("warm start, eps {}", p.epsilon),
        sol.status,
        sol.iterations,
    )];
    Ok(out)
}

/// The [`OcpSolution`] of an interior-point result, with its statistics and warm-start data.
fn finish_solution(p: &BuiltProblem, sol: &Solution) -> Result<OcpSolution, OcpError> {
    let mut out = solution_at(p, &sol.x, sol.status)?;
    out.iterations = sol.iterations;
    out.constraint_violation = sol.constraint_violation;
    out.dual_infeasibility = sol.dual_infeasibility;
    out.timing = sol.timing;
    out.counters = sol.counters;
    out.nlp_warm = Some(WarmStart::from(sol));
    Ok(out)
}
