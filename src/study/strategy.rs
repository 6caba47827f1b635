//! Solve strategies: good optima of the non-convex periodic problems without hand-holding
//! (paper Sect. 7 suggests warm-starting from runs of simplified problems).
//!
//! * [`Strategy::Direct`]: one interior-point solve from the PARAMS.md guess (q ≡ q⁰,
//!   t_f⁽ⁱ⁾ = i), with the geometric guess as fallback ([`super::solve`]).
//! * [`Strategy::Continuation`] (the default): a homotopy in the constraints and the smoothing.
//!   For the periodic problems (eq. 60 ratio objectives) the period T = Σ t_f⁽ⁱ⁾ is the
//!   dominant non-convexity — the QC optimum at T ≈ 2.6 s that a cold start finds is 2–5×
//!   worse than optima at T ≈ 0.7–1.9 s. Each chain k
//!   1. solves with the period fixed to T_k (a grid, [`period_grid`]) and the saturation
//!      smoothed to ε₀ = [`EPS_FACTOR`]·ε (eq. 59: a larger ε rounds the contact geometry),
//!      from the PARAMS.md joint guess with durations T_k/3;
//!   2. frees the period (warm start with primal and dual variables: every stage has the same
//!      NLP layout, the period row only changes its bounds);
//!   3. tightens ε₀ → ε, warm-started.
//!
//!   The chains run in parallel (rayon) and the best successful end point wins. Problems
//!   without a period run the ε-homotopy alone (steps 3 from ε₀ = 10ε).
//! * [`Strategy::Multistart`]: N guesses around the default (joint angles q⁰ ± 0.6 rad
//!   uniform, phase durations log-uniform in [0.05, 1.6] s; start 0 is the default guess
//!   itself, so the result is never worse than `Direct`), solved in parallel; the best
//!   successful solution wins.
//!
//! Every stage/start is recorded ([`StageRecord`]: status, objective, period, iterations,
//! seconds) in [`StrategyReport`], stored in `solution.json`.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{BuiltProblem, OcpSolution, ProblemSettings, Q_GUESS, StartGuess, build, solve};
use super::{GuessKind, solve_warm};
use crate::ipm::Status;
use crate::ocp::OcpError;

/// ε₀ / ε of the first continuation stage of the periodic problems.
pub const EPS_FACTOR: f64 = 5.0;

/// How [`solve_with_strategy`] searches for a good local optimum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Strategy {
    /// One solve from the default guess (geometric guess as fallback).
    Direct,
    /// Period sweep + release + ε-homotopy (module docs); the default.
    #[default]
    Continuation,
    /// `starts` guesses drawn around the default with seed `seed`.
    Multistart {
        /// Number of starts (≥ 1; start 0 is the default guess).
        starts: usize,
        /// Seed of the ChaCha8 generator.
        seed: u64,
    },
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Strategy::Direct => write!(f, "direct"),
            Strategy::Continuation => write!(f, "continuation"),
            Strategy::Multistart { starts, seed } => {
                write!(f, "multistart ({starts} starts, seed {seed})")
            }
        }
    }
}

/// One solve of a strategy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageRecord {
    /// Chain or start index.
    pub chain: usize,
    /// Stage name, e.g. `sweep T=1`, `release`, `eps 0.01`, `start 3`.
    pub stage: String,
    /// Solver status.
    pub status: Status,
    /// Objective φ at the end of the stage (of that stage's problem).
    pub objective: f64,
    /// Period (total duration) at the end of the stage (s).
    pub period: f64,
    /// Interior-point iterations of the stage.
    pub iterations: usize,
    /// Wall time of the stage (s, build included).
    pub seconds: f64,
}

/// Everything a strategy ran, and which result it kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StrategyReport {
    /// The strategy.
    pub strategy: Strategy,
    /// Every stage of every chain/start, in chain order.
    pub records: Vec<StageRecord>,
    /// The chain/start whose final stage was kept (`None` if none succeeded: then the best
    /// failed one is returned).
    pub chosen: Option<usize>,
    /// Total interior-point iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
}

impl StrategyReport {
    /// A plain-text table of the records, one line each, the kept chain marked `*`.
    pub fn table(&self) -> String {
        let mut s = format!(
            "strategy {}: {} solves, {} iterations, {:.2} s\n  chain  stage                 status          objective     period  iter  time(s)\n",
            self.strategy,
            self.records.len(),
            self.iterations,
            self.seconds
        );
        for r in &self.records {
            s.push_str(&format!(
                "{} {:5}  {:<20}  {:<14} {:>12.6e} {:>8.4} {:>5} {:>8.2}\n",
                if Some(r.chain) == self.chosen {
                    '*'
                } else {
                    ' '
                },
                r.chain,
                r.stage,
                format!("{:?}", r.status),
                r.objective,
                r.period,
                r.iterations,
                r.seconds
            ));
        }
        s
    }
}

/// Progress reporter: called after every stage (from worker threads).
pub type Progress<'a> = Option<&'a (dyn Fn(&StageRecord) + Sync)>;

/// Fixed-period values of the continuation's first stage (s): around the QC optima for
/// `periodic-qc`, spread up to [`super::COT_MAX_PERIOD`] for COT.
pub fn period_grid(name: &str) -> Vec<f64> {
    if name == "periodic-qc" {
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

fn failed_record(chain: usize, stage: String, e: &OcpError, t0: Instant) -> StageRecord {
    StageRecord {
        chain,
        stage: format!("{stage} ({e})"),
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
    name: &str,
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
            None => build(name, &settings),
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

/// Solves problem `name` with `strategy`. `settings` are the target problem's (ε, mesh, ...;
/// a warm start in them makes every strategy a single warm-started solve). Returns the final
/// stage's problem (for verification and refinement) and solution, whose
/// [`OcpSolution::strategy`] lists every stage.
pub fn solve_with_strategy(
    name: &str,
    settings: &ProblemSettings,
    strategy: Strategy,
    progress: Progress<'_>,
) -> Result<(BuiltProblem, OcpSolution), OcpError> {
    let t0 = Instant::now();
    let strategy = if settings.warm_start.is_some() {
        Strategy::Direct
    } else {
        strategy
    };
    let target = build(name, settings)?;
    let eps = target.epsilon;
    let nq = target.physics.nq;
    let nphases = target.modes.len();
    let periodic = name.starts_with("periodic");
    let chains: Vec<Vec<(String, ProblemSettings)>> = match strategy {
        Strategy::Direct => vec![vec![("direct".into(), settings.clone())]],
        Strategy::Continuation if periodic => {
            let eps0 = EPS_FACTOR * eps;
            period_grid(name)
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
                return Err(OcpError::InvalidProblem(
                    "multi-start needs at least one start".into(),
                ));
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
    };
    // `direct` solves the problem built above instead of building it again.
    let mut prebuilt: Vec<Option<BuiltProblem>> = chains.iter().map(|_| None).collect();
    if strategy == Strategy::Direct {
        prebuilt[0] = Some(target);
    }
    let results: Vec<ChainResult> = chains
        .into_par_iter()
        .zip(prebuilt)
        .enumerate()
        .map(|(k, (stages, first))| run_chain(name, k, stages, first, progress))
        .collect();
    let best = best_index(&results);
    let records: Vec<StageRecord> = results.iter().flat_map(|(r, _)| r.clone()).collect();
    let iterations = records.iter().map(|r| r.iterations).sum();
    let Some((k, ok)) = best else {
        let why = records
            .iter()
            .map(|r| format!("{}: {}", r.chain, r.stage))
            .collect::<Vec<_>>()
            .join("; ");
        return Err(OcpError::InvalidProblem(format!(
            "every {strategy} solve failed: {why}"
        )));
    };
    let mut results = results;
    let (p, mut sol) = results.swap_remove(k).1.ok_or_else(|| {
        OcpError::InvalidProblem("internal: the chosen chain has no solution".into())
    })?;
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
