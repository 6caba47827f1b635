//! `ball-finger optimize --problem reach-arm --scene FILE`: an arm without a ball moved from
//! rest to rest in minimum time plus effort (`bf_problem::arm`, Radau collocation of paper
//! Sect. 4.2), verified by re-integration element by element (`pipeline::arm`), written as one
//! output set (`solution.json`, `torques.csv`, `trajectory.csv`).

use super::{OUTPUT_DIR, RunSettings, check_size, parse_scheme};
use crate::cli::Inputs as _;
use crate::cli::OptimizeArgs;
use crate::errors::bail_usage;
use crate::io::parse_list;
use crate::pipeline::verify::VERIFIED_DEFECT;
use anyhow::{Context, Result, bail};
use bf_optim::ocp::transcription::MAX_ELEVATION;
use bf_output::{Outcome, OutputDir};
use bf_problem::arm::{ArmSettings, ArmSolution, MAX_DURATION, MIN_DURATION, REACH_ARM};

/// The first non-finite number of an arm solution (objective, duration, dense samples).
fn first_non_finite_arm(sol: &ArmSolution) -> Option<(String, f64)> {
    for (n, v) in [("objective", sol.objective), ("duration", sol.duration)] {
        if !v.is_finite() {
            return Some((n.into(), v));
        }
    }
    let d = &sol.dense;
    for (n, m) in [("q", &d.q), ("qd", &d.qd), ("tau", &d.tau)] {
        for (k, r) in m.iter().enumerate() {
            if let Some(i) = r.iter().position(|v| !v.is_finite()) {
                return Some((format!("dense.{n}[{k}][{i}]"), r[i]));
            }
        }
    }
    None
}

/// `optimize --problem reach-arm --scene FILE`: an arm without a ball from rest at `--start`
/// to rest at `--target` in minimum time plus effort (`bf_problem::arm`), verified by
/// re-integration element by element (`pipeline::arm`). Writes `solution.json`, `torques.csv`
/// and `trajectory.csv`; a solve that does not converge or verify is marked FAILED.
pub(super) fn run_reach_arm(args: &OptimizeArgs, opts: RunSettings) -> Result<()> {
    use crate::pipeline::arm::{failure_of, solve_verified, write_arm_solution};
    let Some(path) = &args.scene else {
        bail_usage!(
            "--problem {REACH_ARM} needs --scene FILE (an arm, e.g. scenes/puma560.toml): it has \
             no built-in scene"
        );
    };
    if args.scheme != "radau" {
        bail_usage!(
            "--scheme {}: --problem {REACH_ARM} is transcribed with radau only",
            args.scheme
        );
    }
    if args.points < 2 {
        bail_usage!("--points must be at least 2 (got {})", args.points);
    }
    let scheme = parse_scheme(&args.scheme, args.elements)?;
    // `--scheme radau` only (refused otherwise above): its element count, defaulted once.
    let elements = match scheme {
        bf_optim::ocp::Scheme::Radau { elements } => elements,
        bf_optim::ocp::Scheme::Lg => crate::cli::DEFAULT_ELEMENTS,
    };
    check_size(args.points, scheme)?;
    crate::commands::check_verify_rtol(args.verify_rtol)?;
    let (scene, text) = crate::commands::load_scene_with_params(path, &args.chain, &args.param)?;
    let params = crate::commands::parse_params(&args.param)?;
    let nq = scene.links.len();
    // A configuration outside the joint limits is a value out of its range: a usage error
    // that names the option (the problem's own check, `check_configuration`).
    let config = |opt: &str, what: &str, v: &Option<String>| -> Result<Option<Vec<f64>>> {
        let q = v
            .as_deref()
            .map(|s| parse_list(opt, s, Some(nq)))
            .transpose()
            .with_context(|| format!("scene {} has {nq} joints", path.display()))?;
        if let Some(q) = &q
            && let Err(e) = bf_problem::arm::check_configuration(&scene, what, q)
        {
            bail_usage!("{opt}: {e}");
        }
        Ok(q)
    };
    let weight = |opt: &str, v: Option<f64>, default: f64| -> Result<f64> {
        match v {
            Some(w) if w.is_finite() && w >= 0.0 => Ok(w),
            Some(w) => bail_usage!(
                "{opt} must be a finite number >= 0 (got {})",
                crate::cli::shown(w)
            ),
            None => Ok(default),
        }
    };
    let settings = ArmSettings {
        points: args.points.max(2 * elements),
        elements,
        start: config("--start", "start", &args.start)?,
        target: config("--target", "target", &args.target)?,
        effort_weight: weight("--effort-weight", args.effort_weight, 1.0)?,
        acceleration_weight: weight(
            "--acceleration-weight",
            args.acceleration_weight,
            bf_problem::arm::DEFAULT_ACCELERATION_WEIGHT,
        )?,
        duration: match args.duration {
            Some(t) if (MIN_DURATION..=MAX_DURATION).contains(&t) => Some(t),
            Some(t) => {
                bail_usage!(
                    "--duration must be in [{MIN_DURATION}, {MAX_DURATION}] s (got {})",
                    crate::cli::shown(t)
                )
            }
            None => None,
        },
        torque_hull: match args.torque_hull {
            Some(m) if m <= MAX_ELEVATION => m,
            Some(m) => bail_usage!("--torque-hull must be in 0..={MAX_ELEVATION} (got {m})"),
            None => bf_problem::arm::DEFAULT_TORQUE_HULL,
        },
        max_iter: args.max_iter,
        print_level: args.print_level,
        ..ArmSettings::default()
    };
    let mut out = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    if let Some(n) = opts.fail_at_write {
        out.inject_fault_at_write(n);
    }
    if scene.ball.is_some() {
        crate::errln!(
            "note: {}: the ball of scene `{}` is ignored by {REACH_ARM} (the arm moves freely)",
            path.display(),
            scene.name
        );
    }
    crate::errln!(
        "optimize: {REACH_ARM} on scene `{}` from {} ({nq} joints), node functions on \
         interpreted graphs (no node kernels are emitted for arms)",
        scene.name,
        path.display()
    );
    // The arm's node functions are interpreted: a long chain takes minutes, which the spinner
    // (on a terminal) shows are being spent.
    let pb = super::iteration_spinner(REACH_ARM);
    pb.set_message(format!(
        "solving on {} elements of {} points, then re-integrating (the mesh doubled until it \
         verifies) ...",
        settings.elements, settings.points
    ));
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    let solved = solve_verified(
        &scene,
        &settings,
        args.verify_rtol,
        args.verify_refinements
            .unwrap_or(crate::pipeline::arm::ARM_MESH_DOUBLINGS),
        &text,
        &params,
    );
    pb.finish_and_clear();
    let mut attempts = solved.with_context(|| {
        // The cost's weights enter every value the solver computes: a weight given on the
        // command line is named beside the scene, which alone would take the blame for an
        // objective that overflows.
        let given: Vec<String> = [
            ("--effort-weight", args.effort_weight),
            ("--acceleration-weight", args.acceleration_weight),
        ]
        .into_iter()
        .filter_map(|(opt, w)| w.map(|w| format!("{opt} {}", crate::cli::shown(w))))
        .collect();
        if given.is_empty() {
            format!("--scene {}", path.display())
        } else {
            format!("--scene {} with {}", path.display(), given.join(", "))
        }
    })?;
    for a in &attempts {
        let v = a.solution.verification.as_ref();
        crate::outln!(
            "mesh {} elements, {} points: {}, objective {:.6e}, re-integration defect {}",
            a.elements,
            a.points,
            crate::names::name(&a.solution.status),
            a.solution.objective,
            v.map_or("not checked".into(), |v| format!("{:.3e}", v.max_defect))
        )?;
    }
    let sol = attempts
        .pop()
        .map(|a| a.solution)
        .ok_or_else(|| anyhow::anyhow!("internal: no {REACH_ARM} solve"))?;
    if let Some((field, v)) = first_non_finite_arm(&sol) {
        bail!(
            "the solution of {REACH_ARM} has a non-finite {field} ({v}); nothing was written to {}",
            args.out.display()
        );
    }
    for f in ["solution.json", "torques.csv", "trajectory.csv"] {
        out.file(f)?;
    }
    write_arm_solution(&sol, out.path())
        .map_err(|e| anyhow::anyhow!(out.rename_in(&crate::errors::chain(&e))))?;
    let failure = failure_of(&sol);
    out.commit(match &failure {
        None => Outcome::Success,
        Some(f) => Outcome::Failed(f),
    })?;
    crate::outln!(
        "{REACH_ARM}: {} after {} iterations in {:.2} s; objective {:.6e}, duration {:.4} s",
        crate::names::name(&sol.status),
        sol.iterations,
        sol.solve_seconds,
        sol.objective,
        sol.duration
    )?;
    crate::outln!("start  {:?}\ntarget {:?}", sol.start, sol.target)?;
    // The state points too: the dense grid can fall between them where the torque peaks.
    let peak: Vec<f64> = (0..nq)
        .map(|i| {
            (sol.dense.tau.iter().chain(&sol.nodes.tau))
                .map(|t| t[i].abs())
                .fold(0.0, f64::max)
        })
        .collect();
    let limits: Vec<String> = sol
        .tau_max
        .iter()
        .map(|l| l.map_or("none".to_string(), |l| l.to_string()))
        .collect();
    crate::outln!(
        "max |tau| per joint {peak:?}, tau_max [{}]",
        limits.join(", ")
    )?;
    crate::outln!(
        "constraint violation {:.2e}, dual infeasibility {:.2e}",
        sol.constraint_violation,
        sol.dual_infeasibility
    )?;
    if let Some(v) = &sol.verification {
        crate::outln!(
            "verified: {} (element re-integration defect {:.3e}, tolerance {:e}; open-loop \
             replay from the start ends {:.3e} from the target)",
            if crate::pipeline::arm::is_verified(&sol) {
                "yes"
            } else {
                "NO"
            },
            v.max_defect,
            VERIFIED_DEFECT,
            v.open_loop_end_error
        )?;
    } else {
        crate::outln!("verified: not checked (--verify-rtol 0: no re-integration)")?;
    }
    crate::outln!(
        "wrote {}/solution.json, torques.csv and trajectory.csv{}",
        args.out.display(),
        if failure.is_none() {
            ""
        } else {
            " (marked FAILED)"
        }
    )?;
    if !sol.status.is_success()
        && let Some(h) =
            super::gravity_hint(&scene, &[("start", &sol.start), ("target", &sol.target)])
    {
        crate::outln!("{h}")?;
    }
    if let Some(f) = failure {
        bail!("{f}");
    }
    Ok(())
}
