//! Solve strategies: good optima of the non-convex periodic problems without hand-holding
//! (paper Sect. 7 suggests warm-starting from runs of simplified problems).
//!
//! * [`Strategy::Direct`]: one interior-point solve from the docs/parameters.md guess (q ≡ q⁰,
//!   t_f⁽ⁱ⁾ = i), with the geometric guess as fallback ([`super::solve::solve`]).
//! * [`Strategy::Continuation`] ([`Strategy::default`]; what [`default_strategy`] runs for
//!   the Radau problems without a period): a homotopy in the constraints and the smoothing.
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
//! * [`Strategy::Multistart`]: N guesses (phase durations log-uniform in [0.05, 1.6] s; start
//!   0 is the default guess itself, so the result is never worse than `Direct`), solved in
//!   parallel; the best successful solution wins. The joints of a start: for the global
//!   search ([`super::search`]) each revolute joint anywhere in its revolution q⁰ᵢ ± π, cut to
//!   its limits where the scene gives them ([`start_intervals`]), its fallback to the starts
//!   included; for the plain multi-start (`optimize --hops 0`) within
//!   ±[`START_NEIGHBOURHOOD`] of q⁰. [`default_strategy`] of the periodic problems:
//!   [`GLOBAL_STARTS`] starts with seed [`DEFAULT_SEED`] (the global search's sampling;
//!   [`DEFAULT_STARTS`] without it).
//!
//! [`solve_with_strategy`] returns the best end point as solved. For `periodic-qc` the chains
//! can run as a continuation in the stick phase's lower bound (a stage relaxing it to the
//! problem's bound, at most [`RELAX_MAX_ITER`] iterations, warm-started: from the short default
//! bound most cold starts end in "taps" on it, while the relaxed optima of a real stick phase
//! are better). The search that `optimize` and the paper report run on these chains —
//! re-integration, candidates, hp refinement, the choice of the best verified optimum — is
//! [`super::search`]. A [`Shard`] runs every m-th start (`optimize --shard k/m`).
//!
//! Every stage/start (and refinement) is recorded ([`StageRecord`]: status, objective, period,
//! iterations, seconds) in [`StrategyReport`], stored in `solution.json`.

use std::time::Instant;

use bf_codegen::Scene;
use bf_codegen::spec::JointType;
use bf_optim::ipm::Status;
use bf_problem::{BuiltProblem, GuessKind, OcpSolution, Problem, ProblemSettings, StartGuess};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::build;
use super::error::PipelineError;
use super::solve::{solve, solve_warm, warm_start_kind};
use bf_optim::ocp::Scheme;
pub use bf_problem::solution::records::{StageRecord, Strategy, StrategyReport};

/// ε₀ / ε of the first continuation stage of the periodic problems.
pub const EPS_FACTOR: f64 = 5.0;

/// Iteration limit of the relaxation stage of the stick continuation.
pub const RELAX_MAX_ITER: usize = 200;

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

pub(crate) fn record(chain: usize, stage: String, sol: &OcpSolution, t0: Instant) -> StageRecord {
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

pub(crate) fn failed_record(
    chain: usize,
    stage: String,
    e: &PipelineError,
    t0: Instant,
) -> StageRecord {
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
pub(crate) type ChainResult = (Vec<StageRecord>, Option<(BuiltProblem, OcpSolution)>);

/// Runs `stages` (settings of each stage; stage k > 0 warm-starts from stage k − 1, whose NLP
/// layout must be the same) as chain `chain`; stops at the first stage that errors.
pub(crate) fn run_chain(
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

/// Half-width (rad, or m for a prismatic joint) of the neighbourhood of q⁰ that the starts of
/// a plain multi-start draw every joint from ([`random_start`] without intervals), and the
/// global search's starts a prismatic joint ([`start_intervals`]). A plain
/// multi-start keeps the best start as solved, with no moves or hops to carry a start into
/// a better basin, so its starts stay near the default guess: on `periodic-qc` (sticking law)
/// 4 starts within it reach J = 0.0877, while 8 drawn over the revolution end at 0.124.
pub const START_NEIGHBOURHOOD: f64 = 0.6;

/// The interval `[lo, hi]` each joint of a random start is drawn from ([`random_start`]): a
/// revolute joint anywhere in its revolution, q⁰ᵢ ± π, a prismatic one within
/// ±[`START_NEIGHBOURHOOD`] of q⁰ᵢ, each cut to the joint's limits where the scene gives them
/// ([`bf_problem::arm::joint_limits`]; an interval the limits leave empty is q⁰ᵢ alone).
///
/// The whole revolution, not a neighbourhood of q⁰: the starts are the global search's only
/// sampling of the configuration space, and the basins of the periodic problems differ in
/// which joints swing and where the finger meets the ball. The lowest `periodic-cot` plans
/// swing the first joint through about 4.6 rad and touch the ball at q₁ ≈ −1.35 rad; starts
/// within ±0.6 rad of q⁰ (q⁰₁ = 0.1) never reached them on three seeds in ten, which ended
/// at 13× their objective with the first joint held still (decision record 0054).
pub fn start_intervals(scene: &Scene, q0: &[f64]) -> Vec<(f64, f64)> {
    let limits = bf_problem::arm::joint_limits(scene);
    q0.iter()
        .zip(&scene.links)
        .zip(limits)
        .map(|((&q, link), (q_min, q_max))| {
            let half = match link.joint {
                JointType::Prismatic => START_NEIGHBOURHOOD,
                JointType::Revolute => std::f64::consts::PI,
            };
            let (lo, hi) = ((q - half).max(q_min), (q + half).min(q_max));
            if lo < hi { (lo, hi) } else { (q, q) }
        })
        .collect()
}

/// Random start `k` of a multi-start from the default guess's configuration `q0` (the
/// problem's [`BuiltProblem::guess`]`.free`; k = 0: the default guess itself): joint i uniform
/// in `intervals[i]` ([`start_intervals`]; `q0[i]` where none is given), or, without
/// intervals, within ±[`START_NEIGHBOURHOOD`] of `q0[i]` (the draws the plain multi-start has
/// always made, so its optima stay as they were); every phase duration log-uniform in
/// [0.05, 1.6] s.
pub fn random_start(
    k: usize,
    seed: u64,
    q0: &[f64],
    intervals: Option<&[(f64, f64)]>,
    nphases: usize,
) -> StartGuess {
    if k == 0 {
        return StartGuess {
            q: q0.to_vec(),
            durations: vec![1.0; nphases],
        };
    }
    // One stream per start, so that start k is the same whatever N is.
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(k as u64);
    StartGuess {
        // One draw per joint whatever its interval, so that the durations of start k do not
        // depend on the intervals.
        q: q0
            .iter()
            .enumerate()
            .map(|(i, &q)| match intervals {
                None => q + rng.random_range(-START_NEIGHBOURHOOD..START_NEIGHBOURHOOD),
                Some(iv) => {
                    let u: f64 = rng.random();
                    iv.get(i).map_or(q, |&(lo, hi)| lo + (hi - lo) * u)
                }
            })
            .collect(),
        durations: (0..nphases)
            .map(|_| libm::pow(10f64, rng.random_range(-1.3..0.2)))
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
    revolution: bool,
) -> Result<Vec<Vec<(String, ProblemSettings)>>, PipelineError> {
    let eps = target.epsilon;
    let q0 = &target.guess.free;
    let intervals = revolution.then(|| start_intervals(&target.scene, q0));
    let nphases = target.modes.len();
    let periodic = problem.is_periodic();
    Ok(match strategy {
        // `target` is built with `settings`, so its warm start is the chain's (docs/optima.md,
        // "A guess of your own").
        Strategy::Direct => {
            let label = match warm_start_kind(target) {
                Some(kind) => format!("direct, {kind}"),
                None => "direct".into(),
            };
            vec![vec![(label, settings.clone())]]
        }
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
                                    q: q0.clone(),
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
                return Err(PipelineError::NoStarts);
            }
            (0..starts)
                .map(|k| {
                    let sg = random_start(k, seed, q0, intervals.as_deref(), nphases);
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
pub(crate) fn effective(settings: &ProblemSettings, strategy: Strategy) -> Strategy {
    if settings.warm_start.is_some() {
        Strategy::Direct
    } else {
        strategy
    }
}

/// The stages of one chain: (label, settings of the stage).
pub(crate) type Chain = Vec<(String, ProblemSettings)>;

/// The target problem (built with `settings`) and the stages of every chain of `strategy`
/// (index = chain/start index), with the stick continuation where it applies (`periodic-qc`,
/// a first bound `stick_continuation` above the problem's); a multi-start's joints drawn over
/// their revolution with `revolution` (the global search's sampling), near q⁰ without.
pub(crate) fn prepare_chains(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    stick_continuation: Option<f64>,
    revolution: bool,
) -> Result<(BuiltProblem, Vec<Chain>), PipelineError> {
    let target = build(problem, settings)?;
    let mut chains = chains_of(problem, settings, strategy, &target, revolution)?;
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
    Ok((target, chains))
}

/// Runs the chains of `strategy` that belong to `shard` (all of them for [`Shard::WHOLE`]),
/// in parallel; the results come back in chain order with their global chain indices, so
/// nothing depends on the scheduling of the threads.
pub(crate) fn run_chains(
    problem: Problem,
    settings: &ProblemSettings,
    strategy: Strategy,
    shard: Shard,
    stick_continuation: Option<f64>,
    progress: Progress<'_>,
) -> Result<Vec<(usize, ChainResult)>, PipelineError> {
    let (target, chains) = prepare_chains(problem, settings, strategy, stick_continuation, false)?;
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
) -> Result<(BuiltProblem, OcpSolution), PipelineError> {
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
        return Err(PipelineError::AllChainsFailed {
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
        .ok_or(PipelineError::Internal("the chosen chain has no solution"))?;
    sol.iterations = iterations;
    sol.solve_seconds = t0.elapsed().as_secs_f64();
    sol.strategy = Some(StrategyReport {
        strategy,
        records,
        chosen: ok.then_some(k),
        iterations,
        seconds: sol.solve_seconds,
        basin_hits: None,
        refinements: Vec::new(),
    });
    Ok((p, sol))
}

/// Starts of the multi-start of the periodic problems without the global search (`optimize
/// --hops 0`); the budget curve in BENCHMARKS.md shows how the best objective grows with the
/// starts.
pub const DEFAULT_STARTS: usize = 32;

/// Starts of the global search's sampling on its coarse mesh (`optimize --hops N --starts
/// 128`, `report strategies`; [`super::search::CoarseSampling`], where a start costs about a
/// fifth of one on the default mesh): the good `periodic-qc` basins are each reached by about
/// one start in 250 (BENCHMARKS.md, "Global search on a coarse mesh"), so the starts find the
/// neighbourhoods and the basin hopping the optima.
pub const GLOBAL_STARTS: usize = 128;

/// Seed of the default multi-start.
pub const DEFAULT_SEED: u64 = 0;

/// The default strategy of `problem` on `scheme`: a seeded multi-start of
/// [`GLOBAL_STARTS`] starts for the periodic problems, the sampling of the global search that
/// `optimize` and the paper report run on it (their landscapes have many local optima: for
/// `periodic-qc` the continuation's best end point is 66 % above the best known optimum; for
/// `periodic-cot` it is 25× above the multi-start's verified optimum, BENCHMARKS.md), the
/// continuation in ε for the others, and one direct solve with Legendre–Gauss (an LG solve
/// takes about 4× a Radau one).
pub fn default_strategy(problem: Problem, scheme: Scheme) -> Strategy {
    match scheme {
        Scheme::Lg => Strategy::Direct,
        Scheme::Radau { .. } if problem.is_periodic() => Strategy::Multistart {
            starts: GLOBAL_STARTS,
            seed: DEFAULT_SEED,
        },
        Scheme::Radau { .. } => Strategy::Continuation,
    }
}

/// [`default_strategy`] without the global search (`optimize --hops 0`): for the periodic
/// problems [`DEFAULT_STARTS`] starts on the problem's own mesh, a cheaper search whose optima
/// depend more on the seed (decision record 0029).
pub fn multistart_strategy(problem: Problem, scheme: Scheme) -> Strategy {
    match default_strategy(problem, scheme) {
        Strategy::Multistart { seed, .. } => Strategy::Multistart {
            starts: DEFAULT_STARTS,
            seed,
        },
        other => other,
    }
}
