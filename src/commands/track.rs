//! `track`: executes an optimum in closed loop ([`crate::paper::closed_loop`]) and writes the
//! files of `simulate` (trajectory, events, summary) plus `tracking.json` (docs/files.md) into
//! an output directory replaced as a whole (`bf_output::OutputDir`); a run that lost the ball,
//! or whose energy balance failed the simulator's check, is marked FAILED and exits non-zero
//! (`Tracking::failure`). `--robustness` runs the robustness table of
//! [`crate::paper::closed_loop::robustness_rows`] instead (robustness.md, robustness.json),
//! marked FAILED when a plant misses the target.

use crate::cli::Inputs as _;
use crate::cli::TrackArgs;
use crate::errors::bail_usage;
use crate::paper::closed_loop::{
    ControllerKind, FIRST_JUDGED_PERIOD, Tracking, finger_model, robustness_rows, robustness_table,
    run_tracking_replanned, solution_scene, tracked_joints, with_joints,
};
use crate::paper::replan::{REPLAN_MAX_ITER, ReplanRecord};
use crate::pipeline::SolutionIo as _;
use anyhow::{Context, Result, anyhow, bail};
use bf_control::PeriodMetrics;
use bf_output::{DirSpec, Outcome, OutputDir};
use bf_problem::OcpSolution;
use serde::Serialize;

/// The output directory of `track`.
pub const OUTPUT_DIR: DirSpec<'static> = DirSpec {
    option: "--out",
    command: "track",
};

/// The contents of `tracking.json`.
#[derive(Debug, Serialize)]
pub struct TrackingJson<'a> {
    /// `open-loop`, `pd` or `hybrid`.
    pub controller: &'static str,
    /// The plant's scene name and the impact law.
    pub plant_scene: &'a str,
    /// The plant's impact law.
    pub impact_law: &'a str,
    /// The impact law the optimum was planned with (`solution.json`'s `impact_law`).
    pub planned_impact_law: &'static str,
    /// The optimum's mean ω (rad/s).
    pub optimum_mean_omega: [f64; 3],
    /// Whether the plan passed its own verification: the verdict of `solution.json`'s
    /// `verification` record (what `optimize` wrote as `verified`), false without a record.
    /// An unverified plan's errors include the plan's own.
    pub plan_verified: bool,
    /// How the plan's solve ended (`solution.json`'s `status`): a plan of a solve that did not
    /// converge (`MaxIterations`, …) is no optimum, whatever its re-integration shows.
    pub plan_status: String,
    /// Periods asked for.
    pub requested_periods: usize,
    /// Periods completed (at most the requested ones).
    pub completed_periods: usize,
    /// Whether the run lost the ball.
    pub lost_ball: bool,
    /// Why, if it did.
    pub lost_reason: Option<&'a str>,
    /// Why the run's energy balance failed the simulator's check, if it did
    /// (`Tracking::energy_check_failure`): the run is then no result either.
    pub energy_check_failure: Option<String>,
    /// Why the run's contact is not the plant's physics, if it is not: the simulator held it
    /// while the ball pulled the finger (`RunSummary::held_contact`); the run is then no
    /// result either.
    pub held_contact: Option<String>,
    /// Largest `omega_error` over the completed periods.
    pub max_omega_error: f64,
    /// The periods.
    pub periods: &'a [PeriodMetrics],
    /// Whether the controller re-planned at every lift-off (`--replan`).
    pub replan: bool,
    /// The set-up solve of the re-planning (from the optimum's own lift-off state; null
    /// without `--replan`).
    pub replan_setup: Option<&'a ReplanRecord>,
    /// The re-plans, one per lift-off (empty without `--replan`): plant time, wall time (s),
    /// iterations, status, whether the plan was used.
    pub replans: &'a [ReplanRecord],
    /// The budget of one re-plan: a tenth of the optimum's period (s).
    pub replan_budget_seconds: f64,
    /// Median and largest wall time of the re-plans (s; null without re-plans).
    pub replan_seconds_median: Option<f64>,
    /// Largest wall time of a re-plan (s).
    pub replan_seconds_max: Option<f64>,
}

impl<'a> TrackingJson<'a> {
    /// The record of run `r` on plant `plant_scene` with impact law `impact_law`.
    pub fn of<const N: usize>(
        r: &'a Tracking<N>,
        plant_scene: &'a str,
        impact_law: &'a str,
        planned_impact_law: &'static str,
        sol: &OcpSolution,
        replan: bool,
    ) -> Self {
        let mut secs: Vec<f64> = r.replans.replans.iter().map(|p| p.seconds).collect();
        secs.sort_by(f64::total_cmp);
        TrackingJson {
            controller: r.controller.name(),
            plant_scene,
            impact_law,
            planned_impact_law,
            optimum_mean_omega: sol.mean_omega,
            plan_verified: crate::pipeline::verify::is_verified(sol),
            plan_status: crate::names::name(&sol.status),
            requested_periods: r.requested_periods,
            completed_periods: r.periods.len(),
            lost_ball: r.lost.is_some(),
            lost_reason: r.lost.as_deref(),
            energy_check_failure: r.energy_check_failure(),
            held_contact: r.report.summary.held_contact().map(|w| w.message.clone()),
            max_omega_error: r.periods.iter().map(|p| p.omega_error).fold(0.0, f64::max),
            periods: &r.periods,
            replan,
            replan_setup: r.replans.setup.as_ref(),
            replans: &r.replans.replans,
            replan_budget_seconds: sol.period / 10.0,
            // The mean of the middle two for an even count (the upper one alone was the
            // maximum of two re-plans).
            replan_seconds_median: (!secs.is_empty()).then(|| {
                let m = secs.len() / 2;
                if secs.len().is_multiple_of(2) {
                    0.5 * (secs[m - 1] + secs[m])
                } else {
                    secs[m]
                }
            }),
            replan_seconds_max: secs.last().copied(),
        }
    }
}

/// The re-plan iteration limit of `args` (`None` without `--replan`), checked against the
/// other options (`controller`: one that re-plans).
fn replan_limit(args: &TrackArgs, controller: ControllerKind) -> Result<Option<usize>> {
    let max_iter = args.replan_iterations.unwrap_or(REPLAN_MAX_ITER);
    if args.replan_iterations.is_some() && !args.replan {
        bail_usage!("--replan-iterations needs --replan");
    }
    if args.replan && !controller.replans() {
        bail_usage!(
            "--replan needs a hybrid controller (hybrid or hybrid-unbounded), not `{}`",
            controller.name()
        );
    }
    Ok(args.replan.then_some(max_iter))
}

/// `track --robustness`: the robustness table of `controller` on `sol`, printed and written
/// (robustness.md, robustness.json); the directory is marked FAILED, and the command fails,
/// when a plant misses the target.
fn robustness(args: &TrackArgs, controller: ControllerKind, sol: &OcpSolution) -> Result<()> {
    let replan = replan_limit(args, controller)?;
    let mut out_dir = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    let name = args.solution.display().to_string();
    let rows = robustness_rows(sol, controller, args.periods, replan);
    let caveats = plan_caveats(args, sol);
    let mut md: String = caveats
        .iter()
        .map(|c| format!("**Warning**: {c}.\n\n"))
        .collect();
    md.push_str(&robustness_table(&name, controller, args.periods, &rows)?);
    for caveat in &caveats {
        crate::errln!("warning: {caveat}");
    }
    out_dir.write("robustness.md", md.as_bytes())?;
    out_dir.write("robustness.json", &serde_json::to_vec_pretty(&rows)?)?;
    let missed: Vec<&str> = rows
        .iter()
        .filter(|r| !r.meets_target)
        .map(|r| r.plant.as_str())
        .collect();
    let failure = (!missed.is_empty()).then(|| {
        format!(
            "{} of {} plants miss the robustness target: {}",
            missed.len(),
            rows.len(),
            missed.join(", ")
        )
    });
    out_dir.commit(match &failure {
        Some(f) => Outcome::Failed(f),
        None => Outcome::Success,
    })?;
    crate::outln!("{md}")?;
    crate::outln!("output: {}", args.out.display())?;
    match failure {
        Some(f) => bail!("{f}"),
        None => Ok(()),
    }
}

/// What a run of the plan `sol` measures besides the controller, as sentences naming the
/// file: a plan that failed its own verification or was not re-integrated (its errors are the
/// plan's too), a solve that stopped before converging (no optimum). Printed as warnings by
/// both kinds of run and written at the head of the robustness table.
fn plan_caveats(args: &TrackArgs, sol: &OcpSolution) -> Vec<String> {
    let path = args.solution.display();
    let mut out = Vec::new();
    if !crate::pipeline::verify::is_verified(sol) {
        let why = if sol.verification.is_some() {
            "failed its own verification (solution.json `verification`)"
        } else {
            "was not re-integrated (it has no `verification` record: `optimize --verify-rtol 0`)"
        };
        out.push(format!("{path} {why}: the errors below include the plan's"));
    }
    if !sol.status.is_success() {
        out.push(format!(
            "{path}: its solve ended {} (status): the plan tracked is where that solve \
             stopped, not an optimum",
            crate::names::name(&sol.status)
        ));
    }
    out
}

/// Runs `track`.
pub fn run(args: &TrackArgs) -> Result<()> {
    args.chain
        .check_given_with(args.plant_scene.as_deref(), "--plant-scene")?;
    let controller = ControllerKind::parse(&args.controller)
        .map_err(|e| crate::errors::usage(format!("--controller: {e}")))?;
    let law = super::simulate::parse_impact_law(&args.impact_law)?;
    if args.robustness && args.periods < FIRST_JUDGED_PERIOD {
        bail_usage!(
            "--periods {}: --robustness judges each plant from period {FIRST_JUDGED_PERIOD} \
             on; give --periods {FIRST_JUDGED_PERIOD} or more",
            args.periods
        );
    }
    // An arm's solution is named as one; the reader below checks the rest of a finger's (the
    // range of every number included: a value no optimum has would surface as a lost ball).
    let doc = super::optimize::read_json_value("track", &args.solution)?;
    if crate::pipeline::arm::is_arm_solution(&doc) {
        bail!(
            "{}: a solution of `optimize --problem {}` (an arm without a ball); `track` \
             executes the periodic plans of a finger on its ball. Replay an arm's motion with \
             `simulate --init {}`",
            args.solution.display(),
            bf_problem::arm::REACH_ARM,
            args.solution.display()
        );
    }
    let sol = OcpSolution::read_json(&args.solution)
        // Every error of the reader names the file it is about.
        .context("reading the solution")?;
    // Another problem's solution is refused by the closed loop itself, naming the problem.
    if sol
        .problem
        .parse::<bf_problem::Problem>()
        .is_ok_and(|p| p.is_periodic())
    {
        check_mean_omega(&sol).with_context(|| args.solution.display().to_string())?;
    }
    if args.robustness {
        return robustness(args, controller, &sol);
    }
    let (scene, name) =
        solution_scene(&sol).with_context(|| args.solution.display().to_string())?;
    let joints = tracked_joints(&scene)
        .with_context(|| format!("the solution's scene `{name}`"))
        .with_context(|| args.solution.display().to_string())?;
    with_joints!(
        joints,
        run_n(args, controller, law, &sol),
        bail!("the solution's scene `{name}` has {joints} joints")
    )
}

/// Errors unless the plan's stated mean ω, against which every period's error is measured,
/// is that of its own trajectory ([`bf_problem::mean_omega`] of its collocation data, the
/// definition it was written with, so equal to the bit but for an edit) and not zero: an
/// edited or zero `mean_omega` would make every error relative to a wrong or vanishing target.
fn check_mean_omega(sol: &OcpSolution) -> Result<()> {
    let nq = sol.dense.q.first().map_or(0, Vec::len);
    let own = bf_problem::mean_omega(&sol.raw, nq);
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(norm(own).is_finite() && norm(own) > 0.0) {
        bail!(
            "the plan's collocation data give no mean ball rotation ({own:?} rad/s): the \
             tracking error of a period is relative to it"
        );
    }
    let diff = norm(std::array::from_fn(|j| sol.mean_omega[j] - own[j]));
    if diff.is_nan() || diff > 1e-9 * norm(own) {
        bail!(
            "its `mean_omega` {:?} rad/s is not the mean of its own ω, {own:?} rad/s (differs \
             by {:.1e} relatively): the file was altered",
            sol.mean_omega,
            diff / norm(own)
        );
    }
    Ok(())
}

/// `track` of the optimum `sol` of a finger with `N` joints.
fn run_n<const N: usize>(
    args: &TrackArgs,
    controller: ControllerKind,
    law: bf_model::ImpactLaw,
    sol: &OcpSolution,
) -> Result<()> {
    let (plant, plant_name, kernels) = match &args.plant_scene {
        Some(path) => {
            let (scene, _) = super::load_scene(path, &args.chain)?;
            let (model, _, kernels) = finger_model::<N>(&scene)
                .with_context(|| format!("--plant-scene {}", path.display()))?;
            (model, path.display().to_string(), kernels)
        }
        None => {
            let (scene, name) = solution_scene(sol)?;
            let (model, _, kernels) = finger_model::<N>(&scene).with_context(|| {
                format!("{}: the solution's scene `{name}`", args.solution.display())
            })?;
            (model, name, kernels)
        }
    };
    let replan = replan_limit(args, controller)?;
    let mut out_dir = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    let mut run = run_tracking_replanned(sol, controller, args.periods, plant, law, replan)
        .with_context(|| format!("tracking {}", args.solution.display()))?;
    run.report.summary.kernels = Some(kernels.name().to_string());
    out_dir.file("summary.json")?;
    run.report
        .write_dir(out_dir.path(), &run.output, run.stopped.as_deref())
        .map_err(|e| anyhow!(out_dir.rename_in(&crate::errors::chain(&e))))
        .with_context(|| format!("cannot write the output to {}", args.out.display()))?;
    let record = TrackingJson::of(
        &run,
        &plant_name,
        law.name(),
        sol.impact_law.name(),
        sol,
        args.replan,
    );
    let bytes = serde_json::to_vec_pretty(&record)?;
    out_dir.write("tracking.json", &bytes)?;
    let failure = run.failure();
    out_dir.commit(match &failure {
        Some(f) => Outcome::Failed(f),
        None => Outcome::Success,
    })?;
    for caveat in plan_caveats(args, sol) {
        crate::errln!("warning: {caveat}");
    }
    if law.name() != sol.impact_law.name() {
        // A sticking plan on a Newton plant: short stick phases spin the ball by an impulse
        // the plant does not give (docs/optima.md, "Low optima that a Newton plant cannot
        // execute").
        crate::errln!(
            "note: the optimum was planned with the {} impact law, the plant uses {}",
            sol.impact_law.name(),
            law.name()
        );
        if law == bf_model::ImpactLaw::Newton {
            crate::errln!(
                "note: plans that the hybrid controller executes on a Newton plant, also with \
                 model error: `optimize` without --impact-law, which plans periodic problems \
                 for Newton's law with a torque margin and an approach clearance \
                 (docs/closed-loop.md)"
            );
        }
    }
    crate::outln!(
        "controller {}, plant {plant_name} ({kernels} kernels), impact law {}: {} of {} periods, \
         max omega error {:.3} %",
        controller.name(),
        law.name(),
        record.completed_periods,
        args.periods,
        100.0 * record.max_omega_error
    )?;
    crate::outln!("period  omega error [%]  stick [s]  slip [s]  max |tau| [N m]")?;
    for (k, p) in run.periods.iter().enumerate() {
        crate::outln!(
            "{:>6}  {:>15.3}  {:>9.4}  {:>8.4}  {:>15.4}",
            k + 1,
            100.0 * p.omega_error,
            p.stick_time,
            p.slip_time,
            p.max_abs_tau
        )?;
    }
    for line in run.report.summary.warning_lines() {
        crate::errln!("warning: {line}");
    }
    if let (Some(median), Some(max)) = (record.replan_seconds_median, record.replan_seconds_max) {
        let used = run.replans.replans.iter().filter(|p| p.used).count();
        crate::outln!(
            "re-plans: {} ({used} converged and used), wall time median {median:.3} s, max {max:.3} s (budget a tenth of the period: {:.3} s)",
            run.replans.replans.len(),
            record.replan_budget_seconds
        )?;
        let late = run
            .replans
            .replans
            .iter()
            .filter(|p| p.used && p.seconds > record.replan_budget_seconds)
            .count();
        if late > 0 {
            // The plant waits for each plan in simulated time (so a run is the same on any
            // machine); on a real plant a plan that overruns arrives after the contact it was
            // made for.
            crate::errln!(
                "warning: {late} of the re-plans used took longer than their budget of {:.3} s \
                 (wall time on this machine): a real-time controller would get them late",
                record.replan_budget_seconds
            );
        }
    }
    crate::outln!("output: {}", args.out.display())?;
    match failure {
        Some(f) => bail!("{f}"),
        None => Ok(()),
    }
}
