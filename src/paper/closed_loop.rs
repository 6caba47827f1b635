//! Closed-loop execution of an optimum (paper Sect. 6.2 and 7): the optimum's torques replayed
//! open loop, with the joint-space PD of [`super::openloop`], or with bf-control's
//! [`HybridController`] (computed torque in free phases, event-timed hybrid force/velocity
//! control in contact, outer loop on the mean ω), on a plant that may differ from the
//! controller's model (another scene file, another impact law), and its figures period by
//! period ([`bf_control::period_metrics`]: the mean ω̄_k of eq. 61 per period and its error
//! ‖ω̄_k − ω̄*‖ / ‖ω̄*‖). The search's check of a plan ([`execution_check`]) runs each
//! perturbed plant of the robustness table only up to its first period, from the 4th on, that
//! misses [`ROBUSTNESS_TARGET`] ([`run_tracking_with`]'s `until_miss`); the paper's tables and
//! `track` run every period. Every run ends at the impact that completes its last period
//! (`count_period_starts`): the horizon's margin is there for a late plant, not simulated after
//! the periods. The hybrid controller runs fingers of 3 to [`MAX_TRACKED_JOINTS`]
//! joints ([`tracked_joints`]; `run_tracking_with`, [`Tracking`] and the robustness runs are
//! generic in the joint count N, and `track`, the robustness rows and [`execution_check`]
//! dispatch on the solution's, `with_joints!`). The robustness table perturbs the scene's
//! text (`PERTURBATIONS`: the values of the paper's finger, which the human finger and
//! `scenes/paper4.toml` share). Only periodic optima are tracked.
//! A run takes at most [`MAX_TRACKING_PERIODS`] periods, with a simulator step budget that
//! grows with them ([`tracking_step_budget`]).

use super::openloop::{
    DEFAULT_PD_TRACK, Until, initial_state, periodic_torques, simulate_optimum_until,
    tracking_input,
};
use crate::pipeline::verify::nan_max;
use anyhow::{Context, Result, anyhow, bail};
use bf_control::{
    HybridController, HybridGains, InverseDynamics, PeriodMetrics, PeriodStarts, Reference,
    period_metrics, reference::Samples,
};
use bf_model::{DynKernels, ImpactLaw, Kernels, Mode, Model};
use bf_problem::OcpSolution;
use bf_problem::node::PhaseMode;
use bf_problem::solution::records::ExecutionCheck;
use bf_sim::ball_finger::{BallFingerSettings, RunReport};
use bf_sim::{SimOutput, SimSettings};
use std::path::Path;

/// `$f::<N>(args…)` with N the joint count `$n` of a finger the closed loop runs (3 to
/// [`MAX_TRACKED_JOINTS`]), `$other` for any other count: one compiled copy of the controller
/// and the simulator's finger per joint count, as `simulate` has.
macro_rules! with_joints {
    ($n:expr, $f:ident($($a:expr),* $(,)?), $other:expr) => {
        match $n {
            3 => $f::<3>($($a),*),
            4 => $f::<4>($($a),*),
            5 => $f::<5>($($a),*),
            6 => $f::<6>($($a),*),
            7 => $f::<7>($($a),*),
            _ => $other,
        }
    };
}
pub(crate) use with_joints;

/// The controller executing the optimum.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControllerKind {
    /// The optimal torques τ*(t), periodically (Sect. 6.2).
    OpenLoop,
    /// τ*(t) plus joint-space PD on (q*(t), q̇*(t)) in the free phases ([`DEFAULT_PD_TRACK`]).
    Pd,
    /// bf-control's [`HybridController`] with the gains for the scene's ball
    /// ([`default_gains`]), its torque saturated
    /// at the scene's bounds ([`torque_bound`]).
    Hybrid,
    /// The same controller without the torque bounds.
    HybridUnbounded,
}

impl ControllerKind {
    /// The name used on the command line and in `tracking.json`.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::OpenLoop => "open-loop",
            ControllerKind::Pd => "pd",
            ControllerKind::Hybrid => "hybrid",
            ControllerKind::HybridUnbounded => "hybrid-unbounded",
        }
    }

    /// Whether the controller can re-plan at lift-off (`--replan`): the hybrid ones.
    pub fn replans(self) -> bool {
        matches!(
            self,
            ControllerKind::Hybrid | ControllerKind::HybridUnbounded
        )
    }

    /// Parses `open-loop`, `pd`, `hybrid` or `hybrid-unbounded`; the error lists them.
    pub fn parse(text: &str) -> Result<Self> {
        Ok(match text {
            "open-loop" => ControllerKind::OpenLoop,
            "pd" => ControllerKind::Pd,
            "hybrid" => ControllerKind::Hybrid,
            "hybrid-unbounded" => ControllerKind::HybridUnbounded,
            _ => bail!(
                "unknown controller `{text}`; expected one of: open-loop, pd, hybrid, \
                 hybrid-unbounded"
            ),
        })
    }
}

/// A closed-loop run of a finger with `N` joints.
pub struct Tracking<const N: usize = 3> {
    /// The controller.
    pub controller: ControllerKind,
    /// Periods asked for.
    pub requested_periods: usize,
    /// The simulation's output.
    pub output: SimOutput<Mode>,
    /// Its derived per-sample quantities (τ, λ, …) and summary.
    pub report: RunReport<N>,
    /// Why the simulation stopped early, if it did.
    pub stopped: Option<String>,
    /// The completed periods, at most `requested_periods`.
    pub periods: Vec<PeriodMetrics>,
    /// The plan's period (s), against which each period's length is judged
    /// ([`PeriodMetrics::contact_failure`]).
    pub plan_period: f64,
    /// Why the run counts as having lost the ball, if it does: fewer periods completed than
    /// asked for, a period without the plan's contact (a touch alone, or a period so long
    /// that the finger missed the ball), or a failed simulation.
    pub lost: Option<String>,
    /// The re-plans at the lift-offs ([`super::replan`]; empty without re-planning).
    pub replans: super::replan::ReplanLog,
}

impl<const N: usize> Tracking<N> {
    /// Why the run is no result, if it is not: the ball was lost ([`Tracking::lost`]), or the
    /// simulation's energy balance missed the simulator's own check
    /// (`RunSummary::energy_check_failure`), when its periods measure the integrator's error
    /// rather than the controller.
    pub fn failure(&self) -> Option<String> {
        if let Some(lost) = &self.lost {
            return Some(format!(
                "the {} controller {}: {lost}",
                self.controller.name(),
                self.loss()
            ));
        }
        self.check_failure()
    }

    /// What [`Tracking::lost`] means for this run: "lost the ball", or, where the simulation
    /// itself stopped (a step limit, a model error), that its periods were not completed: the
    /// ball may still have been in hand.
    pub fn loss(&self) -> &'static str {
        loss_wording(self.stopped.is_some())
    }

    /// Why the simulation is not the plant's physics, if it is not: its energy balance failed
    /// ([`Tracking::energy_check_failure`]), or the Zeno fallback held the contact while the
    /// ball pulled the finger (`RunSummary::held_contact`: λ_n < 0 over steps), so the periods
    /// measure a regularisation rather than the controller. A stick held with σ < 0 is only a
    /// warning (decision record 0086).
    pub fn check_failure(&self) -> Option<String> {
        self.energy_check_failure().or_else(|| {
            self.report.summary.held_contact().map(|w| {
                format!(
                    "the plant's contact was held by the simulator from t = {} s: {}",
                    w.t, w.message
                )
            })
        })
    }

    /// Why the simulation's energy balance failed the simulator's check
    /// (`RunSummary::energy_check_failure`), if it did: its periods measure the integrator's
    /// error, whatever they say of the controller.
    pub fn energy_check_failure(&self) -> Option<String> {
        self.report.summary.energy_check_failure().map(|w| {
            format!(
                "the energy balance failed its check at t = {} s: {}",
                w.t, w.message
            )
        })
    }
}

/// The optimum's scene parsed, with its name ([`crate::pipeline::solve::solution_scene`]).
pub fn solution_scene(sol: &OcpSolution) -> Result<(bf_codegen::Scene, String)> {
    Ok(crate::pipeline::solve::solution_scene(sol)?)
}

/// The model of a finger with `N` joints on the kernels of `scene` (compiled where the scene
/// is a compiled one, interpreted otherwise) and its inverse dynamics for the hybrid
/// controller: the compiled `inverse_dynamics` kernel where the kernels are compiled and the
/// scene emits one, otherwise the model's own M q̈ + C q̇ + g
/// ([`InverseDynamics::from_model`]); and which kernels the model runs on.
pub fn finger_model<const N: usize>(
    scene: &bf_codegen::Scene,
) -> Result<(
    Model<DynKernels<N>, N>,
    InverseDynamics,
    bf_model::KernelSource,
)> {
    let n = tracked_joints(scene)?;
    if n != N {
        bail!("it has {n} joints where the plan's finger has {N}");
    }
    let (kernels, source) = bf_model::registry::contact_kernels_n::<N>(scene)?;
    let model = Model::from_kernels(kernels)?;
    let mu_v = model.params().mu_v();
    let compiled = (source == bf_model::KernelSource::Compiled)
        .then(|| InverseDynamics::compiled(&scene.name, model.kernels().param_values(), mu_v).ok())
        .flatten();
    let id = compiled.unwrap_or_else(|| InverseDynamics::from_model(N, mu_v));
    Ok((model, id, source))
}

/// The optimum's scene ([`solution_scene`]) as a model of a finger with `N` joints, with its
/// name; an error names the scene when it is no such finger.
pub fn solution_model<const N: usize>(
    sol: &OcpSolution,
) -> Result<(Model<DynKernels<N>, N>, String)> {
    let (scene, name) = solution_scene(sol)?;
    let (model, ..) =
        finger_model::<N>(&scene).with_context(|| format!("the solution's scene `{name}`"))?;
    Ok((model, name))
}

/// Most joints of a finger the closed loop runs (the simulator's largest finger).
pub const MAX_TRACKED_JOINTS: usize = 7;

/// The joint count of `scene`, an error unless the closed loop runs it: 3 to
/// [`MAX_TRACKED_JOINTS`] joints. The contact law commands the 3-D contact force through
/// J_cᵀ λ (bf-control's module doc), which a finger of fewer joints cannot give, while
/// `optimize` and `simulate` take such fingers; so a plan of one is refused with what `track`
/// supports rather than with a failure inside the run.
pub fn tracked_joints(scene: &bf_codegen::Scene) -> Result<usize> {
    let n = scene.links.len();
    if (3..=MAX_TRACKED_JOINTS).contains(&n) {
        Ok(n)
    } else {
        Err(anyhow!(
            "it has {n} joints; the closed loop (`track`, the hybrid controller) executes \
             plans on fingers of 3 to {MAX_TRACKED_JOINTS} joints (its contact law commands \
             a 3-D contact force through the joints)"
        ))
    }
}

/// The optimum as a [`Reference`] of the controller's model `model`.
pub fn reference_of<const N: usize>(
    sol: &OcpSolution,
    model: &Model<DynKernels<N>, N>,
) -> Result<Reference<N>> {
    let d = &sol.dense;
    let contact: Vec<bool> = sol.modes.iter().map(|m| *m != PhaseMode::Free).collect();
    Reference::from_samples(
        model,
        &contact,
        &sol.phase_durations,
        Samples {
            t: &d.t,
            phase: &d.phase,
            q: &d.q,
            qd: &d.qd,
            omega: &d.omega,
            tau: &d.tau,
            lambda: &d.lambda,
        },
        sol.mean_omega,
    )
    .context("the solution's trajectory as a reference")
}

/// The torque bounds |τ_i| ≤ τ_max,i of the optimum's scene (N m; infinite where the scene
/// sets none or cannot be read).
pub fn torque_bound<const N: usize>(sol: &OcpSolution) -> [f64; N] {
    match solution_scene(sol) {
        Ok((scene, _)) => scene_torque_bound(&scene),
        Err(_) => [f64::INFINITY; N],
    }
}

/// The torque bounds |τ_i| ≤ τ_max,i of `scene` (N m; infinite where it sets none).
fn scene_torque_bound<const N: usize>(scene: &bf_codegen::Scene) -> [f64; N] {
    let max = bf_codegen::spec::Constants::of(scene).map(|c| c.tau_max);
    std::array::from_fn(|i| {
        max.as_ref()
            .and_then(|m| m.get(i).copied())
            .filter(|b| *b > 0.0)
            .unwrap_or(f64::INFINITY)
    })
}

/// Periods of the closed-loop check of a plan on its nominal plant ([`execution_check`]): the
/// first holds the plant's first impact and lift-off, where a plan that the controller cannot
/// follow shows (the grazing human plans measured: 67 % and 32 % off in periods 1 and 2), the
/// next two whether it settles.
pub const EXECUTION_PERIODS: usize = 3;

/// Largest error of a period's mean ball spin on the nominal plant that the check of a plan
/// passes (relative): the plans `track` executes are within 0.011 % there, the closed-loop
/// tests hold them to 2 % (docs/closed-loop.md).
pub const EXECUTION_TOLERANCE: f64 = 0.02;

/// Periods of the check on each plant of the robustness table: the paper report's table.
pub const EXECUTION_ROBUSTNESS_PERIODS: usize = 10;

/// The closed-loop check of a plan for the plant (the search's
/// [`crate::pipeline::search::Execution`], decision record 0048): [`ControllerKind::Hybrid`]
/// on the nominal plant of the plan's own scene with Newton's impact law for
/// [`EXECUTION_PERIODS`] periods, each within [`EXECUTION_TOLERANCE`] of the plan's mean spin,
/// then on every plant of the robustness table ([`robustness_rows`],
/// [`EXECUTION_ROBUSTNESS_PERIODS`] periods) to its target ([`ROBUSTNESS_TARGET`] from the 4th
/// period on, contact in every period): what `paper` asks of the plans it executes. The
/// plan's scene is `scene` where given (a search's candidate, which records no scene text
/// yet: its problem's scene, `--param` values included), else the one the solution records
/// ([`solution_scene`]). `None` where no run is possible (no such scene, or a finger the
/// closed loop does not run); a nominal
/// run that fails or loses the ball is a failed check (`failure`), a perturbed plant that
/// misses its target a robustness miss (`robustness_failure`), which grades the plan without
/// unverifying it ([`crate::pipeline::verify::robustness_miss`]).
pub fn execution_check(
    sol: &OcpSolution,
    scene: Option<&bf_codegen::Scene>,
) -> Option<ExecutionCheck> {
    let scene = match scene {
        Some(s) => s.clone(),
        None => solution_scene(sol).ok()?.0,
    };
    let joints = tracked_joints(&scene).ok()?;
    with_joints!(joints, execution_check_n(sol, &scene), None)
}

/// [`execution_check`] of a plan for a finger with `N` joints on `scene`.
fn execution_check_n<const N: usize>(
    sol: &OcpSolution,
    scene: &bf_codegen::Scene,
) -> Option<ExecutionCheck> {
    let (plant, ..) = finger_model::<N>(scene).ok()?;
    let mut check = ExecutionCheck {
        controller: ControllerKind::Hybrid.name().to_string(),
        periods: EXECUTION_PERIODS,
        max_omega_error: f64::NAN,
        tolerance: EXECUTION_TOLERANCE,
        robustness_periods: 0,
        robustness_error: f64::NAN,
        robustness_tolerance: ROBUSTNESS_TARGET,
        failure: None,
        robustness_failure: None,
    };
    let nominal = TableRuns {
        controller: ControllerKind::Hybrid,
        periods: EXECUTION_PERIODS,
        replan: None,
        until_miss: false,
    };
    let t = match run_tracking_on(
        sol,
        scene,
        default_gains(scene),
        plant,
        ImpactLaw::Newton,
        nominal,
    ) {
        Ok(t) => t,
        Err(e) => {
            check.failure = Some(format!("the nominal run failed: {e:#}"));
            return Some(check);
        }
    };
    check.max_omega_error = t
        .periods
        .iter()
        .map(|p| p.omega_error)
        .reduce(nan_max)
        .unwrap_or(f64::NAN);
    if let Some(lost) = &t.lost {
        check.failure = Some(format!("the nominal plant {} ({lost})", t.loss()));
        return Some(check);
    }
    if let Some(unbalanced) = t.check_failure() {
        check.failure = Some(format!("the nominal run is not a result: {unbalanced}"));
        return Some(check);
    }
    // A NaN error (no period completed) fails as well.
    if check.max_omega_error.is_nan() || check.max_omega_error > EXECUTION_TOLERANCE {
        check.failure = Some(format!(
            "on the nominal plant a period's mean ball spin is {:.2} % off the plan's \
             (tolerance {} %)",
            100.0 * check.max_omega_error,
            100.0 * EXECUTION_TOLERANCE
        ));
        return Some(check);
    }
    // A perturbed plant that misses the target is run only up to its first missed period:
    // the verdict is the same, and such runs are the chaotic, slow ones.
    let rows = rows_n::<N>(
        sol,
        scene,
        TableRuns {
            controller: ControllerKind::Hybrid,
            periods: EXECUTION_ROBUSTNESS_PERIODS,
            replan: None,
            until_miss: true,
        },
    );
    check.robustness_periods = EXECUTION_ROBUSTNESS_PERIODS;
    check.robustness_error = rows
        .iter()
        .map(|r| r.max_error_from_fourth.unwrap_or(f64::NAN))
        .reduce(nan_max)
        .unwrap_or(f64::NAN);
    if let Some(r) = rows.iter().find(|r| !r.meets_target) {
        check.robustness_failure = Some(match (&r.error, &r.lost, r.max_error_from_fourth) {
            (Some(e), _, _) => format!("the plant `{}` could not be run: {e}", r.plant),
            (_, Some(lost), _) => format!(
                "the plant `{}` {} ({lost})",
                r.plant,
                loss_wording(r.stopped)
            ),
            (_, _, Some(e)) if r.contact_every_period => format!(
                "on the plant `{}` a period from the 4th on is {:.2} % off the plan's mean \
                 spin (target {} %)",
                r.plant,
                100.0 * e,
                100.0 * ROBUSTNESS_TARGET
            ),
            _ => format!(
                "on the plant `{}` a period had no contact or fewer than {} completed",
                r.plant, EXECUTION_ROBUSTNESS_PERIODS
            ),
        });
    }
    Some(check)
}

/// Simulation time allowed for `periods` periods of `period` s after a lead-in of at most one
/// period (the flight to the first impact): a quarter more, so a plant that runs late still
/// completes them.
fn horizon(periods: usize, period: f64) -> f64 {
    1.25 * (periods + 1) as f64 * period
}

/// Most periods a tracking run takes. Every period's samples are kept (about 1.6 MB of memory
/// and 1.3 MB of files per period of the `periodic-qc` plan), so a longer run would exhaust the
/// machine before it ended.
pub const MAX_TRACKING_PERIODS: usize = 1000;

/// Attempted simulator steps allowed per period of a tracking run. The stored plans take about
/// 550 (`periodic-qc`) to 3 000 (`periodic-cot-human-plan`) per period under the hybrid
/// controller, so the
/// budget stops only a run whose steps collapse (a plant chattering on the ball), not a long
/// one. Ten periods get the simulator's default budget, 10⁶.
pub const TRACKING_STEPS_PER_PERIOD: usize = 100_000;

/// The step budget of a tracking run of `periods` periods: [`TRACKING_STEPS_PER_PERIOD`] for
/// each, and at least the simulator's default.
pub fn tracking_step_budget(periods: usize) -> usize {
    (TRACKING_STEPS_PER_PERIOD * periods).max(SimSettings::default().max_steps)
}

/// Runs `controller` on the optimum `sol` for `periods` periods on `plant` with `impact_law`,
/// from the optimum's initial state.
pub fn run_tracking<const N: usize>(
    sol: &OcpSolution,
    controller: ControllerKind,
    periods: usize,
    plant: Model<DynKernels<N>, N>,
    impact_law: ImpactLaw,
) -> Result<Tracking<N>> {
    run_tracking_replanned(sol, controller, periods, plant, impact_law, None)
}

/// [`run_tracking`], with `replan` = `Some(max_iter)`: the hybrid controllers re-plan at every
/// lift-off ([`super::replan::SolverReplanner`], at most `max_iter` iterations per re-plan);
/// an error for the open loop and the PD.
pub fn run_tracking_replanned<const N: usize>(
    sol: &OcpSolution,
    controller: ControllerKind,
    periods: usize,
    plant: Model<DynKernels<N>, N>,
    impact_law: ImpactLaw,
    replan: Option<usize>,
) -> Result<Tracking<N>> {
    run_tracking_with(
        sol, controller, None, periods, plant, impact_law, replan, false,
    )
}

/// The hybrid controller's default gains for the ball of `scene`
/// ([`HybridGains::for_ball`]: the defaults, in metres scaled by the ball's radius); the
/// defaults themselves for a scene without a ball, which no closed loop runs on.
pub fn default_gains(scene: &bf_codegen::Scene) -> HybridGains {
    HybridGains::for_ball(scene.ball.as_ref().map_or(1.0, |b| b.radius))
}

/// The ball's spin ω of every state (q, q̇, ω) of a finger with `joints` joints.
fn ball_spin(x: &[Vec<f64>], joints: usize) -> Vec<[f64; 3]> {
    x.iter()
        .map(|x| std::array::from_fn(|i| x[2 * joints + i]))
        .collect()
}

/// The period starts in the trajectory `tr` recorded so far, before and after its new samples:
/// periods run from impact to impact, a bounce not counted ([`period_metrics`],
/// [`PeriodStarts`]; a run that starts in contact counts its first sample as one), so `periods`
/// are complete at `periods` + 1 starts. `seen`: the samples examined before, the starts among
/// them and the finder's state, so each sample is looked at once.
fn count_period_starts(
    tr: &bf_sim::Trajectory<Mode>,
    seen: &std::cell::Cell<(usize, usize, PeriodStarts)>,
) -> (usize, usize) {
    let (from, before, mut finder) = seen.get();
    let n = tr.t.len().min(tr.mode.len());
    let mut starts = before;
    for i in from..n {
        starts += usize::from(finder.starts(tr.t[i], tr.mode[i]));
    }
    seen.set((n.max(from), starts, finder));
    (before, starts)
}

/// Whether the trajectory `tr` recorded so far holds a completed period, among the first
/// `periods`, from the 4th on whose mean ω is off the plan's `optimum` by more than
/// [`ROBUSTNESS_TARGET`]: [`period_metrics`] on its samples, which are those of the finished
/// run up to there, so the period's error is the one the finished run's row would show, and
/// the row misses its target whatever follows. Asked only when a period has just ended
/// ([`count_period_starts`]).
fn misses_from_fourth(
    tr: &bf_sim::Trajectory<Mode>,
    joints: usize,
    optimum: [f64; 3],
    periods: usize,
) -> bool {
    let n = tr.t.len().min(tr.mode.len()).min(tr.x.len());
    let omega = ball_spin(&tr.x[..n], joints);
    // Torques do not enter the error.
    let tau = vec![Vec::new(); n];
    period_metrics(&tr.t[..n], &tr.mode[..n], &omega, &tau, optimum)
        .iter()
        .take(periods)
        .skip(3)
        .any(|p| p.omega_error > ROBUSTNESS_TARGET)
}

/// [`run_tracking_replanned`] with the hybrid controllers' `gains` where given (`None`: the
/// [`default_gains`] of the solution's scene; ignored by the open loop and the PD): what a gain does to the
/// execution of a plan, measured on the same plant. With `until_miss` the run ends at the
/// first completed period from the 4th on that misses [`ROBUSTNESS_TARGET`]
/// (`misses_from_fourth`): such a run returns the periods up to that one, fewer than
/// `periods`, and is not counted as lost; its row misses the target on that period's error,
/// as the whole run's would, in a fraction of the time (a plan that misses it runs chaotic
/// periods, 10 s of simulation and more where a robust one takes 1–2 s, decision record
/// 0070).
#[allow(clippy::too_many_arguments)]
pub fn run_tracking_with<const N: usize>(
    sol: &OcpSolution,
    controller: ControllerKind,
    gains: Option<HybridGains>,
    periods: usize,
    plant: Model<DynKernels<N>, N>,
    impact_law: ImpactLaw,
    replan: Option<usize>,
    until_miss: bool,
) -> Result<Tracking<N>> {
    let (scene, _) = solution_scene(sol)?;
    let gains = gains.unwrap_or_else(|| default_gains(&scene));
    let how = TableRuns {
        controller,
        periods,
        replan,
        until_miss,
    };
    run_tracking_on(sol, &scene, gains, plant, impact_law, how)
}

/// [`run_tracking_with`] with the controller's model on `scene` (the optimum's scene, which a
/// search's candidate does not record yet: [`execution_check`]), run as `how` says.
fn run_tracking_on<const N: usize>(
    sol: &OcpSolution,
    scene: &bf_codegen::Scene,
    gains: HybridGains,
    plant: Model<DynKernels<N>, N>,
    impact_law: ImpactLaw,
    how: TableRuns,
) -> Result<Tracking<N>> {
    let TableRuns {
        controller,
        periods,
        replan,
        until_miss,
    } = how;
    if replan.is_some() && !controller.replans() {
        bail!(
            "re-planning needs a hybrid controller (hybrid or hybrid-unbounded), not `{}`",
            controller.name()
        );
    }
    if !(1..=MAX_TRACKING_PERIODS).contains(&periods) {
        bail!("a tracking run takes 1 to {MAX_TRACKING_PERIODS} periods (got {periods})");
    }
    // A solution of another problem (`reach`, …) has a duration but no period to repeat, and
    // no mean spin to measure one against.
    if let Ok(problem) = sol.problem.parse::<bf_problem::Problem>()
        && !problem.is_periodic()
    {
        bail!(
            "`{}` is not a periodic problem: the closed loop repeats a periodic optimum \
             ({})",
            sol.problem,
            bf_problem::Problem::ALL
                .iter()
                .filter(|p| p.is_periodic())
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if sol.dense.t.len() < 2 || !(sol.period.is_finite() && sol.period > 0.0) {
        bail!(
            "the solution has no periodic trajectory to track (period {} s, {} dense samples)",
            sol.period,
            sol.dense.t.len()
        );
    }
    if plant.kernels().param_values().len() != plant.kernels().param_names().len() {
        bail!("the plant scene's runtime parameters are incomplete");
    }
    let t_end = horizon(periods, sol.period);
    let max_steps = tracking_step_budget(periods);
    let copies = (t_end / sol.period).ceil() as usize + 1;
    let settings = BallFingerSettings {
        impact_law,
        ..BallFingerSettings::default()
    };
    let log = std::rc::Rc::new(std::cell::RefCell::new(super::replan::ReplanLog::default()));
    let missed = std::cell::Cell::new(false);
    let period_starts = std::cell::Cell::new((0, 0, PeriodStarts::default()));
    // The run ends once its periods are complete (the horizon's margin is for a late plant,
    // not to be simulated after the last period), or, with `until_miss`, at its first
    // missed period from the 4th on.
    let stop = |tr: &bf_sim::Trajectory<Mode>| {
        let (before, now) = count_period_starts(tr, &period_starts);
        if now > periods {
            return true;
        }
        let m = until_miss && now > before && misses_from_fourth(tr, N, sol.mean_omega, periods);
        missed.set(m);
        m
    };
    let until = Some(&stop as Until<'_>);
    let (output, report, stopped) = match controller {
        ControllerKind::OpenLoop => simulate_optimum_until(
            sol,
            plant,
            periodic_torques(sol, copies)?,
            settings,
            t_end,
            max_steps,
            until,
        )?,
        ControllerKind::Pd => simulate_optimum_until(
            sol,
            plant,
            tracking_input(sol, copies, &DEFAULT_PD_TRACK)?,
            settings,
            t_end,
            max_steps,
            until,
        )?,
        ControllerKind::Hybrid | ControllerKind::HybridUnbounded => {
            let (model, id, _) = finger_model::<N>(scene)
                .with_context(|| format!("the solution's scene `{}`", scene.name))?;
            let reference = reference_of(sol, &model)?;
            let x0 = initial_state(sol)?;
            let bound = match controller {
                ControllerKind::Hybrid => scene_torque_bound::<N>(scene),
                _ => [f64::INFINITY; N],
            };
            let mut law = HybridController::new(model, id, reference, gains, 0.0, &x0)?
                .with_torque_bound(bound)?;
            if let Some(max_iter) = replan {
                let replanner = super::replan::SolverReplanner::new(
                    sol,
                    finger_model::<N>(scene)?.0,
                    reference_of::<N>,
                    max_iter,
                    std::rc::Rc::clone(&log),
                )?;
                law = law.with_replanner(Box::new(replanner));
            }
            simulate_optimum_until(sol, plant, law, settings, t_end, max_steps, until)?
        }
    };
    let tr = &output.trajectory;
    let omega = ball_spin(&tr.x, N);
    let tau: Vec<Vec<f64>> = report.samples.iter().map(|s| s.tau.to_vec()).collect();
    let mut metrics = period_metrics(&tr.t, &tr.mode, &omega, &tau, sol.mean_omega);
    metrics.truncate(periods);
    let lost = if missed.get() {
        // Ended on a missed period, not lost (`until_miss`).
        None
    } else if let Some(s) = &stopped {
        Some(format!("the simulation stopped: {s}"))
    } else if let Some((k, why)) = metrics
        .iter()
        .enumerate()
        .find_map(|(k, p)| p.contact_failure(sol.period).map(|w| (k, w)))
    {
        Some(format!(
            "period {} did not execute the plan's contact: {why}",
            k + 1
        ))
    } else if metrics.len() < periods {
        Some(format!(
            "{} of {periods} periods completed in {t_end:.3} s (1.25 times the planned time with the lead-in)",
            metrics.len()
        ))
    } else {
        None
    };
    Ok(Tracking {
        controller,
        requested_periods: periods,
        output,
        report,
        stopped,
        periods: metrics,
        plan_period: sol.period,
        lost,
        replans: log.take(),
    })
}

/// The share of the optimum's ‖ω̄*‖ up to which a period's mean ω counts as matching it, for
/// the verdict on the paper's "match well at the beginning" (Sect. 6.2).
pub const MATCH_ERROR: f64 = 0.05;

/// One controller's line of [`comparison_markdown`].
struct Row {
    controller: ControllerKind,
    tracking: Result<Tracking>,
}

/// The report section that executes the optimum `sol` (scenario `name`) with the open loop,
/// the PD and the hybrid controller with and without the torque bounds for `periods` periods on its own scene (Newton's impact law, slip allowed):
/// completed periods, the ω error of the first period, the largest from the 4th on, stick and
/// slip time, the largest |τ|; and a one-line verdict on the paper's claim that the open loop
/// "matches well at the beginning". With `figures`, the Fig. 17 counterpart with all
/// controllers ([`error_figure`]) is written there and shown.
pub fn comparison_markdown(
    name: &str,
    sol: &OcpSolution,
    periods: usize,
    figures: Option<&Path>,
) -> Result<String> {
    use std::fmt::Write as _;
    // The nominal plant and the text below: Newton's law (eq. 39), not the simulator's
    // default (the sticking impact, which hides the slip after every impact).
    let law = ImpactLaw::Newton;
    // Independent runs, one per thread, collected in the table's order (the table does not
    // depend on the thread count).
    use rayon::prelude::*;
    let rows = [
        ControllerKind::OpenLoop,
        ControllerKind::Pd,
        ControllerKind::Hybrid,
        ControllerKind::HybridUnbounded,
    ]
    .into_par_iter()
    .map(|controller| {
        let (plant, _) = solution_model::<3>(sol)?;
        Ok(Row {
            controller,
            tracking: run_tracking(sol, controller, periods, plant, law),
        })
    })
    .collect::<Result<Vec<Row>>>()?;
    // The optimisation's torque bound: the hybrid controller saturates there, the open loop
    // and the PD do not; a run above it is marked.
    let tau_bound = torque_bound::<3>(sol)
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let pct = |e: f64| format!("{:.2}", 100.0 * e);
    let mut s = String::new();
    writeln!(
        s,
        "**`{name}`** (period {:.3} s, ω̄* = ({:.3}, {:.3}, {:.3}) rad/s), {periods} periods, \
         Newton's impact law, slip allowed:\n",
        sol.period, sol.mean_omega[0], sol.mean_omega[1], sol.mean_omega[2]
    )?;
    writeln!(
        s,
        "| controller | periods completed | ω error, 1st period (%) | max ω error from the 4th period (%) | stick / slip in the last period (ms) | max \\|τ\\| (N m) | ball |"
    )?;
    writeln!(s, "|---|---|---|---|---|---|---|")?;
    for row in &rows {
        match &row.tracking {
            Ok(t) => {
                let first = t.periods.first().map_or("—".into(), |p| pct(p.omega_error));
                let later = max_error_from_fourth(t).map_or("—".into(), pct);
                let last = t.periods.last().map_or("—".into(), |p| {
                    format!("{:.1} / {:.1}", 1e3 * p.stick_time, 1e3 * p.slip_time)
                });
                let tau = t.periods.iter().map(|p| p.max_abs_tau).fold(0.0, f64::max);
                let tau = if tau > tau_bound * (1.0 + 1e-9) {
                    format!("{tau:.3} ⚑ (bound {tau_bound})")
                } else {
                    format!("{tau:.3}")
                };
                let ball = match (&t.lost, t.check_failure()) {
                    (Some(why), _) => format!("**{}**: {why}", t.loss()),
                    (None, Some(why)) => format!("kept, but **not a result**: {why}"),
                    (None, None) => "kept".into(),
                };
                writeln!(
                    s,
                    "| {} | {} of {periods} | {first} | {later} | {last} | {tau} | {ball} |",
                    row.controller.name(),
                    t.periods.len()
                )?;
            }
            Err(e) => writeln!(
                s,
                "| {} | **failed**: {} | | | | | |",
                row.controller.name(),
                crate::errors::render(e)
            )?,
        }
    }
    let first_error = |row: &Row| {
        row.tracking
            .as_ref()
            .ok()
            .and_then(|t| t.periods.first().map(|p| p.omega_error))
    };
    let hybrid = first_error(&rows[2]).map_or("no period".into(), |e| format!("{} %", pct(e)));
    let verdict = match first_error(&rows[0]) {
        Some(e) if e <= MATCH_ERROR => format!(
            "holds: the open loop's first period is within {} % of ω̄* ({} %)",
            100.0 * MATCH_ERROR,
            pct(e)
        ),
        Some(e) => format!(
            "differs: the open loop's first period is {} % off ω̄* (a match is ≤ {} %); the \
             hybrid controller, which starts each contact phase at the plant's impact and \
             regulates the contact force, is {hybrid} off in its first period",
            pct(e),
            100.0 * MATCH_ERROR
        ),
        None => format!(
            "differs: the open loop completes no period (no impact); the hybrid controller's \
             first period is {hybrid} off"
        ),
    };
    let marked = rows.iter().any(|r| {
        r.tracking.as_ref().is_ok_and(|t| {
            t.periods
                .iter()
                .any(|p| p.max_abs_tau > tau_bound * (1.0 + 1e-9))
        })
    });
    if marked {
        writeln!(
            s,
            "\n⚑ Above the optimisation's torque bound |τ| ≤ {tau_bound} N m: `hybrid` saturates \
             there; the open loop, the PD and `hybrid-unbounded` do not enforce it."
        )?;
    }
    writeln!(
        s,
        "\nVerdict on \"the open loop matches well at the beginning\" for `{name}`: {verdict}.\n"
    )?;
    if let Some(dir) = figures {
        // A run without a completed period (the open loop that never reaches the ball) has
        // no point to draw; it is in the table above.
        let runs: Vec<ErrorRun<'_>> = rows
            .iter()
            .filter_map(|r| {
                let t = r.tracking.as_ref().ok()?;
                Some(ErrorRun {
                    controller: r.controller,
                    periods: t.periods.as_slice(),
                    lost: t.lost.as_ref().map(|_| t.loss()),
                })
            })
            .filter(|r| !r.periods.is_empty())
            .collect();
        if !runs.is_empty() {
            let stem = format!("fig17_closed_loop_{name}");
            error_figure(name, &runs, &dir.join(&stem))?;
            writeln!(
                s,
                "![Fig. 17 counterpart, closed loop: ω error per period, `{name}`](figures/{stem}.svg)\n\n\
                 The dashed line is the nominal plant's target, {:.0} % in every period; the \
                 verdict above counts a match up to {:.0} %.\n",
                100.0 * NOMINAL_TARGET,
                100.0 * MATCH_ERROR,
            )?;
        }
    }
    Ok(s)
}

/// What a lost run ([`Tracking::lost`]) is called: "lost the ball", or, where the simulation
/// itself `stopped` (a step limit, a model error), "did not complete its periods", since the
/// ball may still have been in hand.
pub fn loss_wording(stopped: bool) -> &'static str {
    if stopped {
        "did not complete its periods"
    } else {
        "lost the ball"
    }
}

/// One controller's run in [`error_figure`].
pub struct ErrorRun<'a> {
    /// The controller.
    pub controller: ControllerKind,
    /// Its completed periods.
    pub periods: &'a [PeriodMetrics],
    /// Where the run is lost ([`Tracking::lost`]), what that means ([`Tracking::loss`]): its
    /// errors are those of a finger that no longer rolls the ball as planned, or of a
    /// simulation that stopped, and its legend says which.
    pub lost: Option<&'static str>,
}

/// The Fig. 17 counterpart for closed loops: the mean-ω error ‖ω̄_k − ω̄*‖ / ‖ω̄*‖ (%, log
/// axis) of every period k of each controller's run of optimum `name`, with the 2 % target;
/// written to `stem`.svg/.png. Each period is a marker (runs whose errors coincide stay
/// countable), and a run that lost the ball is marked so in the legend. (The paper's Fig. 17
/// plots ω(t) of one open-loop run; over many periods of up to 10 s the per-period error is
/// what separates the controllers.)
pub fn error_figure(name: &str, runs: &[ErrorRun<'_>], stem: &Path) -> Result<()> {
    let mut fig = bf_plot::LineFigure::new(
        format!("Fig. 17 counterpart: ω error per period under each controller ({name})"),
        "period",
        "‖ω_k − ω*‖ / ‖ω*‖ of the period means [%]",
    );
    fig.y_scale = bf_plot::Scale::Log10;
    fig.x_whole = true;
    for run in runs {
        let points = run
            .periods
            .iter()
            .enumerate()
            .map(|(k, p)| ((k + 1) as f64, 100.0 * p.omega_error))
            .collect();
        let label = match run.lost {
            Some(loss) => format!("{} ({loss})", run.controller.name()),
            None => run.controller.name().to_string(),
        };
        fig.series.push(
            bf_plot::Series::new(label, points).styled(bf_plot::SeriesStyle {
                markers: true,
                ..bf_plot::SeriesStyle::default()
            }),
        );
    }
    fig.hlines.push(bf_plot::HLine {
        y: 100.0 * NOMINAL_TARGET,
        label: format!("nominal target {:.0} %", 100.0 * NOMINAL_TARGET),
        colour: bf_plot::Colour::Auto,
        fit: true,
    });
    bf_plot::render(&fig, stem)?;
    Ok(())
}

/// The target of every period's ω error on the plan's own (nominal) plant: a plan to execute
/// is tracked this closely there (the dashed line of [`error_figure`]); perturbed plants are
/// held to [`ROBUSTNESS_TARGET`].
pub const NOMINAL_TARGET: f64 = 0.02;

/// A perturbation of the plant in the robustness table: factors on the scene's physical
/// values ([`Perturbation::apply`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Perturbation {
    /// The ball's mass ×1.1 (its inertia follows where it is the default (2/5) m r²).
    BallMass,
    /// μ_s and μ_k ×0.8.
    Friction,
    /// The socket damping ×1.5.
    SocketDamping,
    /// Every link's mass and inertia ×1.05.
    LinkMasses,
}

/// `v` with 12 significant digits, as a scene file states a value: the perturbed values are
/// the decimals a user would write (0.02 × 1.1 is 0.022, not 0.022000000000000002).
fn stated(v: f64) -> f64 {
    format!("{v:.11e}").parse().unwrap_or(v)
}

impl Perturbation {
    /// `scene` with this perturbation; an error names what the scene lacks (a ball, friction).
    fn apply(self, scene: &mut bf_codegen::Scene) -> Result<()> {
        let name = scene.name.clone();
        match self {
            Perturbation::BallMass => {
                let ball = scene
                    .ball
                    .as_mut()
                    .ok_or_else(|| anyhow!("the scene `{name}` has no ball"))?;
                ball.mass = stated(ball.mass * 1.1);
            }
            Perturbation::Friction | Perturbation::SocketDamping => {
                let f = scene
                    .friction
                    .as_mut()
                    .ok_or_else(|| anyhow!("the scene `{name}` has no [friction]"))?;
                if self == Perturbation::Friction {
                    f.mu_s = stated(f.mu_s * 0.8);
                    f.mu_k = stated(f.mu_k * 0.8);
                } else {
                    f.socket_damping = stated(f.socket_damping * 1.5);
                }
            }
            Perturbation::LinkMasses => {
                for link in &mut scene.links {
                    link.mass = stated(link.mass * 1.05);
                    link.inertia = match link.inertia {
                        bf_codegen::spec::InertiaSpec::Diagonal(d) => {
                            bf_codegen::spec::InertiaSpec::Diagonal(d.map(|v| stated(v * 1.05)))
                        }
                        bf_codegen::spec::InertiaSpec::Full(m) => {
                            bf_codegen::spec::InertiaSpec::Full(
                                m.map(|row| row.map(|v| stated(v * 1.05))),
                            )
                        }
                    };
                }
            }
        }
        Ok(())
    }
}

/// The perturbed plants of the robustness table, each alone, then all together.
const PERTURBATIONS: [(&str, Perturbation); 4] = [
    ("ball mass ×1.1", Perturbation::BallMass),
    ("μ_s, μ_k ×0.8", Perturbation::Friction),
    ("socket damping ×1.5", Perturbation::SocketDamping),
    ("link masses ×1.05", Perturbation::LinkMasses),
];

/// One row of the robustness table: its name, the perturbations and the plant's impact law.
type Case = (String, Vec<Perturbation>, ImpactLaw);

/// A perturbed copy of the compiled scene `name` (the paper scene or the human finger's, which
/// share these values): `edits` applied to its TOML text (every occurrence); an error if an
/// edit finds nothing to replace (the scene file changed).
pub fn perturbed_scene<const N: usize>(
    name: &str,
    edits: &[(&str, &str)],
) -> Result<Model<DynKernels<N>, N>> {
    let mut text = bf_generated::scene_toml(name)
        .ok_or_else(|| anyhow!("the scene `{name}` is not compiled in"))?
        .to_string();
    for (from, to) in edits {
        if !text.contains(from) {
            bail!("the scene `{name}` has no `{from}` to perturb");
        }
        text = text.replace(from, to);
    }
    Ok(finger_model::<N>(&bf_codegen::Scene::from_toml_str(&text, name)?)?.0)
}

/// `scene` with the perturbations `edits`, as a model of a finger with `N` joints.
fn perturbed<const N: usize>(
    scene: &bf_codegen::Scene,
    edits: &[Perturbation],
) -> Result<Model<DynKernels<N>, N>> {
    let mut scene = scene.clone();
    for e in edits {
        e.apply(&mut scene)?;
    }
    // The scene keeps its name: a perturbation of what the model applies outside its kernels
    // (the ball's mass, friction, damping) runs on the compiled kernels with the perturbed
    // parameters; a perturbation of the links (their masses) is interpreted.
    Ok(finger_model::<N>(&scene)?.0)
}

/// The plants of the robustness table: [`PERTURBATIONS`] alone, all four together, and the
/// max-dissipation impact law instead of Newton's on the nominal plant; each with its name,
/// scene edits and impact law.
fn robustness_cases() -> Vec<Case> {
    let mut cases: Vec<Case> = PERTURBATIONS
        .iter()
        .map(|(n, e)| (n.to_string(), vec![*e], ImpactLaw::Newton))
        .collect();
    cases.push((
        "all four".into(),
        PERTURBATIONS.iter().map(|(_, e)| *e).collect(),
        ImpactLaw::Newton,
    ));
    cases.push((
        "max-dissipation impact law".into(),
        Vec::new(),
        ImpactLaw::MaxDissipation,
    ));
    cases
}

/// Runs `controller` on the optimum `sol` for `periods` periods against every plant of the
/// robustness table (perturbed copies of the solution's own scene), re-planning at every
/// lift-off with `replan` = `Some(max_iter)` ([`run_tracking_replanned`]); each run with its
/// row's name. `N`: the joints of the solution's finger.
pub fn robustness_runs<const N: usize>(
    sol: &OcpSolution,
    controller: ControllerKind,
    periods: usize,
    replan: Option<usize>,
) -> Vec<(String, Result<Tracking<N>>)> {
    let how = TableRuns {
        controller,
        periods,
        replan,
        until_miss: false,
    };
    match solution_scene(sol) {
        Ok((scene, _)) => runs(sol, &scene, how),
        Err(e) => robustness_cases()
            .into_iter()
            .map(|(plant, _, _)| (plant, Err(anyhow!("{e:#}"))))
            .collect(),
    }
}

/// How the plants of the robustness table are run: `controller` for `periods` periods,
/// re-planning with `replan` = `Some(max_iter)`; with `until_miss` each run ends at its first
/// period that misses the target ([`run_tracking_with`]).
#[derive(Debug, Clone, Copy)]
struct TableRuns {
    controller: ControllerKind,
    periods: usize,
    replan: Option<usize>,
    until_miss: bool,
}

/// [`robustness_runs`] as `how` says.
fn runs<const N: usize>(
    sol: &OcpSolution,
    scene: &bf_codegen::Scene,
    how: TableRuns,
) -> Vec<(String, Result<Tracking<N>>)> {
    // The plants are independent runs: one per thread, collected in the table's order, so
    // the table does not depend on the thread count.
    use rayon::prelude::*;
    robustness_cases()
        .into_par_iter()
        .map(|(case, edits, law)| {
            let run = perturbed::<N>(scene, &edits).and_then(|plant| {
                run_tracking_on(sol, scene, default_gains(scene), plant, law, how)
            });
            (case, run)
        })
        .collect()
}

/// The robustness target: every period's ω error from the 4th on.
pub const ROBUSTNESS_TARGET: f64 = 0.05;

/// One plant of the robustness table, as run ([`robustness_rows`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct RobustnessRow {
    /// The plant: the perturbation's name.
    pub plant: String,
    /// Periods completed.
    pub completed_periods: usize,
    /// ω error of the first period.
    pub first_error: Option<f64>,
    /// The largest ω error from the 4th period on ([`max_error_from_fourth`]).
    pub max_error_from_fourth: Option<f64>,
    /// Whether every period made contact and the ball was not lost.
    pub contact_every_period: bool,
    /// Why the run lost the ball, if it did.
    pub lost: Option<String>,
    /// Whether the simulation itself stopped (a step limit, a model error): then a
    /// [`RobustnessRow::lost`] run did not complete its periods, rather than lost the ball.
    pub stopped: bool,
    /// The largest |τ| of any period (N m).
    pub max_abs_tau: f64,
    /// Whether the run met the target: all periods completed, contact in each, error ≤
    /// [`ROBUSTNESS_TARGET`] from the 4th period on.
    pub meets_target: bool,
    /// Why the run could not be made (the plant could not be built or simulated), or why it is
    /// not a result (its energy balance failed the simulator's check).
    pub error: Option<String>,
    /// With re-planning at every lift-off (`track --robustness --replan`): the re-plans made
    /// and how many of them converged and were used; absent without.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replans: Option<ReplanCount>,
}

/// The re-plans of a run (`RobustnessRow::replans`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ReplanCount {
    /// Re-plans made, one per lift-off.
    pub made: usize,
    /// Of those, the ones that converged and were tracked.
    pub used: usize,
}

impl RobustnessRow {
    /// The row of a run on `plant` that is no result, for the reason `error`: it misses the
    /// target.
    fn failed(plant: String, error: String) -> RobustnessRow {
        RobustnessRow {
            plant,
            completed_periods: 0,
            first_error: None,
            max_error_from_fourth: None,
            contact_every_period: false,
            lost: None,
            stopped: false,
            max_abs_tau: 0.0,
            meets_target: false,
            error: Some(error),
            replans: None,
        }
    }
}

/// The rows of the robustness table: `controller` on the optimum `sol` for `periods` periods
/// against each plant of [`robustness_runs`].
pub fn robustness_rows(
    sol: &OcpSolution,
    controller: ControllerKind,
    periods: usize,
    replan: Option<usize>,
) -> Vec<RobustnessRow> {
    let how = TableRuns {
        controller,
        periods,
        replan,
        until_miss: false,
    };
    let scene = solution_scene(sol).and_then(|(scene, name)| {
        let n = tracked_joints(&scene).with_context(|| format!("the solution's scene `{name}`"))?;
        Ok((scene, n))
    });
    match scene {
        Ok((scene, n)) => with_joints!(n, rows_n(sol, &scene, how), Vec::new()),
        Err(e) => robustness_cases()
            .into_iter()
            .map(|(plant, _, _)| RobustnessRow::failed(plant, crate::errors::render(&e)))
            .collect(),
    }
}

/// The rows of the robustness table of a finger with `N` joints, run as `how` says; with
/// `until_miss` the same rows' verdicts, a missing row's error that of its first missed
/// period rather than its largest.
fn rows_n<const N: usize>(
    sol: &OcpSolution,
    scene: &bf_codegen::Scene,
    how: TableRuns,
) -> Vec<RobustnessRow> {
    runs::<N>(sol, scene, how)
        .into_iter()
        .map(|(plant, run)| match run {
            Ok(t) => robustness_row(plant, &t, how.periods),
            Err(e) => RobustnessRow::failed(plant, crate::errors::render(&e)),
        })
        .collect()
}

/// The row of the robustness table of run `t` on `plant`, asked for `periods` periods. A run
/// that is no result ([`Tracking::check_failure`]: a failed energy check, a contact held while
/// the ball pulled the finger) measured the simulator, not the plant: its row is an error, and
/// misses the target.
pub fn robustness_row<const N: usize>(
    plant: String,
    t: &Tracking<N>,
    periods: usize,
) -> RobustnessRow {
    if let (None, Some(unbalanced)) = (&t.lost, t.check_failure()) {
        return RobustnessRow {
            completed_periods: t.periods.len(),
            ..RobustnessRow::failed(plant, unbalanced)
        };
    }
    let later = max_error_from_fourth(t);
    let replans = t.replans.setup.is_some().then(|| ReplanCount {
        made: t.replans.replans.len(),
        used: t.replans.replans.iter().filter(|r| r.used).count(),
    });
    let contact = t.lost.is_none()
        && t.periods
            .iter()
            .all(|p| p.contact_failure(t.plan_period).is_none());
    RobustnessRow {
        plant,
        completed_periods: t.periods.len(),
        first_error: t.periods.first().map(|p| p.omega_error),
        max_error_from_fourth: later,
        contact_every_period: contact,
        lost: t.lost.clone(),
        stopped: t.stopped.is_some(),
        max_abs_tau: t.periods.iter().map(|p| p.max_abs_tau).fold(0.0, f64::max),
        meets_target: contact
            && t.periods.len() == periods
            && later.is_some_and(|e| e <= ROBUSTNESS_TARGET),
        error: None,
        replans,
    }
}

/// The robustness table of `rows` (of `controller` on the optimum `name`, `periods` periods) as
/// markdown: the ω error of the first period, the largest from the 4th on (the target:
/// 5 %), contact in every period, the largest |τ|.
pub fn robustness_table(
    name: &str,
    controller: ControllerKind,
    periods: usize,
    rows: &[RobustnessRow],
) -> Result<String> {
    use std::fmt::Write as _;
    let pct = |e: f64| format!("{:.2}", 100.0 * e);
    let replanned = rows.iter().any(|r| r.replans.is_some());
    let mut s = String::new();
    writeln!(
        s,
        "**Robustness** of the {} controller{} on `{name}`, {periods} periods, Newton's impact \
         law unless named; target: ≤ 5 % from the 4th period on, contact in every period:\n",
        controller.name(),
        if replanned {
            ", re-planning at every lift-off on the nominal model"
        } else {
            ""
        }
    )?;
    let (head, rule, blank) = if replanned {
        (" re-plans used |", "---|", " |")
    } else {
        ("", "", "")
    };
    writeln!(
        s,
        "| plant | periods completed | ω error, 1st period (%) | max ω error from the 4th period (%) | contact in every period | max \\|τ\\| (N m) |{head}"
    )?;
    writeln!(s, "|---|---|---|---|---|---|{rule}")?;
    for r in rows {
        if let Some(e) = &r.error {
            writeln!(s, "| {} | **failed**: {e} | | | | |{blank}", r.plant)?;
            continue;
        }
        let first = r.first_error.map_or("—".into(), pct);
        let later = r.max_error_from_fourth.map_or("—".into(), |e| {
            if r.meets_target {
                pct(e)
            } else {
                format!("{} ⚑", pct(e))
            }
        });
        let contact = if r.contact_every_period {
            "yes".to_string()
        } else {
            format!(
                "**no**: {}",
                r.lost.as_deref().unwrap_or("a period without contact")
            )
        };
        let replans = match r.replans {
            Some(c) => format!(" {} of {} |", c.used, c.made),
            None if replanned => " — |".to_string(),
            None => String::new(),
        };
        writeln!(
            s,
            "| {} | {} of {periods} | {first} | {later} | {contact} | {:.3} |{replans}",
            r.plant, r.completed_periods, r.max_abs_tau
        )?;
    }
    if rows.iter().any(|r| !r.meets_target) {
        writeln!(s, "\n⚑ or **no**: the target is missed.\n")?;
    } else {
        writeln!(s, "\nEvery plant meets the target.\n")?;
    }
    Ok(s)
}

/// The robustness table of the bounded hybrid controller (torques saturated at the bound) on
/// the optimum `sol` for `periods` periods ([`robustness_rows`], [`robustness_table`]).
pub fn robustness_markdown(name: &str, sol: &OcpSolution, periods: usize) -> Result<String> {
    let rows = robustness_rows(sol, ControllerKind::Hybrid, periods, None);
    robustness_table(name, ControllerKind::Hybrid, periods, &rows)
}

/// The first period (1-based) whose ω error the robustness target judges: the earlier ones
/// are the controller's transient.
pub const FIRST_JUDGED_PERIOD: usize = 4;

/// The largest ω error from the 4th period on (the robustness window), `None` for a
/// run that completed fewer than four periods.
pub fn max_error_from_fourth<const N: usize>(t: &Tracking<N>) -> Option<f64> {
    t.periods
        .iter()
        .skip(FIRST_JUDGED_PERIOD - 1)
        .map(|p| p.omega_error)
        .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))))
}
