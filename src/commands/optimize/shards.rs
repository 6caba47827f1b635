//! `ball-finger optimize merge DIR…`: the output sets of the shards of one multi-start
//! (`optimize --shard`) merged into one: the best verified candidate by the unsharded rule
//! ([`search::select`]) and the stage records of every shard, written as one output set like
//! an unsharded solve.

use super::{OUTPUT_DIR, commit_solution, failure_of, print_verification, print_wrote};
use crate::cli::MergeArgs;
use crate::study::SolutionIo;
use crate::study::search;
use crate::study::strategy::{StageRecord, Strategy, StrategyReport};
use anyhow::{Context, Result, bail};
use bf_output::OutputDir;
use bf_problem::OcpSolution;
use std::path::Path;

/// The candidates of one `--shard` output set: (start index, solution), by file name.
fn read_candidates(dir: &Path) -> Result<Vec<(usize, OcpSolution)>> {
    let mut names: Vec<(usize, std::path::PathBuf)> = Vec::new();
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("optimize merge: {}", dir.display()))?;
    for e in entries {
        let e = e.with_context(|| format!("optimize merge: {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
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
            let sol = OcpSolution::read_json(&path)
                .with_context(|| format!("optimize merge: {}", path.display()))?;
            Ok((k, sol))
        })
        .collect()
}

/// Run `optimize merge DIR…`: the best verified candidate of the shards ([`search::select`],
/// the unsharded multi-start's rule) with the stage records of every shard.
pub fn merge(args: &MergeArgs) -> Result<()> {
    let out = OutputDir::create(&args.out, &OUTPUT_DIR)?;
    let mut cands: Vec<(usize, OcpSolution)> = Vec::new();
    let mut records: Vec<StageRecord> = Vec::new();
    let mut head: Option<(String, Strategy)> = None;
    let mut seconds: f64 = 0.0;
    for dir in &args.dirs {
        let path = dir.join("solution.json");
        let sol = OcpSolution::read_json(&path)
            .with_context(|| format!("optimize merge: {}", path.display()))?;
        let Some(rep) = &sol.strategy else {
            bail!(
                "optimize merge: {} has no strategy record (not written by optimize --shard)",
                path.display()
            );
        };
        match &head {
            None => head = Some((sol.problem.clone(), rep.strategy)),
            Some((p, st)) if *p != sol.problem || *st != rep.strategy => bail!(
                "optimize merge: {} is {} with {}, the first directory {p} with {st}",
                path.display(),
                sol.problem,
                rep.strategy
            ),
            Some(_) => {}
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
        let found = read_candidates(dir)?;
        if found.is_empty() {
            crate::outln!("note: {} has no candidate files", dir.display())?;
        }
        cands.extend(found);
    }
    let Some((problem, strategy)) = head else {
        bail!("optimize merge: no directories given");
    };
    // Stable: the stages of a chain keep their order.
    records.sort_by_key(|r| r.chain);
    if let Strategy::Multistart { starts, .. } = strategy {
        let mut seen: Vec<usize> = records.iter().map(|r| r.chain).collect();
        seen.dedup();
        if seen.len() != starts {
            crate::outln!(
                "note: the shards ran {} of the {starts} starts of {strategy}",
                seen.len()
            )?;
        }
    }
    let views: Vec<(usize, &OcpSolution)> = cands.iter().map(|(k, s)| (*k, s)).collect();
    let Some(i) = search::select(&views) else {
        bail!("optimize merge: the directories hold no candidate of {problem}");
    };
    let (k, mut sol) = cands.swap_remove(i);
    let iterations = records.iter().map(|r| r.iterations).sum();
    sol.iterations = iterations;
    sol.solve_seconds = seconds;
    let rep = StrategyReport {
        strategy,
        records,
        chosen: sol.status.is_success().then_some(k),
        iterations,
        seconds,
    };
    crate::io::print_out(&rep.table())?;
    sol.strategy = Some(rep);
    print_verification(&sol)?;
    commit_solution(&sol, out)?;
    crate::outln!(
        "{}: merged {} candidates; chose start {k}: {}, objective {:.6e}, period {:.4} s",
        problem,
        cands.len() + 1,
        crate::names::name(&sol.status),
        sol.objective,
        sol.period
    )?;
    print_wrote(&args.out, &sol)?;
    if let Some(f) = failure_of(&sol) {
        bail!("{f}");
    }
    Ok(())
}
