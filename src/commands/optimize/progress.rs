//! Solves of the problem library behind a progress display on stderr: the strategy search
//! (`pipeline::search`: every end point re-integrated, verified optima preferred) and the mesh
//! refinement (`pipeline::refine`), each finished stage or round shown as it ends.

use crate::pipeline::refine::{self, RefineRound, RefineSettings};
use crate::pipeline::search::{self, Search, VerifyPolicy};
use crate::pipeline::strategy::{Shard, StageRecord, Strategy};
use anyhow::{Context, Result};
use bf_problem::{BuiltProblem, OcpSolution, Problem, ProblemSettings};
use indicatif::{ProgressBar, ProgressStyle};

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

/// Solve with `strategy` behind a progress spinner that shows each finished stage; every end
/// point is re-integrated (and a plan for the plant run in closed loop, [`super::execution_for`]),
/// a verified one is preferred and an unverified optimum that beats
/// the best verified one is hp-refined until it verifies ([`search_with_progress`] without the
/// global search, as `optimize --hops 0`); what still fails is flagged in the tables.
pub fn solve_with_progress(
    name: Problem,
    settings: ProblemSettings,
    strategy: Strategy,
) -> Result<(BuiltProblem, OcpSolution)> {
    let policy = VerifyPolicy {
        execution: super::execution_for(name, &settings),
        ..VerifyPolicy::default()
    };
    best_found(name, settings, strategy, &policy)
}

/// [`solve_with_progress`] with `optimize`'s default global search (coarse sampling,
/// reshaping, basin hopping and polishing, [`search::DEFAULT_HOPS`]): what `paper --search`
/// runs, and what produced the optima `paper` presents otherwise
/// ([`crate::paper::stored`]).
pub fn solve_globally_with_progress(
    name: Problem,
    settings: ProblemSettings,
    strategy: Strategy,
) -> Result<(BuiltProblem, OcpSolution)> {
    let policy = VerifyPolicy {
        execution: super::execution_for(name, &settings),
        ..VerifyPolicy::default()
    }
    .global(search::DEFAULT_HOPS);
    best_found(name, settings, strategy, &policy)
}

/// The chosen solution of [`search_with_progress`] with its problem.
fn best_found(
    name: Problem,
    settings: ProblemSettings,
    strategy: Strategy,
    policy: &VerifyPolicy,
) -> Result<(BuiltProblem, OcpSolution)> {
    let record = super::shards::search_settings(&settings, policy);
    let compiled_scene = settings.scene.is_none();
    let found = search_with_progress(name, settings, strategy, Shard::WHOLE, policy)?;
    let (p, mut sol) = found.best()?;
    let p = p.ok_or_else(|| anyhow::anyhow!("internal: the chosen {name} solve has no problem"))?;
    // `paper`'s solution files are those of `optimize`; a `--scene` file's text is its
    // caller's to record.
    let scene = if compiled_scene {
        (super::compiled_scene_text(name)?, Vec::new())
    } else {
        (sol.scene_toml.clone(), sol.scene_params.clone())
    };
    super::record_run(&mut sol, &p, &scene, &record);
    Ok((p, sol))
}

/// [`search::search`] behind a progress spinner that shows each finished stage.
pub fn search_with_progress(
    name: Problem,
    settings: ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    policy: &VerifyPolicy,
) -> Result<Search> {
    let pb = iteration_spinner(name.name());
    pb.set_message(format!("{strategy} ..."));
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    let done = std::sync::atomic::AtomicUsize::new(0);
    // Without a terminal the spinner is hidden; each finished solve is then one line.
    let lines = !std::io::IsTerminal::is_terminal(&std::io::stderr());
    let show = |r: &StageRecord| {
        let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        let msg = format!(
            "{strategy}: {k} solves done; last: chain {} {} -> {}, J {:.4e}, T {:.3} s",
            r.chain,
            r.stage,
            crate::names::name(&r.status),
            r.objective,
            r.period
        );
        if lines {
            crate::errln!("{name}: {msg}");
        }
        pb.set_message(msg);
    };
    let res = search::search(name, &settings, strategy, shard, policy, Some(&show))
        .with_context(|| format!("solving {name}"));
    pb.finish_and_clear();
    res
}

/// Refine the mesh of `sol` (warm-started from it) until the error estimate is ≤ `tol`; prints
/// each round. Returns the final mesh's problem and solution, which keeps `sol`'s strategy
/// record and gains the refinement record.
pub fn refine_with_progress(
    name: Problem,
    settings: &ProblemSettings,
    sol: OcpSolution,
    tol: f64,
    rounds: usize,
) -> Result<(BuiltProblem, OcpSolution)> {
    let opts = RefineSettings {
        tol,
        max_rounds: rounds,
        ..RefineSettings::default()
    };
    crate::outln!("mesh refinement to {tol:e}:")?;
    crate::outln!(
        "  round  points/phase        objective      max error  status        iter  time(s)"
    )?;
    // The callback cannot return an error: a failed write is kept and reported afterwards.
    let mut write_error = None;
    let mut show = |r: &RefineRound| {
        let line = crate::outln!(
            "  {:5}  {:<18}  {:>13.8e}  {:>9.2e}  {:<12}  {:>4}  {:>7.2}{}",
            r.round,
            format!("{:?}", r.points),
            r.objective,
            r.max_error,
            crate::names::name(&r.status),
            r.iterations,
            r.seconds,
            if r.solved_again {
                "  (left its optimum: solved again from a closer start)"
            } else {
                ""
            }
        );
        if let Err(e) = line {
            write_error.get_or_insert(e);
        }
    };
    let (built, out) = refine::refine_solution(name, settings, sol, &opts, None, Some(&mut show))
        .with_context(|| format!("refining the mesh of {name}"))?;
    if let Some(e) = write_error {
        return Err(e);
    }
    if let Some(r) = &out.refinement {
        crate::outln!("  {}", r.stop_reason)?;
    }
    Ok((built, out))
}
