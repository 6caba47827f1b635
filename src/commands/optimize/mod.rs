//! `ball-finger optimize --problem NAME ...`: one multiphase optimal-control problem of the
//! problem library (paper Sect. 4.1, 6.1) transcribed by collocation (Sect. 4.2) and solved by
//! the in-house interior-point solver. Writes `solution.json` (status, objective φ = c₁/c₂
//! (eq. 60), phase durations, trajectories) and `torques.csv` (the format `simulate --torques`
//! reads) as one output set (`bf_output::OutputDir`): `--out` is checked before the solve and
//! replaced as a whole at the end; a solve that does not end Solved or Acceptable still writes
//! its set, marked by a `FAILED` file, and exits non-zero.
//!
//! Sizes are bounded before anything is built. Legendre–Gauss interpolates all points of a
//! phase with one polynomial: the barycentric weights of its nodes (products of node
//! distances) leave the range of f64 at about 900 points, which ends as a singular
//! differentiation matrix, and its dense differentiation blocks make the KKT system grow as
//! N² well before that; so `--points` is at most [`MAX_LG_POINTS`] with `--scheme lg`. With
//! Radau the points of a phase (points per element times elements) are at most
//! [`MAX_RADAU_POINTS`], which bounds the memory of the NLP, and an element holds at most
//! `bf_optim::ocp::mesh::MAX_RADAU_DEGREE` of them.

use crate::cli::Inputs as _;
use crate::cli::{DEFAULT_ELEMENTS, DEFAULT_REFINE_ROUNDS, OptimizeArgs, OptimizeCommand};
use crate::errors::bail_usage;
use crate::pipeline::SolutionIo;
use crate::pipeline::search::{Execution, VerifyPolicy};
use crate::pipeline::strategy::{
    self, DEFAULT_SEED, DEFAULT_STARTS, GLOBAL_STARTS, Shard, Strategy,
};
use crate::pipeline::verify::{
    MAX_VERIFY_JOINTS, VERIFIED_DEFECT, impulse_cone_warning, is_verified, robustness_miss,
    unverified_reason, verdict_failure, verify,
};
use anyhow::{Context, Result, bail};
use bf_optim::ipm::Status;
use bf_optim::ocp::problem::Scheme;
use bf_output::{DirSpec, Outcome, OutputDir};
use bf_problem::arm::REACH_ARM;
use bf_problem::{
    BuiltProblem, COT_MAX_PERIOD, OcpSolution, PhaseMode, PlannedImpact, Problem, ProblemError,
    ProblemSettings, check_settings,
};
use std::path::Path;

mod arm;
mod parts;
mod progress;
mod shards;

use arm::run_reach_arm;
pub use progress::{
    iteration_spinner, refine_with_progress, search_with_progress, solve_globally_with_progress,
    solve_with_progress,
};
pub use shards::merge;

pub use crate::pipeline::solve::{MAX_LG_POINTS, MAX_RADAU_POINTS};

/// The output directory of `optimize`.
pub const OUTPUT_DIR: DirSpec<'static> = DirSpec {
    option: "--out",
    command: "optimize",
};

/// Settings of a run that are not on the command line.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunSettings {
    /// Make the n-th output write fail, as if the process stopped there (tests).
    pub fail_at_write: Option<usize>,
}

/// Parse `--scheme`: `lg` or `radau` (hp elements from `elements`).
pub fn parse_scheme(text: &str, elements: Option<usize>) -> Result<Scheme> {
    match (text, elements) {
        // One Legendre–Gauss polynomial per phase: an element count would be dropped unsaid.
        ("lg", Some(elements)) => bail_usage!(
            "--elements {elements}: --scheme lg has one polynomial per phase (refine it with \
             --points, or use --scheme radau for elements)"
        ),
        ("lg", None) => Ok(Scheme::Lg),
        ("radau", elements) => match elements.unwrap_or(DEFAULT_ELEMENTS) {
            0 => bail_usage!("--elements must be at least 1"),
            elements => Ok(Scheme::Radau { elements }),
        },
        (other, _) => bail_usage!("--scheme: unknown scheme {other:?}; use `lg` or `radau`"),
    }
}

/// Checks the size of the transcription before anything is allocated (see the module docs and
/// [`crate::pipeline::solve::transcription_size_error`], which every solution file's reader
/// applies to the mesh the file records).
pub fn check_size(points: usize, scheme: Scheme) -> Result<()> {
    let Some(why) = crate::pipeline::solve::transcription_size_error(points, scheme) else {
        return Ok(());
    };
    match scheme {
        Scheme::Lg => bail_usage!(
            "--points {points} with --scheme lg: {why}; for a finer mesh use --scheme radau \
             with --elements"
        ),
        Scheme::Radau { elements } => bail_usage!("--points {points} --elements {elements}: {why}"),
    }
}

/// Largest magnitude accepted in a warm-start file (the bound of every solution file's reader).
pub use crate::pipeline::solution_io::MAX_SOLUTION_VALUE as MAX_WARM_START_VALUE;

/// Refuses an arm's solution as a warm start: it has no collocation data to start from, and
/// saying so beats saying that the internals file it never had is missing. Everything else of
/// the file, the range of every number included, the reader checks
/// ([`crate::pipeline::SolutionIo::read_json`]).
pub fn refuse_arm_warm_start(path: &Path) -> Result<()> {
    if crate::pipeline::arm::is_arm_solution(&read_json_value("--warm-start", path)?) {
        bail!(
            "--warm-start {}: a solution of `{REACH_ARM}` (an arm without a ball) cannot start a \
             finger-and-ball problem, and `{REACH_ARM}` takes no warm start",
            path.display()
        );
    }
    Ok(())
}

/// The document of the file given to `option` (`simulate --init`: an initial state, a finger's
/// or an arm's solution) with every number checked against [`MAX_WARM_START_VALUE`], the error
/// naming the option, the file, the field path and the value: a plain initial-state file and
/// an arm's solution are not read by the finger's solution reader, which checks its own.
pub fn check_solution_values(option: &str, path: &Path) -> Result<serde_json::Value> {
    let value = read_json_value(option, path)?;
    if let Some((field, x)) = crate::pipeline::solution_io::out_of_range(&value) {
        bail!(
            "{option} {}: `{field}` = {x:e} is out of range (|value| ≤ {MAX_WARM_START_VALUE:e})",
            path.display()
        );
    }
    Ok(value)
}

/// The JSON document of the file `path` given to `option`; the error names both.
pub fn read_json_value(option: &str, path: &Path) -> Result<serde_json::Value> {
    let text = bf_codegen::spec::read_input_text(path)
        .with_context(|| format!("{option} {}: cannot read", path.display()))?;
    crate::io::json_value(&text)
        .with_context(|| format!("{option} {}: not a valid JSON document", path.display()))
}

/// Parse `--problem` (a catalogue problem; `reach-arm` is dispatched before, by [`run_with`]).
pub fn parse_problem(text: &str) -> Result<Problem> {
    text.parse().map_err(|e| {
        crate::errors::usage(format!(
            "--problem: {e}, {REACH_ARM} (an arm without a ball, with --scene)"
        ))
    })
}

/// Build the problem settings from the command line: every value checked (an option of a part
/// the problem lacks is refused before, by `parts::refuse_missing_parts`), the scene of
/// `--scene` / `--param` ([`scene_from_args`]) and what the plan is planned for
/// ([`PlanFor::of`]).
pub fn settings_from_args(args: &OptimizeArgs) -> Result<ProblemSettings> {
    let problem = parse_problem(problem_arg(args))?;
    if args.points < 2 {
        bail_usage!("--points must be at least 2 (got {})", args.points);
    }
    if let Some(eps) = args.epsilon
        && let Some(why) = bf_codegen::spec::smooth_eps_out_of_range(eps)
    {
        bail_usage!("--epsilon {why} (got {})", crate::cli::shown(eps));
    }
    if let Some(dc) = args.dual_regularization
        && !(dc.is_finite() && dc > 0.0 && dc <= 1e-4)
    {
        bail_usage!(
            "--dual-regularization must be in (0, 1e-4] (got {})",
            crate::cli::shown(dc)
        );
    }
    let scheme = parse_scheme(&args.scheme, args.elements)?;
    check_size(args.points, scheme)?;
    let warm_start = match &args.warm_start {
        Some(path) => {
            refuse_arm_warm_start(path)?;
            let sol = OcpSolution::read_json(path)
                // Every error of the reader names the file it is about.
                .context("--warm-start")?;
            Some(sol)
        }
        None => None,
    };
    let cone_margin = args
        .cone_margin
        .unwrap_or(ProblemSettings::default().cone_margin);
    if !(0.0..1.0).contains(&cone_margin) {
        bail_usage!(
            "--cone-margin must be in [0, 1) (got {})",
            crate::cli::shown(cone_margin)
        );
    }
    let scene = scene_from_args(args, problem)?;
    // The scene the problem will be built on: `--scene`'s, or the problem's compiled one.
    let built_on = match &scene {
        Some(s) => s.clone(),
        None => compiled_scene(problem)?,
    };
    if let (Some(w), Some(path)) = (&warm_start, &args.warm_start)
        && (w.problem != problem.name() || w.scene != built_on.name)
    {
        // A start across problems or scenes is a continuation a user may want, so it is
        // taken, but never silently.
        crate::errln!(
            "warning: --warm-start {}: a solution of `{}` on scene `{}`, taken as the start of \
             `{problem}` on scene `{}`",
            path.display(),
            w.problem,
            w.scene,
            built_on.name
        );
    }
    let joints = built_on.links.len();
    let gap = crate::paper::closed_loop::default_gains(&built_on)
        .clearance
        .gap;
    let plan = PlanFor::of(
        problem,
        joints,
        gap,
        args.impact_law.as_deref(),
        args.torque_margin,
        args.approach_clearance,
    )?;
    let settings = plan.apply(ProblemSettings {
        cone_margin,
        impulse_cone: args.impulse_cone,
        scene,
        points: args.points,
        scheme,
        // Without `--epsilon` the problem takes the scene's `contact.smooth_eps`, as `eval`
        // and `verify` do.
        epsilon: args.epsilon,
        warm_start,
        max_iter: args.max_iter,
        print_level: args.print_level,
        dual_regularization: args.dual_regularization,
        min_stick: args.min_stick.unwrap_or(bf_problem::MIN_STICK),
        kkt_residual_ratio: args.kkt_residual_ratio,
        curvature_extrapolation: args.curvature_extrapolation,
        extrapolate_every_barrier: args.extrapolate_every_barrier,
        proximal_weight: args.proximal_weight,
        ..ProblemSettings::default()
    });
    // Ranges that depend on the problem or the scene (`--min-stick` below the longest phase,
    // `--approach-clearance` within a tenth of the ball's radius) are the problem's own checks,
    // run here so that a wrong value is refused as a usage error before any work starts.
    match check_settings(problem, &settings, &built_on) {
        Ok(()) => Ok(settings),
        Err(e @ ProblemError::InvalidSetting { name, .. }) => match option_of(name) {
            Some(option) => bail_usage!("{option}: {problem}: {e}"),
            None => bail_usage!("{problem}: {e}"),
        },
        Err(e) => Err(e.into()),
    }
}

/// The option of `optimize` that sets the problem setting `name` (the field that
/// [`ProblemError::InvalidSetting`] names), so that a refused value names what the user typed.
fn option_of(name: &str) -> Option<&'static str> {
    match name {
        "epsilon" => Some("--epsilon"),
        "cone_margin" => Some("--cone-margin"),
        "torque_margin" => Some("--torque-margin"),
        "approach_clearance" => Some("--approach-clearance"),
        "min_stick" => Some("--min-stick"),
        _ => None,
    }
}

/// The closed-loop check of a search's candidates ([`VerifyPolicy::execution`]) for the
/// plans meant for `track`'s plant: a periodic problem planned with Newton's impact law is
/// verified only if the hybrid controller executes it on its nominal plant
/// (docs/decisions/0048-plans-verified-in-closed-loop.md); `None` for every other problem.
pub fn execution_for(problem: Problem, settings: &ProblemSettings) -> Option<Execution> {
    (problem.is_periodic() && settings.impact_law == PlannedImpact::Newton)
        .then_some(Execution(crate::paper::closed_loop::execution_check))
}

/// The torque margin of a plan meant for `track`'s Newton plant: the share of every joint's
/// limit left to feedback, with which both default periodic problems' plans meet `track`'s
/// nominal and robustness targets (docs/decisions/0040-touch-check-and-the-default-plan.md).
pub const EXECUTABLE_TORQUE_MARGIN: f64 = 0.3;

/// What a plan is planned for: its impact law, the share of the torque limits it leaves to
/// feedback and the clearance its approach keeps from the ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanFor {
    /// The impact law planned at the touch-down.
    pub impact_law: PlannedImpact,
    /// `--torque-margin`.
    pub torque_margin: f64,
    /// `--approach-clearance` (m).
    pub approach_clearance: f64,
}

impl PlanFor {
    /// The plan of `problem` on a finger of `joints` joints, from `--impact-law` (`law`),
    /// `--torque-margin` and `--approach-clearance` where given. The defaults plan for the
    /// plant that executes the plan (docs/decisions/0040-touch-check-and-the-default-plan.md):
    /// a periodic problem, which `track` executes on a Newton plant, gets Newton's law
    /// (eq. 39) where the Newton impact plan exists (3 joints or more, J_c of rank 3), with
    /// [`EXECUTABLE_TORQUE_MARGIN`] and the clearance that `track`'s hybrid controller keeps
    /// in free flight; the other problems, and the periodic ones on fingers of fewer joints, get the
    /// sticking law (eq. 40) of the paper's Sect. 6 with the exact limits and no clearance.
    /// The margin's and the clearance's defaults follow the law actually planned, so
    /// `--impact-law stick` alone poses the paper's problem. `gap` (m) is the clearance the
    /// controller keeps from the scene's ball
    /// ([`crate::paper::closed_loop::default_gains`]), the default clearance of a plan for it.
    pub fn of(
        problem: Problem,
        joints: usize,
        gap: f64,
        law: Option<&str>,
        torque_margin: Option<f64>,
        approach_clearance: Option<f64>,
    ) -> Result<PlanFor> {
        let impact_law = match law {
            Some(text) => PlannedImpact::parse(text)
                .map_err(|e| crate::errors::usage(format!("--impact-law: {e}")))?,
            None if problem.is_periodic() && joints >= 3 => PlannedImpact::Newton,
            None => PlannedImpact::Stick,
        };
        if law.is_some() && impact_law == PlannedImpact::Newton && joints < 3 {
            bail_usage!(
                "--impact-law newton: the Newton impact plan needs a finger of 3 joints or more \
                 (J_c of rank 3); this one has {joints}"
            );
        }
        let executable = problem.is_periodic() && impact_law == PlannedImpact::Newton;
        let torque_margin = match torque_margin {
            Some(m) if !(0.0..1.0).contains(&m) => {
                bail_usage!(
                    "--torque-margin must be in [0, 1) (got {})",
                    crate::cli::shown(m)
                )
            }
            Some(m) => m,
            None if executable => EXECUTABLE_TORQUE_MARGIN,
            None => 0.0,
        };
        let approach_clearance = match approach_clearance {
            Some(c) => c,
            None if executable => gap,
            None => 0.0,
        };
        Ok(PlanFor {
            impact_law,
            torque_margin,
            approach_clearance,
        })
    }

    /// `settings` with this plan's impact law, torque margin and approach clearance.
    pub fn apply(self, settings: ProblemSettings) -> ProblemSettings {
        ProblemSettings {
            impact_law: self.impact_law,
            torque_margin: self.torque_margin,
            approach_clearance: self.approach_clearance,
            ..settings
        }
    }
}

/// `problem`'s compiled scene, parsed.
fn compiled_scene(problem: Problem) -> Result<bf_codegen::Scene> {
    let id = problem.scene();
    let text = bf_generated::scene_toml(id.as_str())
        .with_context(|| format!("problem {problem}: no compiled scene"))?;
    Ok(bf_codegen::Scene::from_toml_str(text, id.as_str())?)
}

/// The `--problem` text (empty when absent: only `optimize merge` runs without it).
pub fn problem_arg(args: &OptimizeArgs) -> &str {
    args.problem.as_deref().unwrap_or_default()
}

/// Parse `--strategy` (with `--starts` and `--seed` for `multistart`).
pub fn parse_strategy(text: &str, starts: u64, seed: u64) -> Result<Strategy> {
    match text {
        "direct" => Ok(Strategy::Direct),
        "continuation" => Ok(Strategy::Continuation),
        "multistart" => Ok(Strategy::Multistart {
            starts: usize::try_from(starts).context("--starts is too large")?,
            seed,
        }),
        other => bail_usage!(
            "--strategy: unknown strategy {other:?}; use `direct`, `continuation` or `multistart`"
        ),
    }
}

/// Re-integrate every phase with the optimal torques and store the defects in `sol` (printed);
/// a failure to verify is reported, not fatal: the solution itself is still written. Errors
/// are failed writes to standard output.
pub fn attach_verification(problem: &BuiltProblem, sol: &mut OcpSolution, rtol: f64) -> Result<()> {
    match verify(problem, sol, rtol) {
        Ok(v) => {
            crate::outln!("{}", v.summary().trim_end())?;
            if !v.passes(1e-3) {
                crate::outln!(
                    "note: an end-of-phase defect above 1e-3 means the open-loop replay of these \
                     torques drifts from the collocated trajectory (unstable or long phases, or \
                     a coarse mesh: try --refine 1e-4)"
                )?;
            }
            sol.verification = Some(v);
        }
        Err(e) => crate::errln!(
            "warning: trajectory verification failed: {}",
            crate::errors::chain(&e)
        ),
    }
    Ok(())
}

/// The first non-finite number among the solution's results (objective, costs, durations,
/// node and dense trajectories), named like `nodes.tau[3][1]`.
pub fn first_non_finite(sol: &OcpSolution) -> Option<(String, f64)> {
    let scalars = [
        ("objective", sol.objective),
        ("c1", sol.c1),
        ("c2", sol.c2),
        ("period", sol.period),
    ];
    if let Some((n, v)) = scalars.iter().find(|(_, v)| !v.is_finite()) {
        return Some((n.to_string(), *v));
    }
    let vectors: [(&str, &[f64]); 3] = [
        ("phase_durations", &sol.phase_durations),
        ("mean_omega", &sol.mean_omega),
        ("impulse", &sol.impulse),
    ];
    for (n, xs) in vectors {
        if let Some(i) = xs.iter().position(|v| !v.is_finite()) {
            return Some((format!("{n}[{i}]"), xs[i]));
        }
    }
    for (set, s) in [("nodes", &sol.nodes), ("dense", &sol.dense)] {
        let rows: [(&str, &Vec<Vec<f64>>); 5] = [
            ("q", &s.q),
            ("qd", &s.qd),
            ("omega", &s.omega),
            ("tau", &s.tau),
            ("lambda", &s.lambda),
        ];
        for (n, m) in rows {
            for (k, r) in m.iter().enumerate() {
                if let Some(i) = r.iter().position(|v| !v.is_finite()) {
                    return Some((format!("{set}.{n}[{k}][{i}]"), r[i]));
                }
            }
        }
        for (n, xs) in [("t", &s.t), ("h", &s.h), ("sigma", &s.sigma)] {
            if let Some(i) = xs.iter().position(|v| !v.is_finite()) {
                return Some((format!("{set}.{n}[{i}]"), xs[i]));
            }
        }
    }
    None
}

/// Write `solution.json` and `torques.csv` as the output set `out` and move it into place;
/// a solution that did not succeed, or whose re-integration does not verify it, is marked
/// [`bf_output::FAILED`].
pub fn commit_solution(sol: &OcpSolution, out: OutputDir) -> Result<()> {
    commit_solution_with(sol, &[], out, failure_of(sol).as_deref())
}

/// The line naming the files written to `dir`, marked as failed where `failure` (the verdict
/// the set was committed with) is given.
fn print_wrote(dir: &Path, failure: Option<&str>) -> Result<()> {
    crate::outln!(
        "wrote {}/solution.json and torques.csv{}",
        dir.display(),
        if failure.is_none() {
            ""
        } else {
            " (marked FAILED)"
        }
    )?;
    Ok(())
}

/// Why `sol` counts as failed: not converged, or re-integrated and not verified.
pub fn failure_of(sol: &OcpSolution) -> Option<String> {
    if !sol.status.is_success() {
        return Some(format!(
            "the solver did not converge ({})",
            crate::names::name(&sol.status)
        ));
    }
    sol.verification
        .as_ref()
        .and_then(unverified_reason)
        .map(|why| format!("the solution is unverified: {why}"))
}

/// [`commit_solution`] with extra solution files (`--shard` candidates) in the set, marked
/// failed for `failure` (the caller's verdict: [`failure_of`] and its own checks).
pub fn commit_solution_with(
    sol: &OcpSolution,
    extra: &[(String, &OcpSolution)],
    mut out: OutputDir,
    failure: Option<&str>,
) -> Result<()> {
    let path = out.file("solution.json")?;
    sol.write_json(&path)
        .map_err(|e| anyhow::anyhow!(out.rename_in(&crate::errors::chain(&e))))?;
    let path = out.file("torques.csv")?;
    sol.write_torques_csv(&path)
        .map_err(|e| anyhow::anyhow!(out.rename_in(&crate::errors::chain(&e))))?;
    for (name, c) in extra {
        let path = out.file(name)?;
        c.write_json(&path)
            .map_err(|e| anyhow::anyhow!(out.rename_in(&crate::errors::chain(&e))))?;
    }
    let outcome = match failure {
        None => Outcome::Success,
        Some(f) => Outcome::Failed(f),
    };
    out.commit(outcome)?;
    Ok(())
}

/// The scene of `--scene` / `--param` for `problem`, or `None` for the problem's compiled
/// scene unchanged (no `--scene`, no `--param`). A scene file is used as parsed, whatever its
/// name: the problem is posed on its numbers (node functions on the emitted kernels when they
/// match, interpreted otherwise). The error names the file and why the problem cannot use it.
pub fn scene_from_args(args: &OptimizeArgs, problem: Problem) -> Result<Option<bf_codegen::Scene>> {
    let path = match &args.scene {
        Some(p) => p.clone(),
        None if args.param.is_empty() => return Ok(None),
        // `--param` alone: the problem's compiled scene with other runtime parameters.
        None => {
            let mut scene = compiled_scene(problem)?;
            let assignments = super::parse_params(&args.param)?;
            bf_model::registry::set_parameters(&mut scene, &assignments)
                .map_err(|e| crate::errors::usage(format!("--param: {e}")))?;
            return Ok(Some(scene));
        }
    };
    let (scene, _) = super::load_scene_with_params(&path, &args.chain, &args.param)?;
    bf_model::registry::check_contact_scene(&scene).map_err(|e| {
        anyhow::anyhow!(
            "--scene {}: problem {problem} needs a finger-and-ball scene: {e}",
            path.display()
        )
    })?;
    // The problems are posed for any number of joints; the verification, which every solve
    // ends with, re-integrates up to MAX_VERIFY_JOINTS.
    let nq = scene.links.len();
    if nq > MAX_VERIFY_JOINTS {
        bail!(
            "--scene {}: problem {problem} runs fingers with 1 to {MAX_VERIFY_JOINTS} joints; \
             scene `{}` has {nq}",
            path.display(),
            scene.name,
        );
    }
    Ok(Some(scene))
}

/// The scene text and `--param` values the run poses `problem` on, as its solution files
/// record them ([`OcpSolution::scene_toml`], [`OcpSolution::scene_params`]): the `--scene`
/// file's self-contained text (a URDF it names expanded into its chain, as the scene loader
/// reads it), else the problem's compiled scene's.
pub fn scene_record(args: &OptimizeArgs, problem: Problem) -> Result<(String, Vec<(String, f64)>)> {
    let text = match &args.scene {
        // The self-contained text (a `urdf` key resolved to its chain), so that the file needs
        // nothing else to be replayed or tracked.
        Some(p) => {
            bf_codegen::Scene::load_with_text(p, &args.chain.choice())
                .with_context(|| format!("--scene {}", p.display()))?
                .1
        }
        None => compiled_scene_text(problem)?,
    };
    Ok((text, super::parse_params(&args.param)?))
}

/// Records in `s`, an optimum of `problem` or a candidate of its search, what `optimize`
/// writes beside it (docs/files.md): the scene text and runtime parameters it was posed on,
/// the search's settings and the bounds it sits on. The bounds of the problem definition do
/// not depend on the mesh, so the chosen problem's serve every candidate (each may sit on a
/// refined mesh of it).
pub fn record_run(
    s: &mut OcpSolution,
    problem: &BuiltProblem,
    (scene_toml, scene_params): &(String, Vec<(String, f64)>),
    settings: &bf_problem::solution::records::SearchSettings,
) {
    s.scene_toml.clone_from(scene_toml);
    s.scene_params.clone_from(scene_params);
    s.search_settings = Some(settings.clone());
    s.active_bounds = Some(crate::pipeline::bounds::active_bounds(&problem.ocp, s));
}

/// The text of `problem`'s compiled scene, as a solution posed on it records it.
pub fn compiled_scene_text(problem: Problem) -> Result<String> {
    Ok(bf_generated::scene_toml(problem.scene().as_str())
        .with_context(|| format!("problem {problem}: no compiled scene"))?
        .to_string())
}

/// The hint for a plan that a Newton plant cannot execute, or `None`: a sticking-law plan
/// (eq. 40) whose stick phase sits on its minimum `min_stick` (as `active bounds` lists it,
/// [`crate::pipeline::bounds::on_bound`]) spins the ball mostly through the impact impulse,
/// which Newton's law (eq. 39, `track`'s nominal plant) does not give (docs/optima.md, "Low
/// optima that a Newton plant cannot execute").
pub fn tap_hint(
    law: PlannedImpact,
    modes: &[PhaseMode],
    durations: &[f64],
    min_stick: f64,
) -> Option<String> {
    let on_minimum = modes
        .iter()
        .zip(durations)
        .any(|(m, &d)| *m == PhaseMode::Stick && crate::pipeline::bounds::on_bound(d, min_stick));
    (law == PlannedImpact::Stick && on_minimum).then(|| {
        format!(
            "hint: the stick phase is on its minimum ({min_stick} s): the plan spins the ball \
             mostly by the sticking impact (eq. 40), which a plant with Newton's law (`track`'s \
             default) does not reproduce; `optimize` without --impact-law plans a periodic \
             problem for such a plant, --min-stick 0.1 rules such taps out (docs/optima.md)"
        )
    })
}

/// The hint for a failed solve whose configurations `at` (label, q) need more torque than
/// the scene's limits against gravity alone: the joints i with |g_i(q)| > τ_max,i (at rest no
/// other torque acts, so no admissible torque holds the arm there), or `None`.
pub fn gravity_hint(scene: &bf_codegen::Scene, at: &[(&str, &[f64])]) -> Option<String> {
    let (model, _) = bf_model::arm::ArmModel::from_scene(scene).ok()?;
    let limits = bf_problem::arm::torque_limits(scene);
    let mut over = Vec::new();
    for (label, q) in at {
        let (_, g) = model.mass_cqd_g(q, &vec![0.0; q.len()]).ok()?;
        for (i, (g, t)) in g.iter().zip(&limits).enumerate() {
            if g.abs() > *t {
                over.push(format!(
                    "at the {label} joint {} needs |g| = {:.3e} > tau_max {t:e}",
                    i + 1,
                    g.abs()
                ));
            }
        }
    }
    (!over.is_empty()).then(|| {
        format!(
            "hint: gravity alone exceeds the torque limits ({}): raise `tau_max` in the scene \
             or lighten the links",
            over.join("; ")
        )
    })
}

/// File name of the candidate of start `k` in a `--shard` output set.
pub fn candidate_file(k: usize) -> String {
    format!("candidate-{k:04}.json")
}

/// Prints the verification of `sol` (if any) and whether it passes [`VERIFIED_DEFECT`].
fn print_verification(sol: &OcpSolution) -> Result<()> {
    if let Some(v) = &sol.verification {
        crate::outln!("{}", v.summary().trim_end())?;
        // The verdict is the re-integration's: a solve that stopped before converging can
        // still describe the model's motion, but it is no optimum, which the line says.
        let unconverged = if sol.status.is_success() {
            String::new()
        } else {
            format!(
                "; but the solve ended {} before converging: no optimum",
                crate::names::name(&sol.status)
            )
        };
        crate::outln!(
            "verified: {} (re-integration defect {:.3e}, tolerance {:e}{}{unconverged})",
            if is_verified(sol) { "yes" } else { "NO" },
            v.max_defect,
            VERIFIED_DEFECT,
            verdict_failure(v)
                .map(|p| format!("; {p}"))
                .unwrap_or_default()
        )?;
        if let Some(w) = impulse_cone_warning(v) {
            crate::outln!("impulse cone: FLAGGED, {w}")?;
        }
        if let Some(miss) = robustness_miss(v).filter(|_| is_verified(sol)) {
            crate::outln!(
                "robustness: MISSED {miss}: the plan is executed on the plant it was planned \
                 for, but the controller does not hold it to the target under that model \
                 error (docs/closed-loop.md)"
            )?;
        }
    }
    Ok(())
}

/// The basin hopping of `--hops` and `--hop-scale` ([`VerifyPolicy::hops`]): `None` with
/// `--hops 0` (the search keeps its best verified start), else
/// [`crate::pipeline::search::DEFAULT_HOPS`] with the budget N (default: its own, 64; the
/// global search is the default of the periodic problems since decision record 0029, the
/// callers drop it for the others without `--hops`).
pub fn hop_settings(
    hops: Option<usize>,
    hop_scale: Option<f64>,
) -> Result<Option<crate::pipeline::global::HopSettings>> {
    let mut h = crate::pipeline::search::DEFAULT_HOPS;
    if let Some(s) = hop_scale {
        if !(s.is_finite() && s > 0.0 && s <= 3.0) {
            bail_usage!(
                "--hop-scale must be in (0, 3] (got {})",
                crate::cli::shown(s)
            );
        }
        h.scale = s;
    }
    match hops {
        Some(0) => Ok(None),
        Some(n) => Ok(Some(crate::pipeline::global::HopSettings {
            budget: n,
            ..h
        })),
        None => Ok(Some(h)),
    }
}

/// Run `optimize`.
pub fn run(args: &OptimizeArgs) -> Result<()> {
    run_with(args, RunSettings::default())
}

/// Errors naming `--warm-start FILE` unless its collocation data fit the phases of `problem`
/// built with `settings` (their count and the widths of their states, algebraic variables and
/// controls, which no mesh changes): checked where the file is read, before any solve, and
/// not where a stage of the search first builds the problem. Other errors of the build are
/// left to the stage that meets them.
fn check_warm_start_fits(problem: Problem, settings: &ProblemSettings, path: &Path) -> Result<()> {
    use bf_problem::ProblemError as P;
    match crate::pipeline::build(problem, settings) {
        Err(crate::pipeline::PipelineError::Problem(
            e @ (P::WarmStartShape { .. } | P::WarmStartPhases { .. }),
        )) => Err(anyhow::Error::new(e).context(format!(
            "--warm-start {} (its collocation data, `raw` in its internals file)",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// Run `optimize` with `opts`.
pub fn run_with(args: &OptimizeArgs, opts: RunSettings) -> Result<()> {
    if let Some(OptimizeCommand::Merge(m)) = &args.command {
        return merge(m);
    }
    args.chain
        .check_given_with(args.scene.as_deref(), "--scene")?;
    if problem_arg(args) == REACH_ARM {
        parts::refuse_missing_parts(args, parts::Posed::ReachArm)?;
        return run_reach_arm(args, opts);
    }
    let name = parse_problem(problem_arg(args))?;
    parts::refuse_missing_parts(args, parts::Posed::Catalogue(name))?;
    let settings = settings_from_args(args)?;
    // Without `--hops` the global search runs for the periodic problems only (the others'
    // default is the continuation; an explicit multi-start of them keeps its best start).
    let hops = hop_settings(args.hops, args.hop_scale)?
        .filter(|_| args.hops.is_some() || name.is_periodic());
    // The global search samples many cheap coarse starts; without it (`--hops 0`) the
    // multi-start keeps its 32 starts on the problem's mesh.
    let default_starts = if hops.is_some() {
        GLOBAL_STARTS
    } else {
        DEFAULT_STARTS
    };
    let starts = args.starts.unwrap_or(default_starts as u64);
    let seed = args.seed.unwrap_or(DEFAULT_SEED);
    let strategy = match (&args.strategy, args.starts.is_some() || args.seed.is_some()) {
        (Some(text), _) => parse_strategy(text, starts, seed)?,
        (None, true) => parse_strategy("multistart", starts, seed)?,
        (None, false) if hops.is_some() => strategy::default_strategy(name, settings.scheme),
        (None, false) => strategy::multistart_strategy(name, settings.scheme),
    };
    // The multi-start's options must not be dropped silently by another strategy.
    if !matches!(strategy, Strategy::Multistart { .. }) {
        for (opt, given) in [
            ("--starts", args.starts.is_some()),
            ("--seed", args.seed.is_some()),
            // `--hops 0` asks for no hops, which is what the other strategies run.
            ("--hops", args.hops.is_some_and(|h| h > 0)),
            ("--hop-scale", args.hop_scale.is_some()),
        ] {
            if given {
                let why = match &args.strategy {
                    Some(_) => format!("got --strategy {strategy}"),
                    None => format!(
                        "the default strategy of --problem {name} with --scheme {} is {strategy}; \
                         give --strategy multistart",
                        args.scheme
                    ),
                };
                bail_usage!("{opt}: only the multi-start takes it ({why})");
            }
        }
    }
    let shard = match &args.shard {
        Some(text) => {
            let sh = Shard::parse(text).map_err(crate::errors::usage)?;
            let Strategy::Multistart { starts, .. } = strategy else {
                bail_usage!(
                    "--shard {text}: sharding needs the multi-start (got --strategy {strategy})"
                );
            };
            if sh.index >= starts {
                bail_usage!("--shard {text}: shard {sh} of {starts} starts has no start");
            }
            sh
        }
        None => Shard::WHOLE,
    };
    if let (None, Some(rounds)) = (args.refine, args.refine_rounds) {
        bail_usage!("--refine-rounds {rounds}: the rounds of --refine TOL, which was not given");
    }
    if let Some(tol) = args.refine {
        if !(tol.is_finite() && tol > 0.0) {
            bail_usage!(
                "--refine must be a finite positive tolerance (got {})",
                crate::cli::shown(tol)
            );
        }
        if settings.scheme == Scheme::Lg {
            bail_usage!("--refine needs --scheme radau (mesh refinement splits Radau elements)");
        }
    }
    crate::commands::check_verify_rtol(args.verify_rtol)?;
    // After the usage checks: a wrong command line is said as such first.
    if let Some(path) = &args.warm_start {
        check_warm_start_fits(name, &settings, path)?;
    }
    let mut out = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    if let Some(n) = opts.fail_at_write {
        out.inject_fault_at_write(n);
    }
    let policy = VerifyPolicy {
        rtol: args.verify_rtol,
        refine_attempts: args
            .verify_refinements
            .unwrap_or(crate::pipeline::search::VERIFY_REFINEMENTS),
        execution: execution_for(name, &settings),
        ..VerifyPolicy::default()
    };
    let policy = match hops {
        Some(h) => policy.global(h),
        None => policy,
    };
    let found = search_with_progress(name, settings.clone(), strategy, shard, &policy)?;
    // A shard keeps every distinct optimum it sampled (unrefined) for `optimize merge`.
    let mut candidates: Vec<(String, OcpSolution)> = if args.shard.is_some() {
        found
            .sampled
            .iter()
            .map(|c| (candidate_file(c.index), c.solution.clone()))
            .collect()
    } else {
        Vec::new()
    };
    let (problem, mut sol) = found.best()?;
    let mut problem = problem
        .ok_or_else(|| anyhow::anyhow!("internal: the chosen {name} solve has no problem"))?;
    if let Some(rep) = &sol.strategy {
        crate::io::print_out(&rep.table())?;
        crate::io::print_out(&rep.refinement_lines())?;
    }
    if args.shard.is_some() {
        crate::outln!("shard {shard}: {} distinct optima kept", candidates.len())?;
    }
    let mut refine_unmet: Option<String> = None;
    if let Some(tol) = args.refine {
        // From the mesh the solution is on: the verification may have refined it already,
        // and a refinement from the problem's own mesh would solve the coarser mesh again.
        // Only the mesh: the rest of a stage's settings (a hop's iteration cap) is the stage's.
        let on_its_mesh = ProblemSettings {
            points: problem.settings.points,
            scheme: problem.settings.scheme,
            mesh: problem.settings.mesh.clone(),
            ..settings.clone()
        };
        let rounds = args.refine_rounds.unwrap_or(DEFAULT_REFINE_ROUNDS);
        (problem, sol) = refine_with_progress(name, &on_its_mesh, sol, tol, rounds)?;
        // A tolerance the user asked for and the rounds did not reach is a check the result
        // failed, whatever the verification says after it.
        refine_unmet = sol.refinement.as_ref().filter(|r| !r.converged).map(|r| {
            let largest = r
                .errors
                .iter()
                .flatten()
                .fold(0.0f64, |a, &e| crate::pipeline::verify::nan_max(a, e));
            format!(
                "the mesh refinement did not reach --refine {tol:e}: {} (largest element \
                 error {largest:.2e})",
                r.stop_reason
            )
        });
        sol.verification = None;
        // Verified as the search verifies (closed loop included); a mesh whose error estimate
        // meets `tol` need not re-integrate within the verification's tolerance, so the
        // verification's own hp refinements go on from it, as for the search's optima.
        if args.verify_rtol > 0.0 {
            let before = sol.strategy.as_ref().map_or(0, |r| r.refinements.len());
            let (built, verified) =
                crate::pipeline::search::verify_refined(name, &on_its_mesh, problem, sol, &policy);
            problem = built.ok_or_else(|| {
                anyhow::anyhow!("internal: the refined {name} solve has no problem")
            })?;
            sol = verified;
            if let Some(rep) = &sol.strategy {
                crate::io::print_out(&rep.refinement_lines_from(before))?;
            }
        }
    }
    // A re-integration that could not run leaves the solution unverified: a failed check.
    let mut unverifiable = None;
    if args.verify_rtol > 0.0 {
        if sol.verification.is_none() {
            match verify(&problem, &sol, args.verify_rtol) {
                Ok(v) => sol.verification = Some(v),
                Err(e) => {
                    crate::errln!("warning: trajectory verification failed: {e}");
                    unverifiable = Some(format!(
                        "the solution is unverified: its re-integration did not run: {e}"
                    ));
                }
            }
        }
        if sol.verification.is_some() {
            print_verification(&sol)?;
        } else {
            crate::outln!("verified: NO (the re-integration did not run: see the warning above)")?;
        }
    } else {
        crate::outln!("verified: not checked (--verify-rtol 0: no re-integration)")?;
    }
    let scene = scene_record(args, name)?;
    let record = shards::search_settings(&settings, &policy);
    for s in std::iter::once(&mut sol).chain(candidates.iter_mut().map(|(_, c)| c)) {
        record_run(s, &problem, &scene, &record);
    }
    if let Some((field, v)) = first_non_finite(&sol) {
        bail!(
            "the solution of {} has a non-finite {field} ({v}); nothing was written to {}",
            name,
            args.out.display()
        );
    }
    let extra: Vec<(String, &OcpSolution)> =
        candidates.iter().map(|(n, c)| (n.clone(), c)).collect();
    let failure = failure_of(&sol).or(unverifiable).or(refine_unmet);
    commit_solution_with(&sol, &extra, out, failure.as_deref())?;
    crate::errln!(
        "optimize: scene `{}`, node functions on the {} kernels",
        sol.scene,
        sol.kernels
    );
    crate::outln!(
        "{}: {} after {} iterations in {:.2} s; objective {:.6e} (c1 {:.6e}, c2 {:.6e})",
        sol.problem,
        crate::names::name(&sol.status),
        sol.iterations,
        sol.solve_seconds,
        sol.objective,
        sol.c1,
        sol.c2
    )?;
    crate::outln!(
        "period {:.4} s, phase durations {:?}, mean omega {:?}",
        sol.period,
        sol.phase_durations,
        sol.mean_omega
    )?;
    crate::outln!(
        "constraint violation {:.2e}, dual infeasibility {:.2e}",
        sol.constraint_violation,
        sol.dual_infeasibility
    )?;
    // The bounds the optimum sits on (phase durations, period, torque and joint limits): an
    // optimum on a bound is the bound's as much as the problem's.
    let active = sol.active_bounds.clone().unwrap_or_default();
    if active.is_empty() {
        crate::outln!("active bounds: none")?;
    } else {
        crate::outln!("active bounds:")?;
        for b in &active {
            crate::outln!("  {}", b.describe())?;
        }
    }
    // How often the search met this optimum's basin: a count of sightings, not a forecast
    // (docs/optima.md, "The global search").
    if let Some(line) = sol
        .strategy
        .as_ref()
        .and_then(crate::pipeline::search::basin_line)
    {
        crate::outln!("{line}")?;
    }
    if sol.problem.starts_with("periodic-cot") {
        crate::outln!(
            "note: the COT period is bounded by {} s (COT lets the finger rest at no cost)",
            COT_MAX_PERIOD
        )?;
    }
    if let Some(h) = tap_hint(
        sol.impact_law,
        &sol.modes,
        &sol.phase_durations,
        settings.min_stick,
    ) {
        crate::outln!("{h}")?;
    }
    print_wrote(&args.out, failure.as_deref())?;
    // An Acceptable end of the default KKT settings may end Solved on another path.
    if sol.status == Status::Acceptable
        && !args.kkt_residual_ratio
        && args.dual_regularization.is_none()
    {
        crate::outln!(
            "hint: the solve met only the acceptable tolerances; fine meshes can stall where \
             the KKT factor is inaccurate, and another path may end Solved: try \
             --kkt-residual-ratio or --dual-regularization 3e-8 (optim/README.md)"
        )?;
    }
    // An iteration limit on a fine mesh can be a wander of an early barrier problem that the
    // proximal term did not end (decision record 0011); the extrapolation on every barrier
    // problem takes another path (decision record 0010).
    if sol.status == Status::MaxIterations && !args.extrapolate_every_barrier {
        crate::outln!(
            "hint: the iteration limit stopped the solve; --max-iter raises it, and \
             --extrapolate-every-barrier (steps along negative curvature from the first barrier \
             problem on, not only once μ ≤ tol) ends some wanders on fine meshes \
             (docs/decisions/0010-curvature-extrapolation.md)"
        )?;
    }
    if !sol.status.is_success()
        && let Some(h) = gravity_hint(&problem.scene, &[("start", &problem.guess.free)])
    {
        crate::outln!("{h}")?;
    }
    if !sol.status.is_success()
        && let Some(h) = friction_hint(&problem.scene, &sol.modes)
    {
        crate::outln!("{h}")?;
    }
    if let Some(f) = failure {
        bail!("{f}");
    }
    Ok(())
}

/// Why a problem with a stick phase may have no solution on `scene`: without static friction
/// (μ_s = 0) the contact force of a stick phase must lie along the normal (the cone of eq. 18
/// shrinks to its axis), through the ball's centre, where it exerts no moment on the ball.
/// `None` where the scene has friction or the problem no stick phase.
pub fn friction_hint(scene: &bf_codegen::Scene, modes: &[PhaseMode]) -> Option<String> {
    // A scene without a [friction] table has none (μ_s = 0, `Constants::of`).
    let frictionless = scene.friction.as_ref().is_none_or(|f| f.mu_s == 0.0);
    (frictionless && modes.contains(&PhaseMode::Stick)).then(|| {
        format!(
            "hint: scene `{}` has no static friction (mu_s = 0): a stick phase's contact force \
             must then lie along the normal (the friction cone, eq. 18, is its axis), through \
             the ball's centre, and cannot spin the ball; give the scene a [friction] table \
             with mu_s > 0",
            scene.name
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults plan periodic problems on 3 joints or more for `track`'s Newton plant
    /// (Newton's law, the torque margin, the controller's clearance); `--impact-law stick`,
    /// fingers of fewer joints and other problems get the paper's problem; given values win.
    #[test]
    fn periodic_problems_on_three_joints_or_more_plan_for_the_newton_plant_by_default() {
        let gap = bf_control::HybridGains::default().clearance.gap;
        let plan = |p: Problem, joints, law, margin, clearance| {
            PlanFor::of(p, joints, gap, law, margin, clearance).unwrap()
        };
        let newton = PlanFor {
            impact_law: PlannedImpact::Newton,
            torque_margin: EXECUTABLE_TORQUE_MARGIN,
            approach_clearance: gap,
        };
        let paper = PlanFor {
            impact_law: PlannedImpact::Stick,
            torque_margin: 0.0,
            approach_clearance: 0.0,
        };
        for p in [
            Problem::PeriodicQc,
            Problem::PeriodicCot,
            Problem::PeriodicCotHuman,
        ] {
            assert_eq!(plan(p, 3, None, None, None), newton);
            assert_eq!(plan(p, 4, None, None, None), newton);
            assert_eq!(plan(p, 7, None, None, None), newton);
            // The paper's problem by name, and fingers without a Newton impact plan.
            assert_eq!(plan(p, 3, Some("stick"), None, None), paper);
            assert_eq!(plan(p, 2, None, None, None), paper);
            // Given values win; the law's defaults fill the rest.
            let own = plan(p, 3, None, Some(0.1), Some(0.0));
            assert_eq!((own.torque_margin, own.approach_clearance), (0.1, 0.0));
            assert_eq!(
                plan(p, 3, Some("stick"), Some(0.2), None).torque_margin,
                0.2
            );
        }
        assert_eq!(plan(Problem::Reach, 3, None, None, None), paper);
        // Applied to settings, the plan sets its three fields and keeps the others.
        let base = ProblemSettings {
            min_stick: 0.1,
            ..ProblemSettings::default()
        };
        let s = newton.apply(base);
        assert_eq!(
            (
                s.impact_law,
                s.torque_margin,
                s.approach_clearance,
                s.min_stick
            ),
            (PlannedImpact::Newton, EXECUTABLE_TORQUE_MARGIN, gap, 0.1)
        );
        assert!(PlanFor::of(Problem::PeriodicQc, 3, gap, None, Some(1.0), None).is_err());
        assert!(PlanFor::of(Problem::PeriodicQc, 3, gap, Some("elastic"), None, None).is_err());
    }

    /// Only a sticking plan whose stick phase is on its minimum gets the hint: a longer stick
    /// phase, a Newton plan or a plan without a stick phase does not.
    #[test]
    fn the_tap_hint_names_sticking_plans_on_the_stick_minimum_only() {
        use PhaseMode::{Free, Stick};
        let modes = [Free, Stick, Free];
        let tap = [0.5, 0.01, 0.1];
        let long = [0.5, 0.0102, 0.1];
        let hint = tap_hint(PlannedImpact::Stick, &modes, &tap, 0.01).unwrap();
        assert!(
            hint.contains("without --impact-law") && hint.contains("0.01 s"),
            "{hint}"
        );
        assert!(tap_hint(PlannedImpact::Stick, &modes, &long, 0.01).is_none());
        assert!(tap_hint(PlannedImpact::Newton, &modes, &tap, 0.01).is_none());
        assert!(tap_hint(PlannedImpact::Stick, &[Free, Free, Free], &tap, 0.01).is_none());
        // The larger minimum of `--min-stick 0.1` is the one compared with.
        assert!(tap_hint(PlannedImpact::Stick, &modes, &[0.5, 0.1, 0.1], 0.1).is_some());
    }

    /// A failed problem with a stick phase on a scene without static friction says why it
    /// may have no solution (it used to end at its iteration limit without a word of it); a
    /// scene with friction, or a problem without a stick phase, gets no such hint.
    #[test]
    fn the_friction_hint_names_a_scene_without_static_friction() {
        use PhaseMode::{Free, Stick};
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/paper.toml");
        let mut scene = bf_codegen::Scene::load(&path).unwrap();
        assert!(friction_hint(&scene, &[Free, Stick, Free]).is_none());
        scene.friction.as_mut().unwrap().mu_s = 0.0;
        let hint = friction_hint(&scene, &[Free, Stick, Free]).unwrap();
        assert!(
            hint.contains("`paper`") && hint.contains("mu_s = 0"),
            "{hint}"
        );
        assert!(friction_hint(&scene, &[Free]).is_none());
        // No [friction] table at all is no friction either.
        scene.friction = None;
        assert!(friction_hint(&scene, &[Free, Stick, Free]).is_some());
    }
}
