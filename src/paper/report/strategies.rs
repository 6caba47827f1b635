//! The solve-strategy comparison (paper Sect. 4 problems, Sect. 6.1 objectives):
//! cold start (`direct`) vs `continuation` vs `multistart` (N = 8, 32: the best start) vs the
//! global search of `optimize` (its default starts on a coarse mesh, basin hopping and
//! polishing, `pipeline::global`, then the best re-solved on the mesh, re-integrated, refined) on the periodic problems, with objective φ (eq. 60),
//! iterations, wall time, the period found and the re-integration defects of each final
//! solution (`pipeline::verify`). `--quick` runs `periodic-qc` only, without N = 32.

use std::fmt::Write as _;
use std::time::Instant;

use crate::pipeline::search::{VerifyPolicy, search};
use crate::pipeline::strategy::{Shard, Strategy, solve_with_strategy};
use crate::pipeline::verify::verify;
use anyhow::Result;
use bf_problem::{OcpSolution, Problem, ProblemSettings};

/// One (problem, strategy) result.
#[derive(Debug, Clone)]
pub struct StrategyRow {
    /// Problem name.
    pub problem: String,
    /// Strategy.
    pub strategy: Strategy,
    /// Whether the global search ran on it (verification, refinement, basin hopping).
    pub global: bool,
    /// Final status (Debug text) or the error.
    pub status: String,
    /// Objective φ (NaN on error).
    pub objective: f64,
    /// Period (s).
    pub period: f64,
    /// Total interior-point iterations.
    pub iterations: usize,
    /// Wall time (s).
    pub seconds: f64,
    /// Solves that ended Solved/Acceptable, of all solves.
    pub successes: (usize, usize),
    /// Max end-of-phase state defect of the re-integration (NaN if not verified).
    pub defect: f64,
}

impl StrategyRow {
    /// The strategy's name, with `+ global search` where the global search ran on it.
    pub fn label(&self) -> String {
        if self.global {
            format!("{} + global search", self.strategy)
        } else {
            self.strategy.to_string()
        }
    }
}

/// The strategies compared (with whether the global search runs on them).
pub fn strategies(quick: bool) -> Vec<(Strategy, bool)> {
    let n = if quick { 8 } else { 32 };
    let mut v = vec![
        (Strategy::Direct, false),
        (Strategy::Continuation, false),
        (Strategy::Multistart { starts: 8, seed: 0 }, false),
    ];
    if !quick {
        v.push((Strategy::Multistart { starts: n, seed: 0 }, false));
    }
    // The global search with its starts (sampled on the coarse mesh).
    let g = if quick {
        n
    } else {
        crate::pipeline::strategy::GLOBAL_STARTS
    };
    v.push((Strategy::Multistart { starts: g, seed: 0 }, true));
    v
}

fn row(problem: Problem, strategy: Strategy, global: bool) -> StrategyRow {
    let t0 = Instant::now();
    let settings = ProblemSettings::default();
    let res = if global {
        search(
            problem,
            &settings,
            strategy,
            Shard::WHOLE,
            &VerifyPolicy::default().global(crate::pipeline::search::DEFAULT_HOPS),
            None,
        )
        .and_then(|s| s.best())
        .and_then(|(p, sol)| {
            p.map(|p| (p, sol))
                .ok_or(crate::pipeline::PipelineError::Internal(
                    "the global search's optimum has no problem",
                ))
        })
    } else {
        solve_with_strategy(problem, &settings, strategy, None)
    };
    let seconds = t0.elapsed().as_secs_f64();
    match res {
        Ok((p, sol)) => {
            let defect = verify(&p, &sol, 1e-10).map_or(f64::NAN, |v| v.max_defect);
            StrategyRow {
                problem: problem.to_string(),
                strategy,
                global,
                status: crate::names::name(&sol.status),
                objective: sol.objective,
                period: sol.period,
                iterations: sol.iterations,
                seconds,
                successes: successes(&sol),
                defect,
            }
        }
        Err(e) => StrategyRow {
            problem: problem.to_string(),
            strategy,
            global,
            status: format!("error: {}", crate::errors::chain(&e)),
            objective: f64::NAN,
            period: f64::NAN,
            iterations: 0,
            seconds,
            successes: (0, 0),
            defect: f64::NAN,
        },
    }
}

fn successes(sol: &OcpSolution) -> (usize, usize) {
    sol.strategy.as_ref().map_or((0, 0), |r| {
        (
            r.records.iter().filter(|r| r.status.is_success()).count(),
            r.records.len(),
        )
    })
}

/// Runs the comparison and returns its markdown section; `progress` is told each finished row.
pub fn strategies_report(quick: bool, progress: &dyn Fn(&StrategyRow)) -> Result<String> {
    let problems: &[Problem] = if quick {
        &[Problem::PeriodicQc]
    } else {
        &[
            Problem::PeriodicQc,
            Problem::PeriodicCot,
            Problem::PeriodicCotHuman,
        ]
    };
    let mut rows = Vec::new();
    for &p in problems {
        for (s, global) in strategies(quick) {
            let r = row(p, s, global);
            progress(&r);
            rows.push(r);
        }
    }
    Ok(markdown(&rows))
}

/// The table of `rows`, with φ relative to the cold start of the same problem.
pub fn markdown(rows: &[StrategyRow]) -> String {
    let mut md = String::from(
        "Default problem settings (hp-Radau 3 × 10 points per phase, ε = 0.01); every \
         strategy from scratch; wall time on this machine with 2 worker threads (rayon) for \
         the parallel strategies. `multistart` keeps its best start (`optimize --hops 0`; \
         each start draws every joint within 0.6 rad of the default guess); \
         `+ global search` is the default of `optimize`: the starts (each joint anywhere in its \
         revolution) solved on a coarse mesh \
         (3 × 4 points per phase; on the COT problems every other start first held to the \
         period of its guess, then released), reshaping moves (the elbow flip, phase-duration bounds) \
         and basin hopping from the best distinct optima and polishing of the winner there, the best optima that differ in shape re-solved on the problem's mesh (each from a warm and from a close barrier start, the lower kept; more of them while a \
         coarse objective is below the best re-solved one, or the best verified one) and re-integrated, unverified better \
         ones hp-refined (each only while it stays below the best verified one), then the moves and hops again around the verified winner on its own mesh \
         (a second round around a new winner at least 0.1 % lower; docs/optima.md). φ/φ_cold < 1 is a better optimum than the cold start's. \
         Defect: the largest end-of-phase state error when each phase is re-integrated with \
         the optimal torques (DOPRI5, rtol 1e-10).\n\n\
         | problem | strategy | status | φ | φ/φ_cold | period (s) | successful solves | iterations | time (s) | defect |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let cold = rows
            .iter()
            .find(|c| c.problem == r.problem && c.strategy == Strategy::Direct && !c.global)
            .map_or(f64::NAN, |c| c.objective);
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.6e} | {:.3} | {:.3} | {}/{} | {} | {:.1} | {:.1e} |",
            r.problem,
            r.label(),
            r.status,
            r.objective,
            r.objective / cold,
            r.period,
            r.successes.0,
            r.successes.1,
            r.iterations,
            r.seconds,
            r.defect
        );
    }
    md
}
