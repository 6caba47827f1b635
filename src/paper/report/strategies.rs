//! The solve-strategy comparison (paper Sect. 4 problems, Sect. 6.1 objectives):
//! cold start (`direct`) vs `continuation` vs `multistart` (N = 8, 32: the best start) vs the
//! global search of `optimize` (its default starts on a coarse mesh, basin hopping and
//! polishing, `pipeline::global`, then the best re-solved on the mesh, re-integrated, refined) on the periodic problems, with objective φ (eq. 60),
//! iterations, wall time, the period found, the re-integration defect of each final solution
//! and whether it passes the verification (`pipeline::verify`). `--quick` runs `periodic-qc`
//! only, without N = 32.
//!
//! The table is a measurement: an unverified row is flagged, not a failure of the report; a
//! row whose solve errored is ([`failures`]), and a φ/φ_cold ratio against a cold start that
//! errored or is unverified is flagged where it is shown ([`flags`]).

use std::fmt::Write as _;
use std::time::Instant;

use crate::pipeline::search::{VerifyPolicy, search};
use crate::pipeline::strategy::{Shard, Strategy, solve_with_strategy};
use crate::pipeline::verify::{VERIFIED_DEFECT, verify};
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
    /// Largest state error at the collocation element ends, each element re-integrated from
    /// its collocated start (NaN if the re-integration could not run).
    pub defect: f64,
    /// Why the solution does not pass the verification
    /// ([`crate::pipeline::verify::unverified_reason`]; `None` where it does, and for a row
    /// that errored).
    pub unverified: Option<String>,
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

    /// Whether the row's solution passes the verification (`pipeline::verify::passes`: every
    /// element re-integrated, defect ≤ [`VERIFIED_DEFECT`], path checks within their
    /// allowances); false for a row that errored.
    pub fn verified(&self) -> bool {
        !self.errored() && self.unverified.is_none()
    }

    /// Whether the row's solve returned an error instead of a solution.
    pub fn errored(&self) -> bool {
        self.status.starts_with("error")
    }

    /// The row's verdict for progress lines and the table: `verified`, `UNVERIFIED (why)` or
    /// `error`.
    pub fn verdict(&self) -> String {
        match (&self.unverified, self.errored()) {
            (_, true) => "error".into(),
            (Some(why), _) => format!("UNVERIFIED ({why})"),
            (None, _) => "verified".into(),
        }
    }

    /// Whether this row is the cold start (`direct`, no global search) its problem's ratios
    /// are taken against.
    fn is_baseline(&self) -> bool {
        self.strategy == Strategy::Direct && !self.global
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
            let (defect, unverified) = match verify(&p, &sol, 1e-10) {
                Ok(v) => (v.max_defect, crate::pipeline::verify::unverified_reason(&v)),
                Err(e) => (
                    f64::NAN,
                    Some(format!(
                        "the re-integration could not run: {}",
                        crate::errors::chain(&e)
                    )),
                ),
            };
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
                unverified,
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
            unverified: None,
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

/// Runs the comparison and returns its rows (for [`markdown`], [`flags`] and [`failures`]);
/// `progress` is told each finished row.
pub fn strategies_report(quick: bool, progress: &dyn Fn(&StrategyRow)) -> Result<Vec<StrategyRow>> {
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
    Ok(rows)
}

/// The cold start of `r`'s problem, the baseline of its φ/φ_cold.
fn baseline<'a>(rows: &'a [StrategyRow], r: &StrategyRow) -> Option<&'a StrategyRow> {
    rows.iter()
        .find(|c| c.problem == r.problem && c.is_baseline())
}

/// What the reader must not take for a plain result, one line each: rows that errored, rows
/// that are unverified, and problems whose φ/φ_cold ratios are taken against a cold start that
/// errored or is unverified.
pub fn flags(rows: &[StrategyRow]) -> Vec<String> {
    let mut out = Vec::new();
    for r in rows {
        if r.errored() {
            out.push(format!("{} {}: {}", r.problem, r.label(), r.status));
        } else if let Some(why) = &r.unverified {
            out.push(format!("{} {}: unverified, {why}", r.problem, r.label()));
        }
    }
    let mut seen: Vec<&str> = Vec::new();
    for r in rows {
        if seen.contains(&r.problem.as_str()) {
            continue;
        }
        seen.push(&r.problem);
        match baseline(rows, r) {
            Some(b) if b.errored() => out.push(format!(
                "{}: no φ/φ_cold ratios, its cold start errored",
                r.problem
            )),
            Some(b) if !b.verified() => out.push(format!(
                "{}: the φ/φ_cold ratios are taken against an unverified cold start",
                r.problem
            )),
            Some(_) => {}
            None => out.push(format!("{}: no cold start, no φ/φ_cold ratios", r.problem)),
        }
    }
    out
}

/// Why the report failed, if it did: the rows whose solve errored (the comparison is missing
/// them). Unverified rows are measurements of the strategies, flagged in the table, not a
/// failure of the report.
pub fn failures(rows: &[StrategyRow]) -> Option<String> {
    let errored: Vec<String> = rows
        .iter()
        .filter(|r| r.errored())
        .map(|r| format!("{} {}", r.problem, r.label()))
        .collect();
    (!errored.is_empty()).then(|| {
        format!(
            "{} of {} rows of the strategy comparison errored: {}",
            errored.len(),
            rows.len(),
            errored.join(", ")
        )
    })
}

/// The table of `rows`, with φ relative to the cold start of the same problem, its verdict
/// column and, above it, what is flagged ([`flags`]).
pub fn markdown(rows: &[StrategyRow]) -> String {
    let mut md = format!(
        "The paper's problems: the sticking impact law (eq. 40) with the exact torque limits \
         and no clearance, which `optimize --impact-law stick` poses (`optimize`'s default for \
         the periodic problems is the plan for the plant, Newton's law with margins: \
         docs/optima.md), on hp-Radau 3 × 10 points per phase, ε = 0.01; every strategy from \
         scratch; wall time on this machine with {threads} worker threads (rayon) for the parallel \
         strategies. `multistart` keeps its best start, each solved once from its guess (each \
         start draws every joint within 0.6 rad of the default guess; `optimize --hops 0` \
         also holds each start's stick phase at 0.1 s or more first and refines, so it can end \
         elsewhere); `+ global search` is the search of `optimize --impact-law stick` (its \
         {starts} starts; 8 with `--quick`): the starts (each joint anywhere in its \
         revolution) solved on a coarse mesh \
         (3 × 4 points per phase; on the COT problems every other start first held to the \
         period of its guess, then released), reshaping moves (the elbow flip, phase-duration bounds) \
         and basin hopping from the best distinct optima and polishing of the winner there, the best optima that differ in shape re-solved on the problem's mesh (each from a warm and from a close barrier start, the lower kept; more of them while a \
         coarse objective is below the best re-solved one, or the best verified one) and re-integrated, unverified better \
         ones hp-refined (each only while it stays below the best verified one), then the moves and hops again around the verified winner on its own mesh \
         (a second round around a new winner at least 0.1 % lower; docs/optima.md); the other \
         strategies are not refined. φ/φ_cold < 1 is a better optimum than the cold start's. \
         Defect: the largest state error at the ends of the collocation elements when each \
         element is re-integrated from its collocated start state with the optimal torques \
         (DOPRI5, rtol 1e-10). Verified: every element re-integrated to its end, defect ≤ ",
        threads = rayon::current_num_threads(),
        starts = crate::pipeline::strategy::GLOBAL_STARTS,
    );
    let _ = write!(
        md,
        "{VERIFIED_DEFECT:e}, the free paths outside the ball and the stick phases inside the \
         friction cone within their allowances (the verification of `optimize`, docs/files.md); \
         an unverified row is a measurement of its strategy, flagged **no**, with the reason \
         in the list above the table.\n\n"
    );
    let flagged = flags(rows);
    if !flagged.is_empty() {
        let _ = writeln!(md, "**Flagged** ({}):\n", flagged.len());
        for f in &flagged {
            let _ = writeln!(md, "- {f}");
        }
        md.push('\n');
    }
    md.push_str(
        "| problem | strategy | status | verified | φ | φ/φ_cold | period (s) | successful solves | iterations | time (s) | defect |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let base = baseline(rows, r);
        let ratio = match base {
            Some(b) if !b.errored() && !r.errored() => {
                let x = format!("{:.3}", r.objective / b.objective);
                if b.verified() {
                    x
                } else {
                    format!("{x} (cold start **unverified**)")
                }
            }
            _ => "—".to_string(),
        };
        let verified = if r.errored() {
            "—"
        } else if r.verified() {
            "yes"
        } else {
            "**no**"
        };
        let num = |v: f64, f: &dyn Fn(f64) -> String| {
            if v.is_finite() {
                f(v)
            } else {
                "—".to_string()
            }
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {verified} | {} | {ratio} | {} | {}/{} | {} | {:.1} | {} |",
            r.problem,
            r.label(),
            r.status,
            num(r.objective, &|v| format!("{v:.6e}")),
            num(r.period, &|v| format!("{v:.3}")),
            r.successes.0,
            r.successes.1,
            r.iterations,
            r.seconds,
            num(r.defect, &|v| format!("{v:.1e}")),
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(
        problem: &str,
        strategy: Strategy,
        objective: f64,
        unverified: Option<&str>,
    ) -> StrategyRow {
        StrategyRow {
            problem: problem.into(),
            strategy,
            global: false,
            status: "Solved".into(),
            objective,
            period: 1.0,
            iterations: 10,
            seconds: 0.1,
            successes: (1, 1),
            defect: if unverified.is_some() { 2e-3 } else { 1e-6 },
            unverified: unverified.map(String::from),
        }
    }

    fn errored(problem: &str, strategy: Strategy) -> StrategyRow {
        StrategyRow {
            status: "error: the solver stopped".into(),
            objective: f64::NAN,
            period: f64::NAN,
            defect: f64::NAN,
            unverified: None,
            ..row(problem, strategy, 0.0, None)
        }
    }

    fn line<'a>(md: &'a str, problem: &str, strategy: &str) -> &'a str {
        md.lines()
            .find(|l| l.starts_with(&format!("| {problem} | {strategy} |")))
            .unwrap_or_else(|| panic!("no row {problem} {strategy}:\n{md}"))
    }

    /// An unverified solution is never shown as a plain result: its verdict cell says **no**,
    /// the reason is listed, and the tolerance is stated; verified rows say yes.
    #[test]
    fn unverified_rows_are_flagged_with_their_reason() {
        let rows = [
            row("periodic-qc", Strategy::Direct, 2.0, None),
            row(
                "periodic-qc",
                Strategy::Continuation,
                1.0,
                Some("its re-integration defect 2.000e-3 exceeds 1e-4"),
            ),
        ];
        let md = markdown(&rows);
        assert!(line(&md, "periodic-qc", "direct").contains("| Solved | yes |"));
        let cont = line(&md, "periodic-qc", "continuation");
        assert!(cont.contains("| Solved | **no** |"), "{cont}");
        assert!(cont.contains("| 0.500 |"), "{cont}");
        assert!(md.contains("defect ≤ 1e-4"), "{md}");
        assert!(
            md.contains("- periodic-qc continuation: unverified, its re-integration defect 2.000e-3 exceeds 1e-4"),
            "{md}"
        );
        // A measurement, not a failure of the report.
        assert_eq!(failures(&rows), None);
        assert_eq!(flags(&rows).len(), 1);
    }

    /// Ratios against an unverified cold start say so in every cell and in the flags; with
    /// an errored cold start there are none.
    #[test]
    fn ratios_against_an_unverified_or_failed_baseline_are_flagged() {
        let rows = [
            row(
                "periodic-cot",
                Strategy::Direct,
                2.0,
                Some("its re-integration defect 1.000e-2 exceeds 1e-4"),
            ),
            row("periodic-cot", Strategy::Continuation, 1.0, None),
            errored("periodic-qc", Strategy::Direct),
            row("periodic-qc", Strategy::Continuation, 1.0, None),
        ];
        let md = markdown(&rows);
        let cont = line(&md, "periodic-cot", "continuation");
        assert!(cont.contains("0.500 (cold start **unverified**)"), "{cont}");
        let qc = line(&md, "periodic-qc", "continuation");
        assert!(qc.contains("| yes | 1.000000e0 | — |"), "{qc}");
        let err = line(&md, "periodic-qc", "direct");
        assert!(
            err.contains("| error: the solver stopped | — | — | — |"),
            "{err}"
        );
        let f = flags(&rows);
        assert!(
            f.iter()
                .any(|l| l
                    .contains("periodic-cot: the φ/φ_cold ratios are taken against an unverified")),
            "{f:?}"
        );
        assert!(
            f.iter()
                .any(|l| l.contains("periodic-qc: no φ/φ_cold ratios, its cold start errored")),
            "{f:?}"
        );
        // An errored row fails the report.
        let why = failures(&rows).unwrap();
        assert!(
            why.contains("1 of 4 rows") && why.contains("periodic-qc direct"),
            "{why}"
        );
    }
}
