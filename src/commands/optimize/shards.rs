//! `ball-finger optimize merge DIR…`: the output sets of the shards of one multi-start
//! (`optimize --shard`) merged into one: the best verified candidate by the unsharded rule
//! ([`search::select`]) and the stage records of every shard, written as one output set like
//! an unsharded solve.

use super::{
    OUTPUT_DIR, commit_solution, failure_of, hop_settings, print_verification, print_wrote,
};
use crate::cli::Inputs as _;
use crate::cli::MergeArgs;
use crate::errors::bail_usage;
use crate::pipeline::SolutionIo;
use crate::pipeline::search::{self, Candidate, Search, VerifyPolicy};
use crate::pipeline::solve::{recompute_at_own_point, settings_of, violation_allowed};
use crate::pipeline::strategy::{Shard, StageRecord, Strategy};
use anyhow::{Context, Result, bail};
use bf_optim::ocp::Scheme;
use bf_output::OutputDir;
use bf_problem::solution::records::SearchSettings;
use bf_problem::{OcpSolution, ProblemSettings};
use std::path::Path;

/// The candidates of one `--shard` output set: (start index, solution), by file name.
/// Each candidate's stated objective is checked against its own trajectory
/// ([`check_own_objective`]).
fn read_candidates(dir: &Path) -> Result<Vec<(usize, std::path::PathBuf, OcpSolution)>> {
    let mut names: Vec<(usize, std::path::PathBuf)> = Vec::new();
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("optimize merge: {}", dir.display()))?;
    for e in entries {
        let e = e.with_context(|| format!("optimize merge: {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
        // Each candidate's internals file sits beside it (read with it).
        if name.ends_with("-internals.json") {
            continue;
        }
        if let Some(k) = name
            .strip_prefix("candidate-")
            .and_then(|r| r.strip_suffix(".json"))
        {
            let k: usize = k.parse().with_context(|| {
                format!(
                    "optimize merge: {}: not a candidate file name",
                    e.path().display()
                )
            })?;
            names.push((k, e.path()));
        }
    }
    names.sort();
    names
        .into_iter()
        .map(|(k, path)| {
            let sol = OcpSolution::read_json(&path).context("optimize merge")?;
            check_own_objective(&path, &sol)?;
            Ok((k, path, sol))
        })
        .collect()
}

/// What every file of one multi-start shares (the shards' `solution.json` and candidates):
/// (quantity, value as shown). The scene text is compared apart ([`check_same_run`]).
fn run_identity(sol: &OcpSolution) -> [(&'static str, String); 10] {
    [
        ("problem", sol.problem.clone()),
        ("scene", sol.scene.clone()),
        (
            "runtime parameters",
            if sol.scene_params.is_empty() {
                "none".to_string()
            } else {
                sol.scene_params
                    .iter()
                    .map(|(n, v)| format!("{n}={v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        ),
        ("impact law", sol.impact_law.name().to_string()),
        ("cone margin", format!("{:e}", sol.cone_margin)),
        ("impulse cone", sol.impulse_cone.to_string()),
        ("torque margin", format!("{:e}", sol.torque_margin)),
        (
            "approach clearance",
            format!("{:e}", sol.approach_clearance),
        ),
        (
            "mesh",
            match sol.scheme {
                Scheme::Lg => format!("Legendre–Gauss, {} points per phase", sol.points),
                Scheme::Radau { elements } => format!(
                    "hp-Radau, {} points per phase over {elements} elements",
                    sol.points
                ),
            },
        ),
        ("epsilon", format!("{:e}", sol.epsilon)),
    ]
}

/// Errors naming both files and the quantity unless `sol` (read from `path`) was solved on the
/// problem, impact law, plan margins, scene (its file text), runtime parameters, mesh and ε of `first`,
/// searched with the same [`SearchSettings`] (where either records them) and (where both were
/// verified) verified with the same tolerances.
fn check_same_run(
    first: &(std::path::PathBuf, OcpSolution),
    path: &Path,
    sol: &OcpSolution,
) -> Result<()> {
    let (fpath, fsol) = first;
    for ((what, a), (_, b)) in run_identity(fsol).into_iter().zip(run_identity(sol)) {
        if a != b {
            bail!(
                "optimize merge: {} has {what} {b}, {} has {a}: merge only the shards of one run",
                path.display(),
                fpath.display()
            );
        }
    }
    // The verification settings, where both files were verified: shards re-integrated with
    // other tolerances do not compete on one scale.
    if let (Some(a), Some(b)) = (&fsol.verification, &sol.verification)
        && (a.rtol != b.rtol || a.atol != b.atol)
    {
        bail!(
            "optimize merge: {} was verified with rtol {:e}, atol {:e}, {} with rtol {:e}, \
             atol {:e} (--verify-rtol): merge only the shards of one run",
            path.display(),
            b.rtol,
            b.atol,
            fpath.display(),
            a.rtol,
            a.atol
        );
    }
    match (&fsol.search_settings, &sol.search_settings) {
        (Some(a), Some(b)) => {
            if let Some((what, va, vb)) = a.first_difference(b) {
                bail!(
                    "optimize merge: {} was searched with {what} {vb}, {} with {what} {va}: \
                     merge only the shards of one run",
                    path.display(),
                    fpath.display()
                );
            }
        }
        (None, None) => {}
        (a, _) => {
            let (with, without) = if a.is_some() {
                (fpath.as_path(), path)
            } else {
                (path, fpath.as_path())
            };
            bail!(
                "optimize merge: {} records no search settings (--min-stick, \
                 --verify-refinements, …; written before they were recorded), {} does: they \
                 cannot be compared; re-run the older shard",
                without.display(),
                with.display()
            );
        }
    }
    if fsol.scene_toml != sol.scene_toml {
        let line = fsol
            .scene_toml
            .lines()
            .zip(sol.scene_toml.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| {
                fsol.scene_toml
                    .lines()
                    .count()
                    .min(sol.scene_toml.lines().count())
            })
            + 1;
        bail!(
            "optimize merge: {} was solved on another scene file text than {} (first \
             difference at line {line}): merge only the shards of one run",
            path.display(),
            fpath.display()
        );
    }
    Ok(())
}

/// Errors naming the file unless the objective, cost states and period that `sol` (read
/// from `path`) states are those of its own trajectory: recomputed at its primal point on its
/// problem rebuilt from the file ([`recompute_at_own_point`]), and unless that point lies
/// within the constraint violation its stated status allows ([`violation_allowed`]). A file
/// edited to claim a better objective or a converged solve is refused before the choice
/// trusts it.
fn check_own_objective(path: &Path, sol: &OcpSolution) -> Result<()> {
    let own = recompute_at_own_point(sol).with_context(|| {
        format!(
            "optimize merge: {}: cannot recompute its objective from its own trajectory",
            path.display()
        )
    })?;
    let same = |a: f64, b: f64| {
        a == b || (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
    };
    for (what, stated, computed) in [
        ("objective", sol.objective, own.objective),
        ("c1", sol.c1, own.c1),
        ("c2", sol.c2, own.c2),
        ("period", sol.period, own.period),
    ] {
        if !same(stated, computed) {
            bail!(
                "optimize merge: {}: its {what} {stated:e} is not its own trajectory's \
                 ({computed:e}, recomputed at its primal point): the file was altered or \
                 belongs to another run",
                path.display()
            );
        }
    }
    let (_, settings) = settings_of(sol)
        .with_context(|| format!("optimize merge: {}: its problem", path.display()))?;
    // The solver tests its slacks' residual, with their bounds relaxed by 1e-8 of each bound,
    // so the point's own violation may exceed the status's tolerance by a little: allowed
    // here up to 1e-3 of that tolerance plus 1e-6 (a judgement; genuine candidates sit near
    // 1e-9, an edited status is off by orders of magnitude).
    if let Some(allowed) = violation_allowed(&settings, sol.status)
        && (own.constraint_violation.is_nan()
            || own.constraint_violation > allowed * (1.0 + 1e-3) + 1e-6)
    {
        bail!(
            "optimize merge: {}: its status {} is not its own point's: the constraints are \
             violated by {:e} there, beyond the {allowed:e} that status allows: the file was \
             altered or belongs to another run",
            path.display(),
            crate::names::name(&sol.status),
            own.constraint_violation
        );
    }
    Ok(())
}

/// Run `optimize merge DIR…`: the best verified candidate of the shards ([`search::select`],
/// the unsharded multi-start's rule) with the stage records of every shard.
pub fn merge(args: &MergeArgs) -> Result<()> {
    // Checked before any work; the hops that run are the shards' own (see below).
    hop_settings(args.hops, args.hop_scale)?;
    let out = OutputDir::create(&args.out, &OUTPUT_DIR, &args.inputs())?;
    let mut cands: Vec<(usize, OcpSolution)> = Vec::new();
    let mut records: Vec<StageRecord> = Vec::new();
    // Directories without candidate files, which the error names when none has any.
    let mut without: Vec<String> = Vec::new();
    let mut head: Option<(std::path::PathBuf, String, Strategy)> = None;
    let mut first: Option<(std::path::PathBuf, OcpSolution)> = None;
    let mut first_candidate: Option<(std::path::PathBuf, OcpSolution)> = None;
    let mut seconds: f64 = 0.0;
    for dir in &args.dirs {
        let path = dir.join("solution.json");
        let sol = OcpSolution::read_json(&path).context("optimize merge")?;
        let Some(rep) = &sol.strategy else {
            bail!(
                "optimize merge: {} has no strategy record (not written by optimize --shard)",
                path.display()
            );
        };
        match &head {
            None => head = Some((path.clone(), sol.problem.clone(), rep.strategy)),
            Some((first, p, st)) if *p != sol.problem || *st != rep.strategy => bail!(
                "optimize merge: {} is {} with {}, {} {p} with {st}",
                path.display(),
                sol.problem,
                rep.strategy,
                first.display()
            ),
            Some(_) => {}
        }
        // A shard of several records its own starts only; the chains of a whole search's hops
        // and reshapes are numbered after them. A whole search writes no candidate files,
        // which a shard always does (`--shard 1/1` runs the whole search and keeps them).
        let found = read_candidates(dir)?;
        if let Strategy::Multistart { starts, .. } = rep.strategy
            && found.is_empty()
            && let Some(r) = rep.records.iter().find(|r| r.chain >= starts)
        {
            bail!(
                "optimize merge: {}: not the output of optimize --shard (no candidate files, and \
                 its search ran chain {} ({}) beyond its {starts} starts: a whole search, whose \
                 optimum is already chosen)",
                path.display(),
                r.chain,
                r.stage
            );
        }
        match &first {
            None => first = Some((path.clone(), sol.clone())),
            Some(f) => check_same_run(f, &path, &sol)?,
        }
        seconds = seconds.max(rep.seconds);
        for r in &rep.records {
            if records
                .iter()
                .any(|o| o.chain == r.chain && o.stage == r.stage)
            {
                bail!(
                    "optimize merge: start {} ({}) appears in two directories, the last {}",
                    r.chain,
                    r.stage,
                    dir.display()
                );
            }
        }
        records.extend(rep.records.iter().cloned());
        if found.is_empty() {
            crate::outln!("note: {} has no candidate files", dir.display())?;
            without.push(dir.display().to_string());
        }
        // Candidates may be on the sampling's coarse mesh: they are compared with each other.
        for (k, cpath, c) in found {
            match &first_candidate {
                Some(f) => check_same_run(f, &cpath, &c)?,
                None => first_candidate = Some((cpath.clone(), c.clone())),
            }
            cands.push((k, c));
        }
    }
    let Some((_, problem, strategy)) = head else {
        bail!("optimize merge: no directories given");
    };
    // A shard re-solved its own best coarse optima on the problem's mesh for its own output;
    // the merge re-solves the best of the union, as the unsharded run does.
    records.retain(|r| !search::is_promotion(&r.stage));
    // So does the search after the starts (hops, reshapes, polish), which only a `--shard
    // 1/1` ran: the merge continues from the starts, as the unsharded run does.
    if let Strategy::Multistart { starts, .. } = strategy {
        records.retain(|r| r.chain < starts);
    }
    // Stable: the stages of a chain keep their order.
    records.sort_by_key(|r| r.chain);
    if let Strategy::Multistart { starts, .. } = strategy {
        let mut seen: Vec<usize> = records.iter().map(|r| r.chain).collect();
        seen.dedup();
        if seen.len() != starts {
            // Shards may be merged as they finish; the result is then not the whole search's.
            crate::errln!(
                "warning: the shards ran {} of the {starts} starts of {strategy}: the merged \
                 optimum is that of those starts, not the whole search's (merge every shard \
                 for that)",
                seen.len()
            );
        }
    }
    if cands.is_empty() {
        bail!(
            "optimize merge: the directories hold no candidate of {problem}: {} {} no \
             candidate files (a whole search's output, which is no shard's, or shards whose \
             starts all failed)",
            without.join(", "),
            if without.len() == 1 { "has" } else { "have" }
        );
    }
    let ncands = cands.len();
    // The global search's exploitation runs here, on the union of the shards' candidates,
    // exactly as after an unsharded multi-start (the problems rebuilt from the files).
    // The shards' own solutions are on the problem's mesh; their candidates may be on the
    // coarse mesh of the sampling.
    let Some((_, full)) = first.as_ref() else {
        bail!("optimize merge: no directories given");
    };
    let (name, settings) =
        settings_of(full).with_context(|| format!("optimize merge: the solution of {problem}"))?;
    let mut found = Search {
        strategy,
        shard: Shard::WHOLE,
        candidates: Vec::new(),
        sampled: Vec::new(),
        records,
        refinements: Vec::new(),
        seconds,
        basin_hits: None,
    };
    for (k, c) in cands {
        let s = ProblemSettings {
            points: c.points,
            scheme: c.scheme,
            mesh: c.refinement.as_ref().map(|r| r.mesh.clone()),
            ..settings.clone()
        };
        let built = crate::pipeline::build(name, &s)
            .with_context(|| format!("optimize merge: rebuilding the problem of start {k}"))?;
        found.candidates.push(Candidate {
            index: k,
            problem: Some(built),
            solution: c,
        });
    }
    // The verification's tolerance of the shards' runs: their own solutions are verified on
    // the problem's mesh; the candidates of a coarse sampling carry no verification.
    let rtol = first
        .iter()
        .map(|(_, s)| s)
        .chain(found.candidates.iter().map(|c| &c.solution))
        .find_map(|s| s.verification.as_ref().map(|v| v.rtol))
        .unwrap_or(0.0);
    let policy = VerifyPolicy {
        rtol,
        execution: super::execution_for(name, &settings),
        ..VerifyPolicy::default()
    };
    // As `optimize`: without `--hops` the global search runs for the periodic problems only.
    let (given_hops, hops) = merge_hops(args, full)?;
    let policy = match hops.filter(|_| given_hops || name.is_periodic()) {
        Some(h) => policy.global(h),
        None => policy,
    };
    let t0 = std::time::Instant::now();
    search::verify_again(&mut found.candidates, &policy);
    found.candidates = search::representatives(std::mem::take(&mut found.candidates));
    found.candidates.sort_by_key(|c| c.index);
    found.explore(name, &settings, &policy, None);
    let promote = policy.coarse.map(|c| c.promote).filter(|_| {
        found
            .candidates
            .iter()
            .any(|c| c.solution.points < settings.points)
    });
    found.promote_and_refine(name, &settings, &policy, promote, None);
    found.fall_back_to_the_starts(name, &settings, &policy, None)?;
    found.polish_the_winner(name, &settings, &policy, None);
    found.seconds = seconds + t0.elapsed().as_secs_f64();
    let (built, mut sol) = found.best()?;
    // The merged solution records the run's scene and settings as the shards' files do
    // (every shard's, checked equal above): a solution re-solved in the merge carries none.
    sol.scene_toml.clone_from(&full.scene_toml);
    sol.scene_params.clone_from(&full.scene_params);
    sol.search_settings.clone_from(&full.search_settings);
    if let Some(p) = &built {
        sol.active_bounds = Some(crate::pipeline::bounds::active_bounds(&p.ocp, &sol));
    }
    let k = sol.strategy.as_ref().and_then(|r| r.chosen).unwrap_or(0);
    let rep = sol
        .strategy
        .take()
        .ok_or_else(|| anyhow::anyhow!("internal: the merged search has no record"))?;
    crate::io::print_out(&rep.table())?;
    crate::io::print_out(&rep.refinement_lines())?;
    sol.strategy = Some(rep);
    print_verification(&sol)?;
    commit_solution(&sol, out)?;
    crate::outln!(
        "{}: merged {} candidates; chose chain {k}: {}, objective {:.6e}, period {:.4} s",
        problem,
        ncands,
        crate::names::name(&sol.status),
        sol.objective,
        sol.period
    )?;
    if let Some(line) = sol
        .strategy
        .as_ref()
        .and_then(crate::pipeline::search::basin_line)
    {
        crate::outln!("{line}")?;
    }
    let failure = failure_of(&sol);
    print_wrote(&args.out, failure.as_deref())?;
    if let Some(f) = failure {
        bail!("{f}");
    }
    Ok(())
}

/// The hops the merge runs, and whether they were given rather than the problem's default:
/// the shards' recorded `--hops` and `--hop-scale` (a merge's own values must equal them, or
/// the merge would run another search than the unsharded one), or the merge's options for
/// shards written before the hops were recorded.
fn merge_hops(
    args: &MergeArgs,
    shard: &OcpSolution,
) -> Result<(bool, Option<crate::pipeline::global::HopSettings>)> {
    let recorded = shard.search_settings.as_ref().filter(|s| s.hops.is_some());
    let Some(rec) = recorded else {
        return Ok((
            args.hops.is_some(),
            hop_settings(args.hops, args.hop_scale)?,
        ));
    };
    let mismatch = |opt: &str, given: String, theirs: String| -> Result<()> {
        bail_usage!(
            "{opt} {given}: the shards searched with {opt} {theirs}, and the merge runs their \
             search; give their value or leave {opt} out"
        )
    };
    if let (Some(a), Some(b)) = (args.hops, rec.hops)
        && a != b
    {
        mismatch("--hops", a.to_string(), b.to_string())?;
    }
    if let Some(a) = args.hop_scale
        && rec.hop_scale != Some(a)
    {
        mismatch(
            "--hop-scale",
            a.to_string(),
            rec.hop_scale
                .map_or_else(|| "none (no hops)".to_string(), |b| b.to_string()),
        )?;
    }
    Ok((true, hop_settings(rec.hops, rec.hop_scale)?))
}

/// The record of the settings a search of `optimize` ran with (`solution.json`'s
/// `search_settings`), which [`check_same_run`] compares across shards.
pub(super) fn search_settings(settings: &ProblemSettings, policy: &VerifyPolicy) -> SearchSettings {
    SearchSettings {
        min_stick: settings.min_stick,
        stick_continuation: policy.stick_continuation,
        verify_rtol: policy.rtol,
        verify_refinements: policy.refine_attempts,
        refine_rounds: policy.refine_rounds,
        refine_tol: policy.refine_tol,
        max_points: policy.max_points,
        clusters: policy.clusters,
        max_iter: settings.max_iter,
        dual_regularization: settings.dual_regularization,
        kkt_residual_ratio: settings.kkt_residual_ratio,
        curvature_extrapolation: settings.curvature_extrapolation,
        extrapolate_every_barrier: settings.extrapolate_every_barrier,
        proximal_weight: settings.proximal_weight,
        hops: Some(policy.hops.as_ref().map_or(0, |h| h.budget)),
        hop_scale: policy.hops.as_ref().map(|h| h.scale),
    }
}
