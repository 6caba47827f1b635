//! The problem catalogue (paper Sect. 4.1 archetypes, Sect. 6.1 periodic problems): a
//! [`Problem`] and [`ProblemSettings`] → [`build`] → a [`BuiltProblem`], the multiphase
//! problem and its transcription, ready for the study layer to solve. One function per
//! archetype builds the phases, costs and point functions ([`archetypes`]); the initial guesses
//! are in [`guess`]; [`extract`] turns an NLP point of a built problem into its solution record
//! ([`crate::solution`]) and a record into a warm start. The problems themselves are named by
//! [`Problem`] ([`crate::id`]). [`check_settings`] runs [`build`]'s checks of the numeric
//! settings alone, for callers that refuse a user's value before any work starts.
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
//! | any periodic one with [`ProblemSettings::replan`] | free–free–stick from a measured lift-off state to the optimum's ([`replan`]) | the same ratio |
//!
//! Transcription: the default is Legendre–Gauss–Radau with 3 elements per phase (30 points
//! per phase in total). The paper's Legendre–Gauss scheme ([`Scheme::Lg`]) is available. With
//! it the stick phases impose the no-slip constraint at the acceleration level,
//! d(Δv)/dt = 0 at the Gauss nodes ([`StickLevel::Acceleration`]), with Δv⁺ = 0 from the
//! impact law and no end-point Δv row: at the velocity level the stick phase is an index-2
//! DAE, which Gauss collocation (not stiffly accurate) resolves with an undamped alternating
//! mode, and LG-20/30 stalled with δ_w ≈ 1e-3 in every iteration. The Gauss defects are in
//! integral form (`ocp::transcription`): with the differential form (rows with the O(N²)
//! entries of the Gauss differentiation matrix) `periodic-cot`/`-human` LG-30 stalled
//! (δ_w ≈ 1e-2 in every iteration, MaxIterations) and `periodic-qc` LG-30 needed an extra
//! inactive period row.
//!
//! The solve policy (dual regularization of LG solves, retries) is the study layer's.
//!
//! The periodic problems start the period at the apex of the free arc (ḣ(0) = 0), which
//! removes the time-shift degeneracy of the free arc without changing the optimum.
//! Common constraints: |τ_i| ≤ τ_max (1 N m), h ≥ 0 in free approach phases, λ_n ≥ 0 and the
//! smooth friction cone in stick, the sticking impact law (eq. 40) with ι_n ≥ 0,
//! 0 ≤ h(t_f⁽¹⁾) ≤ 10⁻⁴ and h⁽³⁾ ≥ −10⁻⁴ (Sect. 7 work-arounds), Δv = 0 at the stick phase's
//! end point with Radau (LG: see above), and |h| ≤ 10⁻⁴ at the stick nodes of the free–stick
//! archetypes: Δv = 0 (or its rate) alone does not hold h where the contact point slides over
//! the smoothed fingertip (sat, eq. 58–59), and the fixed-horizon spinning problems exploited
//! that (the finger ended far inside the ball). The periodic problems' stick phases stay
//! within about 1e-4 without the row, and the row's narrow barrier band lengthens their solves
//! considerably, so they go without it.

pub mod archetypes;
pub mod extract;
pub mod guess;
pub mod replan;

use std::fmt;
use std::str::FromStr;

use bf_codegen::Scene;
use bf_codegen::spec::SceneId;
use bf_optim::ipm::Settings;
use bf_optim::ocp::{KernelUse, MeshSpec, Ocp, Scheme, Transcription};

use crate::ProblemError;
use serde::{Deserialize, Serialize};

pub use crate::id::Problem;
use crate::node::{PhaseMode, Physics, StickLevel};
use crate::solution::OcpSolution;
use archetypes::Archetype;
pub use extract::{mean_omega, node_kernel_source, solution_at, warm_initial_point};
pub use guess::{GuessConfigurations, Q_DEEP, Q_GUESS, StartGuess, guess_configurations};

impl Problem {
    /// The compiled scene the problem is posed on.
    pub fn scene(self) -> SceneId {
        match self {
            Problem::PeriodicCotHuman => SceneId::HUMAN,
            _ => SceneId::PAPER,
        }
    }

    /// Whether it is one of the periodic problems (a period to sweep in a continuation).
    pub fn is_periodic(self) -> bool {
        self.archetype() == Archetype::Periodic
    }

    /// Whether the finger strikes the ball and then sticks to it: every problem but `reach`,
    /// which ends touching the ball at rest. Only such a problem has an impact law, an
    /// impulse cone and a friction cone for its stick phase to leave a margin of.
    pub fn has_impact(self) -> bool {
        self.archetype() != Archetype::Reach
    }

    fn archetype(self) -> Archetype {
        match self {
            Problem::PeriodicQc | Problem::PeriodicCot | Problem::PeriodicCotHuman => {
                Archetype::Periodic
            }
            Problem::Reach => Archetype::Reach,
            Problem::Reorient | Problem::RotateRef | Problem::RotateFast => Archetype::FreeStick,
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Problem {
    type Err = ProblemError;

    fn from_str(s: &str) -> Result<Problem, ProblemError> {
        Problem::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| ProblemError::UnknownProblem {
                name: s.to_string(),
            })
    }
}

/// What the catalogue needs from the crate generated at build time (bf-generated), handed in
/// by the caller: this crate is a build-dependency of that one and cannot depend on it.
#[derive(Debug, Clone, Copy)]
pub struct Generated {
    /// The TOML text of a compiled scene by name.
    pub scene_toml: fn(name: &str) -> Option<&'static str>,
    /// Whether the phase node functions may or must run on emitted kernels.
    pub kernels: KernelUse,
}

/// Upper bound of the total period of the COT problems (s): the COT ratio is otherwise free
/// to trade period length against efficiency without limit.
pub const COT_MAX_PERIOD: f64 = 10.0;

/// ω_ref of `periodic-qc` (rad/s; the paper's QC objective, eq. 64–65).
pub const QC_OMEGA_REF: [f64; 3] = [0.0, 0.0, 2.2];

/// Kind of the initial guess.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GuessKind {
    /// docs/parameters.md / Sect. 6.1: q ≡ q⁰ ([`BuiltProblem::guess`]`.free`, [`Q_GUESS`] for
    /// a 3-joint finger), t_f⁽ⁱ⁾ = i, all else 0.
    Paper,
    /// Geometric: free phases move linearly between q⁰ and a contact configuration q_c
    /// (h(q_c) = 0, found by bisection between q⁰ and [`GuessConfigurations::deep`]), stick
    /// phases hold q_c; velocities consistent.
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
    /// The impact law of the plan: the sticking law (eq. 40, default) or Newton's (eq. 39: ω
    /// unchanged, the finger arriving without tangential velocity relative to the ball), so
    /// that a plant with Newton's law executes the plan ([`crate::points::impact`]).
    pub impact_law: crate::solution::PlannedImpact,
    /// Share of the friction cone a stick phase leaves unused, in [0, 1): the plan's cone is
    /// (1 − m) μ_s λ_n ≥ |λ_∥| (eq. 18), so that a force controller executing it keeps m μ_s λ_n
    /// of grip for its feedback (`track`'s hybrid controller keeps 20 %). 0: the paper's cone.
    /// The verdict checks the scene's cone, which a plan with a margin meets with room.
    pub cone_margin: f64,
    /// Share of every joint's torque limit the plan leaves unused, in [0, 1): |τ_i| ≤ (1 − m)
    /// τ_max,i, so that feedback has m τ_max,i of authority under the limit. 0: the scene's
    /// limits.
    pub torque_margin: f64,
    /// Clearance (m) the periodic problems' approach keeps from the ball: h ≥ this at its
    /// collocation nodes, falling linearly to h ≥ 0 over the approach's last 1 % (an
    /// `EndRamp` of bf-optim), so that no node of the approach grazes the ball before the
    /// impact (the smoothed contact, eq. 58–59, lets a path pass micrometres from it where
    /// the exact one, the plant's, touches). 0: the paper's h ≥ 0.
    pub approach_clearance: f64,
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
    /// the study layer's mesh refinement.
    pub mesh: Option<Vec<MeshSpec>>,
    /// Static dual regularization δ_c of the KKT factorization
    /// ([`bf_optim::ipm::LinearSolverSettings::static_dual_regularization`]) at the start of
    /// a solve; `None`: the solver's 1e-9 with either scheme, which the solver itself raises to 3e-8 within a solve
    /// whose factor turns out misleading or inaccurate.
    /// Overrides `ipm`.
    pub dual_regularization: Option<f64>,
    /// Judge each KKT solve by the residual ratio `‖K s − r‖ / (‖r‖ + ‖s‖)`
    /// ([`bf_optim::ipm::ExperimentalSettings::residual_ratio_with_solution`]) in every solve
    /// of the problem; overrides `ipm`.
    pub kkt_residual_ratio: bool,
    /// Largest step size of the solver's extrapolation along negative curvature
    /// ([`bf_optim::ipm::LineSearchSettings::max_curvature_extrapolation`]) in every solve of
    /// the problem; `None`: the solver's default (16, on the barrier problems whose μ is at most the tolerance; 1 turns
    /// it off). Overrides `ipm`.
    pub curvature_extrapolation: Option<f64>,
    /// Extrapolate along negative curvature on every barrier problem
    /// ([`bf_optim::ipm::ExtrapolationScope::EveryBarrier`]); overrides `ipm`.
    pub extrapolate_every_barrier: bool,
    /// Weight of the proximal term on stalled barrier problems above the tolerance
    /// ([`bf_optim::ipm::BarrierSettings::proximal_weight`]) in every solve of the problem;
    /// `None`: the solver's default (0.1; 0 turns it off). Overrides `ipm`.
    pub proximal_weight: Option<f64>,
    /// The scene to pose the problem on instead of the problem's compiled scene (a parsed scene
    /// file, e.g. `optimize --scene`); its phase node functions run on emitted kernels where
    /// their fingerprint matches one and are interpreted otherwise (`KernelUse::Prefer`).
    #[serde(skip)]
    pub scene: Option<Scene>,
    /// Lower bound of the stick phase's duration in the periodic problems (s; default
    /// [`MIN_STICK`]). Many QC optima sit on it ("taps": the ball is spun mostly by the
    /// impact impulse), so it is a modelling choice, not a numerical one.
    pub min_stick: f64,
    /// Re-plan a periodic problem from a measured lift-off state: its transient period from
    /// there back to the periodic optimum's lift-off state ([`replan`]); `None`: the periodic
    /// problem itself. An error for the other problems.
    #[serde(skip)]
    pub replan: Option<replan::LiftOff>,
}

/// Default lower bound of every phase duration of the periodic problems, the stick phase's
/// included ([`ProblemSettings::min_stick`]), in seconds.
pub const MIN_STICK: f64 = 0.01;

impl Default for ProblemSettings {
    fn default() -> Self {
        ProblemSettings {
            points: 30,
            scheme: Scheme::Radau { elements: 3 },
            epsilon: None,
            warm_start: None,
            impulse_cone: false,
            impact_law: crate::solution::PlannedImpact::Stick,
            cone_margin: 0.0,
            torque_margin: 0.0,
            approach_clearance: 0.0,
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
            kkt_residual_ratio: false,
            curvature_extrapolation: None,
            extrapolate_every_barrier: false,
            proximal_weight: None,
            scene: None,
            min_stick: MIN_STICK,
            replan: None,
        }
    }
}

/// A transcribed problem ready to solve.
#[derive(Debug, Clone)]
pub struct BuiltProblem {
    /// The problem.
    pub problem: Problem,
    /// Problem name ([`Problem::name`]).
    pub name: String,
    /// Scene.
    pub scene: Scene,
    /// Physical constants.
    pub physics: Physics,
    /// PhaseMode of every phase.
    pub modes: Vec<PhaseMode>,
    /// The multiphase problem.
    pub ocp: Ocp,
    /// Its transcription.
    pub nlp: Transcription,
    /// ε used.
    pub epsilon: f64,
    /// Settings used.
    pub settings: ProblemSettings,
    /// The build-time artefacts it was built with (for rebuilds with other settings).
    pub generated: Generated,
    /// The joint configurations of its guesses (the scene's, see [`guess_configurations`]):
    /// `free` is q⁰ of the default guess, where `reach` and the free–stick problems start.
    pub guess: GuessConfigurations,
}

/// The scene `id` from `generated`.
fn scene(generated: &Generated, id: &SceneId) -> Result<Scene, ProblemError> {
    let name = id.as_str();
    let text = (generated.scene_toml)(name).ok_or_else(|| ProblemError::UnknownScene {
        scene: name.to_string(),
    })?;
    Scene::from_toml_str(text, name).map_err(|source| ProblemError::Scene {
        scene: name.to_string(),
        source,
    })
}

/// Builds `problem` with `settings`, on the scenes and node kernels of `generated`.
///
/// Runs on a helper thread with a large stack: building the graphs of a scene with runtime
/// parameters (`human`) recurses deeper in bf-codegen than a default 2 MiB test thread allows.
pub fn build(
    problem: Problem,
    settings: &ProblemSettings,
    generated: &Generated,
) -> Result<BuiltProblem, ProblemError> {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(s, || build_inner(problem, settings, generated))
            .map_err(ProblemError::BuildThread)?
            .join()
            .map_err(|_| ProblemError::BuildPanicked)?
    })
}

/// Longest phase of a `periodic-qc` plan, s: its optimum has a short period, so each phase is
/// bounded on its own (the COT problems bound only the period, by [`COT_MAX_PERIOD`]).
pub(crate) const QC_MAX_PHASE: f64 = 5.0;

/// The longest a phase of `problem` may last, s: what `min_stick` must stay below.
pub(crate) fn max_phase_duration(problem: Problem) -> f64 {
    if problem == Problem::PeriodicQc {
        QC_MAX_PHASE
    } else {
        COT_MAX_PERIOD
    }
}

/// Checks the numeric settings that [`build`] refuses for `problem` on `scene` (ε, the cone
/// and torque margins, the approach clearance against the ball's radius, the effort scale and,
/// for the periodic problems, the minimum stick duration) without building anything, so that
/// a caller who takes them from a user can refuse a wrong value before any work starts.
/// [`build`] runs the same checks.
pub fn check_settings(
    problem: Problem,
    settings: &ProblemSettings,
    scene: &Scene,
) -> Result<(), ProblemError> {
    check_settings_on(problem, settings, scene, &crate::points::physics(scene)?)
}

/// The contact smoothing ε of a solve: the setting's, else the scene's, else 0.01.
fn smoothing_eps(settings: &ProblemSettings, scene: &Scene) -> f64 {
    settings
        .epsilon
        .or(scene.contact.as_ref().map(|c| c.smooth_eps))
        .unwrap_or(0.01)
}

fn check_settings_on(
    problem: Problem,
    settings: &ProblemSettings,
    scene: &Scene,
    ph: &Physics,
) -> Result<(), ProblemError> {
    let eps = smoothing_eps(settings, scene);
    if bf_scene::smooth_eps_out_of_range(eps).is_some() {
        return Err(ProblemError::InvalidSetting {
            name: "epsilon",
            value: eps,
            expected: bf_scene::SMOOTH_EPS_RANGE,
        });
    }
    for (name, value) in [
        ("cone_margin", settings.cone_margin),
        ("torque_margin", settings.torque_margin),
    ] {
        if !(0.0..1.0).contains(&value) {
            return Err(ProblemError::InvalidSetting {
                name,
                value,
                expected: "in [0, 1)",
            });
        }
    }
    // Up to a tenth of the ball's radius: the approach starts at h ≥ 0.3 r.
    if !(settings.approach_clearance >= 0.0 && settings.approach_clearance <= 0.1 * ph.radius) {
        return Err(ProblemError::InvalidSetting {
            name: "approach_clearance",
            value: settings.approach_clearance,
            expected: "in [0, r / 10] m, r the ball's radius",
        });
    }
    if !(settings.effort_scale.is_finite() && settings.effort_scale > 0.0) {
        return Err(ProblemError::InvalidSetting {
            name: "effort_scale",
            value: settings.effort_scale,
            expected: "positive",
        });
    }
    let tmax = max_phase_duration(problem);
    if problem.is_periodic()
        && !(settings.min_stick.is_finite()
            && settings.min_stick > 0.0
            && settings.min_stick < tmax)
    {
        return Err(ProblemError::InvalidSetting {
            name: "min_stick",
            value: settings.min_stick,
            expected: "positive and below the phase's maximum duration, in s (5 s for QC, the \
                       maximum period for COT)",
        });
    }
    Ok(())
}

fn build_inner(
    problem: Problem,
    settings: &ProblemSettings,
    generated: &Generated,
) -> Result<BuiltProblem, ProblemError> {
    let scene = match &settings.scene {
        Some(s) => s.clone(),
        None => scene(generated, &problem.scene())?,
    };
    // A scene given by the caller may have no emitted node kernels (other numbers): interpret
    // what has none rather than fail.
    let kernels = match (&settings.scene, generated.kernels) {
        (Some(_), KernelUse::Require(f)) => KernelUse::Prefer(f),
        (_, k) => k,
    };
    let ph = crate::points::physics(&scene)?;
    check_settings_on(problem, settings, &scene, &ph)?;
    let eps = smoothing_eps(settings, &scene);
    // The scene's ε, not the solve's: q⁰ is where `reach` starts, so it must not move with
    // the ε of a continuation stage.
    let conf = guess::guess_configurations(
        &scene,
        scene.contact.as_ref().map_or(0.01, |c| c.smooth_eps),
    )?;
    let ctx = archetypes::Context {
        problem,
        scene: &scene,
        physics: &ph,
        eps,
        settings,
        q_guess: &conf.free,
    };
    if settings.replan.is_some() && problem.archetype() != Archetype::Periodic {
        return Err(ProblemError::Replan {
            msg: format!("`{problem}` is not a periodic problem; only those are re-planned"),
        });
    }
    let spec = match problem.archetype() {
        Archetype::Periodic => archetypes::periodic(&ctx)?,
        Archetype::Reach => archetypes::reach(&ctx)?,
        Archetype::FreeStick => archetypes::free_stick(&ctx)?,
    };
    let modes: Vec<PhaseMode> = spec.phases.iter().map(|d| d.mode).collect();
    let mut phases = guess::make_phases(
        &scene,
        &ph,
        &spec.phases,
        spec.cost,
        eps,
        settings.points,
        &spec.q_limits,
        &conf.free,
        settings.start.as_ref(),
        // LG: the index-1 stick constraint (see `node::node_function`).
        if settings.scheme == Scheme::Lg {
            StickLevel::Acceleration
        } else {
            StickLevel::Velocity
        },
        guess::PlanMargins {
            cone: settings.cone_margin,
            torque: settings.torque_margin,
        },
    )?;
    // A warm start replaces the whole initial point after the transcription (below).
    if settings.warm_start.is_none() && settings.guess == GuessKind::Contact {
        guess::contact_guess(&scene, eps, &mut phases, &modes, &conf)?;
    }
    let ocp = Ocp {
        phases,
        n_costs: 2,
        params: spec.params,
        points: spec.points,
        cost_bounds: spec.cost_bounds,
        objective: spec.objective,
        scheme: settings.scheme,
    };
    let meshes: Vec<_> = settings.mesh.iter().flatten().cloned().map(Some).collect();
    let nlp = Transcription::with_kernels(&ocp, &meshes, kernels)?;
    let mut built = BuiltProblem {
        problem,
        name: problem.name().to_string(),
        scene,
        physics: ph,
        modes,
        ocp,
        nlp,
        epsilon: eps,
        settings: settings.clone(),
        generated: *generated,
        guess: conf,
    };
    if let Some(ws) = &settings.warm_start {
        // The element polynomials of the previous solution evaluated at the new mesh's points
        // (exact where the meshes agree), rather than the sampled phase guess above.
        warm_initial_point(&mut built, ws)?;
    }
    Ok(built)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> Scene {
        Scene::from_toml_str(include_str!("../../../scenes/paper.toml"), "paper").unwrap()
    }

    fn refused(problem: Problem, settings: &ProblemSettings) -> Option<&'static str> {
        match check_settings(problem, settings, &paper()) {
            Ok(()) => None,
            Err(ProblemError::InvalidSetting { name, .. }) => Some(name),
            Err(e) => panic!("not a setting's range: {e}"),
        }
    }

    /// The ranges that depend on the problem or the scene, at their edges: the approach
    /// clearance up to a tenth of the ball's radius, and the minimum stick duration below the
    /// longest phase of the periodic problems (5 s for QC, the period bound for COT) and
    /// ignored by the others.
    #[test]
    fn check_settings_refuses_the_ranges_that_depend_on_the_problem_and_the_scene() {
        let r = crate::points::physics(&paper()).unwrap().radius;
        let with = |clearance: f64, min_stick: f64| ProblemSettings {
            approach_clearance: clearance,
            min_stick,
            ..ProblemSettings::default()
        };
        let qc = Problem::PeriodicQc;
        assert_eq!(refused(qc, &with(0.1 * r, 0.01)), None);
        assert_eq!(
            refused(qc, &with(0.1 * r * (1.0 + 1e-9), 0.01)),
            Some("approach_clearance")
        );
        assert_eq!(refused(qc, &with(-1e-12, 0.01)), Some("approach_clearance"));
        assert_eq!(refused(qc, &with(0.0, 4.99)), None);
        for min_stick in [QC_MAX_PHASE, 0.0, f64::NAN] {
            assert_eq!(refused(qc, &with(0.0, min_stick)), Some("min_stick"));
        }
        let cot = Problem::PeriodicCot;
        assert_eq!(refused(cot, &with(0.0, QC_MAX_PHASE)), None);
        assert_eq!(refused(cot, &with(0.0, COT_MAX_PERIOD)), Some("min_stick"));
        assert_eq!(refused(Problem::Reach, &with(0.0, COT_MAX_PERIOD)), None);
    }
}
