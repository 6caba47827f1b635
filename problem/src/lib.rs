//! bf-problem: the ball-and-finger optimal-control problem (paper Sect. 4–7) in one place.
//!
//! * [`node`]: the node functions of a phase on the bf-codegen expression graph — free and
//!   stick dynamics (eq. 26, 29), the stick constraint (eq. 14/27 or its index-1 form
//!   eq. 31–32), validity (h eq. 4, λ_n eq. 12, friction cone eq. 18–19), cost integrands
//!   (eq. 60–65) — and the scene constants they read ([`node::Physics`]);
//! * [`kernels`]: which node functions are emitted as flat kernels, and their emission
//!   (bf-generated's build script calls [`kernels::emit_node_kernels`]);
//!
//! and, with the `catalogue` feature (default; needs bf-optim):
//!
//! * [`points`]: the sticking impact law (eq. 40, 66) or Newton's (eq. 39) and the other point
//!   functions, contact diagnostics;
//! * [`catalogue`]: the problems ([`Problem`]) with one function per archetype, their
//!   settings and initial guesses, built into a transcribed [`BuiltProblem`], whose solution
//!   record it builds at an NLP point ([`solution_at`]);
//! * [`solution`]: the solution record ([`OcpSolution`], `solution.json`), data only;
//! * [`arm`]: point-to-point optimal control of an arm without a ball (`reach-arm`);
//! * [`error`]: [`ProblemError`], the crate's error enum, and below it the two types it names:
//!   [`id`] ([`Problem`]) and [`start`] ([`StartGuess`]).
//!
//! bf-generated depends on this crate at build time, so this crate does not depend on it: the
//! scenes and the emitted node kernels come in through [`Generated`].

pub mod kernels;
pub mod node;

#[cfg(feature = "catalogue")]
pub mod arm;
#[cfg(feature = "catalogue")]
pub mod catalogue;
#[cfg(feature = "catalogue")]
pub mod error;
#[cfg(feature = "catalogue")]
pub mod id;
#[cfg(feature = "catalogue")]
pub mod points;
#[cfg(feature = "catalogue")]
pub mod solution;
#[cfg(feature = "catalogue")]
pub mod start;

pub use node::{CostKind, PhaseMode, Physics, StickLevel};

#[cfg(feature = "catalogue")]
pub use catalogue::{
    BuiltProblem, COT_MAX_PERIOD, Generated, GuessKind, MIN_STICK, Problem, ProblemSettings,
    QC_OMEGA_REF, StartGuess, build, check_settings, mean_omega, solution_at, warm_initial_point,
};
#[cfg(feature = "catalogue")]
pub use error::ProblemError;
#[cfg(feature = "catalogue")]
pub use solution::{OcpSolution, PlannedImpact, Samples};
