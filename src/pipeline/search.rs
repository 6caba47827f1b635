//! The default search of `optimize` and the paper report ([`search`]): the chains of a
//! [`Strategy`] (for `periodic-qc` a continuation in the stick phase's lower bound, first
//! ≥ [`STICK_CONTINUATION`], then relaxed to the problem's bound), every end point re-integrated
//! ([`verify`]), one [`Candidate`] per distinct optimum (objectives within [`CLUSTER_RTOL`]),
//! hp refinement of the unverified optima that beat the best verified one (lowest objective
//! first, one after the other until one verifies), driven by their element-wise
//! re-integration defects, until these are at most
//! [`super::verify::VERIFIED_DEFECT`] ([`VerifyPolicy`]), and the choice [`select`]: verified first, then the lowest objective, then the lowest start
//! index. Results are collected in index order and every choice depends on values only, so the
//! result is bitwise the same with any number of threads; a [`Shard`] runs every m-th start
//! and [`select`] over the shards' candidates gives the unsharded choice.

use std::time::Instant;

use bf_problem::{BuiltProblem, OcpSolution, Problem, ProblemSettings};
use rayon::prelude::*;

use super::error::PipelineError;
use super::refine::{self, RefineCriterion, RefineSettings};
use super::strategy::{
    Progress, Shard, StageRecord, Strategy, StrategyReport, effective, failed_record, record,
    run_chains,
};
use super::verify::{VERIFIED_DEFECT, is_verified, verify};

/// Relative objective difference within which two end points are one local optimum.
pub const CLUSTER_RTOL: f64 = 1e-6;

/// First stick-phase lower bound (s) of the stick continuation
/// ([`VerifyPolicy::stick_continuation`]).
pub const STICK_CONTINUATION: f64 = 0.1;

/// How a search verifies its candidates ([`search`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifyPolicy {
    /// DOPRI5 relative tolerance of the re-integration ([`verify`]); 0 skips verification
    /// (and with it the refinement).
    pub rtol: f64,
    /// Tolerance on the element-wise re-integration defects (state units) of the first hp
    /// refinement of an unverified optimum ([`RefineCriterion::Reintegration`]); each further
    /// attempt divides it by 10.
    pub refine_tol: f64,
    /// hp refinements (each up to `refine_rounds` rounds) of one unverified optimum at most.
    pub refine_attempts: usize,
    /// Rounds of one refinement.
    pub refine_rounds: usize,
    /// Collocation points per phase at most ([`VERIFY_MAX_POINTS`] by default).
    pub max_points: usize,
    /// Distinct unverified optima (better than the best verified one) refined at most: they are
    /// refined one after the other, lowest objective first, until one verifies, so a spurious
    /// optimum that cannot be verified (e.g. a collapsed phase) does not hide the next one.
    /// Default 6: the budget costs refinements only when the better candidates fail, and with
    /// 3 the `periodic-cot` search of seed 8 ended unverified (its fifth candidate verifies;
    /// BENCHMARKS.md, 2026-11-26).
    pub clusters: usize,
    /// Continuation in the stick phase's lower bound (`periodic-qc` only): every chain first
    /// runs with the stick phase at least this long (s), then one warm-started stage relaxes
    /// the bound to the problem's ([`ProblemSettings::min_stick`]). With the short default
    /// bound most cold starts end in "taps" on it; from a stick phase of real duration the
    /// relaxation reaches better optima with an interior stick duration. `None`: no
    /// continuation.
    pub stick_continuation: Option<f64>,
}

/// hp refinements of one unverified optimum by default ([`VerifyPolicy::refine_attempts`],
/// `optimize --verify-refinements`): to element defects of 1e-4, 1e-5, …, 1e-8. A chain of
/// refinements does not converge monotonically (each re-solve on the refined mesh may move
/// within or out of the basin): the best candidate of seed 8 of the `periodic-cot` search
/// verifies at its fourth (defects 6.2e-2, 3.1e-1, 1.5e-2, 9.3e-8), where three sent the
/// search on to its fifth-best candidate, at a higher objective and more cost
/// (BENCHMARKS.md, "Five refinements per candidate (2026-11-26)"). Costs nothing where the
/// third verifies.
pub const VERIFY_REFINEMENTS: usize = 5;

/// Collocation points per phase that the refinements of an unverified optimum may reach by
/// default ([`VerifyPolicy::max_points`]). The `periodic-cot` optima have long free phases
/// whose element-wise defects need many short elements: with 400, three
/// of the default searches over seeds 0–19 stopped the refinement of their best candidate
/// on the limit (defects 5.1e-2, 6.2e-3, 2.1e-4) and reported a candidate 3–4× worse; with
/// 800 those candidates verify, and each of those searches takes less time, not more
/// (BENCHMARKS.md, "A point limit of 800 (2026-11-26)").
pub const VERIFY_MAX_POINTS: usize = 800;

impl Default for VerifyPolicy {
    fn default() -> Self {
        VerifyPolicy {
            rtol: 1e-10,
            refine_tol: VERIFIED_DEFECT,
            refine_attempts: VERIFY_REFINEMENTS,
            refine_rounds: 4,
            max_points: VERIFY_MAX_POINTS,
            clusters: 6,
            stick_continuation: Some(STICK_CONTINUATION),
        }
    }
}

/// One end point of a search: the final solution of chain/start `index`.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Global chain/start index.
    pub index: usize,
    /// Its transcribed problem (`None` for a candidate read from a file).
    pub problem: Option<BuiltProblem>,
    /// The solution, with its [`OcpSolution::verification`] when verified.
    pub solution: OcpSolution,
}

/// The result of [`search`]: one candidate per distinct local optimum (verified, refined
/// where needed) and the record of every solve.
#[derive(Debug, Clone)]
pub struct Search {
    /// The strategy that ran.
    pub strategy: Strategy,
    /// The shard that ran.
    pub shard: Shard,
    /// One candidate per distinct optimum (its lowest-index start), in index order.
    pub candidates: Vec<Candidate>,
    /// Every stage of every chain/start, in index order.
    pub records: Vec<StageRecord>,
    /// The hp refinements of unverified optima (one record per refinement, its chain the
    /// start index), in index order; their iterations count in the solution's total, not in
    /// [`StrategyReport::iterations`].
    pub refinements: Vec<StageRecord>,
    /// Wall time (s).
    pub seconds: f64,
}

/// Rank class of a solution: 0 verified, 1 successful but not verified, 2 failed.
fn class(sol: &OcpSolution) -> u8 {
    if !sol.status.is_success() || !sol.objective.is_finite() {
        2
    } else if is_verified(sol) {
        0
    } else {
        1
    }
}

fn same_optimum(a: &OcpSolution, b: &OcpSolution) -> bool {
    (a.objective - b.objective).abs() <= CLUSTER_RTOL * a.objective.abs().max(b.objective.abs())
        && (a.period - b.period).abs() <= 1e-3 * a.period.abs().max(b.period.abs())
}

/// The candidate a search returns (its position in `cands`, given as (start index,
/// solution)): the best class (verified, then successful, then failed), in it the lowest
/// objective, and among the end points within [`CLUSTER_RTOL`] of that objective (one optimum,
/// reached from several starts) the lowest start index. The rule depends on the set only, not
/// on its order, so shards merged give the unsharded choice.
pub fn select(cands: &[(usize, &OcpSolution)]) -> Option<usize> {
    let best_class = cands.iter().map(|(_, s)| class(s)).min()?;
    let in_class = || {
        cands
            .iter()
            .enumerate()
            .filter(|(_, (_, s))| class(s) == best_class)
    };
    let jmin = in_class()
        .map(|(_, (_, s))| s.objective)
        .filter(|j| j.is_finite())
        .fold(f64::INFINITY, f64::min);
    in_class()
        .filter(|(_, (_, s))| !jmin.is_finite() || s.objective <= jmin + CLUSTER_RTOL * jmin.abs())
        .min_by_key(|(_, (k, _))| *k)
        .map(|(i, _)| i)
}

/// One candidate per distinct optimum: candidates sorted by (class, objective, index) are
/// grouped greedily (a group takes every following end point of its class within
/// [`same_optimum`] of its first); each group is represented by its lowest start index.
fn representatives(cands: Vec<Candidate>) -> Vec<Candidate> {
    let mut order: Vec<usize> = (0..cands.len()).collect();
    let key = |c: &Candidate| {
        let j = c.solution.objective;
        (
            class(&c.solution),
            if j.is_nan() { f64::INFINITY } else { j },
        )
    };
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&cands[a]), key(&cands[b]));
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(cands[a].index.cmp(&cands[b].index))
    });
    let mut keep = vec![false; cands.len()];
    let mut i = 0;
    while i < order.len() {
        let first = &cands[order[i]];
        let mut j = i + 1;
        while j < order.len() {
            let c = &cands[order[j]];
            if class(&c.solution) != class(&first.solution)
                || !same_optimum(&first.solution, &c.solution)
            {
                break;
            }
            j += 1;
        }
        let rep = order[i..j]
            .iter()
            .copied()
            .min_by_key(|&o| cands[o].index)
            .unwrap_or(order[i]);
        keep[rep] = true;
        i = j;
    }
    cands
        .into_iter()
        .zip(keep)
        .filter_map(|(c, k)| k.then_some(c))
        .collect()
}

/// Re-integrates the candidate's solution ([`verify`]) and stores the result in it.
fn attach_verification(c: &mut Candidate, rtol: f64) {
    if let Some(p) = &c.problem {
        c.solution.verification = verify(p, &c.solution, rtol).ok();
    }
}

/// hp-refines an unverified candidate (Radau only) until it is verified or the policy's
/// attempts are spent: attempt a refines from the previous attempt's mesh, each round
/// splitting or raising the degree of the elements whose element-wise re-integration defect
/// exceeds `refine_tol`·10⁻ᵃ, and re-integrates. An attempt that could not refine its mesh
/// at all (point limit, non-finite defects) ends the attempts. Returns the last successful
/// refinement (or the candidate unchanged) and a record per attempt.
fn refine_until_verified(
    problem: Problem,
    settings: &ProblemSettings,
    mut cur: Candidate,
    policy: &VerifyPolicy,
) -> (Candidate, Vec<StageRecord>) {
    let mut records = Vec::new();
    let mut tol = policy.refine_tol;
    for _ in 0..policy.refine_attempts {
        if is_verified(&cur.solution) {
            break;
        }
        let Some(p) = cur.problem.as_ref() else { break };
        let Ok(mesh) = refine::current_mesh(p) else {
            break;
        };
        let t0 = Instant::now();
        let s = ProblemSettings {
            mesh: Some(mesh),
            ..settings.clone()
        };
        let opts = RefineSettings {
            tol,
            criterion: RefineCriterion::Reintegration { rtol: policy.rtol },
            max_rounds: policy.refine_rounds,
            max_points: policy.max_points,
            ..RefineSettings::default()
        };
        // One significant digit: the tolerance is divided by 10 per attempt, which leaves
        // rounding digits (1.0000000000000002e-6) that say nothing.
        let label = format!("refine start {} to {tol:.0e}", cur.index);
        let iters0 = cur.solution.iterations;
        match refine::refine_solution(problem, &s, cur.solution.clone(), &opts, None) {
            Ok((b, sol)) => {
                let mut next = Candidate {
                    index: cur.index,
                    problem: Some(b),
                    solution: sol,
                };
                attach_verification(&mut next, policy.rtol);
                let defect = next
                    .solution
                    .verification
                    .as_ref()
                    .map_or(f64::NAN, |v| v.max_defect);
                let mut r = record(
                    cur.index,
                    format!("{label} (defect {defect:.1e})"),
                    &next.solution,
                    t0,
                );
                r.iterations = next.solution.iterations.saturating_sub(iters0);
                records.push(r);
                if !next.solution.status.is_success() {
                    break;
                }
                // A refinement that stopped after solving its starting mesh only, without
                // meeting its tolerance, was stopped by the point limit or by non-finite
                // defects: a tighter tolerance marks a superset of the elements and stops on the
                // same limit, so a further attempt would only solve the same mesh again. (One
                // whose refined mesh failed to solve also returns its starting mesh, but a
                // tighter tolerance refines differently and may succeed: that one goes on.)
                let stuck = next
                    .solution
                    .refinement
                    .as_ref()
                    .is_some_and(|r| !r.converged && r.history.len() == 1);
                cur = next;
                if stuck {
                    break;
                }
            }
            Err(e) => {
                records.push(failed_record(cur.index, label, &e, t0));
                break;
            }
        }
        tol *= 0.1;
    }
    (cur, records)
}

/// Applies `refine` to the items of `order` one after the other until `verified` holds for a
/// result, at most `max` of them; returns each item refined with its result. Sequential on
/// purpose: the next candidate is refined only if the previous one did not verify, which
/// depends on values only, so the outcome does not depend on the number of threads.
fn refine_in_order<I: Copy, T>(
    order: &[I],
    max: usize,
    mut refine: impl FnMut(&I) -> T,
    verified: impl Fn(&T) -> bool,
) -> Vec<(I, T)> {
    let mut out = Vec::new();
    for i in order.iter().take(max) {
        let r = refine(i);
        let done = verified(&r);
        out.push((*i, r));
        if done {
            break;
        }
    }
    out
}

/// A search for the best verified optimum: runs the chains of `strategy` in `shard`
/// (in parallel, results in index order), re-integrates every end point, keeps one
/// candidate per distinct optimum, and hp-refines the unverified optima that beat the best
/// verified one, lowest objective first, until one verifies ([`refine_until_verified`], at
/// most `policy.clusters` of them). Every
/// decision depends on the computed values only, never on thread scheduling, so the result is
/// the same bit for bit with any number of threads. [`Search::best`] then picks by [`select`].
pub fn search(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    policy: &VerifyPolicy,
    progress: Progress<'_>,
) -> Result<Search, PipelineError> {
    let t0 = Instant::now();
    let strategy = effective(settings, strategy);
    let results = run_chains(
        problem,
        settings,
        strategy,
        shard,
        policy.stick_continuation,
        progress,
    )?;
    let records: Vec<StageRecord> = results.iter().flat_map(|(_, (r, _))| r.clone()).collect();
    let mut refinements = Vec::new();
    let mut cands: Vec<Candidate> = results
        .into_iter()
        .filter_map(|(k, (_, r))| {
            r.map(|(p, s)| Candidate {
                index: k,
                problem: Some(p),
                solution: s,
            })
        })
        .collect();
    if policy.rtol > 0.0 {
        cands
            .par_iter_mut()
            .for_each(|c| attach_verification(c, policy.rtol));
    }
    let mut cands = representatives(cands);
    if policy.rtol > 0.0 {
        let best_verified = cands
            .iter()
            .filter(|c| class(&c.solution) == 0)
            .map(|c| c.solution.objective)
            .fold(f64::INFINITY, f64::min);
        let mut todo: Vec<usize> = (0..cands.len())
            .filter(|&i| {
                let s = &cands[i].solution;
                class(s) == 1 && s.objective < best_verified
            })
            .collect();
        todo.sort_by(|&a, &b| {
            cands[a]
                .solution
                .objective
                .total_cmp(&cands[b].solution.objective)
                .then(cands[a].index.cmp(&cands[b].index))
        });
        let refined = refine_in_order(
            &todo,
            policy.clusters,
            |&i| refine_until_verified(problem, settings, cands[i].clone(), policy),
            |(c, _)| is_verified(&c.solution),
        );
        for (i, (c, recs)) in refined {
            cands[i] = c;
            refinements.extend(recs);
        }
    }
    cands.sort_by_key(|c| c.index);
    Ok(Search {
        strategy,
        shard,
        candidates: cands,
        records,
        refinements,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

impl Search {
    /// The chosen candidate ([`select`]) with its [`OcpSolution::strategy`] record (every
    /// stage, total iterations and time; the refinements are not in it, the chosen
    /// candidate's own is in [`OcpSolution::refinement`]); its problem is `None` only for candidates read
    /// from files. Errors when no chain produced a solution.
    pub fn best(mut self) -> Result<(Option<BuiltProblem>, OcpSolution), PipelineError> {
        let views: Vec<(usize, &OcpSolution)> = self
            .candidates
            .iter()
            .map(|c| (c.index, &c.solution))
            .collect();
        let Some(i) = select(&views) else {
            let stages = self
                .records
                .iter()
                .map(|r| format!("{}: {}", r.chain, r.stage))
                .collect();
            return Err(PipelineError::AllChainsFailed {
                strategy: self.strategy,
                stages,
            });
        };
        let c = self.candidates.swap_remove(i);
        let mut sol = c.solution;
        let iterations = self.records.iter().map(|r| r.iterations).sum();
        sol.iterations = iterations + self.refinements.iter().map(|r| r.iterations).sum::<usize>();
        sol.solve_seconds = self.seconds;
        sol.strategy = Some(StrategyReport {
            strategy: self.strategy,
            records: self.records,
            chosen: sol.status.is_success().then_some(c.index),
            iterations,
            seconds: self.seconds,
        });
        Ok((c.problem, sol))
    }
}

#[cfg(test)]
mod tests {
    use super::refine_in_order;

    /// The first candidate that verifies ends the refinements; a failed one passes on to the
    /// next; at most `max` are refined.
    #[test]
    fn refinement_moves_on_until_a_candidate_verifies() {
        let verifies = [false, false, true, true];
        let run = |max: usize| {
            let mut calls = Vec::new();
            let out = refine_in_order(
                &[0usize, 1, 2, 3],
                max,
                |&i| {
                    calls.push(i);
                    verifies[i]
                },
                |&v| v,
            );
            (calls, out)
        };
        let (calls, out) = run(10);
        assert_eq!(calls, [0, 1, 2]);
        assert_eq!(out, [(0, false), (1, false), (2, true)]);
        let (calls, _) = run(2);
        assert_eq!(calls, [0, 1]);
        let (calls, out) = run(0);
        assert!(calls.is_empty() && out.is_empty());
    }
}
