//! The optima `paper` presents in Sect. 6.1 (the periodic problems of eq. 60–66 with the
//! sticking impact law of eq. 40) and the plan it executes in closed loop (Sect. 6.2, Newton's
//! law eq. 39): the verified results of `optimize`'s default global search (seed 0;
//! [`crate::pipeline::global`]), stored under `data/optima/` and compiled into the program, so
//! that the report shows the global search's optima without spending the three minutes
//! of CPU those searches take on two cores (decision record 0041).
//!
//! * [`STORED_OPTIMA`]: one entry per presented problem, with the command that produced it
//!   ([`StoredOptimum::command`]);
//! * [`StoredOptimum::resolve`]: the stored optimum solved again by this program on its own
//!   problem and mesh, warm from its own primal-dual point
//!   ([`crate::pipeline::solve::resolve_at_own_point`]); `paper` verifies the result as it
//!   verifies any optimum, so a stored optimum that this program no longer reproduces or
//!   verifies is flagged like any other;
//! * [`stored_optimum`]: the entry for a problem, impact law and stick-phase bound, if one is
//!   stored.
//!
//! Kept current like golden files: `cargo test --release --test stored_optima -- --ignored`
//! runs each search again and fails when it no longer finds the stored optimum; with
//! `BF_OVERWRITE_OPTIMA=1` it writes the new results instead.

use std::path::{Path, PathBuf};

use bf_problem::catalogue::MIN_STICK;
use bf_problem::{BuiltProblem, OcpSolution, Problem};

use crate::pipeline::error::PipelineError;

/// One stored optimum: the problem, impact law and stick-phase bound it was searched with, and
/// its two documents (`solution.json` and `solution-internals.json` as `optimize` wrote them).
#[derive(Debug, Clone, Copy)]
pub struct StoredOptimum {
    /// Directory under `data/optima/`.
    pub dir: &'static str,
    /// The problem.
    pub problem: Problem,
    /// `--impact-law` of the search (`None`: `optimize`'s default plan, decision record 0040).
    pub law: Option<&'static str>,
    /// `--min-stick` of the search (s).
    pub min_stick: f64,
    /// `--impulse-cone` of the search (eq. 66 imposed at the impact).
    pub impulse_cone: bool,
    solution: &'static str,
    internals: &'static str,
}

macro_rules! stored {
    ($dir:literal, $problem:expr, $law:expr, $min_stick:expr) => {
        stored!($dir, $problem, $law, $min_stick, false)
    };
    ($dir:literal, $problem:expr, $law:expr, $min_stick:expr, $impulse_cone:expr) => {
        StoredOptimum {
            dir: $dir,
            problem: $problem,
            law: $law,
            min_stick: $min_stick,
            impulse_cone: $impulse_cone,
            solution: include_str!(concat!("../../data/optima/", $dir, "/solution.json")),
            internals: include_str!(concat!(
                "../../data/optima/",
                $dir,
                "/solution-internals.json"
            )),
        }
    };
}

/// The optima `paper` presents: the three problems of Sect. 6.1, `periodic-qc` with a stick
/// phase of at least 0.1 s and `periodic-cot` with the impulse cone of eq. 66 imposed (Sect. 7),
/// posed as the paper poses them (the sticking impact law, eq. 40), and the plans `optimize`
/// makes of `periodic-qc` and `periodic-cot-human` by default for the plant that executes them
/// (Newton's impact law with margins), which the report executes in closed loop.
pub static STORED_OPTIMA: [StoredOptimum; 7] = [
    stored!("periodic-qc", Problem::PeriodicQc, Some("stick"), MIN_STICK),
    stored!(
        "periodic-cot",
        Problem::PeriodicCot,
        Some("stick"),
        MIN_STICK
    ),
    stored!(
        "periodic-cot-human",
        Problem::PeriodicCotHuman,
        Some("stick"),
        MIN_STICK
    ),
    stored!(
        "periodic-qc-min-stick-0.1",
        Problem::PeriodicQc,
        Some("stick"),
        crate::paper::report::min_stick::LONG_MIN_STICK
    ),
    stored!(
        "periodic-cot-impulse-cone",
        Problem::PeriodicCot,
        Some("stick"),
        MIN_STICK,
        true
    ),
    stored!("periodic-qc-plan", Problem::PeriodicQc, None, MIN_STICK),
    stored!(
        "periodic-cot-human-plan",
        Problem::PeriodicCotHuman,
        None,
        MIN_STICK
    ),
];

impl StoredOptimum {
    /// Where the documents live in the repository (and where the overwrite writes them).
    pub fn path(&self) -> PathBuf {
        Path::new("data/optima").join(self.dir)
    }

    /// The command that produced the stored optimum (`optimize`'s default global search,
    /// seed 0).
    pub fn command(&self) -> String {
        let law = self
            .law
            .map(|l| format!(" --impact-law {l}"))
            .unwrap_or_default();
        let stick = if self.min_stick == MIN_STICK {
            String::new()
        } else {
            format!(" --min-stick {}", self.min_stick)
        };
        let cone = if self.impulse_cone {
            " --impulse-cone"
        } else {
            ""
        };
        format!(
            "ball-finger optimize --problem {}{law}{stick}{cone} --out {}",
            self.problem.name(),
            self.path().display()
        )
    }

    /// The stored solution as `optimize` wrote it.
    pub fn solution(&self) -> Result<OcpSolution, PipelineError> {
        crate::pipeline::solution_io::read_documents(
            self.solution,
            self.internals,
            &self.path().join("solution.json"),
            &self.path().join("solution-internals.json"),
        )
    }

    /// The stored optimum solved again on its own problem and mesh, warm from its own
    /// primal-dual point (not verified here).
    pub fn resolve(&self) -> Result<(BuiltProblem, OcpSolution), PipelineError> {
        crate::pipeline::solve::resolve_at_own_point(&self.solution()?)
    }
}

/// The stored optimum of `problem` searched with the impact law `law` (`--impact-law`, `None`
/// for `optimize`'s default plan), the stick-phase bound `min_stick` and, where
/// `impulse_cone`, eq. 66 imposed, if one of [`STORED_OPTIMA`] is (a test checks that every
/// file records the problem and settings its entry names).
pub fn stored_optimum(
    problem: Problem,
    law: Option<&str>,
    min_stick: f64,
    impulse_cone: bool,
) -> Option<&'static StoredOptimum> {
    STORED_OPTIMA.iter().find(|s| {
        s.problem == problem
            && s.law == law
            && s.min_stick == min_stick
            && s.impulse_cone == impulse_cone
    })
}

/// The stored optimum of `problem` posed as the paper's Sect. 6.1 poses it: the sticking law,
/// the default stick-phase bound, no impulse cone ([`stored_optimum`]).
pub fn sticking_optimum(problem: Problem) -> Option<&'static StoredOptimum> {
    stored_optimum(problem, Some("stick"), MIN_STICK, false)
}

/// The stored plan for the plant of `problem`: what `optimize --problem P` makes by default
/// (Newton's law with the plan margins, [`stored_optimum`] with no `--impact-law`).
pub fn plan_for_the_plant(problem: Problem) -> Option<&'static StoredOptimum> {
    stored_optimum(problem, None, MIN_STICK, false)
}
