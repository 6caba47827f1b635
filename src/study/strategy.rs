//! Solve strategies: good optima of the non-convex periodic problems without hand-holding
//! (paper Sect. 7 suggests warm-starting from runs of simplified problems).
//!
//! * [`Strategy::Direct`]: one interior-point solve from the docs/parameters.md guess (q ≡ q⁰,
//!   t_f⁽ⁱ⁾ = i), with the geometric guess as fallback ([`super::solve::solve`]).
//! * [`Strategy::Continuation`] ([`Strategy::default`]; what [`default_strategy`] runs for
//!   every Radau problem except `periodic-qc`): a homotopy in the constraints and the smoothing.
//!   For the periodic problems (eq. 60 ratio objectives) the period T = Σ t_f⁽ⁱ⁾ is the
//!   dominant non-convexity — the QC optimum at T ≈ 2.6 s that a cold start finds is 2–5×
//!   worse than optima at T ≈ 0.7–1.9 s. Each chain k
//!   1. solves with the period fixed to T_k (a grid, [`period_grid`]) and the saturation
//!      smoothed to ε₀ = [`EPS_FACTOR`]·ε (eq. 59: a larger ε rounds the contact geometry),
//!      from the docs/parameters.md joint guess with durations T_k/3;
//!   2. frees the period (warm start with primal and dual variables: every stage has the same
//!      NLP layout, the period row only changes its bounds);
//!   3. tightens ε₀ → ε, warm-started.
//!
//!   The chains run in parallel (rayon) and the best successful end point wins. Problems
//!   without a period run the ε-homotopy alone (steps 3 from ε₀ = 10ε).
//! * [`Strategy::Multistart`]: N guesses around the default (joint angles q⁰ ± 0.6 rad
//!   uniform, phase durations log-uniform in [0.05, 1.6] s; start 0 is the default guess
//!   itself, so the result is never worse than `Direct`), solved in parallel; the best
//!   successful solution wins. [`default_strategy`] of `periodic-qc`: [`DEFAULT_STARTS`]
//!   starts with seed [`DEFAULT_SEED`].
//!
//! [`solve_with_strategy`] returns the best end point as solved. [`search`] (what `optimize`
//! and the paper report run) runs the chains of `periodic-qc` as a continuation in the stick
//! phase's lower bound (first ≥ [`STICK_CONTINUATION`], then relaxed to the problem's bound,
//! warm-started: from the short default bound most cold starts end in "taps" on it, while the
//! relaxed optima of a real stick phase are better), re-integrates every end point
//! ([`verify`]), keeps one candidate
//! per distinct optimum (objectives within [`CLUSTER_RTOL`]), hp-refines the best unverified
//! optima that beat the best verified one until their re-integration defect is at most
//! [`super::verify::VERIFIED_DEFECT`] ([`VerifyPolicy`]), and [`Search::best`] picks by
//! [`select`]: verified first, then the lowest objective, then the lowest start index. The
//! chains run in parallel, but their results are collected in index order and every choice
//! depends on values only, so the result is bitwise the same with any number of threads. A
//! [`Shard`] runs every m-th start, and [`select`] over the shards' candidates gives the
//! unsharded choice (`optimize --shard k/m`, `optimize merge`).
//!
//! Every stage/start (and refinement) is recorded ([`StageRecord`]: status, objective, period,
//! iterations, seconds) in [`StrategyReport`], stored in `solution.json`.

use std::time::Instant;

use bf_optim::ipm::Status;
use bf_problem::catalogue::Q_GUESS;
use bf_problem::{BuiltProblem, GuessKind, OcpSolution, Problem, ProblemSettings, StartGuess};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::build;
use super::error::StudyError;
use super::refine::{self, RefineOptions};
use super::solve::{solve, solve_warm};
use super::verify::{is_verified, verify};
use bf_optim::ocp::Scheme;
pub use bf_problem::solution::records::{StageRecord, Strategy, StrategyReport};

/// ε₀ / ε of the first continuation stage of the periodic problems.
pub const EPS_FACTOR: f64 = 5.0;

/// Progress reporter: called after every stage (from worker threads).
pub type Progress<'a> = Option<&'a (dyn Fn(&StageRecord) + Sync)>;

/// Fixed-period values of the continuation's first stage (s): around the QC optima for
/// `periodic-qc`, spread up to [`bf_problem::COT_MAX_PERIOD`] for COT.
pub fn period_grid(problem: Problem) -> Vec<f64> {
    if problem == Problem::PeriodicQc {
        vec![0.5, 0.75, 1.0, 1.5, 2.0, 3.0]
    } else {
        vec![1.0, 2.0, 3.0, 5.0, 7.5, 10.0]
    }
}

fn record(chain: usize, stage: String, sol: &OcpSolution, t0: Instant) -> StageRecord {
    StageRecord {
        chain,
        stage,
        status: sol.status,
        objective: sol.objective,
        period: sol.period,
        iterations: sol.iterations,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

fn failed_record(chain: usize, stage: String, e: &StudyError, t0: Instant) -> StageRecord {
    StageRecord {
        chain,
        stage: format!("{stage} ({})", crate::errors::chain(e)),
        status: Status::ErrorInStepComputation,
        objective: f64::NAN,
        period: f64::NAN,
        iterations: 0,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// The outcome of one chain/start: its records and final problem and solution (if any).
type ChainResult = (Vec<StageRecord>, Option<(BuiltProblem, OcpSolution)>);

/// Runs `stages` (settings of each stage; stage k > 0 warm-starts from stage k − 1, whose NLP
/// layout must be the same) as chain `chain`; stops at the first stage that errors.
fn run_chain(
    problem: Problem,
    chain: usize,
    stages: Vec<(String, ProblemSettings)>,
    mut prebuilt: Option<BuiltProblem>,
    progress: Progress<'_>,
) -> ChainResult {
    let mut records = Vec::new();
    let mut last: Option<(BuiltProblem, OcpSolution)> = None;
    for (label, settings) in stages {
        let t0 = Instant::now();
        // The first stage may come built already (`prebuilt` has that stage's settings).
        let built = match prebuilt.take() {
            Some(p) => Ok(p),
            None => build(problem, &settings),
        };
        let res = built.and_then(|p| {
            let sol = match last.as_ref().and_then(|(_, s)| s.nlp_warm.as_ref()) {
                Some(w) => solve_warm(&p, w, None)?,
                None => solve(&p, None)?,
            };
            Ok((p, sol))
        });
        match res {
            Ok((p, sol)) => {
                let r = record(chain, label, &sol, t0);
                if let Some(f) = progress {
                    f(&r);
                }
                records.push(r);
                last = Some((p, sol));
            }
            Err(e) => {
                let r = failed_record(chain, label, &e, t0);
                if let Some(f) = progress {
                    f(&r);
                }
                records.push(r);
                return (records, None);
            }
        }
    }
    (records, last)
}

/// The index of the best result: successful before failed, then lower objective (ties by
/// index, so the choice is deterministic).
fn best_index(results: &[ChainResult]) -> Option<(usize, bool)> {
    let mut best: Option<(usize, bool, f64)> = None;
    for (k, (_, r)) in results.iter().enumerate() {
        let Some((_, sol)) = r else { continue };
        let ok = sol.status.is_success() && sol.objective.is_finite();
        let obj = if sol.objective.is_finite() {
            sol.objective
        } else {
            f64::INFINITY
        };
        let better = match best {
            None => true,
            Some((_, bok, bobj)) => (ok && !bok) || (ok == bok && obj < bobj),
        };
        if better {
            best = Some((k, ok, obj));
        }
    }
    best.map(|(k, ok, _)| (k, ok))
}

/// Random start `k` of a multi-start (k = 0: the default guess).
pub fn random_start(k: usize, seed: u64, nq: usize, nphases: usize) -> StartGuess {
    if k == 0 {
        return StartGuess {
            q: (0..nq).map(|i| Q_GUESS[i % 3]).collect(),
            durations: vec![1.0; nphases],
        };
    }
    // One stream per start, so that start k is the same whatever N is.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(k as u64);
    StartGuess {
        q: (0..nq)
            .map(|i| Q_GUESS[i % 3] + rng.random_range(-0.6..0.6))
            .collect(),
        durations: (0..nphases)
            .map(|_| 10f64.powf(rng.random_range(-1.3..0.2)))
            .collect(),
    }
}

/// A contiguous part of a multi-start: shard `index` (0-based) of `count` runs the starts k
/// with k mod `count` = `index` (`optimize --shard k/m` is shard k − 1 of m). The starts keep
/// their global indices, so the union of the shards' candidates is the unsharded set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 0-based shard index, < `count`.
    pub index: usize,
    /// Number of shards, ≥ 1.
    pub count: usize,
}

impl Shard {
    /// All starts in one shard.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `k/m` (1 ≤ k ≤ m, as Slurm's `SLURM_ARRAY_TASK_ID` counts from 1 with
    /// `--array=1-m`).
    pub fn parse(text: &str) -> Result<Shard, String> {
        let bad = || format!("--shard {text:?}: expected k/m with 1 <= k <= m, e.g. 2/4");
        let (k, m) = text.split_once('/').ok_or_else(bad)?;
        let k: usize = k.trim().parse().map_err(|_| bad())?;
        let m: usize = m.trim().parse().map_err(|_| bad())?;
        if k == 0 || m == 0 || k > m {
            return Err(bad());
        }
        Ok(Shard {
            index: k - 1,
            count: m,
        })
    }

    /// Whether start `k` belongs to this shard.
    pub fn contains(self, k: usize) -> bool {
        k % self.count == self.index
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index + 1, self.count)
    }
}

/// The stages of every chain of `strategy` (index = chain/start index).
fn chains_of(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    target: &BuiltProblem,
) -> Result<Vec<Vec<(String, ProblemSettings)>>, StudyError> {
    let eps = target.epsilon;
    let nq = target.physics.nq;
    let nphases = target.modes.len();
    let periodic = problem.is_periodic();
    Ok(match strategy {
        Strategy::Direct => vec![vec![("direct".into(), settings.clone())]],
        Strategy::Continuation if periodic => {
            let eps0 = EPS_FACTOR * eps;
            period_grid(problem)
                .into_iter()
                .map(|t| {
                    // Every stage carries the period row (its bounds only), so that each
                    // stage warm-starts the next with primal and dual variables.
                    let free_period = ProblemSettings {
                        period_bounds: Some(settings.period_bounds.unwrap_or((0.0, f64::MAX))),
                        ..settings.clone()
                    };
                    let smooth = ProblemSettings {
                        epsilon: Some(eps0),
                        ..free_period.clone()
                    };
                    vec![
                        (
                            format!("sweep T={t}, eps {eps0}"),
                            ProblemSettings {
                                period_bounds: Some((t, t)),
                                start: Some(StartGuess {
                                    q: (0..nq).map(|i| Q_GUESS[i % 3]).collect(),
                                    durations: vec![t / nphases as f64; nphases],
                                }),
                                guess: GuessKind::Paper,
                                ..smooth.clone()
                            },
                        ),
                        (format!("release T, eps {eps0}"), smooth),
                        (format!("eps {eps}"), free_period),
                    ]
                })
                .collect()
        }
        Strategy::Continuation => {
            let eps0 = 10.0 * eps;
            vec![vec![
                (
                    format!("eps {eps0}"),
                    ProblemSettings {
                        epsilon: Some(eps0),
                        ..settings.clone()
                    },
                ),
                (format!("eps {eps}"), settings.clone()),
            ]]
        }
        Strategy::Multistart { starts, seed } => {
            if starts == 0 {
                return Err(StudyError::NoStarts);
            }
            (0..starts)
                .map(|k| {
                    let sg = random_start(k, seed, nq, nphases);
                    vec![(
                        format!("start {k}"),
                        ProblemSettings {
                            start: Some(sg),
                            guess: if k == 0 {
                                settings.guess
                            } else {
                                GuessKind::Paper
                            },
                            ..settings.clone()
                        },
                    )]
                })
                .collect()
        }
    })
}

/// The strategy a warm start leaves: a warm-started solve is one direct solve.
fn effective(settings: &ProblemSettings, strategy: Strategy) -> Strategy {
    if settings.warm_start.is_some() {
        Strategy::Direct
    } else {
        strategy
    }
}

/// Runs the chains of `strategy` that belong to `shard` (all of them for [`Shard::WHOLE`]),
/// in parallel; the results come back in chain order with their global chain indices, so
/// nothing depends on the scheduling of the threads.
fn run_chains(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    stick_continuation: Option<f64>,
    progress: Progress<'_>,
) -> Result<Vec<(usize, ChainResult)>, StudyError> {
    let target = build(problem, settings)?;
    let mut chains = chains_of(problem, settings, strategy, &target)?;
    if let Some(s0) = stick_continuation
        && problem == Problem::PeriodicQc
        && s0 > settings.min_stick
        && strategy != Strategy::Direct
    {
        // Every stage of a chain has the same NLP layout (a duration bound is a bound), so
        // the relaxation warm-starts exactly from the chain's end point.
        for chain in &mut chains {
            for (label, st) in chain.iter_mut() {
                st.min_stick = s0;
                label.push_str(&format!(", stick >= {s0}"));
            }
            let min = settings.min_stick;
            // A relaxation from an optimum converges in tens of iterations or not at all.
            let last = chain.last().map(|(_, st)| ProblemSettings {
                min_stick: min,
                max_iter: st.max_iter.min(RELAX_MAX_ITER),
                ..st.clone()
            });
            if let Some(st) = last {
                chain.push((format!("relax stick >= {min}"), st));
            }
        }
    }
    // `direct` solves the problem built above instead of building it again.
    let mut prebuilt: Vec<Option<BuiltProblem>> = chains.iter().map(|_| None).collect();
    if strategy == Strategy::Direct {
        prebuilt[0] = Some(target);
    }
    Ok(chains
        .into_iter()
        .zip(prebuilt)
        .enumerate()
        .filter(|(k, _)| shard.contains(*k))
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(k, (stages, first))| (k, run_chain(problem, k, stages, first, progress)))
        .collect())
}

/// Solves `problem` with `strategy`. `settings` are the target problem's (ε, mesh, ...;
/// a warm start in them makes every strategy a single warm-started solve). Returns the final
/// stage's problem (for verification and refinement) and solution, whose
/// [`OcpSolution::strategy`] lists every stage.
pub fn solve_with_strategy(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    progress: Progress<'_>,
) -> Result<(BuiltProblem, OcpSolution), StudyError> {
    let t0 = Instant::now();
    let strategy = effective(settings, strategy);
    let results: Vec<ChainResult> =
        run_chains(problem, settings, strategy, Shard::WHOLE, None, progress)?
            .into_iter()
            .map(|(_, r)| r)
            .collect();
    let best = best_index(&results);
    let records: Vec<StageRecord> = results.iter().flat_map(|(r, _)| r.clone()).collect();
    let iterations = records.iter().map(|r| r.iterations).sum();
    let Some((k, ok)) = best else {
        return Err(StudyError::AllChainsFailed {
            strategy,
            stages: records
                .iter()
                .map(|r| format!("{}: {}", r.chain, r.stage))
                .collect(),
        });
    };
    let mut results = results;
    let (p, mut sol) = results
        .swap_remove(k)
        .1
        .ok_or(StudyError::Internal("the chosen chain has no solution"))?;
    sol.iterations = iterations;
    sol.solve_seconds = t0.elapsed().as_secs_f64();
    sol.strategy = Some(StrategyReport {
        strategy,
        records,
        chosen: ok.then_some(k),
        iterations,
        seconds: sol.solve_seconds,
    });
    Ok((p, sol))
}

/// Starts of the default multi-start of the periodic problems ([`default_strategy`]); the
/// budget curve in BENCHMARKS.md shows how the best objective grows with the starts.
pub const DEFAULT_STARTS: usize = 32;

/// Seed of the default multi-start.
pub const DEFAULT_SEED: u64 = 0;

/// The default strategy of `problem` on `scheme`: a seeded multi-start of
/// [`DEFAULT_STARTS`] starts for `periodic-qc` (whose landscape has many local optima: the
/// continuation's best end point is 66 % above the best known optimum, which one start in 32
/// reaches), the continuation for the others (a COT start takes up to 30× a QC one, so 32
/// of them leave any time budget), and one direct solve with Legendre–Gauss (an LG solve
/// takes about 4× a Radau one).
pub fn default_strategy(problem: Problem, scheme: Scheme) -> Strategy {
    match scheme {
        Scheme::Lg => Strategy::Direct,
        Scheme::Radau { .. } if problem == Problem::PeriodicQc => Strategy::Multistart {
            starts: DEFAULT_STARTS,
            seed: DEFAULT_SEED,
        },
        Scheme::Radau { .. } => Strategy::Continuation,
    }
}

/// Relative objective difference within which two end points are one local optimum.
pub const CLUSTER_RTOL: f64 = 1e-6;

/// First stick-phase lower bound (s) of the stick continuation
/// ([`VerifyPolicy::stick_continuation`]).
pub const STICK_CONTINUATION: f64 = 0.1;

/// Iteration limit of the relaxation stage of the stick continuation.
pub const RELAX_MAX_ITER: usize = 200;

/// How a search verifies its candidates ([`search`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifyPolicy {
    /// DOPRI5 relative tolerance of the re-integration ([`verify`]); 0 skips verification
    /// (and with it the refinement).
    pub rtol: f64,
    /// Error-estimate tolerance of the first hp refinement of an unverified optimum; each
    /// further attempt divides it by 10.
    pub refine_tol: f64,
    /// hp refinements (each up to `refine_rounds` rounds) of one unverified optimum at most.
    pub refine_attempts: usize,
    /// Rounds of one refinement.
    pub refine_rounds: usize,
    /// Collocation points per phase at most.
    pub max_points: usize,
    /// Distinct unverified optima (better than the best verified one) refined at most.
    pub clusters: usize,
    /// Continuation in the stick phase's lower bound (`periodic-qc` only): every chain first
    /// runs with the stick phase at least this long (s), then one warm-started stage relaxes
    /// the bound to the problem's ([`ProblemSettings::min_stick`]). With the short default
    /// bound most cold starts end in "taps" on it; from a stick phase of real duration the
    /// relaxation reaches better optima with an interior stick duration. `None`: no
    /// continuation.
    pub stick_continuation: Option<f64>,
}

impl Default for VerifyPolicy {
    fn default() -> Self {
        VerifyPolicy {
            rtol: 1e-10,
            refine_tol: 1e-4,
            refine_attempts: 2,
            refine_rounds: 4,
            max_points: 400,
            clusters: 1,
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
/// attempts are spent: attempt a refines from the previous attempt's mesh to the error
/// estimate `refine_tol`·10⁻ᵃ and re-integrates. Returns the last successful refinement (or
/// the candidate unchanged) and a record per attempt.
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
        let opts = RefineOptions {
            tol,
            max_rounds: policy.refine_rounds,
            max_points: policy.max_points,
            ..RefineOptions::default()
        };
        let label = format!("refine start {} to {tol:e}", cur.index);
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
                cur = next;
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

/// A search for the best verified optimum: runs the chains of `strategy` in `shard`
/// (in parallel, results in index order), re-integrates every end point, keeps one
/// candidate per distinct optimum, and hp-refines the best `policy.clusters` unverified optima
/// that beat the best verified one until they verify ([`refine_until_verified`]). Every
/// decision depends on the computed values only, never on thread scheduling, so the result is
/// the same bit for bit with any number of threads. [`Search::best`] then picks by [`select`].
pub fn search(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    policy: &VerifyPolicy,
    progress: Progress<'_>,
) -> Result<Search, StudyError> {
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
        todo.truncate(policy.clusters);
        let refined: Vec<(usize, (Candidate, Vec<StageRecord>))> = todo
            .into_par_iter()
            .map(|i| {
                (
                    i,
                    refine_until_verified(problem, settings, cands[i].clone(), policy),
                )
            })
            .collect();
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
    pub fn best(mut self) -> Result<(Option<BuiltProblem>, OcpSolution), StudyError> {
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
            return Err(StudyError::AllChainsFailed {
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
