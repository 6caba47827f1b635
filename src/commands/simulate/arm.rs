//! `ball-finger simulate` on a scene without a ball: the free motion of an arm with any number
//! of joints, M q̈ = τ − C q̇ − g − μ_v q̇ (`bf_sim::arm`), under `--torques`, `--pd`, zero
//! torques or the replay of an arm solution given as `--init`; writes `trajectory.csv` and
//! `summary.json` (energy balance) as one output set.

use super::torques::{CliInput, pd_controller};
use super::{OUTPUT_DIR, RunSettings, check_limits, check_t_end, interpreted_note, settings};
use crate::cli::Inputs as _;
use crate::cli::SimulateArgs;
use crate::errors::bail_usage;
use crate::io::parse_list;
use anyhow::{Context, Result, anyhow, bail};
use bf_output::{Outcome, OutputDir};
use bf_sim::arm::{ArmMode, FreeArm};
use std::time::Instant;

/// Free motion of an arm without a ball (any number of joints, `bf_sim::arm`): τ from
/// `--torques` (one column per joint), `--pd` (one target per joint) or zero; initial state
/// from `--q0`/`--qd0` (default 0). Writes `trajectory.csv` and `summary.json`.
pub(super) fn run_arm(
    args: &SimulateArgs,
    run_opts: RunSettings,
    scene: &bf_codegen::Scene,
    scene_label: &str,
) -> Result<()> {
    let n = scene.links.len();
    let name = &scene.name;
    // `--init` an arm solution.json (`optimize --problem reach-arm`): replay its optimal
    // torques from its start at rest, over its duration unless --t-end says otherwise.
    let replay = match &args.init {
        Some(p) => Some(arm_replay(p, n)?),
        None => None,
    };
    let inp = if let Some(path) = &args.torques {
        super::torques::series(path, name, n)?
    } else if let Some(target) = &args.pd {
        CliInput::Pd(pd_controller(args, target, n)?)
    } else if let Some((_, torque, _)) = &replay {
        CliInput::Replay(torque.clone())
    } else {
        CliInput::Arm(n)
    };
    // A replayed solution ends with its duration unless --t-end or a --torques series says
    // otherwise, also when --pd drives the arm from its start.
    let end = super::run_end(args, &inp, replay.as_ref().map(|(_, _, d)| *d));
    let t_end = end.t;
    check_t_end(t_end)?;
    if args.pd_track.is_some() || args.pd_track_contact {
        bail_usage!(
            "--pd-track: scene `{name}` ({scene_label}) has no ball; --pd-track tracks a \
             solution of the ball and finger, and an arm solution given as --init is replayed \
             with its own torques (use --pd TARGETS for a PD law of the arm)"
        );
    }
    for (opt, given) in [
        ("--omega0", args.omega0.is_some()),
        ("--mode0", args.mode0.is_some()),
        ("--impact-law", args.impact_law.is_some()),
        ("--no-projection", args.no_projection),
    ] {
        if given {
            bail_usage!(
                "{opt}: scene `{name}` ({scene_label}) has no ball; only free motion of the arm is simulated (use --q0, --qd0)"
            );
        }
    }
    let set = settings(args)?;
    check_limits(args, &set, end)?;
    let held = super::torques_held(&inp, end);
    for w in &held {
        crate::errln!("warning: {}", w.message);
    }
    let q0 = match (&args.q0, &replay) {
        (Some(s), _) => parse_list("--q0", s, Some(n))?,
        (None, Some((q, _, _))) => q.clone(),
        (None, None) => vec![0.0; n],
    };
    super::check_initial_angles(args, scene, &q0)?;
    let qd0 = match &args.qd0 {
        Some(s) => parse_list("--qd0", s, Some(n))?,
        None => vec![0.0; n],
    };
    let setup = Instant::now();
    let (model, source) = bf_model::arm::ArmModel::from_scene(scene)
        .with_context(|| format!("{scene_label}: scene cannot be simulated"))?;
    crate::errln!(
        "simulate: scene `{name}` from {scene_label} (no ball: free motion of {n} joints) on the \
         {source} kernels{}",
        interpreted_note(source, setup.elapsed())
    );
    let inputs = super::input_options(args, &inp);
    let sys = FreeArm::new(model, inp)?;
    let x0: Vec<f64> = q0.iter().chain(&qd0).copied().collect();
    let mut out_dir = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    if let Some(k) = run_opts.fail_at_write {
        out_dir.inject_fault_at_write(k);
    }
    let arm: &dyn bf_sim::HybridSystem<Mode = ArmMode> = &sys;
    let mut sim =
        bf_sim::Simulator::new(arm, set, ArmMode::Free, 0.0, &x0, t_end).map_err(|e| {
            anyhow!(
                "cannot start the simulation: {e}; initial state: {}; torques: {inputs}",
                super::initial_state_options(args)
            )
        })?;
    let (error, cpu) = super::advance_within_limits(&mut sim, args, 0.0, t_end)?;
    let error = error.map(|e| format!("simulation failed at t = {} s: {e}", sim.t()));
    let out = sim.finish();
    let mut report = sys.report(&out, cpu).map_err(|e| anyhow!("{e}"))?;
    report.summary.kernels = Some(source.name().to_string());
    report.summary.warnings.extend(held);
    // A run that ends but fails its energy check is no result either, as for the ball and
    // finger: written whole, marked as failed.
    let failure = error.or_else(|| {
        report.summary.energy_check_failure().map(|w| {
            format!(
                "the energy balance failed its check: {w}; the whole trajectory ({} samples) was \
                 written to {}",
                report.samples.len(),
                args.out.display()
            )
        })
    });
    out_dir.file("summary.json")?;
    report
        .write_dir(out_dir.path(), failure.as_deref())
        .map_err(|e| anyhow!(out_dir.rename_in(&e.to_string())))
        .with_context(|| format!("cannot write the output to {}", args.out.display()))?;
    out_dir.commit(match &failure {
        Some(e) => Outcome::Failed(e),
        None => Outcome::Success,
    })?;
    crate::outln!("{}", report.summary)?;
    crate::outln!("output: {}", args.out.display())?;
    match failure {
        Some(e) => bail!("{e}"),
        None => Ok(()),
    }
}

/// The replay of an arm solution (`optimize --problem reach-arm`) given as `--init`: its start
/// configuration, its optimal torques (the control polynomials of its collocation elements)
/// and its duration.
fn arm_replay(
    path: &std::path::Path,
    n: usize,
) -> Result<(Vec<f64>, crate::pipeline::arm::PhaseTorque, f64)> {
    let sol = crate::pipeline::arm::read_arm_solution(path).with_context(|| {
        format!(
            "--init {}: an arm (no ball) replays only a solution of `optimize --problem \
             reach-arm`",
            path.display()
        )
    })?;
    if sol.start.len() != n {
        bail!(
            "--init {}: the solution has {} joints, the scene {n}",
            path.display(),
            sol.start.len()
        );
    }
    let r = &sol.raw;
    let shaped = !r.elements.is_empty()
        && r.elements
            .iter()
            .all(|&(a, b)| a < b && b <= r.state_tau.len())
        && r.x.len() == r.state_tau.len()
        && r.x.iter().all(|x| x.len() == 3 * n)
        && r.duration.is_finite()
        && r.duration > 0.0;
    if !shaped {
        bail!(
            "--init {}: the solution's raw collocation data (`raw`: elements, states (q, q̇, τ) \
             of {n} joints) is missing or inconsistent",
            path.display()
        );
    }
    let limits = crate::pipeline::arm::torque_limits(&sol);
    let torque = crate::pipeline::arm::PhaseTorque::new(&sol.raw, n, &limits);
    Ok((sol.start.clone(), torque, sol.duration))
}
