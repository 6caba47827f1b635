//! `ball-finger optimize --problem NAME ...`: one multiphase optimal-control problem of the
//! problem library (paper Sect. 4.1, 6.1) transcribed by collocation (Sect. 4.2) and solved by
//! the in-house interior-point solver. Writes `solution.json` (status, objective φ = c₁/c₂
//! (eq. 60), phase durations, trajectories) and `torques.csv` (the format `simulate --torques`
//! reads).

use crate::cli::OptimizeArgs;
use crate::study::SolutionIo;
use crate::study::refine::{self, RefineOptions, RefineRound};
use crate::study::solution_io::write_solution;
use crate::study::strategy::{self, StageRecord, Strategy};
use crate::study::verify::verify;
use anyhow::{Context, Result, anyhow, bail};
use bf_optim::ipm::Status;
use bf_optim::ocp::problem::Scheme;
use bf_problem::{BuiltProblem, COT_MAX_PERIOD, OcpSolution, Problem, ProblemSettings};
use indicatif::{ProgressBar, ProgressStyle};

/// Parse `--scheme`: `lg` or `radau` (hp elements from `elements`).
pub fn parse_scheme(text: &str, elements: usize) -> Result<Scheme> {
    match text {
        "lg" => Ok(Scheme::Lg),
        "radau" if elements >= 1 => Ok(Scheme::Radau { elements }),
        "radau" => bail!("--elements must be at least 1"),
        other => bail!("--scheme: unknown scheme {other:?}; use `lg` or `radau`"),
    }
}

/// Parse `--problem`.
pub fn parse_problem(text: &str) -> Result<Problem> {
    text.parse().map_err(|e| anyhow!("--problem: {e}"))
}

/// Build the problem settings from the command line.
pub fn settings_from_args(args: &OptimizeArgs) -> Result<ProblemSettings> {
    parse_problem(&args.problem)?;
    if args.points < 2 {
        bail!("--points must be at least 2 (got {})", args.points);
    }
    if !(args.epsilon.is_finite() && args.epsilon > 0.0) {
        bail!(
            "--epsilon must be a finite positive number (got {})",
            args.epsilon
        );
    }
    if let Some(dc) = args.dual_regularization
        && !(dc.is_finite() && dc > 0.0 && dc <= 1e-4)
    {
        bail!("--dual-regularization must be in (0, 1e-4] (got {dc})");
    }
    let warm_start = match &args.warm_start {
        Some(path) => Some(
            OcpSolution::read_json(path)
                .with_context(|| format!("--warm-start {}", path.display()))?,
        ),
        None => None,
    };
    Ok(ProblemSettings {
        points: args.points,
        scheme: parse_scheme(&args.scheme, args.elements)?,
        epsilon: Some(args.epsilon),
        warm_start,
        max_iter: args.max_iter,
        print_level: args.print_level,
        dual_regularization: args.dual_regularization,
        ..ProblemSettings::default()
    })
}

/// A progress spinner that shows the interior-point iteration log line.
pub fn iteration_spinner(label: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {prefix} {elapsed:>4} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    pb.set_prefix(label.to_string());
    pb
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
        other => bail!(
            "--strategy: unknown strategy {other:?}; use `direct`, `continuation` or `multistart`"
        ),
    }
}

/// Solve with `strategy` behind a progress spinner that shows each finished stage.
pub fn solve_with_progress(
    problem: Problem,
    settings: ProblemSettings,
    strategy: Strategy,
) -> Result<(BuiltProblem, OcpSolution)> {
    let pb = iteration_spinner(problem.name());
    pb.set_message(format!("{strategy} ..."));
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    let done = std::sync::atomic::AtomicUsize::new(0);
    let show = |r: &StageRecord| {
        let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        pb.set_message(format!(
            "{strategy}: {k} solves done; last: chain {} {} -> {:?}, J {:.4e}, T {:.3} s",
            r.chain, r.stage, r.status, r.objective, r.period
        ));
    };
    let res = strategy::solve_with_strategy(problem, &settings, strategy, Some(&show))
        .with_context(|| format!("solving {problem}"));
    pb.finish_and_clear();
    res
}

/// Refine the mesh of `sol` (warm-started from it) until the error estimate is ≤ `tol`; prints
/// each round. Returns the final mesh's problem and solution ([`refine::refine_solution`]).
pub fn refine_with_progress(
    problem: Problem,
    settings: &ProblemSettings,
    sol: OcpSolution,
    tol: f64,
    rounds: usize,
) -> Result<(BuiltProblem, OcpSolution)> {
    let opts = RefineOptions {
        tol,
        max_rounds: rounds,
        ..RefineOptions::default()
    };
    println!("mesh refinement to {tol:e}:");
    println!("  round  points/phase        objective      max error  status        iter  time(s)");
    let mut show = |r: &RefineRound| {
        println!(
            "  {:5}  {:<18}  {:>13.8e}  {:>9.2e}  {:<12}  {:>4}  {:>7.2}",
            r.round,
            format!("{:?}", r.points),
            r.objective,
            r.max_error,
            format!("{:?}", r.status),
            r.iterations,
            r.seconds
        );
    };
    let (built, out) = refine::refine_solution(problem, settings, sol, &opts, Some(&mut show))
        .with_context(|| format!("refining the mesh of {problem}"))?;
    if let Some(r) = &out.refinement {
        println!("  {}", r.stop_reason);
    }
    Ok((built, out))
}

/// Re-integrate every phase with the optimal torques and store the defects in `sol` (printed);
/// a failure to verify is reported, not fatal: the solution itself is still written.
pub fn attach_verification(problem: &BuiltProblem, sol: &mut OcpSolution, rtol: f64) {
    match verify(problem, sol, rtol) {
        Ok(v) => {
            println!("{}", v.summary().trim_end());
            if !v.passes(1e-3) {
                println!(
                    "note: an end-of-phase defect above 1e-3 means the open-loop replay of these \
                     torques drifts from the collocated trajectory (unstable or long phases, or \
                     a coarse mesh: try --refine 1e-4)"
                );
            }
            sol.verification = Some(v);
        }
        Err(e) => eprintln!("warning: trajectory verification failed: {e}"),
    }
}

/// Run `optimize`.
pub fn run(args: &OptimizeArgs) -> Result<()> {
    let name = parse_problem(&args.problem)?;
    let settings = settings_from_args(args)?;
    if let Some(scene) = &args.scene {
        let (s, _) = super::load_scene(scene)?;
        let expected = name.scene();
        if s.name != expected {
            bail!(
                "--scene {}: problem {} is defined on the built-in scene `{expected}` \
                 (got scene `{}`); other scenes are not supported by the problem library yet",
                scene.display(),
                args.problem,
                s.name
            );
        }
    }
    let strategy = match &args.strategy {
        Some(text) => parse_strategy(text, args.starts, args.seed)?,
        None if settings.scheme == Scheme::Lg => Strategy::Direct,
        None => Strategy::default(),
    };
    if let Some(tol) = args.refine {
        if !(tol.is_finite() && tol > 0.0) {
            bail!("--refine must be a finite positive tolerance (got {tol})");
        }
        if settings.scheme == Scheme::Lg {
            bail!("--refine needs --scheme radau (mesh refinement splits Radau elements)");
        }
    }
    if !(args.verify_rtol == 0.0 || (args.verify_rtol > 0.0 && args.verify_rtol <= 0.1)) {
        bail!(
            "--verify-rtol must be 0 (skip) or in (0, 0.1] (got {})",
            args.verify_rtol
        );
    }
    let (mut problem, mut sol) = solve_with_progress(name, settings.clone(), strategy)?;
    if let Some(rep) = &sol.strategy {
        print!("{}", rep.table());
    }
    if let Some(tol) = args.refine {
        (problem, sol) = refine_with_progress(name, &settings, sol, tol, args.refine_rounds)?;
    }
    if args.verify_rtol > 0.0 {
        attach_verification(&problem, &mut sol, args.verify_rtol);
    }
    write_solution(&sol, &args.out)?;
    println!(
        "{}: {:?} after {} iterations in {:.2} s; objective {:.6e} (c1 {:.6e}, c2 {:.6e})",
        sol.problem, sol.status, sol.iterations, sol.solve_seconds, sol.objective, sol.c1, sol.c2
    );
    println!(
        "period {:.4} s, phase durations {:?}, mean omega {:?}",
        sol.period, sol.phase_durations, sol.mean_omega
    );
    println!(
        "constraint violation {:.2e}, dual infeasibility {:.2e}",
        sol.constraint_violation, sol.dual_infeasibility
    );
    if sol.problem.starts_with("periodic-cot") {
        println!(
            "note: the COT period is bounded by {} s (COT lets the finger rest at no cost)",
            COT_MAX_PERIOD
        );
    }
    println!("wrote {}/solution.json and torques.csv", args.out.display());
    // A failed solve was already retried with 3e-8 (`study::solve`); an Acceptable one was
    // not.
    if sol.status == Status::Acceptable
        && args.scheme == "radau"
        && args.dual_regularization.is_none()
    {
        println!(
            "hint: Radau meshes finer than the default can stall with the default KKT \
             regularization; try --dual-regularization 3e-8 (optim/README.md)"
        );
    }
    if !sol.status.is_success() {
        bail!("the solver did not converge ({:?})", sol.status);
    }
    Ok(())
}
