//! The study layer: everything that solves, checks and reports the ball-and-finger problems
//! of bf-problem on the engines below it.
//!
//! * [`arm`]: `reach-arm` on arms without a ball: solve, per-element re-integration, files;
//! * [`appendix`]: the paper's Appendix A/B as printed against derivations (the misprints);
//! * [`solve`](mod@solve): the solve-and-retry policy (interior-point settings, dual-regularization retry,
//!   geometric-guess fallback) and primal-dual warm starts;
//! * [`strategy`]: continuation and multi-start searches for good local optima (Sect. 7);
//! * [`refine`]: adaptive hp mesh refinement (Sect. 5);
//! * [`verify`]: re-integration of the optimal torques with the simulator (bf-sim);
//! * [`solution_io`]: `solution.json` and `torques.csv`;
//! * [`scenarios`]: the three scenarios of Sect. 6.1 solved, verified, plotted and checked;
//! * [`claims`]: the paper's claims of Sect. 6.1 with verdicts and, where they differ, why; the
//!   bounds an optimum sits on;
//! * [`openloop`]: the optimal torques replayed open loop in the full hybrid model (Sect. 6.2);
//! * [`extremes`]: numerical stability at the edges of the domain (one file per probe);
//! * [`speed_accuracy`]: error versus computing time for integrators, collocation meshes, the
//!   smoothing ε and the generated-kernel variants (one file per study).
//!
//! [`build`] builds a catalogue problem on the scenes and node kernels of bf-generated
//! ([`GENERATED`]); it requires every phase node function to run on an emitted kernel, so a
//! graph that changed without its kernels being re-emitted is an error, not a slow solve.

pub mod appendix;
pub mod arm;
pub mod claims;
pub mod closed_loop;
pub mod error;
pub mod extremes;
pub mod openloop;
pub mod refine;
pub mod scenarios;
pub mod search;
pub mod solution_io;
pub mod solve;
pub mod speed_accuracy;
pub mod strategy;
pub mod verify;

use bf_optim::ocp::{KernelUse, NodeKernel};
use bf_problem::{BuiltProblem, Generated, Problem, ProblemSettings};

pub use bf_problem::OcpSolution;

pub use error::StudyError;
pub use solution_io::SolutionIo;
pub use solve::{solve, solve_warm, solver_settings, warm_settings};

/// The emitted node kernel of bf-generated with this structural fingerprint, as bf-optim's
/// collocation takes it.
pub fn node_kernel(fingerprint: u128) -> Option<NodeKernel> {
    bf_generated::node_kernel(fingerprint).map(|k| NodeKernel {
        name: k.name,
        n_out: k.n_out,
        n_local: k.n_local,
        n_fixed: k.n_fixed,
        jacobian_pattern: k.jacobian_pattern,
        hessian_pattern: k.hessian_pattern,
        value: k.value,
        jacobian: k.jacobian,
        hessian: k.hessian,
        x4: k.x4.map(|b| bf_optim::ocp::NodeKernelX4 {
            value: b.value,
            jacobian: b.jacobian,
            hessian: b.hessian,
        }),
    })
}

/// The scenes and node kernels of bf-generated, kernels required.
pub const GENERATED: Generated = Generated {
    scene_toml: bf_generated::scene_toml,
    kernels: KernelUse::Require(node_kernel),
};

/// Builds `problem` with `settings` on [`GENERATED`].
pub fn build(problem: Problem, settings: &ProblemSettings) -> Result<BuiltProblem, StudyError> {
    Ok(bf_problem::build(problem, settings, &GENERATED)?)
}
