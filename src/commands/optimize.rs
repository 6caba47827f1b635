//! `ball-finger optimize --problem NAME ...`: one multiphase optimal-control problem of the
//! problem library (paper Sect. 4.1, 6.1) transcribed by collocation (Sect. 4.2) and solved by
//! the in-house interior-point solver. Writes `solution.json` (status, objective φ = c₁/c₂
//! (eq. 60), phase durations, trajectories) and `torques.csv` (the format `simulate --torques`
//! reads).

use crate::cli::OptimizeArgs;
use anyhow::{Context, Result, bail};
use bf_optim::ocp::problem::Scheme;
use bf_optim::problems::{self, OcpSolution, ProblemSettings};
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

/// Build the problem settings from the command line.
pub fn settings_from_args(args: &OptimizeArgs) -> Result<ProblemSettings> {
    if !problems::PROBLEMS.contains(&args.problem.as_str()) {
        bail!(
            "--problem: unknown problem {:?}; known problems: {}",
            args.problem,
            problems::PROBLEMS.join(", ")
        );
    }
    if args.points < 2 {
        bail!("--points must be at least 2 (got {})", args.points);
    }
    if !(args.epsilon.is_finite() && args.epsilon > 0.0) {
        bail!(
            "--epsilon must be a finite positive number (got {})",
            args.epsilon
        );
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

/// Solve with a progress spinner.
pub fn solve_with_progress(name: &str, settings: ProblemSettings) -> Result<OcpSolution> {
    let built = problems::build(name, &settings).with_context(|| format!("building {name}"))?;
    let pb = iteration_spinner(name);
    let mut cb = |it: &bf_optim::ipm::IterationInfo| {
        pb.set_message(format!(
            "iter {:4} obj {:+.6e} inf_pr {:.1e} inf_du {:.1e} lg(mu) {:+.1}",
            it.iter,
            it.objective,
            it.inf_pr,
            it.inf_du,
            it.mu.log10()
        ));
        pb.tick();
        true
    };
    let sol = problems::solve(&built, Some(&mut cb)).with_context(|| format!("solving {name}"))?;
    pb.finish_and_clear();
    Ok(sol)
}

/// Write `solution.json` and `torques.csv` into `dir` (atomically, by the library writers).
pub fn write_solution(sol: &OcpSolution, dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    sol.write_json(&dir.join("solution.json"))?;
    sol.write_torques_csv(&dir.join("torques.csv"))?;
    Ok(())
}

/// Run `optimize`.
pub fn run(args: &OptimizeArgs) -> Result<()> {
    let settings = settings_from_args(args)?;
    if let Some(scene) = &args.scene {
        let (s, _) = super::load_scene(scene)?;
        let expected = if args.problem.ends_with("-human") {
            "human"
        } else {
            "paper"
        };
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
    let sol = solve_with_progress(&args.problem, settings)?;
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
            problems::COT_MAX_PERIOD
        );
    }
    println!("wrote {}/solution.json and torques.csv", args.out.display());
    if !sol.status.is_success() {
        bail!("the solver did not converge ({:?})", sol.status);
    }
    Ok(())
}
